"""verify_fk on descriptions written on one line (longer than PyBullet's 8,191-byte lines).

rcl parses ``-p robot_description:="$(cat robot.urdf)"`` as YAML and folds the multi-line text
into one line; a description published on one line, or a file written so, arrives the same way.
PyBullet's URDF reader cuts every line after 8,191 bytes, so the twin must be written with short
lines. The references are pybullet_data's A1 and the Go2-like fixture loaded from their own
multi-line files, never through the code under test.
"""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pybullet
import pytest
from exported_urdf import FEET, exported_quadruped, unitree_style_a1
from node_harness import LATCHED, NodeClient, node_command, parse_tokens
from pybullet_reference import A1_URDF, PyBulletRobot, assert_twin_agrees
from shared import A1_FEET, LEGS, PYBULLET_NAMES, UNITREE_NAMES
from std_msgs.msg import String

from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.verify import MAX_LINE_BYTES, PyBulletFeet, kinematic_urdf

TOLERANCE_M = 1e-7
PYBULLET_LINE_BYTES = 8191
"""The longest line PyBullet's URDF reader reads whole (its ``readLine`` buffer is 8,192)."""
LONG_SUFFIX = "_of_the_go2_like_robot_whose_exporter_writes_long_link_names"
ANGLES = [0.1, 0.7, -1.4, -0.1, 0.9, -1.2, 0.2, 0.6, -1.6, -0.2, 0.8, -1.1]


def folded(xml: str) -> str:
    """``xml`` on one line, as rcl's YAML parser folds a multi-line plain scalar: each line break
    and the indentation after it become one space."""
    return " ".join(line.strip() for line in xml.splitlines() if line.strip())


def go2_with_long_names(meshes: bool = True) -> str:
    """The Go2-like fixture with every link but the feet renamed ``<name>`` + :data:`LONG_SUFFIX`,
    with no XML declaration or comment (rcl would refuse the exporter header's ``key: value``)."""
    xml = exported_quadruped("go2", meshes=meshes)
    robot = ElementTree.fromstring(xml)
    for link in robot.findall("link"):
        name = link.get("name", "")
        if name not in FEET:
            xml = xml.replace(f'"{name}"', f'"{name}{LONG_SUFFIX}"')
    return xml[xml.index("<robot") :]


ROBOTS = {"a1": unitree_style_a1(), "go2_long_names": go2_with_long_names()}
"""Multi-line descriptions, both with Unitree's joint names (:data:`UNITREE_NAMES`) and root link
``base`` (+ the suffix): the node's default A1 says ``trunk``, so the frame tells which robot
answered."""
ROOTS = {"a1": "base", "go2_long_names": f"base{LONG_SUFFIX}"}
REFERENCE_NAMES = {"a1": (PYBULLET_NAMES, A1_FEET), "go2_long_names": (UNITREE_NAMES, FEET)}
"""The joints and feet of each reference, in slot order (the A1's: pybullet_data's own file)."""


def reference(tmp_path: Path, robot: str) -> PyBulletRobot:
    """PyBullet's own model of ``robot``, from a multi-line file with short lines."""
    if robot == "a1":
        return PyBulletRobot(A1_URDF)
    path = tmp_path / "go2_long_names_primitives.urdf"
    path.write_text(go2_with_long_names(meshes=False), encoding="utf-8")
    return PyBulletRobot(path)


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_the_twin_of_a_one_line_description_matches_pybullet(tmp_path: Path, robot: str) -> None:
    names, feet = REFERENCE_NAMES[robot]
    one_line = folded(ROBOTS[robot])
    assert "\n" not in one_line and len(one_line.encode()) > PYBULLET_LINE_BYTES
    twin_text = kinematic_urdf(one_line)
    assert max(len(line.encode()) for line in twin_text.splitlines()) <= MAX_LINE_BYTES
    config = load_robot(one_line)
    twin = PyBulletFeet(config.quadruped, config.urdf_xml)
    try:
        with reference(tmp_path, robot) as pybullet_itself:
            limits = pybullet_itself.limits(names)
            configurations = np.random.default_rng(19).uniform(*limits, size=(20, len(names)))
            assert_twin_agrees(twin, pybullet_itself, names, feet, configurations, TOLERANCE_M)
    finally:
        twin.close()


def cut_inside_a_name(one_line: str) -> tuple[str, str]:
    """``one_line`` with its robot name padded so that PyBullet's cut after byte 8,191 falls five
    bytes into a joint's name; (the text, that joint's name)."""
    robot = ElementTree.fromstring(one_line)
    starts = [
        (one_line.index(f'name="{joint.get("name")}"') + len('name="'), joint.get("name", ""))
        for joint in robot.findall("joint")
    ]
    start, name = max((s, n) for s, n in starts if s + 5 <= PYBULLET_LINE_BYTES)
    pad = PYBULLET_LINE_BYTES - 5 - start
    robot_name = robot.get("name", "")
    padded = one_line.replace(f'name="{robot_name}"', f'name="{robot_name}{"x" * pad}"', 1)
    return padded, name


def old_twin(one_line: str) -> str:
    """The twin as it was written before: the tree without visuals and collisions, in
    ElementTree's own layout (one line for a one-line description)."""
    robot = ElementTree.fromstring(one_line)
    for link in robot.iter("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
    return ElementTree.tostring(robot, encoding="unicode")


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_pybullet_itself_cuts_a_long_line_the_old_twin_had(tmp_path: Path, robot: str) -> None:
    """Why the twin is indented: the old twin of a one-line description, its cut placed inside a
    joint's name, fails to load or loads with a corrupted name; the new twin of it loads."""
    text, cut_name = cut_inside_a_name(old_twin(folded(ROBOTS[robot])))
    assert "\n" not in text and text.index(f'"{cut_name}"') + 6 == PYBULLET_LINE_BYTES
    expected = {joint.get("name") for joint in ElementTree.fromstring(text).iter("joint")}
    path = tmp_path / "one_line.urdf"
    path.write_text(text, encoding="utf-8")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
        loaded = {
            pybullet.getJointInfo(body, j, physicsClientId=client)[1].decode()
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))
        }
        assert loaded != expected and cut_name not in loaded, "PyBullet read the long line whole"
    except pybullet.error:
        pass  # refused: the other way the cut shows
    finally:
        pybullet.disconnect(client)
    config = load_robot(text)  # the new twin of the same text loads and agrees
    twin = PyBulletFeet(config.quadruped, config.urdf_xml)
    try:
        assert twin.verify([0.0, 0.8, -1.5] * 4, TOLERANCE_M).success
    finally:
        twin.close()


# --- through the node, over DDS -----------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("source", ["parameter", "topic", "urdf_file"])
@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_verify_fk_succeeds_on_a_one_line_description(
    processes, ros, tmp_path: Path, robot: str, source: str
) -> None:
    xml = ROBOTS[robot]
    if source == "parameter":  # multi-line, as a user types it: rcl folds it into one line
        command = node_command("-p", f"robot_description:={xml}")
    elif source == "topic":
        publisher = ros.node.create_publisher(String, "robot_description", LATCHED)
        publisher.publish(String(data=folded(xml)))
        command = node_command()
    else:
        path = tmp_path / f"{robot}_one_line.urdf"
        path.write_text(folded(xml), encoding="utf-8")
        command = node_command("-p", f"urdf_file:={path}")
    process = processes.start(command)
    client = NodeClient(ros)

    def sent_and_all_arrived() -> bool:
        client.send(client.joint_state(UNITREE_NAMES, ANGLES))
        return all(
            client.positions[leg] and client.positions[leg][-1].header.frame_id == ROOTS[robot]
            for leg in LEGS
        )

    assert client.probe.spin_until(sent_and_all_arrived, 30.0), processes.output(process)
    response = client.verify()
    assert response.success, response.message
    tokens = parse_tokens(response.message)
    assert float(tokens["max_error_m"]) <= TOLERANCE_M
    assert all(float(tokens[leg]) <= float(tokens["max_error_m"]) for leg in LEGS)
    assert tokens["outside_limits"] == "none"
    names, feet = REFERENCE_NAMES[robot]
    with reference(tmp_path, robot) as pybullet_itself:
        expected = pybullet_itself.feet(names, feet, ANGLES)
    for slot, leg in enumerate(LEGS):
        point = client.positions[leg][-1].point
        assert np.linalg.norm(np.array([point.x, point.y, point.z]) - expected[slot]) <= 1e-7
