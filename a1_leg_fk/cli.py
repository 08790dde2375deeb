"""``a1-leg-fk``: echo | verify | plot | demo, for installs without the ROS 2 command line tools.

Everything after ``--ros-args`` (up to a lone ``--``) goes to ``rclpy.init`` unchanged, so
``--ros-args -r __ns:=/robot1`` moves this tool's own node, and with it every relative name it
uses, into ``/robot1``. ``--namespace NS`` instead prefixes the names themselves
(``NS/foot_positions/FR``, ``NS/verify_fk``); an absolute ``NS`` (``/robot1``) is then not
affected by ``__ns``.

Exit codes: 0 success; 1 failure (verify said no, a demo child died, a plot could not be made);
2 nobody answered in time (or bad usage); 130 interrupted (Ctrl-C or SIGTERM), except ``echo``,
for which Ctrl-C is the normal way to stop (0).
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import deque
from pathlib import Path
from typing import Callable, Sequence, TextIO

from a1_leg_fk import cli_bag, cli_gait, cli_ik
from a1_leg_fk.legs import LEG_NAMES

PROG = "a1-leg-fk"
EXIT_OK, EXIT_FAILED, EXIT_NO_ANSWER, EXIT_INTERRUPTED = 0, 1, 2, 130
RATE_WINDOW_S = 2.0
TTY_INTERVAL_S = 0.2
PIPE_INTERVAL_S = 1.1
"""Default refresh periods [s]: on a terminal, and otherwise. Neither divides the demo trot's 0.5 s
cycle, so successive tables show different phases instead of seemingly frozen feet."""
DEMO_START_TIMEOUT_S = 20.0
CHILD_STOP_TIMEOUT_S = 5.0


# --- command line ------------------------------------------------------------------------------


def split_ros_args(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """``(our arguments, ROS arguments)``: ROS arguments run from ``--ros-args`` to a lone ``--``.

    The ROS part keeps its ``--ros-args`` (and its closing ``--``), as ``rclpy.init`` expects.
    """
    ours: list[str] = []
    ros: list[str] = []
    inside = False
    for argument in argv:
        if argument == "--ros-args":
            inside = True
            ros.append(argument)
        elif inside and argument == "--":
            inside = False
            ros.append(argument)
        elif inside:
            ros.append(argument)
        else:
            ours.append(argument)
    return ours, ros


def build_parser() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--namespace",
        metavar="NS",
        default="",
        help="prefix the topic/service names with NS (e.g. /robot1 -> /robot1/foot_positions/FR); "
        "or move the tool's own node with --ros-args -r __ns:=/robot1",
    )
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Tools around foot_fk_node (the a1_leg_fk feet forward kinematics) for installs "
        "without the ROS 2 command line. ROS arguments go last: ... --ros-args -r __ns:=/robot1",
        epilog="exit codes: 0 ok, 1 failed, 2 no answer in time / bad usage, 130 interrupted",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    echo = commands.add_parser(
        "echo",
        parents=[common],
        help="live table of the four feet (foot_positions/<leg>): x/y/z in mm and each topic's rate",
        description="Subscribe to foot_positions/FR|FL|RR|RL and show x, y, z [mm] per foot and the rate "
        "of each topic [Hz], refreshed in place (a new table per refresh when the output is not a "
        "terminal). Ctrl-C stops (exit 0).",
    )
    echo.add_argument("--once", action="store_true", help="print the first complete table (all four feet) and exit")
    echo.add_argument("--duration", type=_positive, metavar="S", help="stop after S seconds (default: run until Ctrl-C)")
    echo.add_argument("--interval", type=_positive, metavar="S",
                      help=f"refresh period [s] (default {TTY_INTERVAL_S:g} on a terminal, else {PIPE_INTERVAL_S:g})")
    echo.add_argument("--timeout", type=_positive, default=10.0, metavar="S",
                      help="with --once: give up (exit 2) when no complete table arrives within S s (default 10)")
    echo.set_defaults(handler=run_echo)

    verify = commands.add_parser(
        "verify",
        parents=[common],
        help="call verify_fk: compare the node's feet with PyBullet's for the last joint state",
        description="Call the node's verify_fk service (std_srvs/Trigger) and print its answer. Exit 0 when "
        "the node's FK agrees with PyBullet's, 1 when it does not or the node has no joint state yet, "
        "2 when no service answers within --timeout.",
    )
    verify.add_argument("--timeout", type=_positive, default=5.0, metavar="S", help="seconds to wait for the service (default 5)")
    verify.set_defaults(handler=run_verify)

    plot = commands.add_parser(
        "plot",
        help="write PNGs: a leg's reach envelope, and the feet over the demo gait (needs matplotlib)",
        description="Write reach_<leg>.png (where the leg's foot can be, in its hip's sagittal plane, with "
        "the inner/outer reach circles) and demo_gait_feet.png (the four feet over two cycles of the "
        "demo trot, side and top views). No ROS needed.",
    )
    plot.add_argument("--out", default=".", metavar="DIR", help="output folder (default: current folder)")
    plot.add_argument("--leg", default="FR", choices=LEG_NAMES, help="leg of the reach plot (default FR)")
    plot.add_argument("--urdf", metavar="FILE", help="robot description (default: the embedded Unitree A1)")
    plot.set_defaults(handler=run_plot)

    demo = commands.add_parser(
        "demo",
        parents=[common],
        help="start foot_fk_node and joint_state_demo, show the feet live, verify, stop everything",
        description="The whole pipeline in one command: starts foot_fk_node and joint_state_demo (a simulated "
        "A1 that stands up, then trots in place), shows the live echo table for --duration seconds, calls "
        "verify_fk, then stops both. Uses ROS_DOMAIN_ID if set, else picks one for itself.",
    )
    demo.add_argument("--duration", type=_positive, default=10.0, metavar="S", help="seconds of live view (default 10)")
    demo.add_argument("--interval", type=_positive, metavar="S",
                      help=f"refresh period [s] (default {TTY_INTERVAL_S:g} on a terminal, else {PIPE_INTERVAL_S:g})")
    demo.add_argument("--log-dir", metavar="DIR", help="where the children's output goes (default: a new temp folder)")
    demo.set_defaults(handler=run_demo)
    cli_bag.add_parser(commands)
    cli_gait.add_parser(commands)
    cli_ik.add_parser(commands)
    return parser


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number: {text!r}")
    return value


def prefixed(namespace: str, name: str) -> str:
    """``name`` under ``namespace`` ('' leaves the relative name as it is)."""
    if not namespace:
        return name
    return namespace.rstrip("/") + "/" + name if namespace != "/" else "/" + name


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``a1-leg-fk``; returns the exit code."""
    arguments = list(sys.argv[1:] if argv is None else argv)
    ours, ros_args = split_ros_args(arguments)
    options = build_parser().parse_args(ours)
    try:
        return options.handler(options, ros_args)
    except KeyboardInterrupt:  # a Ctrl-C that arrived outside the commands' own handling
        return EXIT_OK if options.command == "echo" else EXIT_INTERRUPTED


# --- stopping on Ctrl-C / SIGTERM ---------------------------------------------------------------


class StopSignals:
    """Turns SIGINT and SIGTERM into a flag (``stop.is_set()``) instead of an exception.

    With rclpy's own signal handlers off, nothing is raised in the middle of a DDS call or of the
    cleanup; every loop here waits in short slices and checks the flag.
    """

    def __init__(self) -> None:
        self.stop = threading.Event()
        self.signal_name = ""
        self._previous: dict[int, object] = {}

    def __enter__(self) -> "StopSignals":
        for number in (signal.SIGINT, signal.SIGTERM):
            self._previous[number] = signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc_info: object) -> None:
        for number, handler in self._previous.items():
            signal.signal(number, handler)  # type: ignore[arg-type]

    def _handle(self, number: int, _frame: object) -> None:
        self.signal_name = signal.Signals(number).name
        self.stop.set()


class Ros:
    """This tool's own rclpy context, node and executor (rclpy's signal handlers off)."""

    def __init__(self, command: str, ros_args: Sequence[str]) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(args=[PROG, *ros_args], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        try:
            self.node = rclpy.create_node(f"a1_leg_fk_{command}_{os.getpid()}", context=self.context)
        except BaseException:
            rclpy.try_shutdown(context=self.context)
            raise
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_for(self, seconds: float, stop: threading.Event) -> None:
        deadline = time.monotonic() + seconds
        while not stop.is_set() and self.context.ok():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self.executor.spin_once(timeout_sec=min(remaining, 0.05))

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def _start_ros(command: str, ros_args: Sequence[str]) -> Ros | None:
    try:
        return Ros(command, ros_args)
    except Exception as error:  # noqa: BLE001 (rclpy raises its internal RCLError for bad --ros-args)
        print(f"{PROG} {command}: cannot start ROS: {error}", file=sys.stderr)
        return None


# --- echo --------------------------------------------------------------------------------------


class FootTable:
    """The latest position of each foot and each topic's message rate, rendered as text lines."""

    def __init__(self, topics: Sequence[str]) -> None:
        self.topics = list(topics)
        self.latest: dict[str, tuple[float, float, float, str] | None] = {leg: None for leg in LEG_NAMES}
        self.received = {leg: 0 for leg in LEG_NAMES}
        # (arrival time [s, monotonic], publication sequence number or None) within RATE_WINDOW_S
        self._arrivals: dict[str, deque[tuple[float, int | None]]] = {leg: deque() for leg in LEG_NAMES}

    def callback(self, leg: str) -> Callable[[object, dict], None]:
        def on_message(message, info: dict) -> None:  # noqa: ANN001 (geometry_msgs/PointStamped)
            point = message.point
            self.latest[leg] = (point.x, point.y, point.z, message.header.frame_id)
            self.received[leg] += 1
            arrivals = self._arrivals[leg]
            sequence = info.get("publication_sequence_number") if isinstance(info, dict) else None
            if arrivals and sequence is not None and arrivals[-1][1] is not None and sequence <= arrivals[-1][1]:
                arrivals.clear()  # a restarted or second publisher: start measuring again
            arrivals.append((time.monotonic(), sequence))

        return on_message

    @property
    def complete(self) -> bool:
        return all(value is not None for value in self.latest.values())

    def rate_hz(self, leg: str, now: float) -> float | None:
        """Messages per second the publisher sent over the last RATE_WINDOW_S (None: too few to tell).

        Counted from the publication sequence numbers where the middleware reports them, so that
        messages this tool could not keep up with still count; else from the arrivals.
        """
        arrivals = self._arrivals[leg]
        while arrivals and arrivals[0][0] < now - RATE_WINDOW_S:
            arrivals.popleft()
        if len(arrivals) < 2 or arrivals[-1][0] <= arrivals[0][0]:
            return None
        (first_time, first_seq), (last_time, last_seq) = arrivals[0], arrivals[-1]
        sent = last_seq - first_seq if first_seq is not None and last_seq is not None else len(arrivals) - 1
        return sent / (last_time - first_time)

    def lines(self, heading: str) -> list[str]:
        """The table: a heading, a column header, one row per leg."""
        now = time.monotonic()
        frames = sorted({value[3] for value in self.latest.values() if value is not None and value[3]})
        rows = [
            heading + (f", frame {'/'.join(frames)}" if frames else ""),
            f"{'leg':<4}{'x [mm]':>9}{'y [mm]':>9}{'z [mm]':>9}{'rate [Hz]':>11}",
        ]
        for leg in LEG_NAMES:
            value = self.latest[leg]
            rate = self.rate_hz(leg, now)
            rate_text = f"{rate:11.1f}" if rate is not None else f"{'-':>11}"
            if value is None:
                rows.append(f"{leg:<4}{'-':>9}{'-':>9}{'-':>9}{rate_text}   no message yet")
            else:
                x, y, z, _ = value
                rows.append(f"{leg:<4}{1000 * x:9.1f}{1000 * y:9.1f}{1000 * z:9.1f}{rate_text}")
        return rows


class TableWriter:
    """Prints tables: over the previous one (ANSI cursor-up) on a terminal, one after another otherwise."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.in_place = stream.isatty() and os.environ.get("TERM") != "dumb"
        self._height = 0

    def write(self, lines: list[str]) -> None:
        if self.in_place:
            up = f"\x1b[{self._height}F" if self._height else ""
            self.stream.write(up + "".join(f"{line}\x1b[K\n" for line in lines))
        else:
            self.stream.write("\n".join(lines) + "\n\n")
        self.stream.flush()
        self._height = len(lines)


def _subscribe_feet(ros: Ros, namespace: str) -> FootTable:
    from geometry_msgs.msg import PointStamped
    from rclpy.qos import qos_profile_sensor_data

    names = [prefixed(namespace, f"foot_positions/{leg}") for leg in LEG_NAMES]
    table = FootTable(names)
    # Best effort and volatile: matches reliable and best-effort, volatile and transient-local publishers.
    subscriptions = [
        ros.node.create_subscription(PointStamped, name, table.callback(leg), qos_profile_sensor_data)
        for leg, name in zip(LEG_NAMES, names)
    ]
    table.topics = [subscription.topic_name for subscription in subscriptions]
    return table


def _topics_heading(table: FootTable) -> str:
    common = os.path.commonprefix(table.topics)
    return f"feet from {common}<{'|'.join(LEG_NAMES)}>" if common.endswith("/") else "feet from " + ", ".join(table.topics)


def echo_loop(
    ros: Ros,
    table: FootTable,
    stop: threading.Event,
    heading: str,
    interval_s: float | None,
    duration_s: float | None = None,
    once: bool = False,
    data_timeout_s: float | None = None,
    duration_after_data: bool = False,
    healthy: Callable[[], bool] = lambda: True,
) -> str:
    """Spin and print tables; returns why it ended.

    'once' (``once`` and all four feet arrived: that table printed), 'duration' (``duration_s``
    passed, counted from the first complete table when ``duration_after_data``), 'no_data' (not all
    four feet within ``data_timeout_s``), 'stop' (a signal), 'unhealthy' (``healthy()`` turned false).
    Without ``once`` a table is printed every ``interval_s``, and a last one at the end.
    """
    writer = TableWriter(sys.stdout)
    if interval_s is None:
        interval_s = TTY_INTERVAL_S if writer.in_place else PIPE_INTERVAL_S
    start = time.monotonic()
    complete_at: float | None = None
    next_refresh = start + (interval_s if once else 0.0)
    while True:
        if stop.is_set() or not ros.context.ok():
            return "stop"
        now = time.monotonic()
        if complete_at is None and table.complete:
            complete_at = now
            if once:
                writer.write(table.lines(heading))
                return "once"
        if complete_at is None and data_timeout_s is not None and now - start >= data_timeout_s:
            return "no_data"
        duration_start = complete_at if duration_after_data else start
        if duration_s is not None and duration_start is not None and now - duration_start >= duration_s:
            writer.write(table.lines(heading))
            return "duration"
        if not healthy():
            return "unhealthy"
        if not once and now >= next_refresh:
            writer.write(table.lines(heading))
            next_refresh += interval_s * (int((now - next_refresh) / interval_s) + 1)
        ros.executor.spin_once(timeout_sec=0.02)


def run_echo(options: argparse.Namespace, ros_args: Sequence[str]) -> int:
    with StopSignals() as signals:
        ros = _start_ros("echo", ros_args)
        if ros is None:
            return EXIT_NO_ANSWER
        try:
            table = _subscribe_feet(ros, options.namespace)
            heading = _topics_heading(table) + ("" if options.once else " (Ctrl-C to stop)")
            ended = echo_loop(
                ros, table, signals.stop, heading, options.interval, duration_s=options.duration,
                once=options.once, data_timeout_s=options.timeout if options.once else None,
            )
        finally:
            ros.close()
    if ended == "no_data":
        print(
            f"{PROG} echo: no message from all of {', '.join(table.topics)} within {options.timeout:g} s "
            "(is foot_fk_node running, in this namespace and ROS domain, and receiving joint_states?)",
            file=sys.stderr,
        )
        return EXIT_NO_ANSWER
    return EXIT_OK


# --- verify ------------------------------------------------------------------------------------


VERIFY_ASK_AGAIN_S = 1.0


def call_verify(ros: Ros, namespace: str, timeout_s: float, stop: threading.Event) -> tuple[int, str]:
    """Call verify_fk: ``(exit code, text to print)``."""
    from rclpy.qos import QoSProfile
    from std_srvs.srv import Trigger

    # Every client of a service receives the replies to all its clients: a deeper history keeps
    # ours from being pushed out while others call too.
    client = ros.node.create_client(Trigger, prefixed(namespace, "verify_fk"), qos_profile=QoSProfile(depth=100))
    name = ros.node.resolve_service_name(client.srv_name)
    try:
        deadline = time.monotonic() + timeout_s
        while not client.service_is_ready():
            if stop.is_set():
                return EXIT_INTERRUPTED, "verify_fk: interrupted"
            if time.monotonic() > deadline:
                return EXIT_NO_ANSWER, (
                    f"verify_fk: no service {name} within {timeout_s:g} s "
                    "(is foot_fk_node running, in this namespace and ROS domain?)"
                )
            ros.executor.spin_once(timeout_sec=0.05)
        future, asked = client.call_async(Trigger.Request()), time.monotonic()
        deadline = asked + timeout_s
        while not future.done():
            if stop.is_set():
                return EXIT_INTERRUPTED, "verify_fk: interrupted"
            now = time.monotonic()
            if now > deadline:
                return EXIT_NO_ANSWER, f"verify_fk: {name} did not answer within {timeout_s:g} s"
            if now - asked > VERIFY_ASK_AGAIN_S:
                # Fast DDS drops a response sent before the server has matched our reply reader
                # ("failed to send response"); verify_fk only reads, so asking again is safe.
                client.remove_pending_request(future)
                future, asked = client.call_async(Trigger.Request()), now
            ros.executor.spin_once(timeout_sec=0.05)
        response = future.result()
    finally:
        ros.node.destroy_client(client)
    verdict = "OK, the node's FK agrees with PyBullet" if response.success else "FAILED"
    return (EXIT_OK if response.success else EXIT_FAILED), f"verify_fk ({name}): {verdict}\n  {response.message}"


def run_verify(options: argparse.Namespace, ros_args: Sequence[str]) -> int:
    with StopSignals() as signals:
        ros = _start_ros("verify", ros_args)
        if ros is None:
            return EXIT_NO_ANSWER
        try:
            code, text = call_verify(ros, options.namespace, options.timeout, signals.stop)
        finally:
            ros.close()
    print(text, file=sys.stdout if code in (EXIT_OK, EXIT_FAILED) else sys.stderr)
    return code


# --- plot --------------------------------------------------------------------------------------


def run_plot(options: argparse.Namespace, ros_args: Sequence[str]) -> int:
    from a1_leg_fk.urdf import LegFkError

    try:
        from a1_leg_fk import plots
        from a1_leg_fk.kinematics import Quadruped

        plots.pyplot()  # fail early, with the install hint, when matplotlib is missing
        quadruped = Quadruped.from_urdf(options.urdf)
        out = Path(options.out)
        out.mkdir(parents=True, exist_ok=True)
        written = [
            plots.plot_reach(quadruped, options.leg, out / f"reach_{options.leg}.png"),
            plots.plot_gait_feet(quadruped, out / "demo_gait_feet.png"),
        ]
    except (LegFkError, OSError) as error:
        print(f"{PROG} plot: {error}", file=sys.stderr)
        return EXIT_FAILED
    for path in written:
        print(f"wrote {path} ({path.stat().st_size} bytes)")
    return EXIT_OK


# --- demo --------------------------------------------------------------------------------------


def child_command(script: str, module: str) -> list[str]:
    """An installed console script beside this Python (bin/, or lib/a1_leg_fk/ as ``ros2 run`` uses), else ``python -m``."""
    here = Path(sys.executable).parent
    for candidate in (here / script, Path(sys.prefix) / "lib" / "a1_leg_fk" / script):
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return [str(candidate)]
    found = shutil.which(script)
    if found and Path(found).parent == here:
        return [found]
    return [sys.executable, "-m", module]


def _die_with_parent() -> None:
    """In the child before exec: get SIGTERM if the demo process dies (even by SIGKILL). Linux only."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG = 1
    except Exception:  # noqa: BLE001, S110 (best effort; other platforms just lack the safety net)
        pass


class Child:
    """A child process in its own process group, its output in a log file."""

    def __init__(self, name: str, command: list[str], log: Path) -> None:
        self.name = name
        self.log = log
        with open(log, "wb") as output:
            self.process = subprocess.Popen(
                command,
                stdin=subprocess.DEVNULL,
                stdout=output,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # own process group: a terminal Ctrl-C reaches only us
                preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
            )

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self, timeout_s: float = CHILD_STOP_TIMEOUT_S) -> int:
        """SIGINT (as Ctrl-C), then SIGKILL to its group after ``timeout_s``; returns the exit code."""
        if self.process.poll() is None:
            self._signal_group(signal.SIGINT)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self._signal_group(signal.SIGKILL)
                self.process.wait(5.0)
        self._signal_group(signal.SIGKILL)  # anything it left behind in its group
        return self.process.returncode

    def _signal_group(self, number: int) -> None:
        try:
            os.killpg(self.process.pid, number)
        except (ProcessLookupError, PermissionError):
            pass

    def tail(self, lines: int = 15) -> str:
        try:
            text = self.log.read_text(errors="replace").rstrip().splitlines()
        except OSError:
            return "(no output)"
        return "\n".join("    | " + line for line in text[-lines:]) or "    | (no output)"


def _say(text: str = "") -> None:
    print(text, flush=True)


def run_demo(options: argparse.Namespace, ros_args: Sequence[str]) -> int:
    with StopSignals() as signals:
        demo = Demo(options, ros_args, signals)
        code = EXIT_FAILED  # if run() raises
        try:
            code = demo.run()
        finally:
            if signals.stop.is_set():
                _say(f"\n{signals.signal_name or 'interrupted'}: stopping")
            code = demo.cleanup(code)
    return EXIT_INTERRUPTED if signals.stop.is_set() else code


class Demo:
    """``a1-leg-fk demo``: the two nodes as children, the live table, verify, then a clean stop."""

    def __init__(self, options: argparse.Namespace, ros_args: Sequence[str], signals: StopSignals) -> None:
        self.options = options
        self.ros_args = list(ros_args)
        self.signals = signals
        self.children: list[Child] = []
        self.temporary_log_dir: Path | None = None  # made by us: removed after a clean run
        self.ros: Ros | None = None

    def run(self) -> int:
        options, stop = self.options, self.signals.stop
        _say("== a1-leg-fk demo: joint_state_demo -> foot_fk_node -> feet ==")
        if not os.environ.get("ROS_DOMAIN_ID"):
            domain = 1 + os.getpid() % 100
            os.environ["ROS_DOMAIN_ID"] = str(domain)
            os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
            _say(f"ROS_DOMAIN_ID was unset: using {domain} for this demo and its nodes "
                 f"(discovery range {os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE']}); to watch from another "
                 f"terminal: export ROS_DOMAIN_ID={domain}")
        else:
            _say(f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} (from the environment)")
        if options.log_dir:
            log_dir = Path(options.log_dir)
            log_dir.mkdir(parents=True, exist_ok=True)
        else:
            log_dir = self.temporary_log_dir = Path(tempfile.mkdtemp(prefix="a1_leg_fk_demo_"))
        child_ros_args = self.ros_args
        if options.namespace:
            namespace = options.namespace if options.namespace.startswith("/") else "/" + options.namespace
            child_ros_args = ["--ros-args", "-r", f"__ns:={namespace}", *self.ros_args]
        os.environ["PYTHONUNBUFFERED"] = "1"

        kept = "kept only if something fails" if self.temporary_log_dir else "kept"
        _say(f"\n[1/4] starting the two nodes (their output goes to {log_dir}/, {kept})")
        for name, module in (("foot_fk_node", "a1_leg_fk.node"), ("joint_state_demo", "a1_leg_fk.demo")):
            if stop.is_set():
                return EXIT_INTERRUPTED
            command = child_command(name, module) + child_ros_args
            self.children.append(Child(name, command, log_dir / f"{name}.log"))
            _say(f"  {name:<17} pid {self.children[-1].process.pid}: {' '.join(command)}")
        _say("  joint_state_demo: publishes joint_states at 500 Hz: the A1 stands up from a crouch (2 s), then trots in place")
        _say("  foot_fk_node:     joint_states -> forward kinematics -> foot_positions/<leg>; offers verify_fk")

        self.ros = _start_ros("demo", self.ros_args)
        if self.ros is None:
            return EXIT_FAILED
        table = _subscribe_feet(self.ros, options.namespace)
        _say(f"\n[2/4] the feet, live for {options.duration:g} s: x forward, y left, z up, in mm from the trunk "
             "origin; rate = messages per second on each topic   (Ctrl-C stops everything)")
        ended = echo_loop(
            self.ros, table, stop, _topics_heading(table), options.interval, duration_s=options.duration,
            data_timeout_s=DEMO_START_TIMEOUT_S, duration_after_data=True,
            healthy=lambda: all(child.alive() for child in self.children),
        )
        if ended == "stop":
            return EXIT_INTERRUPTED
        if ended == "unhealthy":
            return EXIT_FAILED  # which child died, and its output, is reported when stopping
        code = EXIT_OK
        if ended == "no_data":
            _say(f"  no feet from all of {', '.join(table.topics)} within {DEMO_START_TIMEOUT_S:g} s")
            code = EXIT_FAILED

        _say("\n[3/4] verify_fk: the node recomputes the latest feet with PyBullet and compares (distance per foot, m)")
        verify_code, text = call_verify(self.ros, options.namespace, 5.0, stop)
        _say("  " + text.replace("\n", "\n  "))
        if verify_code == EXIT_INTERRUPTED:
            return EXIT_INTERRUPTED
        return code if verify_code == EXIT_OK else EXIT_FAILED

    def cleanup(self, code: int) -> int:
        """Close our node, stop the children; the exit code, made 1 if a child misbehaved."""
        if self.ros is not None:
            self.ros.close()
            self.ros = None
        code = _stop_children(self.children, code)
        if self.temporary_log_dir is not None and code in (EXIT_OK, EXIT_INTERRUPTED):
            shutil.rmtree(self.temporary_log_dir, ignore_errors=True)
        return code


def _stop_children(children: list[Child], code: int) -> int:
    """Stop every child; report each; EXIT_FAILED if one died early or exited badly."""
    if not children:
        return code
    _say("\n[4/4] stopping the nodes (SIGINT, as Ctrl-C)")
    died = [child for child in children if not child.alive()]
    for child in children:
        returncode = child.stop()
        if child not in died and returncode == -signal.SIGINT:
            # Our SIGINT arrived before the child's Python had installed rclpy's handlers (it was
            # still importing): the default action ended it. Stopped as asked, nothing to report.
            _say(f"  {child.name} stopped (by SIGINT while still starting)")
        elif child in died or returncode != 0:
            how = "had already exited" if child in died else "exited"
            _say(f"  {child.name} {how} with code {returncode}; its last output ({child.log}):\n{child.tail()}")
            code = EXIT_FAILED
        else:
            _say(f"  {child.name} stopped (exit code 0)")
    if code == EXIT_OK:
        _say("demo finished: OK")
    elif code == EXIT_INTERRUPTED:
        _say("demo interrupted: everything stopped")
    else:
        _say(f"demo finished: FAILED (exit {code})")
    return code


if __name__ == "__main__":
    sys.exit(main())
