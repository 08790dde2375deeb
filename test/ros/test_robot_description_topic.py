"""foot_fk_node beside robot_state_publisher: the robot_description topic and sim time, over DDS.

The test's own node plays robot_state_publisher (std_msgs/String on ``robot_description``,
reliable + transient local + depth 1) and, for sim time, a bag replay's ``/clock``.
"""

from __future__ import annotations

from typing import Any

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from exported_urdf import FEET, exported_quadruped, reference_robot, unitree_style_a1
from node_harness import LATCHED, Diagnostics, NodeClient, distance, node_command, stamp_ns
from pybullet_reference import A1_URDF, PyBulletRobot
from rosgraph_msgs.msg import Clock
from shared import A1_FEET, LEGS, PYBULLET_NAMES, STANDING, UNITREE_NAMES
from std_msgs.msg import String

pytestmark = pytest.mark.slow

TOLERANCE_M = 1e-7
ANGLES = [0.1, 0.7, -1.4, -0.1, 0.9, -1.2, 0.2, 0.6, -1.6, -0.2, 0.8, -1.1]
BILLION_LAUGHS = (
    '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa"><!ENTITY b '
    '"&a;&a;&a;&a;&a;&a;&a;&a;">]><robot name="bomb"><link name="&b;"/></robot>'
)


def publish_description(ros, xml: str, topic: str = "robot_description"):
    publisher = ros.node.create_publisher(String, topic, LATCHED)
    publisher.publish(String(data=xml))
    return publisher


def feet_in(client: NodeClient, names, angles, frame: str, timeout_s: float = 30.0) -> list:
    """Send ``angles`` until all four feet come back in ``frame``; the latest foot per leg."""

    def arrived() -> bool:
        client.send(client.joint_state(names, angles))
        return all(
            client.positions[leg] and client.positions[leg][-1].header.frame_id == frame
            for leg in LEGS
        )

    assert client.probe.spin_until(arrived, timeout_s), {
        leg: [m.header.frame_id for m in client.positions[leg][-3:]] for leg in LEGS
    }
    return [client.positions[leg][-1] for leg in LEGS]


def assert_feet(messages, expected) -> None:
    for message, position in zip(messages, expected):
        assert distance(message.point, position) <= TOLERANCE_M


def latest_diagnostics(
    client: NodeClient, key: str, contains: str, timeout_s: float = 10.0
) -> dict[str, Any]:
    """The foot_fk_node's latest status once its ``key`` contains ``contains``, with its level."""
    diagnostics = Diagnostics(client.probe)
    assert client.probe.spin_until(
        lambda: contains in diagnostics.latest.get(key, ""), timeout_s
    ), diagnostics.latest or "none"
    return {"level": diagnostics.level, **diagnostics.latest}


def test_a_description_published_before_the_node_starts_is_used_with_no_parameter(processes, ros):
    """A Unitree-style A1 (root base, X_thigh/X_calf joints, X_foot links, package:// meshes)."""
    publisher = publish_description(ros, unitree_style_a1())
    process = processes.start(node_command())
    client = NodeClient(ros)
    feet = feet_in(client, UNITREE_NAMES, ANGLES, "base")
    with PyBulletRobot(A1_URDF) as reference:  # the same geometry under pybullet_data's names
        assert_feet(feet, reference.feet(PYBULLET_NAMES, A1_FEET, ANGLES))
    response = client.verify()
    assert response.success, response.message
    log = processes.output(process)
    assert "until a description arrives on /robot_description (followed)" in log
    assert "loaded /robot_description: root link 'base'" in log
    ros.node.destroy_publisher(publisher)


def test_a_description_published_later_switches_the_robot_and_republishing_does_not_reload(
    processes, ros, tmp_path
):
    process = processes.start(node_command())
    client = NodeClient(ros)
    with PyBulletRobot(A1_URDF) as a1:
        assert_feet(
            feet_in(client, PYBULLET_NAMES, ANGLES, "trunk"),
            a1.feet(PYBULLET_NAMES, A1_FEET, ANGLES),
        )
    xml = exported_quadruped("go2")
    publisher = publish_description(ros, xml)
    with reference_robot(tmp_path, "go2") as go2:
        assert_feet(
            feet_in(client, UNITREE_NAMES, ANGLES, "base"), go2.feet(UNITREE_NAMES, FEET, ANGLES)
        )
    assert client.verify().success
    # robot_state_publisher republishes on parameter changes: the same text must not reload (a
    # reload
    # empties the joint state), so two of FR's joints still complete FR with the knee merged
    # before.
    publisher.publish(String(data=xml))
    client.probe.spin_for(1.0)
    client.clear()
    client.send(client.joint_state(UNITREE_NAMES[:2], ANGLES[:2]))
    assert client.wait_for_feet(1, legs=("FR",))
    assert processes.output(process).count("loaded /robot_description") == 1


@pytest.mark.parametrize(
    ("xml", "reason"),
    [
        ("<robot name='broken'><link name='a'>", "malformed XML"),
        ("<robot name='legless'><link name='base'/></robot>", "leg FR"),
        (BILLION_LAUGHS, "entity"),
    ],
    ids=["malformed", "no-legs", "entity-bomb"],
)
def test_a_bad_description_on_the_topic_is_rejected_and_the_old_robot_keeps_publishing(
    processes, ros, xml, reason
):
    process = processes.start(node_command())
    client = NodeClient(ros)
    feet_in(client, PYBULLET_NAMES, STANDING, "trunk")
    publish_description(ros, xml)
    values = latest_diagnostics(client, "robot_description_topic", "rejected")
    assert (
        reason in values["robot_description_topic"] and values["level"] == DiagnosticStatus.WARN
    ), values
    assert "rejected" in values["message"]
    client.clear()
    with PyBulletRobot(A1_URDF) as a1:
        assert_feet(
            feet_in(client, PYBULLET_NAMES, ANGLES, "trunk"),
            a1.feet(PYBULLET_NAMES, A1_FEET, ANGLES),
        )
    assert process.poll() is None
    assert f"description on /robot_description rejected, keeping {A1_URDF}" in processes.output(
        process
    )


def test_an_explicit_urdf_file_wins_over_the_topic(processes, ros):
    publish_description(ros, exported_quadruped("go2"))
    process = processes.start(node_command("-p", f"urdf_file:={A1_URDF}"))
    client = NodeClient(ros)
    with PyBulletRobot(A1_URDF) as a1:
        assert_feet(
            feet_in(client, PYBULLET_NAMES, ANGLES, "trunk"),
            a1.feet(PYBULLET_NAMES, A1_FEET, ANGLES),
        )
    values = latest_diagnostics(client, "robot_description_topic", "ignored")
    assert (
        values["robot_description_topic"]
        == "/robot_description: ignored: parameter urdf_file is set"
    )
    log = processes.output(process)
    assert "parameter urdf_file is set, so /robot_description is ignored" in log
    assert log.count("ignoring the description on /robot_description") == 1


def test_a_namespaced_node_follows_its_namespaced_description_topic(processes, ros, tmp_path):
    publish_description(ros, exported_quadruped("go2"), "/robot1/robot_description")
    publish_description(
        ros, exported_quadruped("b2"), "/robot_description"
    )  # another robot's: not ours
    processes.start(node_command("-r", "__ns:=/robot1"))
    client = NodeClient(ros, prefix="/robot1/")
    with reference_robot(tmp_path, "go2") as go2:
        assert_feet(
            feet_in(client, UNITREE_NAMES, ANGLES, "base"), go2.feet(UNITREE_NAMES, FEET, ANGLES)
        )


def test_an_empty_topic_parameter_follows_no_topic(processes, ros):
    publish_description(ros, exported_quadruped("go2"))
    process = processes.start(node_command("-p", "robot_description_topic:=''"))
    client = NodeClient(ros)
    feet_in(client, PYBULLET_NAMES, STANDING, "trunk")
    client.probe.spin_for(1.0)
    client.clear()
    feet_in(client, PYBULLET_NAMES, STANDING, "trunk")
    assert "no robot_description topic followed" in processes.output(process)


def test_sim_time_stamps_everything_the_node_stamps_itself(processes, ros):
    clock = ros.node.create_publisher(Clock, "/clock", 10)
    sim_ns = 1_234 * 1_000_000_000 + 500_000_000

    def tick() -> None:
        message = Clock()
        message.clock.sec, message.clock.nanosec = divmod(sim_ns, 1_000_000_000)
        clock.publish(message)

    processes.start(node_command("-p", "use_sim_time:=true"))
    client = NodeClient(ros)
    diagnostics: list[DiagnosticArray] = []
    ros.node.create_subscription(DiagnosticArray, "/diagnostics", diagnostics.append, 10)

    def zero_stamped_foot_arrived() -> bool:
        tick()
        client.send(client.joint_state(PYBULLET_NAMES, STANDING, stamp_ns=0))
        return bool(client.positions["FR"]) and bool(diagnostics)

    assert ros.spin_until(zero_stamped_foot_arrived, 30.0)
    # Until the node has heard /clock its sim time reads 0; from then on it is sim_ns, which stands
    # still, so every stamp the node makes itself is exactly sim_ns (wall time would be ~1.8e18
    # ns).
    assert ros.spin_until(
        lambda: zero_stamped_foot_arrived() and stamp_ns(client.positions["FR"][-1]) != 0, 20.0
    )
    for _ in range(3):
        client.clear()
        assert ros.spin_until(zero_stamped_foot_arrived, 10.0)
        assert stamp_ns(client.positions["FR"][-1]) == sim_ns

    def ticked_and_stamped() -> bool:
        tick()
        return stamp_ns(diagnostics[-1]) != 0

    assert ros.spin_until(ticked_and_stamped, 10.0)
    assert stamp_ns(diagnostics[-1]) == sim_ns


def test_an_invalid_topic_parameter_stops_the_node_with_one_line(processes):
    process = processes.start(node_command("-p", "robot_description_topic:=bad//name"))
    assert process.wait(30) == 1
    output = processes.output(process)
    assert "cannot start: robot_description_topic 'bad//name' is not a valid topic name" in output
    assert "Traceback" not in output


def test_the_first_diagnostics_after_a_robot_swap_count_the_period_right(processes, ros):
    """A rejected message reported in an earlier period, then the robot is swapped: the next
    status must neither count a negative rate nor a negative number of rejections (-1 is truthy:
    a spurious WARN)."""
    processes.start(node_command())
    client = NodeClient(ros)
    seen: list[DiagnosticArray] = []
    ros.node.create_subscription(DiagnosticArray, "/diagnostics", seen.append, 10)
    feet_in(client, PYBULLET_NAMES, STANDING, "trunk")
    client.send(client.joint_state(PYBULLET_NAMES, STANDING[:11]))  # rejected: 11 positions
    latest_diagnostics(client, "messages_position_length_mismatch", "1")
    publish_description(ros, exported_quadruped("go2"))
    feet_in(client, UNITREE_NAMES, STANDING, "base")
    assert ros.spin_until(
        lambda: any(
            kv.key == "model" and kv.value == "/robot_description"
            for array in seen
            for kv in array.status[0].values
        ),
        10.0,
    )
    first = next(
        array.status[0]
        for array in seen
        if {kv.key: kv.value for kv in array.status[0].values}["model"] == "/robot_description"
    )
    values = {kv.key: kv.value for kv in first.values}
    assert float(values["input_rate_hz"]) >= 0.0, values
    assert "messages_position_length_mismatch" not in values, values  # a fresh tracker's counts
    if values["messages_received"] == "0":
        assert first.message == "no joint_states received yet", values
    else:
        assert (first.level, first.message) == (DiagnosticStatus.OK, "feet published"), values
