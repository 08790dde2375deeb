"""Where a node's joint states come from: parameter ``input`` (read-only), ``joint_states``
(``sensor_msgs/msg/JointState`` on ``joint_states``, the IMU on ``imu``) or ``unitree_lowstate``
(Unitree's ``LowState`` on ``lowstate``: the motors and the IMU inside the message, stamped with
the receive time; :class:`~a1_leg_fk.wire.lowstate.LowStateJointStates`).

The LowState message class, needed to subscribe, comes from the user's workspace:
``unitree_go`` (Go2, B2; unitree_ros2), else ``unitree_legged_msgs`` (A1, Go1 through a ROS 2
bridge). Without either the node stops at start with one line naming the package to build
(:class:`MissingMessages`, exit 2). The messages are read from their bytes, as the bag tools read
them.
"""

from __future__ import annotations

import importlib

from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from sensor_msgs.msg import JointState

from a1_leg_fk.ros.robot_source import ParameterSpec
from a1_leg_fk.wire.joint_state import JointStateDecoder
from a1_leg_fk.wire.lowstate import KINDS, LowStateJointStates
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

JOINT_STATES, UNITREE_LOWSTATE = "joint_states", "unitree_lowstate"
INPUTS = (JOINT_STATES, UNITREE_LOWSTATE)
LOWSTATE_TOPIC = "lowstate"
INPUT_PARAMETER = ParameterSpec(
    "input",
    JOINT_STATES,
    ParameterType.PARAMETER_STRING,
    "Where the joint states come from: joint_states (sensor_msgs/JointState on joint_states, "
    "the IMU on imu) or unitree_lowstate (unitree_go/LowState, else unitree_legged_msgs/"
    "LowState, on lowstate: its motors and its own IMU; stamps: the receive time)",
    read_only=True,
)
BUILD_HINT = (
    "build Unitree's message package in your workspace and source it: unitree_go "
    "(unitree_ros2: cyclonedds_ws/src/unitree/unitree_go) for a Go2 or B2, "
    "unitree_legged_msgs for an A1 or Go1"
)


class MissingMessages(Exception):
    """``input: unitree_lowstate`` without Unitree's message package, or an unknown ``input``: a
    usage error (one line, exit 2).
    """


def lowstate_class() -> tuple[type, str]:
    """The LowState message class of the user's workspace and its type name;
    :class:`MissingMessages` without one.
    """
    for msgtype in (GO_LOW_STATE, LEGGED_LOW_STATE):
        package = KINDS[msgtype].package
        try:
            module = importlib.import_module(f"{package}.msg")
        except ImportError:
            continue
        message = getattr(module, "LowState", None)
        if isinstance(message, type):
            return message, msgtype
    raise MissingMessages(f"input unitree_lowstate needs Unitree's LowState message: {BUILD_HINT}")


def joint_input(node: Node) -> tuple[type, str, JointStateDecoder | LowStateJointStates]:
    """The message class, topic and decoder of the node's ``input`` parameter (declared by the
    node; a LowState is stamped with the node's clock when it is read).
    :class:`MissingMessages` for an unknown input, or a LowState input without its messages.
    """
    chosen = str(node.get_parameter(INPUT_PARAMETER.name).value)
    if chosen == JOINT_STATES:
        return JointState, JOINT_STATES, JointStateDecoder()
    if chosen != UNITREE_LOWSTATE:
        raise MissingMessages(f"parameter input must be {' or '.join(INPUTS)}: {chosen!r}")
    message, msgtype = lowstate_class()
    return (
        message,
        LOWSTATE_TOPIC,
        LowStateJointStates(msgtype, lambda: node.get_clock().now().nanoseconds),
    )
