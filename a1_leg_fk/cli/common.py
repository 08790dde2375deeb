"""The plumbing the ``a1-leg-fk`` commands share: exit codes, argument types, signals, ROS,
children.

Nothing here imports rclpy at import time: the commands that need no ROS (plot, bag, gait, ik)
never load it.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS, MODEL_CORRECTIONS
from a1_leg_fk.stop_signals import StopSignals

PROG = "a1-leg-fk"
EXIT_OK, EXIT_FAILED, EXIT_NO_ANSWER, EXIT_INTERRUPTED = 0, 1, 2, 130
EXIT_BAD_INPUT = 2
"""Bad usage or input: one line on stderr (argparse's own code for bad usage)."""
EXIT_DAMAGED = EXIT_FAILED
"""A recording damaged before anything a command needs could be read: one line on stderr."""
ROS_ARGS_FLAG = "--ros-args"
CHILD_STOP_TIMEOUT_S = 5.0
T = TypeVar("T")


# --- command line ------------------------------------------------------------------------------


def input_error(prog: str, error: Exception) -> int:
    """Print a bag command's :class:`~a1_leg_fk.model.urdf.LegFkError` (or ``OSError``) as one
    line on stderr; its exit code: :data:`EXIT_DAMAGED` for a damaged recording, else
    :data:`EXIT_BAD_INPUT`.
    """
    from a1_leg_fk.recording.reads import DamagedRecording

    print(f"{prog}: {error}", file=sys.stderr)
    return EXIT_DAMAGED if isinstance(error, DamagedRecording) else EXIT_BAD_INPUT


def our_arguments(argv: Sequence[str]) -> list[str]:
    """``argv`` (program name excluded) less its ROS arguments, as rclpy's ``remove_ros_args``
    says.

    :class:`BadRosArguments` (a ``ValueError``) when rcl cannot parse them.

    rcl reads ROS arguments only after a ``--ros-args``: without one there are none, and rclpy is
    not imported. That keeps the commands without ROS (plot, bag, gait, ik) from paying for
    loading rclpy's C extension (about 0.15 s here) on every run; and rclpy, though a requirement
    of every install of this package, then need not even be importable for them.
    """
    if ROS_ARGS_FLAG not in argv:
        return list(argv)
    from rclpy.utilities import remove_ros_args

    try:
        return remove_ros_args([PROG, *argv])[1:]
    except Exception as error:  # noqa: BLE001 (rclpy raises its internal RCLInvalidROSArgsError)
        raise BadRosArguments(str(error)) from None


class BadRosArguments(ValueError):
    """rcl could not parse the ``--ros-args`` part of the command line."""


def ros_section(argv: Sequence[str]) -> list[str]:
    """``argv`` from its first ``--ros-args`` on (empty without one): what the demo hands its
    nodes.

    rcl finds in it the same ROS arguments as in the whole ``argv``; the nodes ignore the rest
    (anything of ours after a closing ``--``), as ``rclpy.init`` does.
    """
    return list(argv[argv.index(ROS_ARGS_FLAG) :]) if ROS_ARGS_FLAG in argv else []


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


def positive(text: str) -> float:
    """Argparse type: a finite number > 0."""
    value = _number(text)
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number: {text!r}")
    return value


def non_negative(text: str) -> float:
    """Argparse type: a finite number >= 0."""
    value = _number(text)
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0: {text!r}")
    return value


def add_corrections_argument(parser: argparse.ArgumentParser) -> None:
    """``--corrections online|off|FILE``: the nodes' ``model_corrections`` (bag, gait, odom), or
    a calibration's file.
    """
    parser.add_argument(
        "--corrections",
        default=DEFAULT_MODEL_CORRECTIONS,
        metavar="|".join((*MODEL_CORRECTIONS, "FILE")),
        help="the joints' friction and torque bias learnt in swing and taken off the foot "
        "forces, each term once significant (online, the default), not (off), or those of a "
        "calibration's FILE (a1-leg-fk calibrate)",
    )


def namespace_parent() -> argparse.ArgumentParser:
    """A parent parser with ``--namespace NS`` (echo, verify, demo)."""
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument(
        "--namespace",
        metavar="NS",
        default="",
        help="prefix the topic/service names with NS (e.g. /robot1 -> /robot1/foot_positions/FR); "
        "or move the tool's own node with --ros-args -r __ns:=/robot1",
    )
    return parent


def prefixed(namespace: str, name: str) -> str:
    """``name`` under ``namespace`` ('' leaves the relative name as it is)."""
    if not namespace:
        return name
    return namespace.rstrip("/") + "/" + name if namespace != "/" else "/" + name


def say(text: str = "") -> None:
    """Print a line now (the demo's output is interleaved with its children's timing)."""
    print(text, flush=True)


# --- this tool's ROS node ------------------------------------------------------------------------


class Ros:
    """This tool's own rclpy context, node and executor (rclpy's signal handlers off).

    ``argv`` is the whole command line (program name excluded): ``rclpy.init`` takes the ROS
    arguments from it and ignores the rest.
    """

    def __init__(self, command: str, argv: Sequence[str]) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(
            args=[PROG, *argv],
            context=self.context,
            signal_handler_options=SignalHandlerOptions.NO,
        )
        try:
            self.node = rclpy.create_node(
                f"a1_leg_fk_{command}_{os.getpid()}", context=self.context
            )
        except BaseException:
            rclpy.try_shutdown(context=self.context)
            raise
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def close(self) -> None:
        """Shut the executor down, destroy the node and shut this context down."""
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def start_ros(command: str, argv: Sequence[str]) -> Ros | None:
    """:class:`Ros`, or None after one line on stderr (e.g. bad ``--ros-args``)."""
    try:
        return Ros(command, argv)
    except Exception as error:  # noqa: BLE001 (rclpy raises its internal RCLError for bad --ros-args)
        print(f"{PROG} {command}: cannot start ROS: {error}", file=sys.stderr)
        return None


def with_ros(
    command: str, argv: Sequence[str], work: Callable[[Ros, threading.Event], T]
) -> T | None:
    """``work(ros, stop)`` with this tool's node, ``stop`` set by Ctrl-C or SIGTERM; the node is
    closed afterwards. None (after one line on stderr) when ROS cannot start.
    """
    with StopSignals() as signals:
        ros = start_ros(command, argv)
        if ros is None:
            return None
        try:
            return work(ros, signals.stop)
        finally:
            ros.close()


# --- child processes (the demo's nodes; bench/node_throughput.py's roles) -----------------------


def child_command(script: str, module: str) -> list[str]:
    """An installed console script beside this Python (bin/, or lib/a1_leg_fk/ as ``ros2 run``
    uses), else ``python -m module``.
    """
    here = Path(sys.executable).parent
    for candidate in (here / script, Path(sys.prefix) / "lib" / "a1_leg_fk" / script):
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return [str(candidate)]
    found = shutil.which(script)
    if found and Path(found).parent == here:
        return [found]
    return [sys.executable, "-m", module]


def _die_with_parent(death_signal: int) -> None:
    """In the child before exec: get ``death_signal`` if the parent dies (even by SIGKILL). Linux
    only.
    """
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, death_signal)  # PR_SET_PDEATHSIG = 1
    except Exception:  # noqa: BLE001 (best effort; other platforms just lack the safety net)
        pass


class Child:
    """A child process in its own process group (session), its output in the file ``log``.

    A terminal's Ctrl-C reaches only the parent, which stops its children itself; should the
    parent die, the child gets ``death_signal`` (Linux). With ``pipes`` the child's stdin and
    stdout are text pipes to the parent (line buffered) and only its stderr goes to ``log``.
    """

    def __init__(
        self,
        name: str,
        command: Sequence[str],
        log: Path,
        *,
        env: dict[str, str] | None = None,
        cwd: str | Path | None = None,
        pipes: bool = False,
        death_signal: int = signal.SIGTERM,
    ) -> None:
        self.name = name
        self.log = log
        self.killed = False  # stop() had to SIGKILL it
        self.stop_s = 0.0  # seconds from stop()'s signal to the exit
        linux = sys.platform.startswith("linux")
        with open(log, "wb") as output:
            self.process = subprocess.Popen(
                list(command),
                env=env,
                cwd=cwd,
                stdin=subprocess.PIPE if pipes else subprocess.DEVNULL,
                stdout=subprocess.PIPE if pipes else output,
                stderr=output if pipes else subprocess.STDOUT,
                text=pipes,
                bufsize=1 if pipes else -1,
                start_new_session=True,
                # preexec_fn only calls prctl(PR_SET_PDEATHSIG): async-signal-safe, takes no lock.
                preexec_fn=functools.partial(_die_with_parent, death_signal) if linux else None,  # noqa: PLW1509
            )

    def alive(self) -> bool:
        """Whether the process still runs."""
        return self.process.poll() is None

    def stop(self, sig: int = signal.SIGINT, timeout_s: float = CHILD_STOP_TIMEOUT_S) -> int:
        """``sig`` (default SIGINT, as Ctrl-C), then SIGKILL to its group after ``timeout_s``.

        Returns the exit code; sets :attr:`killed` and :attr:`stop_s`.
        """
        if self.process.poll() is None:
            started = time.monotonic()
            self._signal_group(sig)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.killed = True
                self._signal_group(signal.SIGKILL)
                self.process.wait(5.0)
            self.stop_s = time.monotonic() - started
        self._signal_group(signal.SIGKILL)  # anything it left behind in its group
        return self.process.returncode

    def _signal_group(self, number: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, number)

    def tail(self, lines: int = 15) -> str:
        """The last ``lines`` lines of its log, indented for a report."""
        try:
            text = self.log.read_text(errors="replace").rstrip().splitlines()
        except OSError:
            return "(no output)"
        return "\n".join("    | " + line for line in text[-lines:]) or "    | (no output)"
