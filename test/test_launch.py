"""``launch/feet.launch.py``, its presets (``config/robots/``) and ``rviz/feet.rviz``, checked
without the launch system (no wheels of it): the launch file read as source (``ast``), every
executable it starts installed by this package or declared in package.xml, every parameter it and
the presets set declared by the nodes, its arguments' choices the presets and the nodes' inputs;
and every RViz display's topic and message type what the running nodes publish (the ROS graph
asked).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import pytest
import yaml
from conftest import BIN
from shared import ROOT

from a1_leg_fk.ros import foot_fk_parameters, joint_input, odometry_parameters, robot_source

LAUNCH = ROOT / "launch" / "feet.launch.py"
RVIZ = ROOT / "rviz" / "feet.rviz"
PRESETS = ROOT / "config" / "robots"
PACKAGE = "a1_leg_fk"
ARGUMENTS = {"robot", "description", "input", "odometry", "rviz"}
DISPLAY_TYPES = {  # RViz display class -> the message type it shows
    "rviz_default_plugins/RobotModel": "std_msgs/msg/String",
    "rviz_default_plugins/MarkerArray": "visualization_msgs/msg/MarkerArray",
    "rviz_default_plugins/Wrench": "geometry_msgs/msg/WrenchStamped",
    "rviz_default_plugins/Odometry": "nav_msgs/msg/Odometry",
}
NODE_PARAMETERS = {
    "foot_fk_node": {spec.name for spec in (*robot_source.PARAMETERS,
                                            *foot_fk_parameters.PARAMETERS)},
    "leg_odometry_node": {spec.name for spec in (*robot_source.PARAMETERS,
                                                 *odometry_parameters.PARAMETERS)},
}  # fmt: skip


def launch_tree() -> ast.Module:
    return ast.parse(LAUNCH.read_text(), str(LAUNCH))


def calls(name: str) -> list[ast.Call]:
    """Every call of ``name`` in the launch file."""
    return [
        node
        for node in ast.walk(launch_tree())
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == name
    ]


def keyword(call: ast.Call, name: str) -> ast.expr | None:
    return next((item.value for item in call.keywords if item.arg == name), None)


def constant(name: str) -> Any:
    """The value of a module-level constant of the launch file."""
    for node in launch_tree().body:
        if isinstance(node, ast.Assign) and any(
            isinstance(target, ast.Name) and target.id == name for target in node.targets
        ):
            return ast.literal_eval(node.value)
    raise KeyError(name)


def console_scripts() -> set[str]:
    text = (ROOT / "setup.py").read_text()
    return set(__import__("re").findall(r'"(\w+) = a1_leg_fk\.', text))


def test_the_arguments_and_their_choices() -> None:
    declared = {ast.literal_eval(call.args[0]) for call in calls("DeclareLaunchArgument")}
    assert declared == ARGUMENTS
    robots = set(constant("FIXED_FRAMES"))
    assert robots == {path.stem for path in PRESETS.glob("*.yaml")} == {
        "a1", "go1", "go2", "b2", "aliengo"}  # fmt: skip
    assert constant("INPUTS") == joint_input.INPUTS


def test_every_executable_exists() -> None:
    exec_depends = {
        element.text for element in ElementTree.parse(ROOT / "package.xml").findall("exec_depend")
    }
    started = []
    for call in calls("Node"):
        package_node, executable_node = keyword(call, "package"), keyword(call, "executable")
        assert executable_node is not None and package_node is not None
        executable = ast.literal_eval(executable_node)
        if isinstance(package_node, ast.Name):  # PACKAGE
            assert package_node.id == "PACKAGE" and constant("PACKAGE") == PACKAGE
            assert executable in console_scripts(), executable
            assert (BIN / executable).exists(), executable
        else:
            package = ast.literal_eval(package_node)
            assert package in exec_depends, f"{package} is not an exec_depend of package.xml"
        started.append(executable)
    assert started == ["foot_fk_node", "leg_odometry_node", "robot_state_publisher", "rviz2"]


def test_every_parameter_set_is_declared_by_the_nodes() -> None:
    function = next(
        node
        for node in launch_tree().body
        if isinstance(node, ast.FunctionDef) and node.name == "nodes"
    )
    overrides = [node for node in ast.walk(function) if isinstance(node, ast.Dict)]
    named = {ast.literal_eval(key) for node in overrides for key in node.keys if key is not None}
    assert named == {"input", "robot_description"}  # robot_description: robot_state_publisher's
    for parameters in NODE_PARAMETERS.values():
        assert "input" in parameters
    for preset in sorted(PRESETS.glob("*.yaml")):
        document = yaml.safe_load(preset.read_text())
        assert list(document) == ["/**"], preset.name
        values = document["/**"]["ros__parameters"]
        for node, parameters in NODE_PARAMETERS.items():
            assert set(values) <= parameters, (preset.name, node, set(values) - parameters)
        assert values["input"] in joint_input.INPUTS


def test_the_rviz_file_is_the_one_the_launch_file_names() -> None:
    text = LAUNCH.read_text()
    assert '"rviz", "feet.rviz"' in text and RVIZ.is_file()
    assert '"config", "robots", f"{robot}.yaml"' in text


def rviz_displays() -> dict[str, str]:
    """Topic -> message type of every display of feet.rviz that shows a topic."""
    document = yaml.safe_load(RVIZ.read_text())
    shown = {}
    for display in document["Visualization Manager"]["Displays"]:
        kind = display["Class"]
        if kind == "rviz_default_plugins/Grid":
            continue
        topic = display.get("Description Topic") or display["Topic"]
        shown[topic["Value"]] = DISPLAY_TYPES[kind]
    return shown


def test_rviz_shows_the_robot_feet_forces_and_odometry() -> None:
    assert rviz_displays() == {
        "/robot_description": "std_msgs/msg/String",
        "/foot_markers": "visualization_msgs/msg/MarkerArray",
        **{f"/foot_forces/{leg}": "geometry_msgs/msg/WrenchStamped" for leg in
           ("FR", "FL", "RR", "RL")},
        "/leg_odometry": "nav_msgs/msg/Odometry",
    }  # fmt: skip


@pytest.mark.slow
def test_every_rviz_topic_is_what_the_running_nodes_publish(processes, ros) -> None:
    """The nodes started as the launch file starts them (a preset's parameters); the graph
    lists what they publish and subscribe to."""
    preset = str(PRESETS / "a1.yaml")
    started = [
        processes.start([str(BIN / name), "--ros-args", "--params-file", preset])
        for name in ("foot_fk_node", "leg_odometry_node")
    ]
    wanted = rviz_displays()
    published: dict[str, set[str]] = {}

    def listed() -> bool:
        for process in started:
            assert process.poll() is None, processes.output(process)
        published.clear()
        names = {name for name, _ in ros.node.get_node_names_and_namespaces()}
        if not {"a1_leg_fk", "leg_odometry"} <= names:
            return False
        for name in ("a1_leg_fk", "leg_odometry"):
            for topic, types in ros.node.get_publisher_names_and_types_by_node(name, "/"):
                published.setdefault(topic, set()).update(types)
        return all(topic in published for topic in wanted if topic != "/robot_description")

    assert ros.spin_until(listed, 30.0), (published, [processes.output(p) for p in started])
    for topic, msgtype in wanted.items():
        if topic == "/robot_description":  # published by robot_state_publisher, followed here
            subscribed = dict(ros.node.get_subscriber_names_and_types_by_node("a1_leg_fk", "/"))
            assert msgtype in subscribed[topic]
        else:
            assert published[topic] == {msgtype}, topic
    for process in started:
        assert processes.interrupt(process, timeout_s=10.0) == 0


def test_the_launch_file_compiles() -> None:
    subprocess.run(
        [sys.executable, "-m", "py_compile", str(LAUNCH)], check=True, capture_output=True
    )
    assert Path(LAUNCH).read_text().startswith('"""Start the feet')
