"""``foot_fk_node``: sensor_msgs/JointState in, one geometry_msgs/PointStamped per foot out, and
with joint efforts the foot forces (geometry_msgs/WrenchStamped) and contacts (JointState).

Thin ROS glue over :mod:`a1_leg_fk.tracking` (merging, rejection, FK per message),
:mod:`a1_leg_fk.recording.forces` (the forces and contacts of ``a1-leg-fk bag --forces``, one
message at a time) and :mod:`a1_leg_fk.verify` (the ``verify_fk`` service); what it publishes per
message is :mod:`a1_leg_fk.ros.foot_output`'s. All topic and service names are relative, so
``__ns`` and remaps work; every parameter is declared with a description
(:mod:`a1_leg_fk.ros.foot_fk_parameters`). Gravity's direction for the forces comes from the
latest ``imu`` orientation (the IMU assumed aligned with the base frame), else the base's -z; a
gait scheduler's optional ``gait_phase`` is the contact filter's prior
(:mod:`a1_leg_fk.ros.gait_phase`).

The joint states are subscribed raw (serialized) and read by the bag tools' decoder
(:mod:`a1_leg_fk.wire.joint_state`): no message object is built per JointState.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence
from typing import Unpack

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.service import Service
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from a1_leg_fk.estimation.contact_estimator import ImuSample
from a1_leg_fk.estimation.force_pass import ForcePass
from a1_leg_fk.kinematics.robot_config import RobotConfig
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.ros import glue as ros_glue
from a1_leg_fk.ros.correction_choice import with_corrections
from a1_leg_fk.ros.diagnostics import FkReport, PeriodCounter, fk_status, force_values
from a1_leg_fk.ros.foot_fk_parameters import FORCE_PARAMETERS, PARAMETERS
from a1_leg_fk.ros.foot_output import FootOutput
from a1_leg_fk.ros.gait_phase import GaitPhaseInput
from a1_leg_fk.ros.glue import JOINT_STATES_QOS, OUTPUT_QOS
from a1_leg_fk.ros.guarded_input import GuardedInputs, read_imu
from a1_leg_fk.ros.joint_input import MissingMessages, joint_input
from a1_leg_fk.ros.markers import foot_markers
from a1_leg_fk.ros.odometry_wire import imu_sample
from a1_leg_fk.ros.robot_source import ParameterChoiceError, RobotSource
from a1_leg_fk.tracking import REJECTIONS, FootTracker, leg_feet
from a1_leg_fk.verify import PyBulletFeet
from a1_leg_fk.wire.imu import ImuFields
from a1_leg_fk.wire.joint_state import WireFields, doubles

NODE_NAME = "a1_leg_fk"
DIAGNOSTICS_PERIOD_S = 1.0
SUBSCRIBER_CHECK_PERIOD_S = 0.5


class FootFkNode(Node):
    """Publishes the four feet of the robot for every JointState; offers ``verify_fk``."""

    def __init__(self, **node_options: Unpack[ros_glue.NodeOptions]) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        message, topic, self._decoder = joint_input(self)  # before any output: a usage error
        self._inputs = GuardedInputs(self)
        self._robot = RobotSource(self, self._on_robot, self._inputs)
        self._model = self._robot.config
        self._tracker = FootTracker(self._model.quadruped)
        self._verifier: PyBulletFeet | None = None
        self._verifier_error = ""
        self._last_verify = "not called"
        self._verify_disagreed = (
            False  # the latest verify compared with PyBullet and found a foot off
        )
        self._verify_service: Service | None = None
        self._stamp_jumps_back = 0
        self._last_stamp_ns = 0
        self._last_publish = -math.inf
        self._last_markers = -math.inf
        self._markers_wanted = False
        self._period = PeriodCounter()
        self._warnings = ros_glue.WarnThrottle(self)
        self._imu = ImuSample()  # the latest imu
        self._contacts: list[float] | None = None  # the latest contact probabilities
        self._forces: ForcePass | None = None
        self._output = FootOutput(self)
        self._gait_phase = GaitPhaseInput(self._inputs, self._float("gait_phase_timeout_s"))
        self._apply_settings()
        self._set_frame_ids()
        self._build_forces()
        self._marker_pub = self.create_publisher(MarkerArray, "foot_markers", OUTPUT_QOS)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", OUTPUT_QOS)
        self._load_verifier()
        self._update_verify_service()
        self._inputs.subscribe(
            message,
            topic,
            self._decoder.fields,
            self._on_joint_state,
            JOINT_STATES_QOS,
            qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        )
        self._inputs.subscribe(Imu, "imu", read_imu, self._on_imu, JOINT_STATES_QOS)
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.create_timer(SUBSCRIBER_CHECK_PERIOD_S, self._check_subscribers)
        self.add_post_set_parameters_callback(self._after_set_parameters)
        self.get_logger().info(
            f"feet of {self._model.source} in frame '{self._base_frame}' from "
            f"{self.resolve_topic_name(topic)} to "
            f"{self.resolve_topic_name('foot_positions')}/<leg>"
        )

    # --- per message ---------------------------------------------------------------------

    def _on_joint_state(self, fields: WireFields) -> None:
        """One joint state's fields, read from its bytes by the input's decoder (a message that
        cannot be read never gets here: :class:`GuardedInputs`).
        """
        if self._decoder.imu is not None:  # a LowState's own IMU
            self._imu = imu_sample(self._decoder.imu)
        order = fields.order
        names = self._decoder.names
        efforts = doubles(fields.efforts, order) if fields.efforts else ()
        feet = self._tracker.update(
            names, doubles(fields.positions, order), doubles(fields.velocities, order), efforts
        )
        if self._tracker.new_unknown_names:
            self._warn_unknown_names()
        if self._tracker.last_problem:
            self._report_problem()
        if not feet:
            return
        forces = None
        now = time.monotonic()
        if self._forces is not None:  # every message: the contacts carry their state
            forces = self._forces.message(
                fields.stamp_ns or self.get_clock().now().nanoseconds,
                (
                    self._tracker.angles,
                    self._tracker.rates,
                    self._forces.message_efforts(names, efforts) if efforts else None,
                ),
                leg_feet(feet),
                self._imu,
                self._gait_phase.current(now),
            )
            self._contacts = forces.probabilities
        if now - self._last_publish < self._min_publish_interval_s:
            return
        self._last_publish = now
        sec, nanosec = self._stamp_of(fields.stamp_ns)
        self._output.feet(feet, sec, nanosec, self._publish_velocities)
        if forces is not None:
            self._output.forces(forces.forces, forces.normals, forces.probabilities, sec, nanosec)
        if self._markers_wanted and now - self._last_markers >= self._marker_interval_s:
            self._last_markers = now
            self._publish_markers(Time(sec=sec, nanosec=nanosec))

    def _on_imu(self, fields: ImuFields) -> None:
        """The IMU for the forces and contacts: gravity's direction from its orientation (the
        IMU aligned with the base; none: the base's -z), its gyro and accelerometer.
        """
        self._imu = imu_sample(fields)

    def _stamp_of(self, stamp_ns: int) -> tuple[int, int]:
        """(sec, nanosec) of the message's stamp [ns], or of the node clock's now where the stamp
        is zero.
        """
        if stamp_ns == 0:
            sec, nanosec = divmod(self.get_clock().now().nanoseconds, 1_000_000_000)
            return sec, nanosec
        if stamp_ns < self._last_stamp_ns:
            self._stamp_jumps_back += 1
            self._warnings.warn(
                "stamp_went_back",
                f"joint_states stamp went back by {(self._last_stamp_ns - stamp_ns) / 1e9:.3f} "
                f"s, from {self._last_stamp_ns / 1e9:.3f} to {stamp_ns / 1e9:.3f} (bag replay "
                "loop or clock reset?); publishing with the new stamps "
                f"({self._stamp_jumps_back} jumps back so far)",
            )
        self._last_stamp_ns = stamp_ns
        sec, nanosec = divmod(stamp_ns, 1_000_000_000)
        return sec, nanosec

    def _report_problem(self) -> None:
        """Warn about a rejected message or joint, at most once a second per kind of problem."""
        tracker = self._tracker
        outcome = tracker.last_outcome
        if outcome in REJECTIONS:
            self._warnings.warn(
                outcome,
                f"rejected a joint_states message: {outcome.replace('_', ' ')}, "
                f"{tracker.last_problem} ({tracker.counts.outcomes[outcome]} such messages so "
                "far)",
            )
        else:
            self._warnings.warn(
                "non_finite_position",
                f"ignoring a joint_states value: {tracker.last_problem}; its leg is not "
                f"published from this message ({tracker.counts.non_finite_joints} such values so "
                "far)",
            )

    def _warn_unknown_names(self) -> None:
        names = self._tracker.take_new_unknown_names()
        self.get_logger().warn(
            f"ignoring joint names not in the model (warned once per name): {names[:20]}"
        )

    # --- markers and diagnostics ----------------------------------------------------------

    def _check_subscribers(self) -> None:
        self._markers_wanted = (
            self._publish_markers_enabled and self._marker_pub.get_subscription_count() > 0
        )

    def _publish_markers(self, stamp: Time) -> None:
        self._marker_pub.publish(
            foot_markers(
                self._model.quadruped,
                self._tracker.angles,
                self._base_frame,
                stamp,
                self._contacts,
            )
        )

    def _publish_diagnostics(self) -> None:
        received, rejected = self._period.take(
            self._tracker.counts
        )  # the period runs unobserved too
        inputs_rejected = self._inputs.rejected_since()
        if self._diagnostics_pub.get_subscription_count() == 0:
            return
        robot, problem, phase = self._robot, self._forces_problem, self._gait_phase.status()
        refused = self._corrections_refused
        report = FkReport(
            counts=self._tracker.counts,
            received_in_period=received,
            rejected_in_period=rejected,
            period_s=DIAGNOSTICS_PERIOD_S,
            joints_outside_limits=self._tracker.joints_outside_limits(),
            stamp_jumps_back=self._stamp_jumps_back,
            model=self._model.source,
            description_topic=robot.topic_name,
            description_status=robot.topic_status,
            description_rejected=robot.topic_rejected,
            last_verify=self._last_verify,
            verify_disagreed=self._verify_disagreed,
            forces=force_values(self._forces, problem, self._imu, phase, refused),
            inputs_rejected_in_period=inputs_rejected,
            inputs_rejected=self._inputs.values(),
        )
        level, summary, values = fk_status(report)
        hardware_id = self._model.quadruped.model.name
        self._diagnostics_pub.publish(
            ros_glue.diagnostics(self, "foot kinematics", level, summary, hardware_id, values)
        )

    # --- verify_fk -------------------------------------------------------------------------

    def _load_verifier(self) -> None:
        """(Re)load the PyBullet twin of the current model, once per model; never raises."""
        if self._verifier is not None:
            self._verifier.close()
        self._verifier = None
        if not self._enable_verify:
            return
        try:
            self._verifier = PyBulletFeet(self._model.quadruped, self._model.urdf_xml)
            self._verifier_error = ""
        except LegFkError as error:
            self._verifier_error = str(error)
            self.get_logger().warn(f"verify_fk will fail: {error}")

    def _update_verify_service(self) -> None:
        if self._enable_verify and self._verify_service is None:
            self._verify_service = self.create_service(Trigger, "verify_fk", self._on_verify)
        elif not self._enable_verify and self._verify_service is not None:
            self.destroy_service(self._verify_service)
            self._verify_service = None

    def _on_verify(
        self, _request: Trigger.Request, response: Trigger.Response
    ) -> Trigger.Response:
        response.success, response.message = self._verify()
        self._last_verify = ("passed " if response.success else "failed ") + response.message
        return response

    def _verify(self) -> tuple[bool, str]:
        if not self._tracker.complete:
            missing = [
                name
                for name, a in zip(self._model.quadruped.joint_names, self._tracker.angles)
                if math.isnan(a)
            ]
            return False, f"no complete joint state yet: missing {','.join(missing)}"
        if self._verifier is None:
            if not self._verifier_error:  # enabled after a failure or first use
                self._load_verifier()
            if self._verifier is None:
                return False, f"cannot verify: {self._verifier_error}"
        angles = list(self._tracker.angles)
        result = self._verifier.verify(angles, self._verify_tolerance_m)
        self._verify_disagreed = not result.success
        stamp_ns = self._last_stamp_ns
        outside = self._tracker.joints_outside_limits()
        tokens = [f"max_error_m={result.max_error_m:.3g}"]
        tokens += [f"{leg}={error:.3g}" for leg, error in result.errors_m.items()]
        tokens += [
            f"tolerance_m={self._verify_tolerance_m:g}",
            f"stamp={stamp_ns // 1_000_000_000}.{stamp_ns % 1_000_000_000:09d}",
            f"outside_limits={','.join(outside) or 'none'}",
        ]
        return result.success, " ".join(tokens)

    # --- parameters ------------------------------------------------------------------------

    def _float(self, name: str) -> float:
        # ParameterValue (an untyped message): its double_value field is a float.
        return float(self.get_parameter(name).get_parameter_value().double_value)

    def _bool(self, name: str) -> bool:
        return bool(self.get_parameter(name).get_parameter_value().bool_value)

    def _apply_settings(self) -> None:
        """Read the node's parameters; rclpy has checked their types and ranges already."""
        self._base_frame = self._robot.base_frame({})
        self._publish_velocities = self._bool("publish_velocities")
        self._publish_markers_enabled = self._bool("publish_markers")
        self._marker_interval_s = 1.0 / self._float("marker_rate_hz")
        rate = self._float("max_publish_rate_hz")
        self._min_publish_interval_s = 1.0 / rate if rate > 0 else 0.0
        self._enable_verify = self._bool("enable_verify")
        self._verify_tolerance_m = self._float("verify_tolerance_m")
        self._preserialized_output = self._bool("preserialized_output")
        self._gait_phase.timeout_s = self._float("gait_phase_timeout_s")

    def _set_frame_ids(self) -> None:
        self._output.configure(self._base_frame, self._preserialized_output)

    def _build_forces(self) -> None:
        """The force and contact rules for the current robot and thresholds; none while
        ``publish_forces`` is off or the URDF or thresholds do not allow them (with a warning).
        """
        self._forces, self._contacts, self._forces_problem = None, None, "off"
        self._corrections_refused = ""
        if not self._bool("publish_forces"):
            return
        touchdown, liftoff = (
            self._float(name) or None for name in ("touchdown_force_n", "liftoff_force_n")
        )
        model, rule = (self.get_parameter(name).value for name in ("force_model", "contact_rule"))
        try:
            self._forces, self._corrections_refused = with_corrections(
                self,
                lambda fixes: ForcePass(
                    self._model.quadruped, (touchdown, liftoff), model, rule, fixes
                ),
            )
        except LegFkError as error:
            self._forces_problem = f"none: {error}"
            self.get_logger().warn(f"no foot forces: {error}")

    def _on_robot(self, config: RobotConfig) -> None:
        """Another robot was accepted (a parameter or the description topic): start over with
        it.
        """
        self._model = config
        self._period.new_tracker(self._tracker.counts)
        self._tracker = FootTracker(config.quadruped)
        self._apply_settings()
        self._set_frame_ids()
        self._build_forces()
        self._load_verifier()

    def _after_set_parameters(self, parameters: list[Parameter]) -> None:
        self._apply_settings()
        self._set_frame_ids()
        if any(p.name in FORCE_PARAMETERS for p in parameters):
            self._build_forces()
        if any(p.name == "enable_verify" for p in parameters):
            self._load_verifier()
        self._update_verify_service()


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk foot_fk_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node(
        "foot_fk_node", FootFkNode, args, (MissingMessages, ParameterChoiceError)
    )


if __name__ == "__main__":
    sys.exit(main())
