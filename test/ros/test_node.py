"""foot_fk_node as a real process over real DDS: interface, correctness, bad input, parameters,
shutdown."""

from __future__ import annotations

import math
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet_data
import pytest
from conftest import Processes
from node_harness import (
    LEGS,
    PYBULLET_NAMES,
    STANDING,
    UNITREE_NAMES,
    Diagnostics,
    NodeClient,
    distance,
    node_command,
    package_root,
    parse_tokens,
    stamp_ns,
)
from pybullet_reference import A1_URDF, PyBulletRobot
from rcl_interfaces.msg import ParameterType, ParameterValue
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState
from visualization_msgs.msg import Marker, MarkerArray

from a1_leg_fk.kinematics.quadruped import Quadruped

ALIENGO_URDF = Path(pybullet_data.getDataPath()) / "aliengo" / "aliengo.urdf"
STANDING_FR = (0.1684, -0.1320, -0.2923)  # the reference write-up's published value [m]


@pytest.fixture(scope="module")
def reference():
    with PyBulletRobot(A1_URDF) as twin:
        yield twin


def random_in_limits(robot: Quadruped, rng: np.random.Generator) -> np.ndarray:
    lower = np.array([j.lower for j in robot.joints])
    upper = np.array([j.upper for j in robot.joints])
    return rng.uniform(lower, upper)


def send_random_states(
    client: NodeClient,
    robot: Quadruped,
    rng: np.random.Generator,
    names,
    count: int,
    with_rates: bool = False,
) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Send ``count`` joint states with random angles in limits [rad] (and, ``with_rates``, random
    rates in [-2, 2] rad/s, else none); returns stamp [ns] -> (angles, rates)."""
    sent = {}
    for _ in range(count):
        angles = random_in_limits(robot, rng)
        rates = rng.uniform(-2.0, 2.0, 12) if with_rates else np.empty(0)
        msg = client.joint_state(names, angles, rates)
        sent[stamp_ns(msg)] = (angles, rates)
        client.send(msg)
        client.probe.spin_for(0.01)
    return sent


@dataclass
class RunningNode:
    process: subprocess.Popen
    client: NodeClient
    processes: Processes

    def log(self) -> str:
        return self.processes.output(self.process)


def start_node(
    processes, ros, *ros_args: str, prefix: str = "", joint_states_topic: str = ""
) -> RunningNode:
    process = processes.start(node_command(*ros_args))
    client = NodeClient(ros, prefix, joint_states_topic)
    assert client.wait_until_connected(), processes.output(process)
    return RunningNode(process, client, processes)


@pytest.fixture
def a1_node(processes, ros) -> RunningNode:
    return start_node(processes, ros)


@pytest.mark.parametrize(
    "names", [PYBULLET_NAMES, UNITREE_NAMES], ids=["pybullet_names", "unitree_names"]
)
def test_random_joint_states_give_pybullet_feet_with_frame_and_stamp(a1_node, reference, names):
    client = a1_node.client
    robot = Quadruped.from_urdf()
    sent = send_random_states(client, robot, np.random.default_rng(7), names, 40)
    assert client.wait_for_feet(len(sent)), {leg: len(v) for leg, v in client.positions.items()}
    worst_pybullet, worst_core = 0.0, 0.0
    for slot, leg in enumerate(LEGS):
        for msg in client.positions[leg]:
            assert msg.header.frame_id == "trunk"
            angles, _ = sent[stamp_ns(msg)]
            expected = reference.feet(PYBULLET_NAMES, [f"{leg}_toe"], angles)[0]
            worst_pybullet = max(worst_pybullet, distance(msg.point, expected))
            worst_core = max(worst_core, distance(msg.point, robot.fk(angles)[slot]))
    assert worst_pybullet <= 1e-7
    assert worst_core <= 1e-12


def test_foot_velocities_are_jacobian_times_rates_and_match_finite_differences(a1_node):
    client = a1_node.client
    robot = Quadruped.from_urdf()
    rng = np.random.default_rng(3)
    angles, rates = random_in_limits(robot, rng), rng.uniform(-2.0, 2.0, 12)
    msg = client.joint_state(PYBULLET_NAMES, angles, rates)
    client.send(msg)
    assert client.probe.spin_until(lambda: all(client.velocities[leg] for leg in LEGS), 10.0)
    step = 1e-6
    central = (robot.fk(angles + step * rates) - robot.fk(angles - step * rates)) / (2 * step)
    for slot, leg in enumerate(LEGS):
        velocity = client.velocities[leg][0]
        assert velocity.header.frame_id == "trunk" and stamp_ns(velocity) == stamp_ns(msg)
        got = np.array([velocity.vector.x, velocity.vector.y, velocity.vector.z])
        block = slice(3 * slot, 3 * slot + 3)
        np.testing.assert_allclose(got, robot.jacobians(angles)[slot] @ rates[block], atol=1e-12)
        np.testing.assert_allclose(got, central[slot], atol=1e-8)


@pytest.mark.slow
def test_message_object_output_publishes_the_same_feet_velocities_frames_and_stamps(
    processes, ros, reference
):
    """preserialized_output:=false: the message-object path, against PyBullet and the core; then
    switched on at run time, the pre-serialized path sends the very same values for one message."""
    client = start_node(processes, ros, "-p", "preserialized_output:=false").client
    robot = Quadruped.from_urdf()
    sent = send_random_states(
        client, robot, np.random.default_rng(11), PYBULLET_NAMES, 20, with_rates=True
    )
    assert client.probe.spin_until(
        lambda: all(len(client.velocities[leg]) >= len(sent) for leg in LEGS), 10.0
    )
    assert client.wait_for_feet(len(sent))
    for slot, leg in enumerate(LEGS):
        for position, velocity in zip(client.positions[leg], client.velocities[leg]):
            assert position.header.frame_id == velocity.header.frame_id == "trunk"
            angles, rates = sent[stamp_ns(position)]
            assert stamp_ns(velocity) == stamp_ns(position)
            assert (
                distance(position.point, reference.feet(PYBULLET_NAMES, [f"{leg}_toe"], angles)[0])
                <= 1e-7
            )
            assert distance(position.point, robot.fk(angles)[slot]) <= 1e-12
            expected = robot.jacobians(angles)[slot] @ rates[3 * slot : 3 * slot + 3]
            assert distance(velocity.vector, expected) <= 1e-12
    last = client.joint_state(PYBULLET_NAMES, *sent[max(sent)])
    as_objects = _feet_for(client, last)
    switched = client.set_parameter(
        "preserialized_output", ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True)
    )
    assert switched.successful, switched.reason
    assert _feet_for(client, last) == as_objects


def _feet_for(client: NodeClient, msg) -> list[tuple]:
    """Send ``msg`` alone; the (frame, stamp, x, y, z) of every foot position and velocity it
    gives."""
    client.clear()
    client.send(msg)
    assert client.probe.spin_until(lambda: all(client.velocities[leg] for leg in LEGS), 10.0)
    assert client.wait_for_feet(1)
    out = []
    for leg in LEGS:
        position, velocity = client.positions[leg][0], client.velocities[leg][0]
        out.append(
            (
                position.header.frame_id,
                stamp_ns(position),
                position.point.x,
                position.point.y,
                position.point.z,
            )
        )
        out.append(
            (
                velocity.header.frame_id,
                stamp_ns(velocity),
                velocity.vector.x,
                velocity.vector.y,
                velocity.vector.z,
            )
        )
    return out


def test_nan_velocities_publish_positions_without_velocities(a1_node):
    client = a1_node.client
    client.send(client.joint_state(PYBULLET_NAMES, STANDING, [math.nan] * 12))
    assert client.wait_for_feet(1)
    client.probe.spin_for(0.3)
    assert not any(client.velocities[leg] for leg in LEGS)


def test_partial_messages_merge_and_publish_only_completed_legs(processes, ros):
    process = processes.start(node_command())
    client = NodeClient(ros)
    assert client.verify_client.wait_for_service(timeout_sec=20.0), processes.output(process)
    response = client.verify()
    assert response.success is False and "no complete joint state" in response.message
    client.probe.spin_for(1.0)  # let the node's subscription match our publisher
    client.send(client.joint_state(["FR_hip_joint", "FR_upper_joint"], [0.0, 0.8]))
    client.probe.spin_for(0.5)
    assert not client.positions["FR"], "FR was published before its knee was known"
    client.send(client.joint_state(["FR_lower_joint", "RL_hip_joint"], [-1.5, 0.0]))
    assert client.wait_for_feet(1, legs=["FR"])
    client.probe.spin_for(0.3)
    assert distance(client.positions["FR"][0].point, STANDING_FR) < 1e-4
    assert not client.positions["RL"] and not client.positions["FL"]
    response = client.verify()
    assert response.success is False and "RL_upper_joint" in response.message


def test_zero_stamp_is_replaced_by_the_node_clock(a1_node):
    client = a1_node.client
    before = client.probe.node.get_clock().now().nanoseconds
    client.send(client.joint_state(PYBULLET_NAMES, STANDING, stamp_ns=0))
    assert client.wait_for_feet(1)
    after = client.probe.node.get_clock().now().nanoseconds
    assert before - 1e9 < stamp_ns(client.positions["FR"][0]) < after + 1e9


def test_bad_inputs_are_rejected_and_the_next_good_message_is_handled(a1_node):
    client = a1_node.client
    bad_messages = [
        client.joint_state(PYBULLET_NAMES, STANDING[:11]),  # position shorter than name
        client.joint_state(PYBULLET_NAMES, STANDING, [0.0] * 5),  # velocity of another length
        client.joint_state(PYBULLET_NAMES[:3] * 2, STANDING[:6]),  # duplicate names
        client.joint_state(
            ["FR_upper_joint", "FR_thigh_joint"], [0.8, 0.8]
        ),  # one joint under both namings
        client.joint_state(PYBULLET_NAMES, [math.nan] * 12),
        client.joint_state(PYBULLET_NAMES, [math.inf, 0.8, -1.5] + [-math.inf] * 9),
        client.joint_state(["arm_joint_1", "gripper"], [0.1, 0.2]),
        client.joint_state([], []),
    ]
    for msg in bad_messages:
        client.send(msg)
        client.probe.spin_for(0.05)
    client.probe.spin_for(0.5)
    assert not any(client.positions[leg] for leg in LEGS)
    # A NaN for one joint keeps only that leg back.
    client.send(client.joint_state(PYBULLET_NAMES, [math.nan, *STANDING[1:]]))
    assert client.wait_for_feet(1, legs=["FL", "RR", "RL"])
    client.probe.spin_for(0.3)
    assert not client.positions["FR"]
    good = client.joint_state(PYBULLET_NAMES, STANDING)
    client.send(good)
    assert client.probe.spin_until(
        lambda: any(stamp_ns(m) == stamp_ns(good) for m in client.positions["FR"])
    )
    assert distance(client.positions["FR"][-1].point, STANDING_FR) < 1e-4
    for leg in LEGS:
        for msg in client.positions[leg]:
            assert all(math.isfinite(v) for v in (msg.point.x, msg.point.y, msg.point.z))
    assert a1_node.process.poll() is None
    log = a1_node.log()
    for expected in (
        "position length mismatch",
        "velocity length mismatch",
        "duplicate names",
        "arm_joint_1",
    ):
        assert expected in log, log


def test_verify_fk_agrees_with_pybullet_and_reports_limits(a1_node):
    client = a1_node.client
    client.send(
        client.joint_state(PYBULLET_NAMES, [0.0, 0.8, 0.0, *STANDING[3:]])
    )  # FR knee straight: out of limits
    assert client.wait_for_feet(1)
    response = client.verify()
    tokens = parse_tokens(response.message)
    assert response.success is True, response.message
    assert float(tokens["max_error_m"]) <= 1e-7
    assert all(float(tokens[leg]) <= 1e-7 for leg in LEGS)
    assert tokens["outside_limits"] == "FR_lower_joint"
    assert int(tokens["stamp"].replace(".", "")) == stamp_ns(client.positions["FR"][-1])


def test_verify_fk_without_pybullet_fails_with_install_hint_and_feet_keep_flowing(processes, ros):
    process = processes.start(node_command(), env={"A1_LEG_FK_HIDE_PYBULLET": "1"})
    client = NodeClient(ros)
    assert client.wait_until_connected(), processes.output(process)
    response = client.verify()
    assert response.success is False
    assert "pip install pybullet" in response.message
    client.send(client.joint_state(PYBULLET_NAMES, STANDING))
    assert client.wait_for_feet(1)


def test_another_urdf_through_robot_description(processes, ros, tmp_path):
    params = tmp_path / "aliengo.yaml"
    indented = "\n".join("      " + line for line in ALIENGO_URDF.read_text().splitlines())
    params.write_text(f"a1_leg_fk:\n  ros__parameters:\n    robot_description: |\n{indented}\n")
    process = processes.start(node_command("--params-file", str(params)))
    client = NodeClient(ros)
    assert client.verify_client.wait_for_service(timeout_sec=20.0), processes.output(process)
    with PyBulletRobot(ALIENGO_URDF) as aliengo:
        robot = Quadruped.from_urdf(str(ALIENGO_URDF))
        angles = [0.1, 0.7, -1.4, -0.1, 0.9, -1.2, 0.2, 0.6, -1.6, -0.2, 0.8, -1.1]

        def sent_and_all_arrived() -> bool:
            client.send(client.joint_state(robot.joint_names, angles))
            return all(client.positions[leg] for leg in LEGS)  # one topic per foot

        assert client.probe.spin_until(sent_and_all_arrived, 20.0), processes.output(process)
        expected = aliengo.feet(list(robot.joint_names), [f"{leg}_toe" for leg in LEGS], angles)
    for slot, leg in enumerate(LEGS):
        assert distance(client.positions[leg][-1].point, expected[slot]) <= 1e-7
    assert float(parse_tokens(client.verify().message)["max_error_m"]) <= 1e-7


def test_namespace_remap_and_params_file_from_config(processes, ros):
    config = package_root() / "config" / "params.yaml"
    running = start_node(
        processes,
        ros,
        "-r",
        "__ns:=/robot1",
        "-r",
        "joint_states:=/robot1/state_estimator/joints",
        "--params-file",
        str(config),
        prefix="/robot1/",
        joint_states_topic="/robot1/state_estimator/joints",
    )
    assert running.client.verify().success is False or True  # the service is under the namespace
    running.client.send(running.client.joint_state(PYBULLET_NAMES, STANDING))
    assert running.client.wait_for_feet(1)
    assert distance(running.client.positions["FR"][0].point, STANDING_FR) < 1e-4


def test_parameters_change_at_run_time_or_are_rejected_with_a_reason(a1_node):
    client = a1_node.client
    result = client.set_string_parameter("base_frame", "base")
    assert result.successful
    client.send(client.joint_state(PYBULLET_NAMES, STANDING))
    assert client.wait_for_feet(1)
    assert client.positions["FR"][-1].header.frame_id == "base"
    rejected = client.set_parameter(
        "verify_tolerance_m",
        ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=-1.0),
    )
    assert not rejected.successful and "verify_tolerance_m" in rejected.reason
    broken = client.set_string_parameter("robot_description", "<robot name='x'><link name='a'/>")
    assert not broken.successful and "malformed XML" in broken.reason
    client.clear()
    client.send(client.joint_state(PYBULLET_NAMES, STANDING))
    assert client.wait_for_feet(1)
    assert distance(client.positions["FR"][-1].point, STANDING_FR) < 1e-4


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_exits_zero_quickly_without_traceback(a1_node, sig):
    a1_node.process.send_signal(sig)
    started = time.monotonic()
    assert a1_node.process.wait(5) == 0
    assert time.monotonic() - started < 2.0
    assert "Traceback" not in a1_node.log()


def test_diagnostics_and_markers_reach_subscribers(a1_node):
    client = a1_node.client
    node = client.probe.node
    diagnostics = Diagnostics(client.probe)
    markers: list[MarkerArray] = []
    node.create_subscription(MarkerArray, "foot_markers", markers.append, 10)
    client.send(client.joint_state(PYBULLET_NAMES, STANDING[:11]))  # rejected
    client.probe.spin_for(0.1)

    def fed() -> (
        bool
    ):  # keep feeding good joint states until a marker array and a diagnostics report came
        client.send(client.joint_state(PYBULLET_NAMES, STANDING))
        return bool(markers) and diagnostics.latest.get("feet_published", "0") != "0"

    assert client.probe.spin_until(fed, 10.0)
    values = diagnostics.latest
    assert int(values["messages_received"]) >= int(values["messages_accepted"]) >= 1
    assert values["messages_position_length_mismatch"] == "1"
    assert values["joints_outside_limits"] == "none"
    spheres = [m for m in markers[-1].markers if m.type == Marker.SPHERE]
    strips = [m for m in markers[-1].markers if m.type == Marker.LINE_STRIP]
    assert len(spheres) == 4 and len(strips) == 4
    fr_sphere = next(m for m in spheres if m.ns.endswith("FR"))
    assert (
        distance(fr_sphere.pose.position, STANDING_FR) < 1e-4
        and fr_sphere.header.frame_id == "trunk"
    )
    fr_strip = next(m for m in strips if m.ns.endswith("FR"))
    assert distance(fr_strip.points[0], (0.183, -0.047, 0.0)) < 1e-9  # the hip joint's URDF origin
    assert distance(fr_strip.points[-1], STANDING_FR) < 1e-4


def test_joint_states_qos_can_be_overridden_to_reliable(processes, ros):
    process = processes.start(
        node_command("-p", "qos_overrides./joint_states.subscription.reliability:=reliable")
    )
    client = NodeClient(ros)  # its joint_states publisher is reliable: matches
    assert client.wait_until_connected(), processes.output(process)
    best_effort = ros.node.create_publisher(JointState, "joint_states", qos_profile_sensor_data)
    ros.spin_for(1.0)
    for _ in range(20):  # a best-effort writer cannot serve a reliable reader: never heard
        best_effort.publish(client.joint_state(PYBULLET_NAMES, STANDING))
        ros.spin_for(0.05)
    assert not client.positions["FR"]
    client.send(client.joint_state(PYBULLET_NAMES, STANDING))
    assert client.wait_for_feet(1)


def test_urdf_file_foot_links_and_joint_aliases_for_the_mini_cheetah(processes, ros, tmp_path):
    urdf = Path(pybullet_data.getDataPath()) / "mini_cheetah" / "mini_cheetah.urdf"
    feet = {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"}
    params = tmp_path / "mini_cheetah.yaml"
    params.write_text(
        "a1_leg_fk:\n  ros__parameters:\n"
        f"    urdf_file: {urdf}\n"
        f"    foot_links: [{', '.join(f'{leg}={link}' for leg, link in feet.items())}]\n"
        "    joint_aliases: [fr_roll=torso_to_abduct_fr_j]\n"
    )
    process = processes.start(node_command("--params-file", str(params)))
    client = NodeClient(ros)
    assert client.verify_client.wait_for_service(timeout_sec=20.0), processes.output(process)
    robot = Quadruped.from_urdf(str(urdf), feet)
    names = ["fr_roll", *robot.joint_names[1:]]  # the FR hip roll under its alias
    angles = [0.2, -0.7, 1.4, -0.1, -0.9, 1.2, 0.15, -0.6, 1.6, -0.2, -0.8, 1.1]

    def sent_and_all_arrived() -> bool:
        client.send(client.joint_state(names, angles))
        return all(client.positions[leg] for leg in LEGS)

    assert client.probe.spin_until(
        sent_and_all_arrived,
        20.0,
    ), processes.output(process)
    with PyBulletRobot(urdf) as cheetah:
        expected = cheetah.feet(list(robot.joint_names), list(feet.values()), angles)
    for slot, leg in enumerate(LEGS):
        assert client.positions[leg][-1].header.frame_id == "body"
        assert distance(client.positions[leg][-1].point, expected[slot]) <= 1e-7
    assert client.verify().success
