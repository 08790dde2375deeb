"""ROS plumbing shared by the package's nodes: the spin loop of ``main`` with its exit codes, and
one ``/diagnostics`` status. (``foot_ik_node`` uses it; ``foot_fk_node`` and ``joint_state_demo``
still carry their own copies, to be switched over when node.py's robot_description work lands.)
"""

from __future__ import annotations

import sys
from typing import Callable, Mapping, Sequence

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from a1_leg_fk.node import _make_executor
from a1_leg_fk.urdf import LegFkError


def run_node(executable: str, make_node: Callable[[], Node], args: Sequence[str] | None = None) -> int:
    """Start rclpy, spin the node until Ctrl-C/SIGTERM (exit 0); bad ``--ros-args``: one line on
    stderr and exit 2; a :class:`LegFkError` while starting: a fatal log line and exit 1."""
    try:
        rclpy.init(args=args)
    except Exception as error:  # noqa: BLE001 (rclpy raises its internal RCLError for bad --ros-args)
        print(f"{executable}: cannot start: {error}", file=sys.stderr)
        return 2
    node = None
    try:
        node = make_node()
        executor = _make_executor()
        executor.add_node(node)
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except LegFkError as error:
        rclpy.logging.get_logger(executable).fatal(f"cannot start: {error}")
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()  # the signal handler may have shut the context down already
    return 0


def diagnostics(node: Node, name: str, level: bytes, message: str, hardware_id: str, values: Mapping[str, object]) -> DiagnosticArray:
    """A one-status DiagnosticArray stamped with the node's clock; ``name`` follows the node's name."""
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
