"""Unitree's message packages built with colcon from the published field lists (ament_cmake and
the rosidl generators as wheels, requirements-msgs.txt), as a user's workspace builds them, for
the nodes' ``input: unitree_lowstate`` (test/ros/test_lowstate_node.py, bench/fuzz_nodes.py).

``unitree_go`` is built from its definitions as published. ``unitree_legged_msgs`` is a ROS 1
package whose field names (``levelFlag``, ``motorState``) rosidl refuses; a ROS 2 workspace (a
bridge's side, Unitree's own ``ros2_unitree_legged_msgs``) names them in snake case
(``level_flag``, ``motor_state``): the same types in the same order, so the same CDR bytes.
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from shared import ROOT

from a1_leg_fk.wire.unitree_types import UNITREE_GO, UNITREE_LEGGED

BIN = Path(sys.executable).parent
PYTHON_DIR = f"python{sys.version_info.major}.{sys.version_info.minor}"
PACKAGES = {"unitree_go": UNITREE_GO, "unitree_legged_msgs": UNITREE_LEGGED}
"""The packages that can be built, by name: their definitions by type."""
CMAKE = """cmake_minimum_required(VERSION 3.8)
project({package})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
rosidl_generate_interfaces(${{PROJECT_NAME}} {files})
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""
PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>{package}</name>
  <version>0.0.0</version>
  <description>Unitree's {package} messages, from their published field lists</description>
  <maintainer email="tests@example.com">tests</maintainer>
  <license>BSD-3-Clause</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def ros2_definition(text: str) -> str:
    """A .msg text with its field names in snake case, as rosidl requires (``tauEst`` ->
    ``tau_est``, ``SOC`` -> ``soc``); types, order and sizes unchanged.
    """
    lines = []
    for line in text.strip().splitlines():
        kind, name = line.split()
        lines.append(f"{kind} {snake_case(name)}")
    return "\n".join(lines) + "\n"


def snake_case(name: str) -> str:
    """``tauEst`` -> ``tau_est``, ``BQ_NTC`` -> ``bq_ntc``."""
    return re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name).lower()


def write_package(source: Path, package: str) -> None:
    """The package's sources under ``source``."""
    (source / "msg").mkdir(parents=True)
    for msgtype, text in PACKAGES[package].items():
        (source / "msg" / f"{msgtype.split('/')[-1]}.msg").write_text(ros2_definition(text))
    files = " ".join(f'"msg/{msgtype.split("/")[-1]}.msg"' for msgtype in PACKAGES[package])
    (source / "CMakeLists.txt").write_text(CMAKE.format(package=package, files=files))
    (source / "package.xml").write_text(PACKAGE_XML.format(package=package))


def build(workspace: Path, packages: tuple[str, ...]) -> dict[str, dict[str, str]]:
    """Build ``packages`` in ``workspace`` with colcon; per package, the environment a process
    needs to use it alone (as sourcing its install's setup.bash gives).
    """
    for package in packages:
        write_package(workspace / "src" / package, package)
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
    return {package: environment_of(workspace / "install" / package) for package in packages}


def environment_of(prefix: Path) -> dict[str, str]:
    """What a child process needs to use the package installed at ``prefix`` (this process's
    PYTHONPATH kept: a checkout run with ``PYTHONPATH=.`` runs its own nodes, not the installed
    ones)."""
    kept = [part for part in os.environ.get("PYTHONPATH", "").split(os.pathsep) if part]
    return {
        "PYTHONPATH": os.pathsep.join(
            [str(prefix / "lib" / PYTHON_DIR / "site-packages"), str(ROOT / "test"), *kept]
        ),
        "LD_LIBRARY_PATH": os.pathsep.join(
            part for part in (str(prefix / "lib"), os.environ.get("LD_LIBRARY_PATH", "")) if part
        ),
        "AMENT_PREFIX_PATH": os.pathsep.join([str(prefix), str(Path(sys.prefix))]),
    }


def load_here(environment: dict[str, str]) -> None:
    """Make the package of ``environment`` (:func:`build`) usable in this running process, to
    publish its messages raw: its libraries loaded by path (the loader reads LD_LIBRARY_PATH only
    when a process starts; the typesupport is then found by its name), its Python package on
    ``sys.path``.
    """
    prefix = Path(environment["LD_LIBRARY_PATH"].split(os.pathsep)[0]).parent
    for part in ("generator_c", "typesupport_c", "typesupport_fastrtps_c",
                 "typesupport_introspection_c", "generator_py"):  # fmt: skip
        for library in prefix.glob(f"lib/lib*__rosidl_{part}.so"):
            ctypes.CDLL(str(library), mode=ctypes.RTLD_GLOBAL)
    site = environment["PYTHONPATH"].split(os.pathsep)[0]
    if site not in sys.path:
        sys.path.insert(0, site)
