"""a1-leg-fk echo | verify | demo against a real foot_fk_node over real DDS; --help; namespaces."""

from __future__ import annotations

import math
import os
import re
import select
import signal
import subprocess
import time
from pathlib import Path

import pytest
from shared import LEGS, cli_command, node_command
from shared import STAND_LEG as STAND

from a1_leg_fk.cli import build_parser, main
from a1_leg_fk.cli.common import Ros, our_arguments, prefixed, ros_section
from a1_leg_fk.cli.echo import FootTable

# An asymmetric pose, every joint inside its limits, roll included.
TWISTED = (0.1, 0.5, -1.2, -0.2, 1.0, -2.0, 0.3, 0.2, -1.0, -0.1, 1.2, -1.8)
ROW = re.compile(r"^(FR|FL|RR|RL)\s+(-?\d+\.\d)\s+(-?\d+\.\d)\s+(-?\d+\.\d)\s", re.MULTILINE)


CLI = cli_command()
NODE = node_command()


def stand_by_hand_mm(leg: str) -> tuple[float, float, float]:
    """The foot of the A1 in STAND (hip roll 0), from the A1's dimensions, not from the package.

    pybullet_data's a1.urdf: hip-roll joints at (+-0.183, +-0.047, 0) in the trunk, the hip-pitch
    joint 0.08505 m further out sideways, thigh and calf 0.2 m each, both pitching about y:
    x = hip_x - 0.2 sin(pitch) - 0.2 sin(pitch + knee), z = -0.2 cos(pitch) - 0.2 cos(pitch +
    knee).
    """
    _, pitch, knee = STAND
    hip_x = 0.183 if leg[0] == "F" else -0.183
    side = -1.0 if leg[1] == "R" else 1.0
    x = hip_x - 0.2 * math.sin(pitch) - 0.2 * math.sin(pitch + knee)
    y = side * (0.047 + 0.08505)
    z = -0.2 * math.cos(pitch) - 0.2 * math.cos(pitch + knee)
    return 1000 * x, 1000 * y, 1000 * z


def pybullet_feet_mm(angles: tuple[float, ...]) -> dict[str, tuple[float, float, float]]:
    """Feet [mm] of pybullet_data's a1.urdf, computed by PyBullet itself (fixed base at the
    origin)."""
    pytest.importorskip("pybullet")
    from pybullet_reference import A1_URDF, PyBulletRobot

    names = [f"{leg}_{part}_joint" for leg in LEGS for part in ("hip", "upper", "lower")]
    with PyBulletRobot(A1_URDF) as robot:
        feet = robot.feet(names, [f"{leg}_toe" for leg in LEGS], angles)
    return {leg: tuple(1000 * feet[slot]) for slot, leg in enumerate(LEGS)}


def table_values(output: str) -> dict[str, tuple[float, float, float]]:
    """The last table's x, y, z [mm] per leg."""
    values = {}
    for leg, x, y, z in ROW.findall(output):
        values[leg] = (float(x), float(y), float(z))
    return values


def assert_table(output: str, expected: dict[str, tuple[float, float, float]]) -> None:
    values = table_values(output)
    assert set(values) == set(LEGS), output
    for leg in LEGS:
        for got, want in zip(values[leg], expected[leg]):
            assert abs(got - want) <= 0.06, (
                f"{leg}: table {values[leg]} mm, expected {expected[leg]} mm\n{output}"
            )


class JointStatePublisher:
    """Publishes one configurable joint state at 20 Hz from the test's own node (while it
    spins)."""

    def __init__(self, ros, topic: str = "joint_states") -> None:
        from sensor_msgs.msg import JointState

        self.angles: tuple[float, ...] = STAND * 4
        self._ros = ros
        self._message = JointState()
        self._message.name = [
            f"{leg}_{part}_joint" for leg in LEGS for part in ("hip", "upper", "lower")
        ]
        self._publisher = ros.node.create_publisher(JointState, topic, 10)
        ros.node.create_timer(0.05, self._publish)

    def _publish(self) -> None:
        self._message.header.stamp = self._ros.node.get_clock().now().to_msg()
        self._message.position = list(self.angles)
        self._publisher.publish(self._message)


def run_cli(processes, ros, arguments: list[str], timeout_s: float = 25.0) -> tuple[int, str]:
    """Run a1-leg-fk to completion while the test's node spins (publishing); (exit code,
    output)."""
    process = processes.start(CLI + arguments)
    if not ros.spin_until(lambda: process.poll() is not None, timeout_s):
        process.kill()
        pytest.fail(
            f"a1-leg-fk {' '.join(arguments)} still running after {timeout_s} "
            f"s:\n{processes.output(process)}"
        )
    output = processes.output(process)
    assert "Traceback" not in output, output
    return process.returncode, output


def start_node(processes, ros, namespace: str = "/"):
    """foot_fk_node in ``namespace``, with its verify_fk service discovered by the test's node."""
    from std_srvs.srv import Trigger

    arguments = ["--ros-args", "-r", f"__ns:={namespace}"] if namespace != "/" else []
    process = processes.start(NODE + arguments)
    client = ros.node.create_client(Trigger, prefixed(namespace, "verify_fk"))
    ready = ros.spin_until(client.service_is_ready)
    ros.node.destroy_client(client)
    assert ready, f"foot_fk_node did not come up:\n{processes.output(process)}"
    return process


# --- no ROS needed -----------------------------------------------------------------------------


def test_help_lists_the_subcommands() -> None:
    result = subprocess.run(
        [*CLI, "--help"], check=False, capture_output=True, text=True, timeout=30
    )
    assert result.returncode == 0
    for subcommand in ("echo", "verify", "plot", "demo"):
        assert re.search(rf"^\s+{subcommand}\s+\S", result.stdout, re.MULTILINE), result.stdout
    assert "--ros-args" in result.stdout
    for subcommand, option in (
        ("echo", "--once"),
        ("verify", "--timeout"),
        ("plot", "--out"),
        ("demo", "--duration"),
    ):
        sub = subprocess.run(
            [*CLI, subcommand, "--help"], check=False, capture_output=True, text=True, timeout=30
        )
        assert sub.returncode == 0 and option in sub.stdout and len(sub.stdout.splitlines()) > 5
    assert (
        subprocess.run([*CLI, "fly"], check=False, capture_output=True, timeout=30).returncode == 2
    )


def test_ros_arguments_are_split_off() -> None:
    assert our_arguments(["echo", "--once"]) == ["echo", "--once"]
    argv = [
        "verify",
        "--ros-args",
        "-r",
        "__ns:=/r1",
        "-p",
        "use_sim_time:=false",
        "--",
        "--timeout",
        "1",
    ]
    assert our_arguments(argv) == ["verify", "--timeout", "1"]
    options = build_parser().parse_args(our_arguments(argv))
    assert options.command == "verify" and options.timeout == 1.0 and options.namespace == ""
    # Without a closing --, everything after --ros-args is ROS's.
    assert our_arguments(["echo", "--once", "--ros-args", "-r", "__ns:=/r1"]) == ["echo", "--once"]
    # The demo hands its nodes the command line from the first --ros-args on.
    assert ros_section(argv) == argv[1:] and ros_section(["echo"]) == []
    assert prefixed("", "verify_fk") == "verify_fk"
    assert prefixed("/robot1/", "verify_fk") == "/robot1/verify_fk"
    assert prefixed("robot1", "foot_positions/FR") == "robot1/foot_positions/FR"
    assert prefixed("/", "verify_fk") == "/verify_fk"


def test_ros_arguments_reach_rclpy_whole() -> None:
    """rclpy.init gets the whole command line: it applies the remaps and ignores our options."""
    ros = Ros(
        "verify",
        [
            "verify",
            "--ros-args",
            "-r",
            "__ns:=/r1",
            "-r",
            "verify_fk:=check",
            "--",
            "--timeout",
            "1",
        ],
    )
    try:
        assert ros.node.get_namespace() == "/r1"
        assert ros.node.resolve_service_name("verify_fk") == "/r1/check"
    finally:
        ros.close()


def test_bad_ros_arguments_are_one_line_and_exit_2(capsys) -> None:
    assert main(["ik", "FR", "0.2", "-0.13", "-0.3", "--ros-args", "-r"]) == 2
    captured = capsys.readouterr()
    assert not captured.out and len(captured.err.strip().splitlines()) == 1
    assert captured.err.startswith("a1-leg-fk: bad --ros-args: ") and "-r" in captured.err


def test_rate_counts_what_the_publisher_sent() -> None:
    table = FootTable([f"foot_positions/{leg}" for leg in LEGS])

    class Point:
        class header:  # noqa: N801 (named as the message's field)
            frame_id = "trunk"

        class point:  # noqa: N801 (named as the message's field)
            x, y, z = 0.1, 0.2, 0.3

    callback = table.callback("FR")
    for sequence in range(1, 101, 2):  # every other message lost: the rate still counts them
        callback(Point, {"publication_sequence_number": sequence})
        time.sleep(0.002)
    now = time.monotonic()
    rate = table.rate_hz("FR", now)
    first_arrival, last_arrival = table._arrivals["FR"][0][0], table._arrivals["FR"][-1][0]
    arrivals_hz = 49 / (last_arrival - first_arrival)  # 50 messages arrived...
    assert rate == pytest.approx(2 * arrivals_hz, rel=1e-6)  # ...of 99 sent in the same time
    assert table.rate_hz("FL", now) is None and not table.complete
    rows = table.lines("feet")
    assert rows[0] == "feet, frame trunk" and rows[2].split()[:4] == [
        "FR",
        "100.0",
        "200.0",
        "300.0",
    ]
    assert "no message yet" in rows[3]


@pytest.mark.slow
def test_verify_exits_2_without_a_node(processes) -> None:
    process = processes.start([*CLI, "verify", "--timeout", "1"])
    assert process.wait(20) == 2
    output = processes.output(process)
    assert "no service /verify_fk within 1 s" in output and "Traceback" not in output


@pytest.mark.slow
def test_echo_refreshes_in_place_on_a_terminal() -> None:
    controller, terminal = os.openpty()
    process = subprocess.Popen(
        [*CLI, "echo", "--duration", "1.0", "--interval", "0.3"],
        stdout=terminal,
        stderr=terminal,
        start_new_session=True,
    )
    os.close(terminal)
    output = b""
    try:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            ready, _, _ = select.select([controller], [], [], 0.2)
            if ready:
                try:
                    chunk = os.read(controller, 65536)
                except OSError:  # the terminal closed: the process is gone
                    break
                if not chunk:
                    break
                output += chunk
            elif process.poll() is not None:
                break
        assert process.wait(10) == 0
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait(5)
        os.close(controller)
    text = output.decode(errors="replace")
    assert text.count("rate [Hz]") >= 3, text
    assert (
        "\x1b[6F" in text and "\x1b[K" in text
    )  # cursor up over the 6-line table, clear to end of line
    assert "no message yet" in text and "Traceback" not in text


# --- against a running node --------------------------------------------------------------------


@pytest.mark.slow
def test_verify_and_echo_against_the_node(processes, ros) -> None:
    start_node(processes, ros)
    # Node up, no joint state yet: verify fails (1) and says why.
    code, output = run_cli(processes, ros, ["verify", "--timeout", "10"])
    assert code == 1, output
    assert "no complete joint state yet" in output

    publisher = JointStatePublisher(ros)
    code, output = run_cli(processes, ros, ["echo", "--once", "--timeout", "15"])
    assert code == 0, output
    assert_table(output, {leg: stand_by_hand_mm(leg) for leg in LEGS})
    assert re.search(r"^FR\s+168\.4\s+-132\.[01]\s+-292\.3\s", output, re.MULTILINE), (
        output
    )  # as in the brief
    assert "frame trunk" in output and output.count("rate [Hz]") == 1

    code, output = run_cli(processes, ros, ["verify", "--timeout", "10"])
    assert code == 0, output
    errors = dict(re.findall(r"\b(max_error_m|FR|FL|RR|RL)=([0-9.e+-]+)", output))
    assert set(errors) == {"max_error_m", *LEGS} and float(errors["max_error_m"]) < 1e-6, output

    # Another pose, expected values from PyBullet itself; then the live view keeps refreshing.
    publisher.angles = TWISTED
    ros.spin_for(0.5)
    code, output = run_cli(processes, ros, ["echo", "--once"])
    assert code == 0, output
    assert_table(output, pybullet_feet_mm(TWISTED))

    process = processes.start([*CLI, "echo", "--interval", "0.3"])

    def fr_rates() -> list[float]:
        return [
            float(r)
            for r in re.findall(
                r"^FR\s+\S+\s+\S+\s+\S+\s+(\d+\.\d)$", processes.output(process), re.MULTILINE
            )
        ]

    # A table every 0.3 s; the rate (over the last 2 s) settles once messages flow for a while.
    assert ros.spin_until(lambda: len(fr_rates()) >= 4), processes.output(process)
    assert 12.0 <= fr_rates()[-1] <= 28.0, processes.output(
        process
    )  # our 20 Hz stream (its timer lags under load)
    assert processes.interrupt(process) == 0  # Ctrl-C is the normal way to stop echo
    assert "Traceback" not in processes.output(process)


@pytest.mark.slow
def test_namespace_option_and_ros_namespace_remap(processes, ros) -> None:
    start_node(processes, ros, "/robot1")
    JointStatePublisher(ros, "/robot1/joint_states")
    expected = {leg: stand_by_hand_mm(leg) for leg in LEGS}
    for arguments in (["--namespace", "/robot1"], ["--ros-args", "-r", "__ns:=/robot1"]):
        code, output = run_cli(processes, ros, ["echo", "--once", *arguments])
        assert code == 0, output
        assert_table(output, expected)
        assert "/robot1/foot_positions/" in output
        code, output = run_cli(processes, ros, ["verify", *arguments])
        assert code == 0, output
        assert "/robot1/verify_fk" in output and "max_error_m=" in output
    # Outside the namespace there is nobody.
    code, output = run_cli(processes, ros, ["verify", "--timeout", "1"])
    assert code == 2 and "/verify_fk" in output
    code, output = run_cli(processes, ros, ["echo", "--once", "--timeout", "1"])
    assert code == 2 and "no message" in output


# --- the demo command ----------------------------------------------------------------------------


@pytest.mark.slow
def test_demo_runs_the_pipeline_and_verifies(processes, tmp_path: Path) -> None:
    process = processes.start(
        [*CLI, "demo", "--duration", "2", "--interval", "0.7", "--log-dir", str(tmp_path / "logs")]
    )
    assert process.wait(60) == 0, processes.output(process)
    output = processes.output(process)
    assert f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} (from the environment)" in output
    for heading in ("[1/4]", "[2/4]", "[3/4]", "[4/4]"):
        assert heading in output
    assert re.search(r"^FR\s+-?\d+\.\d", output, re.MULTILINE), output
    assert "OK, the node's FK agrees with PyBullet" in output and "max_error_m=" in output
    assert (
        "foot_fk_node stopped (exit code 0)" in output
        and "joint_state_demo stopped (exit code 0)" in output
    )
    assert "demo finished: OK" in output and "Traceback" not in output
    assert (
        tmp_path / "logs" / "foot_fk_node.log"
    ).stat().st_size > 0  # the children's output went there
    for pid in map(int, re.findall(r"pid (\d+):", output)):
        assert not _running(pid)


@pytest.mark.slow
def test_demo_ctrl_c_stops_everything(processes, tmp_path: Path) -> None:
    process = processes.start(
        [
            *CLI,
            "demo",
            "--duration",
            "60",
            "--interval",
            "0.3",
            "--log-dir",
            str(tmp_path / "logs"),
        ]
    )
    deadline = time.monotonic() + 30
    while not re.search(r"^FR\s+-?\d+\.\d", processes.output(process), re.MULTILINE):
        assert time.monotonic() < deadline and process.poll() is None, processes.output(process)
        time.sleep(0.1)
    pids = [int(pid) for pid in re.findall(r"pid (\d+):", processes.output(process))]
    assert len(pids) == 2 and all(_running(pid) for pid in pids)
    assert processes.interrupt(process, timeout_s=15) == 130
    output = processes.output(process)
    assert "SIGINT: stopping" in output and "Traceback" not in output
    assert (
        "foot_fk_node stopped (exit code 0)" in output
        and "joint_state_demo stopped (exit code 0)" in output
    )
    for pid in pids:
        assert not _running(pid), f"child {pid} outlived the demo"


def _running(pid: int) -> bool:
    psutil = pytest.importorskip("psutil")
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def test_a_reader_that_closes_the_pipe_gets_no_traceback() -> None:
    """``a1-leg-fk ik ... | head -0``: the reader is gone before the first line; the command ends
    as a process killed by SIGPIPE would (141), with nothing on stderr."""
    command = [*cli_command(), "ik", "FL", "0.183", "0.132", "-0.38"]
    reader_gone = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert reader_gone.stdout is not None
    reader_gone.stdout.close()
    _, stderr = reader_gone.communicate(timeout=60)
    assert reader_gone.returncode == 128 + signal.SIGPIPE
    assert stderr == ""
