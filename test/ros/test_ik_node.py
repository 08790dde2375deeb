"""foot_ik_node as a real process over real DDS.

The closed loop: joint_state_demo -> foot_fk_node -> foot_ik_node (its foot_targets/<leg>
remapped to foot_positions/<leg>) -> joint_commands, matched by stamp with the demo's own
joint_states: the angles come back within 1e-9 rad. And targets the test sends itself: the
stamp, the command names, an unreachable target (published anyway, counted in /diagnostics),
a target in a foreign frame (rejected with a warning naming it), bad --ros-args, clean exits.
"""

from __future__ import annotations

import signal
import subprocess
from collections import defaultdict

import numpy as np
import pytest
import yaml
from geometry_msgs.msg import PointStamped
from node_harness import Diagnostics, ik_node_command, node_command, stamp_ns
from rclpy.qos import QoSProfile
from references import a1_foot_closed_form
from sensor_msgs.msg import JointState
from shared import LEGS, PYBULLET_NAMES, ROOT, UNITREE_NAMES, demo_command

from a1_leg_fk.ros import foot_ik_node as ik_node
from a1_leg_fk.ros import robot_source


class Commands:
    """joint_commands and /diagnostics as the node publishes them."""

    def __init__(self, ros) -> None:
        self.commands: list[JointState] = []
        self.diagnostics = Diagnostics(ros, "foot inverse kinematics")
        ros.node.create_subscription(
            JointState, "joint_commands", self.commands.append, QoSProfile(depth=5000)
        )
        self.publishers = {
            leg: ros.node.create_publisher(
                PointStamped, f"foot_targets/{leg}", QoSProfile(depth=100)
            )
            for leg in LEGS
        }


@pytest.mark.slow
def test_closed_loop_demo_fk_ik_returns_the_demo_angles(processes, ros) -> None:
    demo_states: dict[int, JointState] = {}
    ros.node.create_subscription(
        JointState,
        "joint_states",
        lambda m: demo_states.__setitem__(stamp_ns(m), m),
        QoSProfile(depth=5000),
    )
    commands = Commands(ros)
    remaps = [
        argument
        for leg in LEGS
        for argument in ("-r", f"foot_targets/{leg}:=foot_positions/{leg}")
    ]
    ik = processes.start(ik_node_command(*remaps))
    fk = processes.start(node_command())
    demo = processes.start(demo_command())
    # Both streams: the probe may discover the demo seconds after the nodes did (Fast DDS under
    # load).
    assert ros.spin_until(lambda: len(commands.commands) > 400 and len(demo_states) > 400, 30.0), (
        f"ik node:\n{processes.output(ik)}\nfk "
        f"node:\n{processes.output(fk)}\ndemo:\n{processes.output(demo)}"
    )
    ros.spin_for(1.0)
    matched: defaultdict[str, int] = defaultdict(int)
    for command in commands.commands:
        state = demo_states.get(stamp_ns(command))
        if state is None:
            continue
        assert next(iter(command.name)).split("_")[0] in LEGS
        expected = dict(zip(state.name, state.position))
        np.testing.assert_allclose(
            command.position, [expected[name] for name in command.name], rtol=0.0, atol=1e-9
        )
        matched[command.name[0][:2]] += 1
    assert all(matched[leg] >= 100 for leg in LEGS), (
        dict(matched),
        len(demo_states),
        len(commands.commands),
    )
    assert ros.spin_until(lambda: commands.diagnostics.latest.get("FR_ok", "0") != "0", 5.0)
    values = commands.diagnostics.latest
    assert values["FR_unreachable"] == values["FR_outside_limits"] == "0"
    for process in (demo, fk, ik):
        assert processes.interrupt(process) == 0, processes.output(process)
    assert "Traceback" not in processes.output(ik)


@pytest.mark.slow
def test_own_targets_names_stamps_statuses_and_frames(processes, ros) -> None:
    commands = Commands(ros)
    ik = processes.start(
        ik_node_command("-p", f"command_joint_names:={UNITREE_NAMES}".replace("'", '"'))
    )
    target = PointStamped()
    target.header.frame_id = "trunk"
    target.header.stamp.sec, target.header.stamp.nanosec = 1234, 5678
    target.point.x, target.point.y, target.point.z = (
        float(v) for v in a1_foot_closed_form("RL", 0.1, 0.9, -1.6)
    )

    def send_until_answered(leg: str, msg: PointStamped, count: int) -> bool:
        def answered() -> bool:
            if len(commands.commands) < count:
                commands.publishers[leg].publish(msg)
                ros.spin_for(0.05)
            return len(commands.commands) >= count

        return ros.spin_until(answered, 20.0)

    assert send_until_answered("RL", target, 1), processes.output(ik)
    first = commands.commands[0]
    assert list(first.name) == UNITREE_NAMES[9:12]
    assert (first.header.stamp.sec, first.header.stamp.nanosec) == (1234, 5678)
    np.testing.assert_allclose(first.position, [0.1, 0.9, -1.6], atol=1e-9)

    # Out of reach: the nearest in-limit angles are published all the same, and counted.
    commands.commands.clear()
    target.point.z = -1.5
    assert send_until_answered("RL", target, 1)
    assert list(commands.commands[0].name) == UNITREE_NAMES[9:12]
    assert np.isfinite(commands.commands[0].position).all()
    assert ros.spin_until(
        lambda: commands.diagnostics.latest.get("RL_unreachable", "0") != "0", 5.0
    )

    # A foreign frame: nothing published, a warning naming the frame.
    commands.commands.clear()
    target.header.frame_id = "odom"
    for _ in range(5):
        commands.publishers["FL"].publish(target)
        ros.spin_for(0.1)
    assert not commands.commands
    assert ros.spin_until(
        lambda: commands.diagnostics.latest.get("rejected_frame", "0") != "0", 5.0
    )
    assert processes.interrupt(ik) == 0
    output = processes.output(ik)
    assert "'odom'" in output and "unreachable" in output and "Traceback" not in output


@pytest.mark.slow
def test_bad_ros_args_exit_2_in_one_line(processes) -> None:
    process = processes.start(ik_node_command("-p"))
    try:
        assert process.wait(20) == 2
    except subprocess.TimeoutExpired:
        pytest.fail("foot_ik_node kept running with a bad --ros-args")
    output = processes.output(process)
    ours = [line for line in output.splitlines() if line.startswith("foot_ik_node:")]
    assert len(ours) == 1 and "cannot start" in ours[0] and "Traceback" not in output


@pytest.mark.slow
def test_wrong_number_of_command_names_fails_with_the_reason_and_sigterm_exits_0(
    processes,
) -> None:
    bad = processes.start(ik_node_command("-p", 'command_joint_names:=["a", "b"]'))
    assert bad.wait(20) == 1
    assert "command_joint_names must hold 12 names" in processes.output(bad)
    good = processes.start(
        ik_node_command("-p", f"command_joint_names:={PYBULLET_NAMES}".replace("'", '"'))
    )
    try:
        good.wait(3)
        pytest.fail(f"foot_ik_node exited:\n{processes.output(good)}")
    except subprocess.TimeoutExpired:
        pass
    good.send_signal(signal.SIGTERM)
    assert good.wait(10) == 0, processes.output(good)


def test_ik_params_yaml_states_every_parameter() -> None:
    """config/ik_params.yaml: every scalar parameter with the node's default, the string arrays
    commented out."""
    path = ROOT / "config" / "ik_params.yaml"
    text = path.read_text()
    stated = yaml.safe_load(text)[ik_node.NODE_NAME]["ros__parameters"]
    specs = (
        robot_source.PARAMETERS + ik_node.PARAMETERS
    )  # the model's parameters and the node's own
    scalars = {spec.name: spec.default for spec in specs if spec.default is not None}
    assert stated == scalars
    for spec in specs:
        if spec.default is None:
            assert f"# {spec.name}: [" in text


@pytest.mark.slow
def test_the_ik_node_follows_the_robot_description_topic(processes, ros) -> None:
    """The same mechanism as foot_fk_node's: a Go2-like description on the topic, no parameter."""
    from exported_urdf import exported_quadruped
    from std_msgs.msg import String

    from a1_leg_fk.kinematics.robot_config import load_robot

    xml = exported_quadruped("go2")
    from node_harness import LATCHED

    ros.node.create_publisher(String, "robot_description", LATCHED).publish(String(data=xml))
    commands = Commands(ros)
    process = processes.start(ik_node_command())
    go2 = load_robot(xml).quadruped
    q = [0.1, 0.7, -1.4]
    target = go2.fk(q * 4)[0]

    def answered_in_base() -> bool:
        message = PointStamped()
        message.header.frame_id = (
            "base"  # Go2's root link: only accepted once the description is loaded
        )
        message.point.x, message.point.y, message.point.z = (float(v) for v in target)
        commands.publishers["FR"].publish(message)
        return bool(commands.commands)

    assert ros.spin_until(answered_in_base, 30.0), processes.output(process)
    command = commands.commands[-1]
    assert list(command.name) == ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"]
    np.testing.assert_allclose(go2.fk(list(command.position) * 4)[0], target, rtol=0.0, atol=1e-9)
    assert "loaded /robot_description: root link 'base'" in processes.output(process)
