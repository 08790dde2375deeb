"""The nodes' ``input: unitree_lowstate`` for real: Unitree's ``unitree_go`` message package is
built with colcon from the published field lists (ament_cmake and the rosidl generators as
wheels, requirements-msgs.txt), as a user's workspace builds it; a process with that install
publishes LowState messages of the A1 standing, and ``foot_fk_node`` answers with the FR foot the
JointState path gives, ``leg_odometry_node`` with odometry. Without the package: one line naming
it, exit 2.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import BIN
from shared import ROOT, STANDING

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.wire.unitree_types import UNITREE_GO

PYTHON_DIR = f"python{sys.version_info.major}.{sys.version_info.minor}"
WAIT_S = 30.0
CMAKE = f"""cmake_minimum_required(VERSION 3.8)
project(unitree_go)
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
rosidl_generate_interfaces(${{PROJECT_NAME}} {" ".join(
    f'"msg/{name.split("/")[-1]}.msg"' for name in UNITREE_GO)})
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""  # fmt: skip
PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>unitree_go</name>
  <version>0.0.0</version>
  <description>Unitree's unitree_go messages, from their published field lists</description>
  <maintainer email="tests@example.com">tests</maintainer>
  <license>BSD-3-Clause</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


@pytest.fixture(scope="module")
def unitree_go(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Builds unitree_go with colcon; the environment a process needs to use it (as sourcing
    the install's setup.bash gives)."""
    workspace = tmp_path_factory.mktemp("unitree_ws")
    source = workspace / "src" / "unitree_go"
    (source / "msg").mkdir(parents=True)
    for msgtype, text in UNITREE_GO.items():
        (source / "msg" / f"{msgtype.split('/')[-1]}.msg").write_text(text.lstrip())
    (source / "CMakeLists.txt").write_text(CMAKE)
    (source / "package.xml").write_text(PACKAGE_XML)
    venv = Path(sys.prefix)
    environment = {
        **{key: value for key, value in os.environ.items() if "PREFIX_PATH" not in key},
        "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
        "CMAKE_PREFIX_PATH": str(venv),
        "AMENT_PREFIX_PATH": str(venv),
        "COLCON_HOME": str(workspace / "colcon_home"),
    }
    assert shutil.which("cmake"), "cmake is needed to build a message package"
    result = subprocess.run(
        [str(BIN / "colcon"), "build", "--executor", "sequential", "--event-handlers",
         "console_cohesion+"],
        cwd=workspace, env=environment, capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert result.returncode == 0, f"colcon build failed:\n{result.stdout}\n{result.stderr}"
    prefix = workspace / "install" / "unitree_go"
    return {
        "PYTHONPATH": os.pathsep.join(
            [str(prefix / "lib" / PYTHON_DIR / "site-packages"), str(ROOT / "test")]
        ),
        "LD_LIBRARY_PATH": os.pathsep.join(
            part for part in (str(prefix / "lib"), os.environ.get("LD_LIBRARY_PATH", "")) if part
        ),
        "AMENT_PREFIX_PATH": os.pathsep.join([str(prefix), str(venv)]),
    }


@pytest.mark.slow
@pytest.mark.parametrize("executable", ["foot_fk_node", "leg_odometry_node"])
def test_without_the_message_package_one_line_and_exit_2(processes, executable: str) -> None:
    process = processes.start(
        [str(BIN / executable), "--ros-args", "-p", "input:=unitree_lowstate"]
    )
    try:
        code = process.wait(WAIT_S)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{executable} kept running without unitree_go")
    output = processes.output(process)
    assert code == 2, output
    lines = [line for line in output.splitlines() if line.strip()]
    assert len(lines) == 1 and "unitree_go" in lines[0] and "Traceback" not in output, output


@pytest.mark.slow
def test_foot_fk_node_reads_lowstate(unitree_go: dict[str, str], processes, ros) -> None:
    from geometry_msgs.msg import PointStamped

    node = processes.start(
        [str(BIN / "foot_fk_node"), "--ros-args", "-p", "input:=unitree_lowstate"],
        env=unitree_go,
    )
    publisher = processes.start(
        [sys.executable, str(ROOT / "test" / "lowstate_publisher.py")], env=unitree_go
    )
    feet: list[PointStamped] = []
    ros.node.create_subscription(PointStamped, "foot_positions/FR", feet.append, 10)

    def arrived() -> bool:
        assert node.poll() is None, processes.output(node)
        assert publisher.poll() is None, processes.output(publisher)
        return bool(feet)

    assert ros.spin_until(arrived, WAIT_S), processes.output(node)
    expected = Quadruped.from_urdf().fk(np.array(STANDING, np.float32).astype(float).tolist())[0]
    point = feet[-1].point
    for got, wanted in zip((point.x, point.y, point.z), expected, strict=True):
        assert math.isclose(got, wanted, abs_tol=1e-9), (got, wanted)
    stamp = feet[-1].header.stamp.sec + feet[-1].header.stamp.nanosec * 1e-9
    assert abs(stamp - time.time()) < 60.0  # the receive time: the LowState has no header
    assert processes.interrupt(node, timeout_s=10.0) == 0, processes.output(node)


@pytest.mark.slow
def test_leg_odometry_node_reads_lowstate(unitree_go: dict[str, str], processes, ros) -> None:
    from nav_msgs.msg import Odometry

    node = processes.start(
        [str(BIN / "leg_odometry_node"), "--ros-args", "-p", "input:=unitree_lowstate"],
        env=unitree_go,
    )
    processes.start([sys.executable, str(ROOT / "test" / "lowstate_publisher.py")], env=unitree_go)
    odometry: list[Odometry] = []
    ros.node.create_subscription(Odometry, "leg_odometry", odometry.append, 10)
    assert ros.spin_until(lambda: len(odometry) >= 20, WAIT_S), processes.output(node)
    position = odometry[-1].pose.pose.position
    assert math.hypot(position.x, position.y) < 0.01  # standing still [m]
    assert "lowstate" in processes.output(node)
    assert processes.interrupt(node, timeout_s=10.0) == 0, processes.output(node)
