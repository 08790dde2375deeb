"""``a1-leg-fk echo --rerun`` over real DDS: foot_fk_node and leg_odometry_node answer a
PyBullet-made stream (joint states with the motor torques as efforts, IMU), ``echo --rerun
--connect`` streams what they publish to a ``rerun --serve-grpc --save`` server started here,
then Ctrl-C; the server's file, read back with Rerun's reader, has the recorded view's entities
with the recorded view's values (``a1-leg-fk view`` of a bag of the same stream) at the same
stamps, and the simulation's joint angles."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bag_factory import joint_state
from nav_msgs.msg import Odometry
from node_harness import Diagnostics, stamp_ns, to_ros
from odometry_bags import IMU_TOPIC, imu_message, joint_state_msg, stamps_of, write_sim_bag
from pybullet_sim import simulate, walking_targets
from rclpy.qos import QoSProfile
from rrd_reader import read_rrd, series
from sensor_msgs.msg import Imu, JointState
from shared import LEGS, cli_command, node_command, odometry_node_command

from a1_leg_fk import cli
from a1_leg_fk.cli.rerun_sdk import viewer_executable

pytest.importorskip("rerun")

SIM_S = 2.0
RATE_HZ = 500.0
WAIT_S = 30.0
WARM_UP_ROW_S = 0.05
"""[s] The stream's pace until echo receives every topic (20 rows a second, not 500)."""
NODE_TOPICS = (
    *(f"foot_positions/{leg}" for leg in LEGS),
    *(f"foot_forces/{leg}" for leg in LEGS),
    "foot_contacts",
    "leg_odometry",
)
PING_IMU = Imu()
"""An Imu both nodes read and drop: no orientation, no acceleration, a gyro that is not finite
(leg_odometry_node rejects it; foot_fk_node keeps it as its latest IMU until the next)."""
PING_IMU.orientation_covariance[0] = PING_IMU.linear_acceleration_covariance[0] = -1.0
PING_IMU.angular_velocity.x = float("nan")
FLOAT32_M = 1e-6
"""[m] positions and transforms are float32 in Rerun (see test_view.py)."""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def listening(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
    except OSError:
        return False
    return True


def wait_for(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True


def recorded_view(run, folder: Path) -> dict:
    """``a1-leg-fk view`` of a bag of the same stream (the reference), ``--causal``: the nodes'
    live answers, not smoothed over the recording."""
    bag = write_sim_bag(folder / "walk", run, truth=False, efforts=True)
    rrd = folder / "recorded.rrd"
    code = cli.main(
        [
            "view",
            str(bag),
            "--imu",
            IMU_TOPIC,
            "--rrd",
            str(rrd),
            "--no-open",
            "--quiet",
            "--causal",
        ]
    )
    assert code == 0
    return read_rrd(rrd)


@pytest.mark.slow
@pytest.mark.accept
def test_live_stream_gives_the_recorded_views_entities(ros, processes, tmp_path) -> None:
    run = simulate(walking_targets(start_s=0.3), SIM_S)
    recorded = recorded_view(run, tmp_path)
    port, saved = free_port(), tmp_path / "live.rrd"
    server = processes.start(  # the binary itself, which writes what it receives at once and
        # ends on SIGINT (python -m rerun ignores SIGINT when started with it ignored)
        [rerun_binary(), "--serve-grpc", "--port", str(port), "--save", str(saved)]
    )
    assert wait_for(lambda: listening(port), WAIT_S), processes.output(server)
    nodes = [processes.start(node_command()), processes.start(odometry_node_command())]
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    echo = processes.start([*cli_command(), "echo", "--rerun", "--connect", url])
    diagnostics = [Diagnostics(ros, "foot kinematics"), Diagnostics(ros, "leg odometry")]
    received: list[Odometry] = []  # the nodes' answers
    contacts: list[JointState] = []
    answers = QoSProfile(depth=5000)
    ros.node.create_subscription(Odometry, "leg_odometry", received.append, answers)
    ros.node.create_subscription(JointState, "foot_contacts", contacts.append, answers)
    imu_pub = ros.node.create_publisher(Imu, "imu", QoSProfile(depth=1000))
    joint_pub = ros.node.create_publisher(JointState, "joint_states", QoSProfile(depth=1000))
    ready = ros.spin_until(
        lambda: joint_pub.get_subscription_count() >= 3 and imu_pub.get_subscription_count() >= 2,
        WAIT_S,  # the two nodes and echo
    )
    assert ready, "\n".join(processes.output(p) for p in [*nodes, echo])

    def publish(row: int) -> None:
        imu_pub.publish(to_ros(imu_message(run, row), Imu))
        ros.executor.spin_once(timeout_sec=0.0002)
        joint_pub.publish(to_ros(joint_state(joint_state_msg(run, row, efforts=True)), JointState))

    row_of = {int(stamp): row for row, stamp in enumerate(stamps_of(run))}

    def answered() -> int:
        """The last row both nodes have answered (-1: none yet)."""
        return min(row_of[stamp_ns(m[-1])] if m else -1 for m in (received, contacts))

    # Our publishers count the nodes' subscriptions before those have found our publishers (under
    # load, row 0 was lost: an estimate that starts at row 1 is not the bag's). Messages the
    # nodes read and drop go first until both count one of each in /diagnostics.
    deadline = time.monotonic() + WAIT_S
    while not all(has_received(status.latest) for status in diagnostics):
        assert time.monotonic() < deadline, [status.latest for status in diagnostics]
        imu_pub.publish(PING_IMU)
        joint_pub.publish(JointState())
        ros.spin_for(WARM_UP_ROW_S)
    pings = [taken(status.fresh()) for status in diagnostics]  # the next second's: all arrived
    # Nor have the nodes' publishers found echo's subscriptions yet (over a second after ours
    # did): the stream's first rows go slowly until echo says it receives every topic; the nodes
    # answer rows, not time, so nothing else changes.
    row, samples = 0, len(run.stamps_s)
    deadline = time.monotonic() + WAIT_S
    while not (received and echo_receives_every_topic(processes.output(echo))):
        assert time.monotonic() < deadline and row < samples // 4, processes.output(echo)
        publish(row)
        ros.spin_for(WARM_UP_ROW_S)
        row += 1
    first_fast, start = row, time.monotonic()
    for row in range(first_fast, samples):
        publish(row)
        delay = start + (row - first_fast + 1) / RATE_HZ - time.monotonic()
        if delay > 0:
            ros.spin_for(delay)
        # the nodes' queues (best effort, 100 deep) never hold 100 messages: none is dropped
        ros.spin_until(lambda: answered() >= row - 40, 10.0)  # noqa: B023 (used at once)
    assert ros.spin_until(lambda: answered() == samples - 1, WAIT_S)
    for status, before in zip(diagnostics, pings):  # every row taken: the bag's are the nodes'
        after = taken(status.fresh())
        assert after == [n + samples for n in before], (status.name_suffix, before, after)
    assert processes.interrupt(echo, timeout_s=20.0) == 0, processes.output(echo)  # it drains
    output = processes.output(echo)
    assert "Traceback" not in output and "streamed:" in output, output
    code = processes.interrupt(server, timeout_s=20.0)
    assert code in (0, 130, -signal.SIGINT), processes.output(server)
    live = read_rrd(saved)
    print(f"{first_fast} rows to start; {output.strip().splitlines()[-1]}")
    print(coverage(live, recorded))
    check_against_the_recorded_view(run, live, recorded)


def taken(values: dict[str, str]) -> list[int]:
    """The Imu and JointState messages a node's /diagnostics count received."""
    return [int(values.get(f"received_{topic}", 0)) for topic in ("imu", "joint_states")]


def has_received(values: dict[str, str]) -> bool:
    """Whether a node's /diagnostics count an Imu and a JointState received."""
    return min(taken(values)) > 0


def rerun_binary() -> str:
    binary = viewer_executable()
    assert binary is not None, "rerun-sdk without its rerun binary"
    return binary


def echo_receives_every_topic(output: str) -> bool:
    """Whether echo has said ``receiving:`` for every topic of the nodes and the joint states."""
    heard = {line.split()[1] for line in output.splitlines() if line.startswith("receiving:")}
    return heard >= {*NODE_TOPICS, "joint_states"}


def coverage(live, recorded) -> str:
    """Per entity of the recorded view (temporal), how many of its stamps the live file has."""
    counts = {}
    for key in sorted(recorded):
        if key.startswith("/") and "stamp" in recorded[key] and key in live:
            counts[key] = len(common_rows(live, recorded, key[1:])[0])
    return "stamps in both: " + ", ".join(f"{k} {v}" for k, v in counts.items())


def common_rows(live, recorded, entity: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(stamps in both, the live rows' indexes, the recorded rows' indexes) of ``entity``."""
    live_stamps = np.array(live["/" + entity]["stamp"])
    recorded_stamps = np.array(recorded["/" + entity]["stamp"])
    stamps, here, there = np.intersect1d(live_stamps, recorded_stamps, return_indices=True)
    return stamps, here, there


def check_against_the_recorded_view(run, live, recorded) -> None:
    samples = len(run.stamps_s)
    expected = {
        key
        for key in recorded
        if not any(part in key for part in ("/plots/filter/", "/summary", "/odom/truth"))
    }
    missing = sorted(expected - live.keys())
    assert not missing, missing
    for leg in LEGS:
        for entity in (f"plots/foot_height/{leg}", f"plots/p_stance/{leg}"):
            stamps, here, there = common_rows(live, recorded, entity)
            assert len(stamps) >= samples // 2, (entity, len(stamps), samples)
            _, live_values = series(live, entity)
            _, recorded_values = series(recorded, entity)
            assert np.allclose(live_values[here], recorded_values[there], rtol=0, atol=1e-9)
        stamps, here, there = common_rows(live, recorded, f"plots/normal_force/{leg}")
        assert len(stamps) >= samples // 2
        _, live_values = series(live, f"plots/normal_force/{leg}")
        _, recorded_values = series(recorded, f"plots/normal_force/{leg}")
        assert np.allclose(live_values[here], recorded_values[there], rtol=0, atol=1e-6)
        for entity, column in (
            (f"feet/{leg}", "Points3D:positions"),
            (f"feet/{leg}/force", "Arrows3D:vectors"),
        ):
            stamps, here, there = common_rows(live, recorded, entity)
            assert len(stamps) >= samples // 2, (entity, len(stamps))
            a = np.array([live["/" + entity][column][i][0] for i in here])
            b = np.array([recorded["/" + entity][column][i][0] for i in there])
            assert np.abs(a - b).max() < FLOAT32_M * max(1.0, np.abs(b).max())
    for slot, joint in enumerate(run.joint_names):  # the simulation's angles, by construction
        stamps, angles = series(live, f"plots/joint_angle/{joint}")
        rows = np.searchsorted(stamps_of(run), stamps)
        assert len(stamps) >= samples // 2
        assert np.allclose(angles, run.angles[rows, slot], rtol=0, atol=1e-12)
    for axis in "xyz":
        entity = f"plots/velocity/{axis}/estimate"
        stamps, here, there = common_rows(live, recorded, entity)
        assert len(stamps) >= samples // 2
        _, live_values = series(live, entity)
        _, recorded_values = series(recorded, entity)
        assert np.allclose(live_values[here], recorded_values[there], rtol=0, atol=1e-9)
    stamps, here, there = common_rows(live, recorded, "robot/base_pose")
    assert len(stamps) >= samples // 2
    a = np.array([live["/robot/base_pose"]["Transform3D:translation"][i][0] for i in here])
    b = np.array([recorded["/robot/base_pose"]["Transform3D:translation"][i][0] for i in there])
    assert np.abs(a - b).max() < FLOAT32_M


def test_bad_inputs_one_line_exit_2(tmp_path: Path, capsys) -> None:
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'/>")
    url = "rerun+http://127.0.0.1:1/proxy"
    for argv, culprit in (
        (["--urdf", str(broken), "--connect", url], "broken.urdf"),
        (["--connect", "nonsense"], "nonsense"),
    ):
        assert cli.main(["echo", "--rerun", *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and err.startswith("a1-leg-fk echo:") and culprit in err, err


def test_without_rerun() -> None:
    hide = (
        "import sys; sys.modules['rerun'] = None; from a1_leg_fk import cli; "
        "sys.exit(cli.main(['echo', '--rerun', '--duration', '1']))"
    )
    done = subprocess.run(
        [sys.executable, "-c", hide], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "pip install" in done.stderr
