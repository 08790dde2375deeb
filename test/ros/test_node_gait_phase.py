"""``foot_fk_node``'s optional ``gait_phase`` input over real DDS: a steady JointState stream (the
A1 standing with its FR foot raised, no efforts) settles the contacts where the filter settles
without a prior; a ``gait_phase`` moves them to where the filter settles with that prior (both
computed here by :class:`ContactEstimator`, the filter's own arithmetic); once the scheduler
stops, its last message goes stale after ``gait_phase_timeout_s`` and the contacts return.
"""

from __future__ import annotations

import math
import time

from node_harness import LEGS, PYBULLET_NAMES, STANDING, Diagnostics, node_command
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.kinematics.quadruped import Quadruped

STEP_NS = 2_000_000  # 500 Hz
ANGLES = [*STANDING[:1], STANDING[1] + 0.25, STANDING[2] - 0.35, *STANDING[3:]]
"""[rad] The FR foot about 5 cm above the others: its height says swing, its stillness stance."""
PRIOR = [0.9, 0.1, 0.5, 0.02]
"""A scheduler's probabilities of stance for FR, FL, RR, RL."""
TIMEOUT_S = 0.3
SETTLED = 1e-9  # the filter's fixed point, reached to rounding within a few hundred samples
MAX_MESSAGES = 2500  # per part: 5 s at 500 Hz, a bound on every wait


def settled_probabilities(prior: list[float] | None) -> list[float]:
    """Where the filter settles on the stream, with or without ``prior``."""
    a1 = Quadruped.from_urdf()
    feet = a1.fk(ANGLES)
    legs = [(feet[leg].tolist(), [0.0, 0.0, 0.0]) for leg in range(4)]
    estimator = ContactEstimator(a1)
    for row in range(1000):
        step = estimator.step(
            row * STEP_NS * 1e-9, (ANGLES, [0.0] * 12, None), legs, ImuSample(), prior
        )
    return step.probabilities


def test_a_gait_phase_moves_the_contacts_as_the_filter_says_until_it_goes_stale(
    ros, processes
) -> None:
    without, with_prior = settled_probabilities(None), settled_probabilities(PRIOR)
    assert max(abs(a - b) for a, b in zip(without, with_prior, strict=True)) > 0.4
    node = processes.start(
        node_command("-p", "enable_verify:=false", "-p", f"gait_phase_timeout_s:={TIMEOUT_S}")
    )
    diagnostics = Diagnostics(ros)
    latest: list[list[float]] = []
    ros.node.create_subscription(
        JointState, "foot_contacts", lambda m: latest.append(m.position.tolist()), 100
    )
    joint_states = ros.node.create_publisher(JointState, "joint_states", QoSProfile(depth=1000))
    gait_phase = ros.node.create_publisher(JointState, "gait_phase", QoSProfile(depth=10))
    assert ros.spin_until(
        lambda: (
            joint_states.get_subscription_count() > 0
            and gait_phase.get_subscription_count() > 0
            and ros.node.count_publishers("foot_contacts") > 0
        ),
        30.0,
    ), processes.output(node)
    ros.spin_for(0.5)  # the node's readers match ours
    sent = [0]
    phase = JointState(name=list(LEGS), position=PRIOR)

    def stream_until(expected: list[float], scheduler: bool) -> bool:
        """Joint states at 500 Hz (and, with ``scheduler``, a gait phase every 10th) until the
        latest contacts are ``expected``; False after MAX_MESSAGES.
        """
        start = time.monotonic()
        for count in range(MAX_MESSAGES):
            if scheduler and count % 10 == 0:
                gait_phase.publish(phase)
            msg = JointState(name=PYBULLET_NAMES, position=ANGLES, velocity=[0.0] * 12)
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(
                1_000_000_000_000 + STEP_NS * sent[0], 1_000_000_000
            )
            joint_states.publish(msg)
            sent[0] += 1
            ros.spin_for(max(0.0, start + (count + 1) * STEP_NS * 1e-9 - time.monotonic()))
            if latest and all(
                math.isclose(p, q, abs_tol=SETTLED) for p, q in zip(latest[-1], expected)
            ):
                return True
        return False

    assert stream_until(without, scheduler=False), (latest[-1:], without)
    assert stream_until(with_prior, scheduler=True), (latest[-1:], with_prior)
    seen, deadline = diagnostics.received, time.monotonic() + 5.0
    while diagnostics.received == seen and time.monotonic() < deadline:  # the scheduler goes on
        gait_phase.publish(phase)
        ros.spin_for(0.05)
    used = diagnostics.latest.get("gait_phase", "")
    assert diagnostics.received > seen and used.startswith("used:"), used
    assert stream_until(without, scheduler=False), (latest[-1:], without)  # stale: no prior
    stale = diagnostics.fresh()["gait_phase"]
    assert stale.startswith("stale:") and "0 malformed" in stale, stale
    assert processes.interrupt(node) == 0
