"""The nodes' ``input: unitree_lowstate`` for real: Unitree's ``unitree_go`` message package is
built with colcon from the published field lists (ament_cmake and the rosidl generators as
wheels, requirements-msgs.txt), as a user's workspace builds it; a process with that install
publishes LowState messages of the A1 standing, and ``foot_fk_node`` answers with the FR foot the
JointState path gives, ``leg_odometry_node`` with odometry; both survive damaged LowStates of
both layouts (issue 38, about 15 s each beyond the build). Without the package: one line
naming it, exit 2.
"""

from __future__ import annotations

import math
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import BIN
from shared import ROOT, STANDING
from unitree_workspace import build, load_here

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE

WAIT_S = 30.0


@pytest.fixture(scope="module")
def unitree_go(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Builds unitree_go with colcon; the environment a process needs to use it (as sourcing
    the install's setup.bash gives)."""
    return build(tmp_path_factory.mktemp("unitree_ws"), ("unitree_go",))["unitree_go"]


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


@pytest.mark.slow
@pytest.mark.parametrize("executable", ["foot_fk_node", "leg_odometry_node"])
def test_survives_damaged_lowstate_of_both_layouts(
    unitree_go: dict[str, str], processes, ros, executable: str
) -> None:
    """Issue 38 on ``lowstate``: damaged unitree_go LowStates and unitree_legged_msgs ones (CDR,
    the other layout) published raw from this process (the built package loaded into it), with
    the checks of every other input topic (test/node_fuzz_run.py); ``foot_fk_node``'s answers
    matched by the FR foot of the pose each drive carries, ``leg_odometry_node``'s counted (one
    odometry message owed per good LowState)."""
    from fuzzed_nodes import LOWSTATE_NODES
    from node_fuzz_run import CI_COUNTS, HEADER, run_node

    load_here(unitree_go)
    from unitree_go.msg import LowState  # type: ignore[import-not-found]  # built above

    node = LOWSTATE_NODES[executable](GO_LOW_STATE, LowState, unitree_go)
    run = run_node(processes, ros, node, CI_COUNTS, seed=38)
    print("\n" + "\n".join([HEADER, *run.lines()]))
    assert not run.failures, (run.failures, run.output[-3000:])
    (row,) = run.rows
    assert row.asked and row.answered == row.asked, row
    assert row.unreadable >= row.sent // 4, row
