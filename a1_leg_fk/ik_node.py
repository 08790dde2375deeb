"""``foot_ik_node``: one geometry_msgs/PointStamped target per foot in, sensor_msgs/JointState
commands out (that leg's three joints).

Thin ROS glue over :meth:`Quadruped.ik_leg` (:mod:`a1_leg_fk.inverse`). Subscribes
``foot_targets/<leg>`` (frame: the base frame, or empty; there is no TF here, so any other frame is
rejected with a warning naming it), publishes ``joint_commands`` with the target's stamp, seeded
with the leg's previous solution. Every answer is published, the best angles for a target out of
reach or out of limits included; the statuses are counted in ``/diagnostics`` and warned about at
most once a second per leg. The model parameters are ``foot_fk_node``'s. All names are relative.
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter
from typing import Callable, Sequence

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PointStamped
from rcl_interfaces.msg import ParameterType
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from sensor_msgs.msg import JointState

from a1_leg_fk import node as fk_node
from a1_leg_fk import ros_glue
from a1_leg_fk.inverse import OK, STATUS_NAMES
from a1_leg_fk.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.robot_config import RobotConfig, load_robot
from a1_leg_fk.urdf import LegFkError

NODE_NAME = "a1_leg_ik"
DIAGNOSTICS_PERIOD_S = 1.0
WARNING_INTERVAL_S = 1.0  # at most one warning per second per leg (and per kind of rejection)
TARGETS_QOS = fk_node.JOINT_STATES_QOS  # best effort, deep: hears reliable and best-effort publishers

PARAMETERS = tuple(spec for spec in fk_node.PARAMETERS if spec.name in fk_node.MODEL_PARAMETERS) + (
    fk_node._ParameterSpec("base_frame", "", ParameterType.PARAMETER_STRING,
                           "frame_id the targets must have (or empty); empty = the URDF's root link (trunk for the A1)"),
    fk_node._ParameterSpec("command_joint_names", None, ParameterType.PARAMETER_STRING_ARRAY,
                           "12 joint names for joint_commands in FR, FL, RR, RL x root-to-foot order "
                           "(e.g. FR_hip_joint, FR_thigh_joint, FR_calf_joint, ...); empty = the URDF's names"),
)


class FootIkNode(Node):
    """Joint angles for foot targets, one leg per message."""

    def __init__(self, **node_options: object) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        self._load_model()
        self._seeds: list[list[float] | None] = [None] * len(LEG_NAMES)
        self._counts: Counter[str] = Counter()
        self._last_status = ["none"] * len(LEG_NAMES)
        self._last_warnings: dict[str, float] = {}
        self._commands = self.create_publisher(JointState, "joint_commands", fk_node.OUTPUT_QOS)
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", fk_node.OUTPUT_QOS)
        for slot, leg in enumerate(LEG_NAMES):
            self.create_subscription(PointStamped, f"foot_targets/{leg}", self._on_target_of(slot), TARGETS_QOS)
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.get_logger().info(
            f"joint angles of {self._model.source} for targets in frame '{self._base_frame}' from "
            f"{self.resolve_topic_name('foot_targets')}/<leg> to {self.resolve_topic_name('joint_commands')}"
        )

    def _load_model(self) -> None:
        """The robot, the accepted target frame and the command names, from the parameters."""
        self._model: RobotConfig = load_robot(
            self._value("robot_description"), self._value("urdf_file"), self._value("foot_links"), self._value("joint_aliases")
        )
        quadruped = self._model.quadruped
        self._base_frame = self._value("base_frame") or quadruped.base_frame
        names = list(self._value("command_joint_names")) or list(quadruped.joint_names)
        if len(names) != len(quadruped.joint_names):
            raise LegFkError(f"command_joint_names must hold {len(quadruped.joint_names)} names, got {len(names)}: {names}")
        self._command_names = [names[slot * JOINTS_PER_LEG : (slot + 1) * JOINTS_PER_LEG] for slot in range(len(LEG_NAMES))]

    def _value(self, name: str):  # noqa: ANN202 (a parameter's value; [] for a string array never given one)
        try:
            return self.get_parameter(name).value
        except ParameterUninitializedException:
            return []

    # --- per message ---------------------------------------------------------------------

    def _on_target_of(self, slot: int) -> Callable[[PointStamped], None]:
        def on_target(msg: PointStamped) -> None:
            self._on_target(slot, msg)

        return on_target

    def _on_target(self, slot: int, msg: PointStamped) -> None:
        leg = LEG_NAMES[slot]
        self._counts["targets_received"] += 1
        frame = msg.header.frame_id
        if frame not in ("", self._base_frame):
            self._counts["rejected_frame"] += 1
            self._warn(f"frame/{leg}", f"leg {leg}: ignoring a target in frame '{frame}': only '{self._base_frame}' "
                       f"(or empty) is accepted, there is no TF here ({self._counts['rejected_frame']} so far)")
            return
        point = msg.point
        try:
            result = self._model.quadruped.ik_leg(leg, (point.x, point.y, point.z), self._seeds[slot])
        except LegFkError as error:
            self._counts["rejected_non_finite"] += 1
            self._warn(f"non_finite/{leg}", f"ignoring a target: {error} ({self._counts['rejected_non_finite']} so far)")
            return
        status = STATUS_NAMES[result.status]
        self._counts[f"{leg}_{status}"] += 1
        self._last_status[slot] = f"{status} ({result.residual_m:.3g} m)"
        if result.status != OK:
            self._warn(f"status/{leg}", f"leg {leg}: target ({point.x:.4f}, {point.y:.4f}, {point.z:.4f}) m is {status}; "
                       f"publishing the nearest in-limit angles, {result.residual_m:.4f} m from it")
        self._seeds[slot] = list(result.angles)
        command = JointState(name=self._command_names[slot], position=list(result.angles))
        command.header.stamp = msg.header.stamp
        self._commands.publish(command)

    def _warn(self, kind: str, text: str) -> None:
        now = time.monotonic()
        if now - self._last_warnings.get(kind, -math.inf) >= WARNING_INTERVAL_S:
            self._last_warnings[kind] = now
            self.get_logger().warn(text)

    # --- diagnostics -------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        if self._diagnostics.get_subscription_count() == 0:
            return
        counts = self._counts
        level, summary = DiagnosticStatus.OK, "joint commands published"
        if not counts["targets_received"]:
            level, summary = DiagnosticStatus.WARN, "no foot targets received yet"
        elif any(counts[f"{leg}_{status}"] for leg in LEG_NAMES for status in STATUS_NAMES[1:]) or counts["rejected_frame"]:
            level, summary = DiagnosticStatus.WARN, "some targets out of reach, outside the limits, or rejected"
        values = {
            "targets_received": counts["targets_received"],
            **{f"{leg}_{status}": counts[f"{leg}_{status}"] for leg in LEG_NAMES for status in STATUS_NAMES},
            **{f"{leg}_last_status": self._last_status[slot] for slot, leg in enumerate(LEG_NAMES)},
            "rejected_frame": counts["rejected_frame"],
            "rejected_non_finite": counts["rejected_non_finite"],
            "base_frame": self._base_frame,
            "model": self._model.source,
        }
        hardware_id = self._model.quadruped.model.name
        array = ros_glue.diagnostics(self, "foot inverse kinematics", level, summary, hardware_id, values)
        self._diagnostics.publish(array)


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk foot_ik_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node("foot_ik_node", FootIkNode, args)


if __name__ == "__main__":
    sys.exit(main())
