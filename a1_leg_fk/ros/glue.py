"""ROS plumbing shared by ``foot_fk_node``, ``foot_ik_node`` and ``joint_state_demo``: the spin
loop of ``main`` with its exit codes and its Ctrl-C/SIGTERM, the QoS profiles, one
``/diagnostics`` status, and warnings limited to one a second per kind.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TypedDict

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.context import Context
from rclpy.executors import Executor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions

from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.stop_signals import StopSignals

WARNING_INTERVAL_S = 1.0
"""At most one warning a second for each kind of problem."""
SPIN_SLICE_S = 0.1
"""The longest turn of a node's executor [s]: how late a Ctrl-C/SIGTERM is noticed at most."""
OUTPUT_QOS = QoSProfile(depth=10)  # reliable: heard by reliable and best-effort subscribers
JOINT_STATES_QOS = QoSProfile(
    # The sensor-data profile (best effort: hears reliable and best-effort publishers alike), with
    # a deeper queue than its 5, so that a burst of a 1 kHz stream is not overwritten while we
    # work.
    history=qos_profile_sensor_data.history,
    depth=100,
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=qos_profile_sensor_data.durability,
)
"""The nodes' QoS: ``OUTPUT_QOS`` for what they publish, ``JOINT_STATES_QOS`` for the streams
they subscribe (joint_states, foot targets)."""


class NodeOptions(TypedDict, total=False):
    """The keyword arguments of :class:`rclpy.node.Node` that our nodes pass on."""

    context: Context | None
    cli_args: list[str] | None
    namespace: str | None
    use_global_arguments: bool
    enable_rosout: bool
    start_parameter_services: bool
    parameter_overrides: list[Parameter] | None
    allow_undeclared_parameters: bool
    automatically_declare_parameters_from_overrides: bool
    enable_logger_service: bool


def run_node(
    executable: str,
    make_node: Callable[[], Node],
    args: Sequence[str] | None = None,
    usage_errors: tuple[type[Exception], ...] = (),
    executor_factory: Callable[[], Executor] | None = None,
) -> int:
    """Start rclpy, spin the node until Ctrl-C/SIGTERM (exit 0, also when it comes while starting).

    Bad ``--ros-args``, or one of ``usage_errors`` while the node starts (a bad parameter): one
    line on stderr and exit 2. A :class:`LegFkError` while starting: a fatal log line and exit 1.
    ``executor_factory`` defaults to :func:`make_executor`.

    SIGINT/SIGTERM only set a flag (:class:`StopSignals`, shared with the executable's, which is
    in place before the slow imports) and rclpy's own handlers stay off. rclpy's would, from a
    thread of theirs, shut the context down in the middle of the node's construction (an
    RCLError traceback, exit 1) and, for SIGINT, also raise KeyboardInterrupt wherever the main
    thread is; before they are installed (the imports, ``rclpy.init``) Python's default handlers
    raise a KeyboardInterrupt traceback or end the process by SIGTERM. The flag is checked before
    ``rclpy.init``, once the node is built and between turns of the executor (at most
    :data:`SPIN_SLICE_S` apart).
    """
    with StopSignals() as signals:
        if signals.stop.is_set():  # a signal during the imports
            return 0
        try:
            rclpy.init(
                args=None if args is None else list(args),
                signal_handler_options=SignalHandlerOptions.NO,
            )
        except Exception as error:  # noqa: BLE001 (rclpy raises its internal RCLError for bad --ros-args)
            print(f"{executable}: cannot start: {_ros_args_error(str(error))}", file=sys.stderr)
            return 2
        node = None
        try:
            node = make_node()
            executor = (executor_factory or make_executor)()
            executor.add_node(node)
            while not signals.stop.is_set():
                executor.spin_once(timeout_sec=SPIN_SLICE_S)
        except LegFkError as error:
            rclpy.logging.get_logger(executable).fatal(f"cannot start: {error}")
            return 1
        except usage_errors as error:
            print(f"{executable}: {error}", file=sys.stderr)
            return 2
        finally:
            if node is not None:
                node.destroy_node()
            rclpy.try_shutdown()
    return 0


def make_executor() -> Executor:
    """Rclpy's EventsExecutor where available (the fastest here), else the single-threaded one.

    Spun with ``spin_once`` in a loop: ``EventsExecutor().spin()`` ignores SIGINT/SIGTERM.
    """
    try:
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    except ImportError:
        return SingleThreadedExecutor()


def _ros_args_error(message: str) -> str:
    """Rcl's refusal of the command line, cut to its first line, with a hint where a URDF given
    with ``-p robot_description:=...`` was refused: rcl parses every ``-p`` value as YAML, and
    exported URDFs (a comment such as ``Commit Version: 1.6.0``) are not valid YAML.
    """
    first_line = message.splitlines()[0] if message else message
    if "robot_description:=" not in message:
        return first_line
    return (
        f"{first_line[:160]}... (rcl parses every -p value as YAML, and this URDF is not valid "
        "YAML: give it in a --params-file as a quoted or block string, through a launch file, "
        "or on the robot_description topic)"
    )


class WarnThrottle:
    """A node's warnings, at most one every :data:`WARNING_INTERVAL_S` for each kind of problem."""

    def __init__(self, node: Node) -> None:
        self._logger = node.get_logger()
        self._last: dict[str, float] = {}  # kind -> time.monotonic() of its last warning

    def warn(self, kind: str, text: str) -> None:
        """Log ``text`` unless a warning of ``kind`` was logged less than the interval ago."""
        now = time.monotonic()
        if now - self._last.get(kind, -math.inf) >= WARNING_INTERVAL_S:
            self._last[kind] = now
            self._logger.warning(text)


def diagnostics(
    node: Node,
    name: str,
    level: bytes,
    message: str,
    hardware_id: str,
    values: Mapping[str, object],
) -> DiagnosticArray:
    """A one-status DiagnosticArray stamped with the node's clock; ``name`` follows the node's
    name.
    """
    status = DiagnosticStatus(
        level=level,
        name=f"{node.get_name()}: {name}",
        message=message,
        hardware_id=hardware_id,
        values=[KeyValue(key=key, value=str(value)) for key, value in values.items()],
    )
    array = DiagnosticArray(status=[status])
    array.header.stamp = node.get_clock().now().to_msg()
    return array
