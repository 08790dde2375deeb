"""``foot_ik_node``: one geometry_msgs/PointStamped target per foot in, sensor_msgs/JointState
commands out (that leg's three joints).

Thin ROS glue over :meth:`Quadruped.ik_leg` (:mod:`a1_leg_fk.kinematics.ik.four_legs`). Subscribes
``foot_targets/<leg>`` (frame: the base frame, or empty; there is no TF here, so any other frame is
rejected with a warning naming it), publishes ``joint_commands`` with the target's stamp, seeded
with the leg's previous solution. Every answer is published, the best angles for a target out of
reach or out of limits included; the statuses are counted in ``/diagnostics`` and warned about at
most once a second per leg. The robot comes from :class:`a1_leg_fk.ros.robot_source.RobotSource`,
exactly as for ``foot_fk_node`` (its parameters and the ``robot_description`` topic). All names
are relative.
"""

from __future__ import annotations

import sys
from collections import Counter
from collections.abc import Callable, Sequence
from typing import Unpack

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PointStamped
from rcl_interfaces.msg import ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from a1_leg_fk.kinematics.ik.four_legs import OK, STATUS_NAMES
from a1_leg_fk.kinematics.robot_config import RobotConfig
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.ros import glue as ros_glue
from a1_leg_fk.ros.diagnostics import INPUTS_REJECTED, robot_description_status
from a1_leg_fk.ros.glue import JOINT_STATES_QOS, OUTPUT_QOS
from a1_leg_fk.ros.guarded_input import GuardedInputs, message_reader
from a1_leg_fk.ros.robot_source import (
    BASE_FRAME_PARAMETER,
    ParameterSpec,
    RobotSource,
    parameter_values,
    string_list,
)

NODE_NAME = "a1_leg_ik"
DIAGNOSTICS_PERIOD_S = 1.0
TARGETS_QOS = JOINT_STATES_QOS  # best effort, deep: hears reliable and best-effort publishers

PARAMETERS = (
    BASE_FRAME_PARAMETER,
    ParameterSpec(
        "command_joint_names",
        None,
        ParameterType.PARAMETER_STRING_ARRAY,
        "12 joint names for joint_commands in FR, FL, RR, RL x root-to-foot order "
        "(e.g. FR_hip_joint, FR_thigh_joint, FR_calf_joint, ...); empty = the URDF's names",
    ),
)
"""The node's own parameters; the model parameters are :class:`RobotSource`'s. Targets must be in
``base_frame`` (or have an empty frame_id)."""


class FootIkNode(Node):
    """Joint angles for foot targets, one leg per message."""

    def __init__(self, **node_options: Unpack[ros_glue.NodeOptions]) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        self._inputs = GuardedInputs(self)
        self._robot = RobotSource(self, self._on_robot, self._inputs)
        self._model: RobotConfig = self._robot.config
        self._apply_settings(self._settings({}))
        self._seeds: list[list[float] | None] = [None] * len(LEG_NAMES)
        self._counts: Counter[str] = Counter()  # targets_received, rejected_frame, ...
        # per leg slot: targets answered with each status code; the latest (code, residual [m])
        self._status_counts = [[0] * len(STATUS_NAMES) for _ in LEG_NAMES]
        self._last_result: list[tuple[int, float] | None] = [None] * len(LEG_NAMES)
        self._warnings = ros_glue.WarnThrottle(self)
        self._pending_settings: tuple[str, list[list[str]]] | None = None
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._after_set_parameters)
        self._commands = self.create_publisher(JointState, "joint_commands", OUTPUT_QOS)
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", OUTPUT_QOS)
        read_target = message_reader(PointStamped)
        for slot, leg in enumerate(LEG_NAMES):
            self._inputs.subscribe(
                PointStamped,
                f"foot_targets/{leg}",
                read_target,
                self._on_target_of(slot),
                TARGETS_QOS,
            )
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.get_logger().info(
            f"joint angles of {self._model.source} for targets in frame '{self._base_frame}' from "
            f"{self.resolve_topic_name('foot_targets')}/<leg> to "
            f"{self.resolve_topic_name('joint_commands')}"
        )

    def _settings(self, changes: dict[str, object]) -> tuple[str, list[list[str]]]:
        """(accepted target frame, command names per leg) for the parameters with ``changes``."""
        value = parameter_values(self, ("command_joint_names",), changes)
        quadruped = self._model.quadruped
        names = string_list(value["command_joint_names"]) or list(quadruped.joint_names)
        if len(names) != len(quadruped.joint_names):
            raise LegFkError(
                f"command_joint_names must hold {len(quadruped.joint_names)} names, got "
                f"{len(names)}: {names}"
            )
        per_leg = [
            names[slot * JOINTS_PER_LEG : (slot + 1) * JOINTS_PER_LEG]
            for slot in range(len(LEG_NAMES))
        ]
        return self._robot.base_frame(changes), per_leg

    def _apply_settings(self, settings: tuple[str, list[list[str]]]) -> None:
        self._base_frame, self._command_names = settings

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        try:
            self._pending_settings = self._settings({p.name: p.value for p in parameters})
        except LegFkError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _after_set_parameters(self, _parameters: list[Parameter]) -> None:
        if self._pending_settings is not None:
            self._apply_settings(self._pending_settings)
            self._pending_settings = None

    def _on_robot(self, config: RobotConfig) -> None:
        """Another robot was accepted (a parameter or the description topic): start over with
        it.
        """
        self._model = config
        self._apply_settings(self._settings({}))
        self._seeds = [None] * len(LEG_NAMES)

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
            self._warnings.warn(
                f"frame/{leg}",
                f"leg {leg}: ignoring a target in frame '{frame}': only '{self._base_frame}' "
                "(or empty) is accepted, there is no TF here "
                f"({self._counts['rejected_frame']} so far)",
            )
            return
        point = msg.point
        try:
            result = self._model.quadruped.ik_leg(
                leg, (point.x, point.y, point.z), self._seeds[slot]
            )
        except LegFkError as error:
            self._counts["rejected_non_finite"] += 1
            self._warnings.warn(
                f"non_finite/{leg}",
                f"ignoring a target: {error} ({self._counts['rejected_non_finite']} so far)",
            )
            return
        self._status_counts[slot][result.status] += 1
        self._last_result[slot] = (result.status, result.residual_m)
        if result.status != OK:
            self._warnings.warn(
                f"status/{leg}",
                f"leg {leg}: target ({point.x:.4f}, {point.y:.4f}, {point.z:.4f}) m is "
                f"{STATUS_NAMES[result.status]}; "
                f"publishing the nearest in-limit angles, {result.residual_m:.4f} m from it",
            )
        self._seeds[slot] = list(result.angles)
        command = JointState(name=self._command_names[slot], position=list(result.angles))
        command.header.stamp = msg.header.stamp
        self._commands.publish(command)

    # --- diagnostics -------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        if self._diagnostics.get_subscription_count() == 0:
            return
        counts = self._counts
        level, summary = DiagnosticStatus.OK, "joint commands published"
        if self._inputs.rejected_since():
            level, summary = DiagnosticStatus.WARN, INPUTS_REJECTED
        if not counts["targets_received"]:
            level, summary = DiagnosticStatus.WARN, "no foot targets received yet"
        elif (
            any(n for row in self._status_counts for code, n in enumerate(row) if code != OK)
            or counts["rejected_frame"]
        ):
            level, summary = (
                DiagnosticStatus.WARN,
                "some targets out of reach, outside the limits, or rejected",
            )
        robot = self._robot
        level, summary, description = robot_description_status(
            level,
            summary,
            self._model.source,
            robot.topic_name,
            robot.topic_status,
            robot.topic_rejected,
        )
        values = {
            "targets_received": counts["targets_received"],
            **{
                f"{leg}_{status}": self._status_counts[slot][code]
                for slot, leg in enumerate(LEG_NAMES)
                for code, status in enumerate(STATUS_NAMES)
            },
            **{
                f"{leg}_last_status": _last_status(self._last_result[slot])
                for slot, leg in enumerate(LEG_NAMES)
            },
            "rejected_frame": counts["rejected_frame"],
            "rejected_non_finite": counts["rejected_non_finite"],
            "base_frame": self._base_frame,
            **description,
            **self._inputs.values(),
        }
        hardware_id = self._model.quadruped.model.name
        array = ros_glue.diagnostics(
            self, "foot inverse kinematics", level, summary, hardware_id, values
        )
        self._diagnostics.publish(array)


def _last_status(last: tuple[int, float] | None) -> str:
    """A leg's ``<leg>_last_status`` diagnostics value: "none", or the status name and the
    residual [m] of its latest target.
    """
    if last is None:
        return "none"
    code, residual_m = last
    return f"{STATUS_NAMES[code]} ({residual_m:.3g} m)"


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk foot_ik_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node("foot_ik_node", FootIkNode, args)


if __name__ == "__main__":
    sys.exit(main())
