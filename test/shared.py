"""What the tests and the bench/ scripts share: the A1's names and standing pose, the machine-wide
ROS-domain lock, the package's installed executables, and local ports and bounded waits.

Standard library only at import time (no pytest, no ROS, no a1_leg_fk), so a bench script imports
it as it is; the commands ask the package's own ``child_command`` where its scripts are.
The names are written from the naming conventions, independently of the package's own tables.
"""

from __future__ import annotations

import fcntl
import os
import socket
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import IO

LEGS = ("FR", "FL", "RR", "RL")
"""Leg order: front-right, front-left, rear-right, rear-left."""

PYBULLET_NAMES = [f"{leg}_{joint}_joint" for leg in LEGS for joint in ("hip", "upper", "lower")]
"""pybullet_data's A1 joint names, in slot order (hip roll, hip pitch, knee per leg)."""

UNITREE_NAMES = [f"{leg}_{joint}_joint" for leg in LEGS for joint in ("hip", "thigh", "calf")]
"""Unitree's names for the same joints (unitree_ros, Gazebo, real-robot bridges)."""

A1_FEET = [f"{leg}_toe" for leg in LEGS]
"""pybullet_data's A1 (and Aliengo) foot links, in leg order."""

STAND_LEG = (0.0, 0.8, -1.5)
"""One leg standing [rad]: hip roll, hip pitch, knee."""

STANDING = list(STAND_LEG) * 4
"""All four legs standing [rad], in slot order: the reference write-up's pose."""

STANDING_FR = (0.1684, -0.1320, -0.2923)
"""The FR foot of the A1 in :data:`STANDING`, trunk frame [m]: the reference write-up's published
value."""

ROOT = Path(__file__).resolve().parent.parent
"""The repository (the package's source tree: package.xml, config/, bench/)."""

DOMAIN_IDS = range(1, 102)
"""ROS domain ids that are safe on one machine (higher ones clash with port ranges)."""

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
"""Clock ticks per second: the unit of the CPU times in /proc."""

DOMAIN_LOCK_FOLDER = Path(tempfile.gettempdir()) / "a1_leg_fk_test_domains"


def claim_domain_id() -> tuple[int, IO[str]]:
    """The first ROS domain id no other test run or soak on this machine holds, with its lock file.

    Keep the returned file open for as long as the domain is in use: the lock (``flock``) goes
    with it. Raises RuntimeError when every id in :data:`DOMAIN_IDS` is held.
    """
    DOMAIN_LOCK_FOLDER.mkdir(exist_ok=True)
    for domain_id in DOMAIN_IDS:
        lock = open(DOMAIN_LOCK_FOLDER / f"{domain_id}.lock", "w")  # noqa: SIM115 (returned, held by the caller)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.close()
            continue
        return domain_id, lock
    raise RuntimeError(
        f"every ROS domain id {DOMAIN_IDS.start}..{DOMAIN_IDS.stop - 1} is held by another run"
    )


def known(value: float | None) -> float:
    """``value``, asserted to be known (not ``None``): for the optional metrics of a report."""
    assert value is not None
    return value


def installed_command(script: str, module: str, *ros_args: str) -> list[str]:
    """The console script ``script`` installed beside this Python (or in colcon's
    ``lib/a1_leg_fk/``, as ``ros2 run`` would start it), else ``python -m module``, as
    :func:`a1_leg_fk.cli.common.child_command` finds it for ``a1-leg-fk demo``; followed by
    ``--ros-args ros_args...`` when any are given."""
    from a1_leg_fk.cli.common import ROS_ARGS_FLAG, child_command

    return child_command(script, module) + ([ROS_ARGS_FLAG, *ros_args] if ros_args else [])


node_command = partial(installed_command, "foot_fk_node", "a1_leg_fk.ros.foot_fk_node")
"""``node_command(*ros_args)``: the installed foot_fk_node (its script enters
``a1_leg_fk.ros.executables``), else ``python -m a1_leg_fk.ros.foot_fk_node``."""

ik_node_command = partial(installed_command, "foot_ik_node", "a1_leg_fk.ros.foot_ik_node")
"""``ik_node_command(*ros_args)``: the installed foot_ik_node, else ``python -m``."""

demo_command = partial(installed_command, "joint_state_demo", "a1_leg_fk.ros.joint_state_demo")
"""``demo_command(*ros_args)``: the installed joint_state_demo, else ``python -m``."""

odometry_node_command = partial(
    installed_command, "leg_odometry_node", "a1_leg_fk.ros.leg_odometry_node"
)
"""``odometry_node_command(*ros_args)``: the installed leg_odometry_node, else ``python -m``."""

cli_command = partial(installed_command, "a1-leg-fk", "a1_leg_fk.cli")
"""``cli_command(*ros_args)``: the installed ``a1-leg-fk``, else ``python -m a1_leg_fk.cli``."""


def rss_mb(pid: int) -> float:
    """Resident set size [MB] of process ``pid``, from /proc/<pid>/status (VmRSS).

    Raises LookupError when the process has no VmRSS (a zombie), FileNotFoundError when it is gone.
    """
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise LookupError(f"no VmRSS for process {pid}")


def cpu_seconds(pid: int) -> float:
    """CPU time [s] process ``pid`` has used so far, user + system (/proc/<pid>/stat: utime and
    stime, fields 14 and 15, counted after the command name's closing parenthesis).

    Raises FileNotFoundError (an OSError) when the process is gone.
    """
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def free_port() -> int:
    """A TCP port nothing listens on at the moment, on 127.0.0.1."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def listening(port: int) -> bool:
    """Whether something accepts TCP connections on 127.0.0.1:``port``."""
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
    except OSError:
        return False
    return True


def wait_for(condition: Callable[[], bool], timeout_s: float, every_s: float = 0.1) -> bool:
    """Whether ``condition()`` became true within ``timeout_s`` [s], asked every ``every_s``."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(every_s)
    return True
