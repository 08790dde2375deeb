"""``foot_fk_node``'s foot forces and contacts over real DDS: a PyBullet trot (joint_states with
efforts + imu at 500 Hz) gives, message for message, the numbers ``a1-leg-fk bag --forces`` gives
on a bag of the same stream; PyBullet's own foot contacts judge the stance; bad efforts cost
their legs only and are counted; a message without efforts publishes no forces and no contacts.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_factory import T0, BagSpec, JointStateMsg, T, header, write_bag
from builtin_interfaces.msg import Time
from force_trot import (
    A1,
    EMPTY_ROW,
    NAMES,
    NAN_FL_ROW,
    SHORT_ROW,
    STEP_NS,
    a1_trot,
    imu,
    joint_state,
    recorded_efforts,
)
from geometry_msgs.msg import WrenchStamped
from node_harness import LEGS, STANDING, Diagnostics, SensorStream, node_command
from rclpy.qos import QoSProfile
from rosbags.highlevel import AnyReader
from sensor_msgs.msg import JointState

from a1_leg_fk import cli
from a1_leg_fk.ros.markers import COLOR_RGBA, STANCE_RGBA, foot_markers


@pytest.fixture(scope="module")
def trot() -> dict[str, np.ndarray]:
    """1.6 s of the A1 in PyBullet (trotting from 0.5 s), 800 samples."""
    return a1_trot(1.6)


def bag_tool_outputs(tmp_path: Path, record: dict[str, np.ndarray]) -> tuple[dict, dict]:
    """``a1-leg-fk bag --forces --imu --causal --output-bag`` on the same stream: per leg
    {stamp: force}, and {stamp: (probabilities, normal forces)}."""
    spec = BagSpec()
    efforts = recorded_efforts(record["torques"])
    for row in range(len(record["angles"])):
        stamp = T0 + STEP_NS * row
        x, y, z, w = record["root_orientation"][row].tolist()
        zeros = T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0)
        message = T["sensor_msgs/msg/Imu"](
            header(stamp, "imu_link"),
            T["geometry_msgs/msg/Quaternion"](x, y, z, w),
            np.zeros(9),
            zeros,
            np.zeros(9),
            zeros,
            np.zeros(9),
        )
        spec.add("/imu", "sensor_msgs/msg/Imu", stamp + 1, message)
        positions, rates = record["angles"][row].tolist(), record["rates"][row].tolist()
        spec.add_joint_state(
            "/joint_states",
            stamp + 2,
            JointStateMsg(stamp, NAMES, positions, rates, "", efforts[row]),
        )
    bag, out = write_bag(tmp_path / "in", spec), tmp_path / "out"
    arguments = [
        "bag",
        str(bag),
        "--topic",
        "/joint_states",
        "--forces",
        "--imu",
        "/imu",
        "--causal",
    ]
    assert cli.main([*arguments, "--output-bag", str(out), "--quiet"]) == 0
    forces: dict[str, dict[int, list[float]]] = {leg: {} for leg in LEGS}
    contacts: dict[int, tuple[list[float], list[float]]] = {}
    with AnyReader([out]) as reader:
        for connection, _, raw in reader.messages():
            msg: Any = reader.deserialize(raw, connection.msgtype)
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            if connection.topic.startswith("/foot_forces/"):
                force = msg.wrench.force
                forces[connection.topic.rpartition("/")[2]][stamp] = [force.x, force.y, force.z]
            elif connection.topic == "/foot_contacts":
                contacts[stamp] = (msg.position.tolist(), msg.effort.tolist())
    return forces, contacts


def stamp_of(msg: Any) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def test_node_gives_the_bag_tools_forces_and_contacts(trot, ros, processes, tmp_path) -> None:
    bag_forces, bag_contacts = bag_tool_outputs(tmp_path, trot)
    node = processes.start(node_command("-p", "enable_verify:=false"))
    diagnostics = Diagnostics(ros)
    forces: dict[str, dict[int, list[float]]] = {leg: {} for leg in LEGS}
    contacts: dict[int, JointState] = {}
    frames: set[str] = set()

    def on_force(leg: str):
        def take(msg: WrenchStamped) -> None:
            force, torque = msg.wrench.force, msg.wrench.torque
            assert (torque.x, torque.y, torque.z) == (0.0, 0.0, 0.0)
            forces[leg][stamp_of(msg)] = [force.x, force.y, force.z]
            frames.add(msg.header.frame_id)

        return take

    depth = QoSProfile(depth=10000)
    for leg in LEGS:
        ros.node.create_subscription(WrenchStamped, f"foot_forces/{leg}", on_force(leg), depth)
    ros.node.create_subscription(
        JointState, "foot_contacts", lambda m: contacts.__setitem__(stamp_of(m), m), depth
    )
    stream = SensorStream(ros, "foot_contacts")
    assert stream.ready, processes.output(node)
    efforts = recorded_efforts(trot["torques"])
    stream.send(
        len(trot["angles"]),
        lambda row: (imu(trot, row), joint_state(trot, row, efforts[row])),
        lambda: len(contacts),  # every input gives contacts (without efforts: kinematic)
    )
    assert ros.spin_until(lambda: len(contacts) >= len(bag_contacts), 20.0), (
        f"{len(contacts)} of {len(bag_contacts)} contact messages\n{processes.output(node)}"
    )
    status = diagnostics.fresh()
    assert processes.interrupt(node) == 0

    assert frames == {A1.base_frame}
    for leg in LEGS:
        assert forces[leg].keys() == bag_forces[leg].keys(), leg
        ours = np.array([forces[leg][s] for s in sorted(forces[leg])])
        theirs = np.array([bag_forces[leg][s] for s in sorted(bag_forces[leg])])
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9)
    rows = sorted(bag_contacts)
    assert sorted(contacts) == rows
    for row in (EMPTY_ROW, SHORT_ROW):  # no efforts: contacts from the kinematics alone
        assert np.isnan(contacts[T0 + STEP_NS * row].effort).all()
        assert np.isfinite(contacts[T0 + STEP_NS * row].position).all()
    assert T0 + STEP_NS * NAN_FL_ROW not in forces["FL"] and T0 + STEP_NS * NAN_FL_ROW in contacts
    for key in ("position", "effort"):
        ours = np.array([list(getattr(contacts[s], key)) for s in rows])
        theirs = np.array([bag_contacts[s][0 if key == "position" else 1] for s in rows])
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9)  # NaN where NaN
    assert all(list(contacts[s].name) == list(LEGS) and not contacts[s].velocity for s in rows)

    # PyBullet's own contacts judge the stance (after the drop settles)
    stance = np.array([list(contacts[s].position) for s in rows]) >= 0.5
    truth = trot["foot_contact"][[(s - T0) // STEP_NS for s in rows]]
    settled = np.array(rows) >= T0 + STEP_NS * 50
    agree = (stance == truth)[settled].mean()
    print(f"node vs bag: {len(rows)} contact messages; stance agrees with PyBullet {agree:.2%}")
    assert agree > 0.97
    assert status["gravity_from"] == "imu orientation"
    # FL's NaN knee; the 11 efforts of one message, the message without efforts
    assert status["legs_without_efforts"] == "9"
    assert status["force_model"] == "dynamic" and status["contact_rule"] == "filter"
    assert status["contacts_with_kinematic_evidence_only"] == "2"
    assert status["legs_near_singular"] == "0"
    estimated = sum(len(forces[leg]) for leg in LEGS)
    assert status["leg_forces_estimated"] == str(estimated)


def test_bad_efforts_cost_their_legs_only(ros, processes) -> None:
    node = processes.start(node_command("-p", "enable_verify:=false"))
    diagnostics = Diagnostics(ros)
    forces: dict[str, list[WrenchStamped]] = {leg: [] for leg in LEGS}
    contacts: list[JointState] = []
    for leg in LEGS:
        ros.node.create_subscription(
            WrenchStamped, f"foot_forces/{leg}", forces[leg].append, QoSProfile(depth=100)
        )
    ros.node.create_subscription(
        JointState, "foot_contacts", contacts.append, QoSProfile(depth=100)
    )
    joint_pub = ros.node.create_publisher(JointState, "joint_states", QoSProfile(depth=100))
    assert ros.spin_until(
        lambda: (
            joint_pub.get_subscription_count() > 0
            and ros.node.count_publishers("foot_contacts") > 0
        ),
        30.0,
    ), processes.output(node)
    ros.spin_for(0.5)
    standing = [1.0, -3.0, 2.4] * 4  # N m: any finite efforts give a force
    nan = float("nan")
    cases = [
        [],  # no efforts: no force, kinematic contacts
        standing[:11],  # wrong length: no leg's force, kinematic contacts
        [nan, *standing[1:]],  # FR's hip NaN: FL, RR, RL
        [*standing[:6], float("inf"), *standing[7:]],  # RR's hip infinite: FR, FL, RL
        [1e308] * 12,  # huge: whatever the estimate gives, no crash
        standing,  # all four
    ]
    for index, efforts in enumerate(cases):
        msg = JointState(name=NAMES, position=STANDING, effort=efforts)
        msg.header.stamp.sec, msg.header.stamp.nanosec = 100, index + 1
        joint_pub.publish(msg)
        ros.spin_for(0.05)

    def answered_the_last() -> bool:  # the huge efforts may give FL no force: not counted
        return any(m.header.stamp.nanosec == len(cases) for m in forces["FL"])

    assert ros.spin_until(answered_the_last, 10.0), processes.output(node)
    ros.spin_for(0.3)
    status = diagnostics.fresh()
    assert node.poll() is None, processes.output(node)
    assert processes.interrupt(node) == 0
    seen = {leg: sorted(m.header.stamp.nanosec for m in forces[leg]) for leg in LEGS}
    assert seen["FR"][:1] == [4] and 3 not in seen["FR"]
    assert 4 not in seen["RR"] and 3 in seen["RR"]
    assert all(6 in seen[leg] and not {1, 2} & set(seen[leg]) for leg in LEGS)
    assert {m.header.stamp.nanosec for m in contacts} >= {3, 4, 6}
    kinematic = [m for m in contacts if m.header.stamp.nanosec in {1, 2}]
    assert len(kinematic) == 2 and all(np.isnan(m.effort).all() for m in kinematic)
    assert int(status["legs_without_efforts"]) >= 4 + 1 + 1
    assert status["gravity_from"] == "base -z (no imu orientation)"


def test_markers_colour_the_feet_in_stance() -> None:
    markers = foot_markers(A1, STANDING, "trunk", Time(), [0.9, 0.1, math.nan, 0.5]).markers
    spheres = [m for m in markers if m.id % 2 == 0]
    colours = [(m.color.r, m.color.g, m.color.b, m.color.a) for m in spheres]
    expected = [STANCE_RGBA, COLOR_RGBA, COLOR_RGBA, STANCE_RGBA]
    np.testing.assert_allclose(colours, expected, atol=1e-6)
    plain = foot_markers(A1, STANDING, "trunk", Time()).markers
    assert all(m.color.b == pytest.approx(COLOR_RGBA[2]) for m in plain)
