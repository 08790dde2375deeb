"""Packaging: package.xml and setup.py agree, config/params.yaml documents the node, and the ROS
path works end to end: `colcon build` of a copy of the package, the lookup `ros2 run` does, and the
installed `foot_fk_node` answering a JointState with the right foot position and stopping on
Ctrl-C (SIGINT) with exit code 0."""

from __future__ import annotations

import importlib.metadata
import math
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

import pytest
import yaml
from conftest import BIN
from shared import PYBULLET_NAMES as JOINTS
from shared import ROOT as REPO
from shared import STANDING as POSE
from shared import STANDING_FR as FR_FOOT

PACKAGE = "a1_leg_fk"
NODE_NAME = "a1_leg_fk"
PYTHON_DIR = f"python{sys.version_info.major}.{sys.version_info.minor}"

EXEC_DEPENDS = {
    "rclpy",
    "std_msgs",
    "sensor_msgs",
    "nav_msgs",
    "geometry_msgs",
    "std_srvs",
    "diagnostic_msgs",
    "visualization_msgs",
    "ament_index_python",
    "launch",
    "launch_ros",
    "robot_state_publisher",
    "rviz2",
    "python3-numpy",
    "python3-pybullet-pip",
}
TEST_DEPENDS = {"python3-pytest", "python3-hypothesis"}
CONSOLE_SCRIPTS = {
    "foot_fk_node": "a1_leg_fk.ros.executables:foot_fk_node",
    "foot_ik_node": "a1_leg_fk.ros.executables:foot_ik_node",
    "joint_state_demo": "a1_leg_fk.ros.executables:joint_state_demo",
    "leg_odometry_node": "a1_leg_fk.ros.executables:leg_odometry_node",
    "a1-leg-fk": "a1_leg_fk.cli:main",
}
# Every node parameter with its default. String arrays have no value a params file can state
# (`[]` has no type), so config/params.yaml only shows them commented out.
SCALAR_DEFAULTS = {
    "robot_description": "",
    "urdf_file": "",
    "robot_description_topic": "robot_description",
    "base_frame": "",
    "input": "joint_states",
    "publish_velocities": True,
    "publish_markers": True,
    "marker_rate_hz": 30.0,
    "max_publish_rate_hz": 0.0,
    "enable_verify": True,
    "verify_tolerance_m": 1e-6,
    "preserialized_output": True,
    "publish_forces": True,
    "force_model": "dynamic",
    "contact_rule": "filter",
    "touchdown_force_n": 0.0,
    "liftoff_force_n": 0.0,
    "model_corrections": "online",
    "model_corrections_file": "",
    "gait_phase_timeout_s": 0.1,
}
STRING_ARRAYS = ("foot_links", "joint_aliases")
# Parameters rclpy declares on every node (and per-topic QoS overrides), not the package's own.
ROS_OWN_PARAMETERS = {"use_sim_time", "start_type_description_service"}

# The copy colcon builds: the package's own files only, so no other package can be picked up.
PACKAGE_FILES = ("package.xml", "setup.py", "setup.cfg", "README.md", "CONTRIBUTING.md", "LICENSE")
PACKAGE_FOLDERS = ("resource", "config", "launch", "rviz", "docs", "a1_leg_fk", "test")

FOOT_TOLERANCE_M = 1e-4
FOOT_WAIT_S = 30.0


def _package_xml() -> ElementTree.Element:
    return ElementTree.parse(REPO / "package.xml").getroot()


def _params_yaml(path: Path = REPO / "config" / "params.yaml") -> dict[str, object]:
    document = yaml.safe_load(path.read_text())
    assert list(document) == [NODE_NAME], f"{path}: the one top-level key must be the node name"
    return document[NODE_NAME]["ros__parameters"]


# --- package.xml, setup.py, setup.cfg, params.yaml (fast) ---------------------------------------


def test_package_xml_is_format_3_with_every_dependency():
    root = _package_xml()
    assert root.tag == "package" and root.get("format") == "3"
    assert root.findtext("name") == PACKAGE
    assert re.fullmatch(r"\d+\.\d+\.\d+", root.findtext("version", ""))
    assert root.findtext("description", "").strip()
    maintainer = root.find("maintainer")
    assert maintainer is not None and maintainer.get("email")
    assert [element.text for element in root.findall("license")] == ["Apache-2.0"]
    assert {element.text for element in root.findall("exec_depend")} >= EXEC_DEPENDS
    assert {element.text for element in root.findall("test_depend")} >= TEST_DEPENDS
    assert root.findtext("export/build_type") == "ament_python"


def test_package_xml_passes_catkin_pkg_validation():
    """The parser colcon, rosdep and bloom use: strict about format 3."""
    from catkin_pkg.package import parse_package

    warnings: list[str] = []
    package = parse_package(str(REPO), warnings=warnings)
    package.validate(warnings=warnings)
    assert warnings == []
    assert package.get_build_type() == "ament_python"
    assert {dependency.name for dependency in package.exec_depends} >= EXEC_DEPENDS


@pytest.mark.slow
def test_setup_py_name_and_version_are_package_xmls():
    result = subprocess.run(
        [sys.executable, "setup.py", "--name", "--version"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    name, version = result.stdout.split()[-2:]
    assert name == PACKAGE
    assert version == _package_xml().findtext("version")


def test_setup_cfg_installs_scripts_where_ros2_run_looks():
    text = (REPO / "setup.cfg").read_text()
    assert re.search(
        r"^\[develop\]\s*\nscript_dir\s*=\s*\$base/lib/a1_leg_fk\s*$", text, re.MULTILINE
    )
    assert re.search(
        r"^\[install\]\s*\ninstall_scripts\s*=\s*\$base/lib/a1_leg_fk\s*$", text, re.MULTILINE
    )


def test_pip_install_puts_the_console_scripts_beside_python():
    """`make venv` (pip, PEP 660) must not follow setup.cfg's colcon script dirs: tests find the
    executables in the venv's bin."""
    entry_points = {
        entry_point.name: entry_point.value
        for entry_point in importlib.metadata.distribution(PACKAGE).entry_points
        if entry_point.group == "console_scripts"
    }
    assert entry_points == CONSOLE_SCRIPTS
    for script in CONSOLE_SCRIPTS:
        path = BIN / script
        assert path.is_file() and os.access(path, os.X_OK), f"{path} missing: run `make venv`"


def test_params_yaml_states_every_scalar_default():
    parameters = _params_yaml()
    assert parameters == SCALAR_DEFAULTS
    for name, value in parameters.items():  # 30.0, not 30: ROS would type it as an integer
        assert type(value) is type(SCALAR_DEFAULTS[name]), name


def test_params_yaml_shows_the_string_arrays_commented_out():
    text = (REPO / "config" / "params.yaml").read_text()
    for name in STRING_ARRAYS:
        example = re.search(rf"^\s*#\s*{name}:\s*(\[.*\])\s*$", text, re.MULTILINE)
        assert example, f"{name}: no commented example"
        entries = yaml.safe_load(example.group(1))
        assert entries and all(re.fullmatch(r"[^=\s]+=[^=\s]+", entry) for entry in entries), name


# --- the ROS path: colcon build, ros2 run's lookup, the installed node (slow) --------------------


@dataclass(frozen=True)
class ColconInstall:
    workspace: Path
    prefix: Path  # install/a1_leg_fk: colcon's default isolated layout
    site_packages: Path

    def environment(self) -> dict[str, str]:
        """What `source install/setup.bash` gives a process, for this package."""
        python_path = [str(self.site_packages), os.environ.get("PYTHONPATH", "")]
        ament_prefix_path = [str(self.prefix), os.environ.get("AMENT_PREFIX_PATH", "")]
        return {
            "PYTHONPATH": os.pathsep.join(part for part in python_path if part),
            "AMENT_PREFIX_PATH": os.pathsep.join(part for part in ament_prefix_path if part),
        }


@pytest.fixture(scope="module")
def colcon_install(tmp_path_factory: pytest.TempPathFactory) -> ColconInstall:
    workspace = tmp_path_factory.mktemp("colcon_ws")
    source = workspace / "src" / PACKAGE
    source.mkdir(parents=True)
    for name in PACKAGE_FILES:
        shutil.copy2(REPO / name, source / name)
    for name in PACKAGE_FOLDERS:
        shutil.copytree(
            REPO / name,
            source / name,
            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", "golden_cache"),
        )
    colcon = BIN / "colcon"
    assert colcon.exists(), f"{colcon} is not installed: run `make venv`"
    environment = {
        key: value
        for key, value in os.environ.items()
        if key
        not in ("AMENT_PREFIX_PATH", "COLCON_PREFIX_PATH", "CMAKE_PREFIX_PATH", "PYTHONPATH")
    }
    environment["COLCON_HOME"] = str(workspace / "colcon_home")  # no user defaults.yaml
    result = subprocess.run(
        [
            str(colcon),
            "--log-base",
            str(workspace / "log"),
            "build",
            "--base-paths",
            str(workspace / "src"),
            "--build-base",
            str(workspace / "build"),
            "--install-base",
            str(workspace / "install"),
            "--executor",
            "sequential",
            "--event-handlers",
            "console_cohesion+",
            "summary+",
        ],
        check=False,
        cwd=workspace,
        env=environment,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, f"colcon build failed:\n{result.stdout}\n{result.stderr}"
    assert "1 package finished" in result.stdout, result.stdout
    prefix = workspace / "install" / PACKAGE
    return ColconInstall(workspace, prefix, prefix / "lib" / PYTHON_DIR / "site-packages")


@pytest.mark.slow
def test_colcon_install_has_what_ros2_run_needs(colcon_install: ColconInstall, monkeypatch):
    prefix = colcon_install.prefix
    assert (prefix / "share" / "ament_index" / "resource_index" / "packages" / PACKAGE).is_file()
    assert (prefix / "share" / PACKAGE / "package.xml").is_file()
    installed_params = prefix / "share" / PACKAGE / "config" / "params.yaml"
    assert installed_params.read_text() == (REPO / "config" / "params.yaml").read_text()
    # what `ros2 launch a1_leg_fk feet.launch.py` finds in the package's share folder
    shared = [
        Path("launch") / "feet.launch.py",
        Path("rviz") / "feet.rviz",
        *(path.relative_to(REPO) for path in sorted((REPO / "config" / "robots").glob("*.yaml"))),
    ]
    assert len(shared) == 7
    for relative in shared:
        installed = prefix / "share" / PACKAGE / relative
        assert installed.read_bytes() == (REPO / relative).read_bytes(), relative

    # `ros2 run a1_leg_fk foot_fk_node`: get_package_prefix, then <prefix>/lib/<package>/<name>.
    from ament_index_python.packages import get_package_prefix, get_package_share_directory

    monkeypatch.setenv("AMENT_PREFIX_PATH", colcon_install.environment()["AMENT_PREFIX_PATH"])
    assert Path(get_package_prefix(PACKAGE)) == prefix
    assert Path(get_package_share_directory(PACKAGE)) == prefix / "share" / PACKAGE
    for script in CONSOLE_SCRIPTS:
        executable = Path(get_package_prefix(PACKAGE)) / "lib" / PACKAGE / script
        assert executable.is_file() and os.access(executable, os.X_OK), executable

    # The installed copy, not the working tree (nor the venv's editable install), is imported.
    result = subprocess.run(
        [sys.executable, "-c", "import a1_leg_fk; print(a1_leg_fk.__file__)"],
        cwd=colcon_install.workspace,
        env={**os.environ, **colcon_install.environment()},
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert Path(result.stdout.strip()).is_relative_to(colcon_install.site_packages), result.stdout


@pytest.mark.slow
def test_colcon_test_runs_the_package_tests(colcon_install: ColconInstall):
    """`colcon test --packages-select a1_leg_fk`, as a ROS user runs it (ament_python: pytest
    over the package's test/), on a fast part of the suite: the layout rules and the launch
    file's static checks; `colcon test-result` counts them, none failing."""
    environment = {**os.environ, "COLCON_HOME": str(colcon_install.workspace / "colcon_home")}
    environment["PATH"] = f"{BIN}{os.pathsep}{environment.get('PATH', '')}"
    common = ["--log-base", str(colcon_install.workspace / "log")]
    selection = "test_layout.py or (test_launch.py and not running)"
    tested = subprocess.run(
        [str(BIN / "colcon"), *common, "test", "--packages-select", PACKAGE,
         "--build-base", str(colcon_install.workspace / "build"),
         "--install-base", str(colcon_install.workspace / "install"),
         "--pytest-args", "-p", "no:cacheprovider", "-k", selection],
        cwd=colcon_install.workspace, env=environment, capture_output=True, text=True,
        timeout=600, check=False,
    )  # fmt: skip
    assert tested.returncode == 0, f"{tested.stdout}\n{tested.stderr}"
    result = subprocess.run(
        [str(BIN / "colcon"), "test-result", "--test-result-base",
         str(colcon_install.workspace / "build")],
        cwd=colcon_install.workspace, env=environment, capture_output=True, text=True,
        timeout=120, check=False,
    )  # fmt: skip
    summary = re.search(r"Summary: (\d+) tests, (\d+) errors, (\d+) failures", result.stdout)
    assert result.returncode == 0 and summary, result.stdout + result.stderr
    assert int(summary.group(1)) > 100 and summary.group(2, 3) == ("0", "0"), summary.group(0)


def _installed_node() -> str:
    from ament_index_python.packages import get_package_prefix

    prefix = get_package_prefix(PACKAGE)  # with the install's AMENT_PREFIX_PATH (monkeypatched)
    return os.path.join(prefix, "lib", PACKAGE, "foot_fk_node")


def _call(ros, service_type, name: str, request, timeout_s: float = 20.0):
    client = ros.node.create_client(service_type, name)
    try:
        return ros.call(client, request, timeout_s)
    finally:
        ros.node.destroy_client(client)


def _node_parameters(ros) -> dict[str, object]:
    """The node's own parameters as plain values (None: declared without a value), asked one by
    one through its parameter services (GetParameters answers nothing at all for a list that
    holds a parameter without a value)."""
    from rcl_interfaces.srv import GetParameters, ListParameters
    from rclpy.parameter import parameter_value_to_python

    names = _call(
        ros,
        ListParameters,
        f"/{NODE_NAME}/list_parameters",
        ListParameters.Request(depth=ListParameters.Request.DEPTH_RECURSIVE),
    ).result.names
    parameters = {}
    for name in names:
        if name in ROS_OWN_PARAMETERS or name.startswith("qos_overrides."):
            continue
        values = _call(
            ros, GetParameters, f"/{NODE_NAME}/get_parameters", GetParameters.Request(names=[name])
        ).values
        parameters[name] = parameter_value_to_python(values[0]) if values else None
    return parameters


@pytest.mark.slow
def test_installed_node_publishes_the_fr_foot_and_stops_on_sigint(
    colcon_install: ColconInstall, processes, ros, monkeypatch
):
    from geometry_msgs.msg import PointStamped
    from sensor_msgs.msg import JointState

    environment = colcon_install.environment()
    monkeypatch.setenv("AMENT_PREFIX_PATH", environment["AMENT_PREFIX_PATH"])
    node = processes.start([_installed_node()], env=environment)

    feet: list[PointStamped] = []
    ros.node.create_subscription(PointStamped, "foot_positions/FR", feet.append, 10)
    publisher = ros.node.create_publisher(JointState, "joint_states", 10)
    last_sent = [0.0]

    def fr_foot_arrived() -> bool:
        assert node.poll() is None, f"foot_fk_node exited:\n{processes.output(node)}"
        if time.monotonic() - last_sent[0] > 0.1:  # until the node has subscribed and answered
            message = JointState(name=JOINTS, position=POSE)
            message.header.stamp = ros.node.get_clock().now().to_msg()
            publisher.publish(message)
            last_sent[0] = time.monotonic()
        return bool(feet)

    started = time.monotonic()
    assert ros.spin_until(fr_foot_arrived, FOOT_WAIT_S), (
        f"no foot_positions/FR within {FOOT_WAIT_S} s:\n{processes.output(node)}"
    )
    print(f"installed foot_fk_node answered after {time.monotonic() - started:.1f} s")
    point = feet[0].point
    for axis, got, expected in zip("xyz", (point.x, point.y, point.z), FR_FOOT):
        assert math.isclose(got, expected, abs_tol=FOOT_TOLERANCE_M), (axis, got, expected)
    assert feet[0].header.frame_id == "trunk"  # base_frame "" = the A1 URDF's root link

    # config/params.yaml documents every parameter the node declares, with the node's defaults.
    parameters = _node_parameters(ros)
    assert set(parameters) == set(SCALAR_DEFAULTS) | set(STRING_ARRAYS), (
        "config/params.yaml and the node's parameters differ"
    )
    assert {name: parameters[name] for name in SCALAR_DEFAULTS} == _params_yaml()
    for name in STRING_ARRAYS:
        assert parameters[name] in (None, []), (name, parameters[name])

    assert processes.interrupt(node, timeout_s=10.0) == 0, processes.output(node)


@pytest.mark.slow
def test_installed_node_loads_the_installed_params_file(
    colcon_install: ColconInstall, processes, ros, monkeypatch
):
    environment = colcon_install.environment()
    monkeypatch.setenv("AMENT_PREFIX_PATH", environment["AMENT_PREFIX_PATH"])
    from ament_index_python.packages import get_package_share_directory

    params_file = os.path.join(get_package_share_directory(PACKAGE), "config", "params.yaml")
    node = processes.start(
        [_installed_node(), "--ros-args", "--params-file", params_file],
        env=environment,
    )
    try:
        parameters = _node_parameters(ros)
    except AssertionError as error:
        raise AssertionError(f"{error}\nnode output:\n{processes.output(node)}") from None
    assert {name: parameters[name] for name in SCALAR_DEFAULTS} == _params_yaml(Path(params_file))
    assert node.poll() is None, processes.output(node)
    assert processes.interrupt(node, timeout_s=10.0) == 0, processes.output(node)
