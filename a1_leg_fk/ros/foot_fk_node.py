"""``foot_fk_node``: sensor_msgs/JointState in, one geometry_msgs/PointStamped per foot out.

Thin ROS glue over :mod:`a1_leg_fk.tracking` (merging, rejection, FK per message) and
:mod:`a1_leg_fk.verify` (the ``verify_fk`` service). All topic and service names are
relative, so ``__ns`` and remaps work; every parameter is declared with a description.

The joint states are subscribed raw (serialized) and read by the bag tools' decoder
(:mod:`a1_leg_fk.recording.joint_state_wire`): no message object is built per JointState.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence
from typing import Unpack

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.service import Service
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from a1_leg_fk.kinematics.robot_config import RobotConfig
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.joint_state_wire import JointStateDecoder, WireError, doubles
from a1_leg_fk.ros import glue as ros_glue
from a1_leg_fk.ros.diagnostics import FkReport, PeriodCounter, fk_status
from a1_leg_fk.ros.glue import JOINT_STATES_QOS, OUTPUT_QOS
from a1_leg_fk.ros.markers import foot_markers
from a1_leg_fk.ros.robot_source import (
    BASE_FRAME_PARAMETER,
    ParameterSpec,
    RobotSource,
)
from a1_leg_fk.ros.serialized_output import SerializedStamped
from a1_leg_fk.tracking import REJECTIONS, Foot, FootTracker
from a1_leg_fk.verify import PyBulletFeet

NODE_NAME = "a1_leg_fk"
DIAGNOSTICS_PERIOD_S = 1.0
SUBSCRIBER_CHECK_PERIOD_S = 0.5

MARKER_RATE_RANGE_HZ = (0.001, 1000.0)
PUBLISH_RATE_RANGE_HZ = (0.0, 1_000_000.0)
VERIFY_TOLERANCE_RANGE_M = (1e-12, 1.0)
"""Inclusive ranges rclpy enforces (FloatingPointRange) on the node's double parameters."""

PARAMETERS = (
    BASE_FRAME_PARAMETER,
    ParameterSpec(
        "publish_velocities",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish foot_velocities/<leg> (J q_dot, m/s) when a message has the leg's three "
        "velocities",
    ),
    ParameterSpec(
        "publish_markers",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish foot_markers (MarkerArray) while someone subscribes",
    ),
    ParameterSpec(
        "marker_rate_hz",
        30.0,
        ParameterType.PARAMETER_DOUBLE,
        f"Highest rate of foot_markers [Hz], in {MARKER_RATE_RANGE_HZ}",
        value_range=MARKER_RATE_RANGE_HZ,
    ),
    ParameterSpec(
        "max_publish_rate_hz",
        0.0,
        ParameterType.PARAMETER_DOUBLE,
        "Highest rate of foot positions/velocities [Hz], in "
        f"{PUBLISH_RATE_RANGE_HZ}; 0 = one set per joint state (no throttling)",
        value_range=PUBLISH_RATE_RANGE_HZ,
    ),
    ParameterSpec(
        "enable_verify",
        True,
        ParameterType.PARAMETER_BOOL,
        "Offer the verify_fk service (compares the FK with PyBullet's)",
    ),
    ParameterSpec(
        "verify_tolerance_m",
        1e-6,
        ParameterType.PARAMETER_DOUBLE,
        "verify_fk succeeds when every foot is within this distance [m] of PyBullet's, in "
        f"{VERIFY_TOLERANCE_RANGE_M}",
        value_range=VERIFY_TOLERANCE_RANGE_M,
    ),
    ParameterSpec(
        "preserialized_output",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish the foot messages as bytes patched into a pre-serialized message (the same "
        "messages, cheaper); false = as message objects",
    ),
)
"""The node's own parameters; the model parameters are
:class:`a1_leg_fk.ros.robot_source.RobotSource`'s."""


class FootFkNode(Node):
    """Publishes the four feet of the robot for every JointState; offers ``verify_fk``."""

    def __init__(self, **node_options: Unpack[ros_glue.NodeOptions]) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        self._robot = RobotSource(self, self._on_robot)
        self._model = self._robot.config
        self._tracker = FootTracker(self._model.quadruped)
        self._decoder = JointStateDecoder()
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
        self._apply_settings()
        self._position_msgs = [PointStamped() for _ in LEG_NAMES]
        self._velocity_msgs = [Vector3Stamped() for _ in LEG_NAMES]
        self._set_frame_ids()
        self._position_pubs = [
            self.create_publisher(PointStamped, f"foot_positions/{leg}", OUTPUT_QOS)
            for leg in LEG_NAMES
        ]
        self._velocity_pubs = [
            self.create_publisher(Vector3Stamped, f"foot_velocities/{leg}", OUTPUT_QOS)
            for leg in LEG_NAMES
        ]
        self._marker_pub = self.create_publisher(MarkerArray, "foot_markers", OUTPUT_QOS)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", OUTPUT_QOS)
        self._load_verifier()
        self._update_verify_service()
        self.create_subscription(
            JointState,
            "joint_states",
            self._on_joint_state,
            JOINT_STATES_QOS,
            qos_overriding_options=QoSOverridingOptions.with_default_policies(),
            raw=True,
        )
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.create_timer(SUBSCRIBER_CHECK_PERIOD_S, self._check_subscribers)
        self.add_post_set_parameters_callback(self._after_set_parameters)
        self.get_logger().info(
            f"feet of {self._model.source} in frame '{self._base_frame}' from "
            f"{self.resolve_topic_name('joint_states')} to "
            f"{self.resolve_topic_name('foot_positions')}/<leg>"
        )

    # --- per message ---------------------------------------------------------------------

    def _on_joint_state(self, raw: bytes) -> None:
        try:
            fields = self._decoder.fields(raw)
        except WireError as error:
            self._warnings.warn("malformed", f"ignoring a joint_states message: {error}")
            return
        order = fields.order
        feet = self._tracker.update(
            self._decoder.names,
            doubles(fields.positions, order),
            doubles(fields.velocities, order),
            doubles(fields.efforts, order) if fields.efforts else (),
        )
        if self._tracker.new_unknown_names:
            self._warn_unknown_names()
        if self._tracker.last_problem:
            self._report_problem()
        if not feet:
            return
        now = time.monotonic()
        if now - self._last_publish < self._min_publish_interval_s:
            return
        self._last_publish = now
        sec, nanosec = self._stamp_of(fields.stamp_ns)
        if self._serialized is not None:
            self._publish_serialized(self._serialized, feet, sec, nanosec)
        else:
            self._publish_objects(feet, Time(sec=sec, nanosec=nanosec))
        if self._markers_wanted and now - self._last_markers >= self._marker_interval_s:
            self._last_markers = now
            self._publish_markers(Time(sec=sec, nanosec=nanosec))

    def _publish_objects(self, feet: list[Foot], stamp: Time) -> None:
        """Publish the feet as message objects (one reused message per leg and kind)."""
        for foot in feet:
            position_msg = self._position_msgs[foot.leg_slot]
            position_msg.header.stamp = stamp
            point = position_msg.point
            point.x, point.y, point.z = foot.position
            self._position_pubs[foot.leg_slot].publish(position_msg)
            if foot.velocity is not None and self._publish_velocities:
                velocity_msg = self._velocity_msgs[foot.leg_slot]
                velocity_msg.header.stamp = stamp
                vector = velocity_msg.vector
                vector.x, vector.y, vector.z = foot.velocity
                self._velocity_pubs[foot.leg_slot].publish(velocity_msg)

    def _publish_serialized(
        self, writer: SerializedStamped, feet: list[Foot], sec: int, nanosec: int
    ) -> None:
        """Publish the feet as pre-serialized bytes (same messages, cheaper than message
        objects).
        """
        serialized = writer.serialized
        velocities = self._publish_velocities
        for foot in feet:
            self._position_pubs[foot.leg_slot].publish(serialized(sec, nanosec, foot.position))
            if foot.velocity is not None and velocities:
                self._velocity_pubs[foot.leg_slot].publish(serialized(sec, nanosec, foot.velocity))

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
            foot_markers(self._model.quadruped, self._tracker.angles, self._base_frame, stamp)
        )

    def _publish_diagnostics(self) -> None:
        received, rejected = self._period.take(
            self._tracker.counts
        )  # the period runs unobserved too
        if self._diagnostics_pub.get_subscription_count() == 0:
            return
        robot = self._robot
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

    def _set_frame_ids(self) -> None:
        """Stamp the output messages with the base frame; the pre-serialized writer is None when
        ``preserialized_output`` is off or the rmw's CDR is not the one it patches.
        """
        for msg in (*self._position_msgs, *self._velocity_msgs):
            msg.header.frame_id = self._base_frame
        writer = SerializedStamped(self._base_frame) if self._preserialized_output else None
        self._serialized = writer if writer is not None and writer.usable else None

    def _on_robot(self, config: RobotConfig) -> None:
        """Another robot was accepted (a parameter or the description topic): start over with
        it.
        """
        self._model = config
        self._period.new_tracker(self._tracker.counts)
        self._tracker = FootTracker(config.quadruped)
        self._apply_settings()
        self._set_frame_ids()
        self._load_verifier()

    def _after_set_parameters(self, parameters: list[Parameter]) -> None:
        self._apply_settings()
        self._set_frame_ids()
        if any(p.name == "enable_verify" for p in parameters):
            self._load_verifier()
        self._update_verify_service()


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk foot_fk_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node("foot_fk_node", FootFkNode, args)


if __name__ == "__main__":
    sys.exit(main())
