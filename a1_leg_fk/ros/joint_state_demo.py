"""``joint_state_demo``: the A1 gait of :mod:`a1_leg_fk.gait.demo_gait` as a sensor_msgs/JointState
stream.

Publishes ``joint_states`` (a relative name: namespaces and remaps apply) at ``rate_hz`` with
the 12 leg joints' positions [rad] and velocities [rad/s]: the robot stands up from a crouch for
2 s, then trots in place forever. Like robot_state_publisher, it also publishes the URDF it
animates (the embedded A1) on ``robot_description`` (transient local), once.

Pacing: an rclpy timer alone drifts and misses ticks at hundreds of Hz, so the timer (period
``1 / rate_hz``) only wakes the node; each wake-up publishes every sample that is due by the
node clock, ``start + k / rate_hz`` for k = 0, 1, 2, ... Each message is stamped with its
sample's time (never in the future, at most a few periods old) and carries the gait at that
time. After a stall longer than :data:`MAX_CATCH_UP_S` the stream skips ahead instead of
bursting.

Run::

    joint_state_demo --ros-args -p rate_hz:=200.0 -p naming:=unitree -r __ns:=/robot1
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Unpack

from a1_leg_fk.gait.demo_gait import Gait, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.model.legs import UNITREE_NAME_PAIRS

if TYPE_CHECKING:
    from rclpy.node import Node

NODE_NAME = "joint_state_demo"
TOPIC = "joint_states"
DESCRIPTION_TOPIC = "robot_description"
NAMINGS = ("pybullet", "unitree")
DEFAULT_RATE_HZ = 500.0
MAX_RATE_HZ = 10000.0
MAX_CATCH_UP_S = 0.1
"""Longest stall [s] made up for by publishing the missed samples at once; longer ones are
skipped."""


def joint_names(quadruped: Quadruped, naming: str) -> list[str]:
    """The 12 joint names in slot order: the URDF's (``pybullet``) or Unitree's (``unitree``).

    pybullet_data's A1 says ``FR_upper_joint``/``FR_lower_joint`` where Unitree says
    ``FR_thigh_joint``/``FR_calf_joint`` (:data:`a1_leg_fk.model.legs.UNITREE_NAME_PAIRS`).
    """
    if naming not in NAMINGS:
        raise ValueError(f"naming must be one of {list(NAMINGS)}, not '{naming}'")
    names = list(quadruped.joint_names)
    for pybullet_part, unitree_part in UNITREE_NAME_PAIRS:
        old, new = (f"_{pybullet_part}_joint", f"_{unitree_part}_joint")
        if naming == "pybullet":
            old, new = new, old
        names = [name[: -len(old)] + new if name.endswith(old) else name for name in names]
    return names


def _node_class() -> type[Node]:
    """The node's class, defined here so that importing this module needs no ROS."""
    from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String

    from a1_leg_fk.ros.glue import NodeOptions
    from a1_leg_fk.ros.robot_source import DESCRIPTION_QOS

    class JointStateDemo(Node):
        """Publishes the demo gait on ``joint_states`` at ``rate_hz``, paced by the node clock."""

        def __init__(self, **kwargs: Unpack[NodeOptions]) -> None:
            super().__init__(NODE_NAME, **kwargs)
            rate = self.declare_parameter(
                "rate_hz",
                DEFAULT_RATE_HZ,
                ParameterDescriptor(
                    type=ParameterType.PARAMETER_DOUBLE,
                    description=f"Messages per second on {TOPIC} (0 < rate_hz <= "
                    f"{MAX_RATE_HZ:g}).",
                    floating_point_range=[
                        FloatingPointRange(from_value=0.0, to_value=MAX_RATE_HZ)
                    ],
                    read_only=True,
                    dynamic_typing=True,  # accept rate_hz:=100 as well as 100.0
                ),
            ).value
            naming = self.declare_parameter(
                "naming",
                "pybullet",
                ParameterDescriptor(
                    type=ParameterType.PARAMETER_STRING,
                    description=(
                        "Joint names: 'pybullet' (FR_hip_joint, FR_upper_joint, FR_lower_joint, "
                        "... as in pybullet_data's a1.urdf) or 'unitree' (FR_hip_joint, "
                        "FR_thigh_joint, FR_calf_joint, ...)."
                    ),
                    additional_constraints=f"one of {', '.join(NAMINGS)}",
                    read_only=True,
                ),
            ).value
            if (
                isinstance(rate, bool)
                or not isinstance(rate, (int, float))
                or not 0.0 < rate <= MAX_RATE_HZ
            ):
                raise ValueError(
                    f"parameter rate_hz must be a number in (0, {MAX_RATE_HZ:g}], not {rate!r}"
                )
            if naming not in NAMINGS:
                raise ValueError(
                    f"parameter naming must be one of {list(NAMINGS)}, not {naming!r}"
                )
            robot = load_robot()
            quadruped = robot.quadruped
            self.gait = Gait(limits_of(quadruped))
            self.names = joint_names(quadruped, naming)
            self.rate_hz = float(rate)
            self.period_ns = max(1, round(1e9 / self.rate_hz))
            self.max_behind = max(1, int(MAX_CATCH_UP_S * self.rate_hz))
            self.sent = 0
            self.skipped = 0
            self._message = JointState()
            self._message.name = self.names
            self.publisher = self.create_publisher(JointState, TOPIC, 10)
            # As robot_state_publisher does: the description of the robot it animates, latched.
            self.description_publisher = self.create_publisher(
                String, DESCRIPTION_TOPIC, DESCRIPTION_QOS
            )
            self.description_publisher.publish(String(data=robot.urdf_xml))
            self.start_ns = self.get_clock().now().nanoseconds
            self.timer = self.create_timer(1.0 / self.rate_hz, self._publish_due)
            self.get_logger().info(
                f"publishing {self.publisher.topic_name} at {self.rate_hz:g} Hz, {naming} joint "
                f"names, and the A1's URDF on {self.description_publisher.topic_name} (transient "
                f"local): standing up for {self.gait.parameters.stand_s:g} s, then trotting in "
                f"place at {self.gait.parameters.trot_hz:g} Hz"
            )

        def _publish_due(self) -> None:
            """Publish every sample due by now (usually one), stamped with its own sample time."""
            now_ns = self.get_clock().now().nanoseconds
            if (
                now_ns < self.start_ns + (self.sent - 1) * self.period_ns
            ):  # the clock went back: restart
                self.start_ns, self.sent = now_ns, 0
            due = (now_ns - self.start_ns) // self.period_ns + 1
            if due - self.sent > self.max_behind:
                self.skipped += due - 1 - self.sent
                self.get_logger().warn(
                    f"{due - self.sent} samples behind: skipping ahead ({self.skipped} skipped "
                    "so far)",
                    throttle_duration_sec=5.0,
                )
                self.sent = due - 1
            message = self._message
            while self.sent < due:
                offset_ns = self.sent * self.period_ns
                stamp_ns = self.start_ns + offset_ns
                message.header.stamp.sec, message.header.stamp.nanosec = divmod(
                    stamp_ns, 1_000_000_000
                )
                message.position, message.velocity = self.gait.state(offset_ns * 1e-9)
                self.publisher.publish(message)
                self.sent += 1

    return JointStateDemo


def main(args: Sequence[str] | None = None) -> int:
    """Run the demo publisher until Ctrl-C or SIGTERM (both exit 0); 2 on a bad parameter."""
    from rclpy.exceptions import NameValidationException, ParameterException
    from rclpy.executors import SingleThreadedExecutor

    from a1_leg_fk.ros import glue as ros_glue

    usage_errors = (
        ValueError,
        ParameterException,
        NameValidationException,
    )  # a bad parameter or name
    return ros_glue.run_node(NODE_NAME, _node_class(), args, usage_errors, SingleThreadedExecutor)


if __name__ == "__main__":
    sys.exit(main())
