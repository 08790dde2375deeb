"""``foot_fk_node``: sensor_msgs/JointState in, one geometry_msgs/PointStamped per foot out.

Thin ROS glue over :mod:`a1_leg_fk.joint_state` (merging, rejection, FK per message) and
:mod:`a1_leg_fk.pybullet_check` (the ``verify_fk`` service). All topic and service names are
relative, so ``__ns`` and remaps work; every parameter is declared with a description.
"""

from __future__ import annotations

import math
import struct
import sys
import time
from typing import Sequence

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Point, PointStamped, Vector3Stamped
from rcl_interfaces.msg import ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

from a1_leg_fk import ros_glue
from a1_leg_fk.joint_state import REJECTIONS, Foot, FootTracker
from a1_leg_fk.legs import LEG_NAMES
from a1_leg_fk.pybullet_check import PyBulletFeet
from a1_leg_fk.robot_config import RobotConfig
from a1_leg_fk.robot_source import BASE_FRAME_PARAMETER, ParameterSpec, RobotSource, parameter_value
from a1_leg_fk.urdf import LegFkError

NODE_NAME = "a1_leg_fk"
DIAGNOSTICS_PERIOD_S = 1.0
SUBSCRIBER_CHECK_PERIOD_S = 0.5
OUTPUT_QOS = QoSProfile(depth=10)  # reliable: heard by reliable and best-effort subscribers
JOINT_STATES_QOS = QoSProfile(
    # The sensor-data profile (best effort: hears reliable and best-effort publishers alike), with a
    # deeper queue than its 5, so that a burst of a 1 kHz stream is not overwritten while we work.
    history=qos_profile_sensor_data.history,
    depth=100,
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=qos_profile_sensor_data.durability,
)


PARAMETERS = (
    BASE_FRAME_PARAMETER,
    ParameterSpec("publish_velocities", True, ParameterType.PARAMETER_BOOL,
                  "Publish foot_velocities/<leg> (J q_dot, m/s) when a message has the leg's three velocities"),
    ParameterSpec("publish_markers", True, ParameterType.PARAMETER_BOOL,
                  "Publish foot_markers (MarkerArray) while someone subscribes"),
    ParameterSpec("marker_rate_hz", 30.0, ParameterType.PARAMETER_DOUBLE,
                  "Highest rate of foot_markers [Hz], > 0"),
    ParameterSpec("max_publish_rate_hz", 0.0, ParameterType.PARAMETER_DOUBLE,
                  "Highest rate of foot positions/velocities [Hz]; 0 = one set per joint state (no throttling)"),
    ParameterSpec("enable_verify", True, ParameterType.PARAMETER_BOOL,
                  "Offer the verify_fk service (compares the FK with PyBullet's)"),
    ParameterSpec("verify_tolerance_m", 1e-6, ParameterType.PARAMETER_DOUBLE,
                  "verify_fk succeeds when every foot is within this distance [m] of PyBullet's, > 0"),
)
"""The node's own parameters; the model parameters are :class:`a1_leg_fk.robot_source.RobotSource`'s."""


class _SerializedStamped:
    """A PointStamped/Vector3Stamped (same CDR layout: a Header, then three float64) serialized once.

    :meth:`serialized` patches a stamp and three values [m or m/s] into the bytes, so a publish
    skips rclpy's Python -> C conversion and serialization of the message (about a third of the
    cost of a publish). ``usable`` is False unless the rmw writes the little-endian CDR this
    expects (checked on a probe message); the node then publishes message objects.
    """

    _PROBE = (1.25, -2.5, 3.75)
    _STAMP = struct.Struct("<iI")  # builtin_interfaces/Time right after the 4-byte encapsulation header
    _VALUES = struct.Struct("<3d")

    def __init__(self, frame_id: str) -> None:
        probes = (PointStamped(), Vector3Stamped())
        for probe, values in zip(probes, (probes[0].point, probes[1].vector)):
            probe.header.frame_id = frame_id
            probe.header.stamp.sec, probe.header.stamp.nanosec = 7, 9
            values.x, values.y, values.z = self._PROBE
        data = [serialize_message(probe) for probe in probes]
        self._offset = data[0].find(self._VALUES.pack(*self._PROBE))
        string_end = 16 + len(frame_id.encode()) + 1  # header, sec, nanosec, length, text, NUL
        self.usable = (
            data[0][:4] == b"\x00\x01\x00\x00"
            and data[0][4:12] == self._STAMP.pack(7, 9)
            and string_end <= self._offset == data[1].find(self._VALUES.pack(*self._PROBE))
            and len(data[0]) == len(data[1]) == self._offset + self._VALUES.size
        )
        self._buffer = bytearray(data[0])
        self._buffer[string_end : self._offset] = bytes(self._offset - string_end)  # zero the padding

    def serialized(self, sec: int, nanosec: int, values: tuple[float, float, float]) -> bytes:
        buffer = self._buffer
        self._STAMP.pack_into(buffer, 4, sec, nanosec)
        self._VALUES.pack_into(buffer, self._offset, *values)
        return bytes(buffer)


class FootFkNode(Node):
    """Publishes the four feet of the robot for every JointState; offers ``verify_fk``."""

    def __init__(self, **node_options: object) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        self._robot = RobotSource(self, self._on_robot)
        self._model = self._robot.config
        self._tracker = FootTracker(self._model.quadruped)
        self._verifier: PyBulletFeet | None = None
        self._verifier_error = ""
        self._last_verify = "not called"
        self._verify_disagreed = False  # the latest verify compared with PyBullet and found a foot off
        self._verify_service = None
        self._stamp_jumps_back = 0
        self._last_stamp_ns = 0
        self._last_publish = -math.inf
        self._last_markers = -math.inf
        self._markers_wanted = False
        self._previous_counts = (0, 0)
        self._warnings = ros_glue.WarnThrottle(self)
        self._apply_settings()
        self._position_msgs = [PointStamped() for _ in LEG_NAMES]
        self._velocity_msgs = [Vector3Stamped() for _ in LEG_NAMES]
        self._set_frame_ids()
        self._position_pubs = [self.create_publisher(PointStamped, f"foot_positions/{leg}", OUTPUT_QOS) for leg in LEG_NAMES]
        self._velocity_pubs = [self.create_publisher(Vector3Stamped, f"foot_velocities/{leg}", OUTPUT_QOS) for leg in LEG_NAMES]
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
        )
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.create_timer(SUBSCRIBER_CHECK_PERIOD_S, self._check_subscribers)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._after_set_parameters)
        self.get_logger().info(
            f"feet of {self._model.source} in frame '{self._base_frame}' from "
            f"{self.resolve_topic_name('joint_states')} to {self.resolve_topic_name('foot_positions')}/<leg>"
        )

    # --- per message ---------------------------------------------------------------------

    def _on_joint_state(self, msg: JointState) -> None:
        feet = self._tracker.update(msg.name, msg.position, msg.velocity)
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
        stamp = self._stamp_of(msg)
        if self._serialized.usable:
            self._publish_serialized(feet, stamp.sec, stamp.nanosec)
            feet = ()
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
        if self._markers_wanted and now - self._last_markers >= self._marker_interval_s:
            self._last_markers = now
            self._publish_markers(stamp)

    def _publish_serialized(self, feet: list[Foot], sec: int, nanosec: int) -> None:
        """Publish the feet as pre-serialized bytes (same messages, cheaper than message objects)."""
        serialized = self._serialized.serialized
        velocities = self._publish_velocities
        for foot in feet:
            self._position_pubs[foot.leg_slot].publish(serialized(sec, nanosec, foot.position))
            if foot.velocity is not None and velocities:
                self._velocity_pubs[foot.leg_slot].publish(serialized(sec, nanosec, foot.velocity))

    def _stamp_of(self, msg: JointState):  # noqa: ANN202 (builtin_interfaces/Time)
        """The message's stamp, or the node clock's now where the stamp is zero."""
        stamp = msg.header.stamp
        stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        if stamp_ns == 0:
            return self.get_clock().now().to_msg()
        if stamp_ns < self._last_stamp_ns:
            self._stamp_jumps_back += 1
            self._warnings.warn(
                "stamp_went_back",
                f"joint_states stamp went back by {(self._last_stamp_ns - stamp_ns) / 1e9:.3f} s, from "
                f"{self._last_stamp_ns / 1e9:.3f} to {stamp_ns / 1e9:.3f} (bag replay loop or clock reset?); "
                f"publishing with the new stamps ({self._stamp_jumps_back} jumps back so far)",
            )
        self._last_stamp_ns = stamp_ns
        return stamp

    def _report_problem(self) -> None:
        """Warn about a rejected message or joint, at most once a second per kind of problem."""
        tracker = self._tracker
        outcome = tracker.last_outcome
        if outcome in REJECTIONS:
            self._warnings.warn(
                outcome,
                f"rejected a joint_states message: {outcome.replace('_', ' ')}, {tracker.last_problem} "
                f"({tracker.counts.outcomes[outcome]} such messages so far)",
            )
        else:
            self._warnings.warn(
                "non_finite_position",
                f"ignoring a joint_states value: {tracker.last_problem}; its leg is not published from this "
                f"message ({tracker.counts.non_finite_joints} such values so far)",
            )

    def _warn_unknown_names(self) -> None:
        names = self._tracker.take_new_unknown_names()
        self.get_logger().warn(f"ignoring joint names not in the model (warned once per name): {names[:20]}")

    # --- markers and diagnostics ----------------------------------------------------------

    def _check_subscribers(self) -> None:
        self._markers_wanted = self._publish_markers_enabled and self._marker_pub.get_subscription_count() > 0

    def _publish_markers(self, stamp) -> None:  # noqa: ANN001
        markers = MarkerArray()
        angles = self._tracker.angles
        for slot, leg in enumerate(self._model.quadruped.legs):
            leg_angles = angles[3 * slot : 3 * slot + 3]
            if any(math.isnan(a) for a in leg_angles):
                continue
            points = [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in leg.joint_points(leg_angles)]
            markers.markers.append(self._marker(stamp, 2 * slot, Marker.SPHERE, points[-1:], leg.chain.leg))
            markers.markers.append(self._marker(stamp, 2 * slot + 1, Marker.LINE_STRIP, points, leg.chain.leg))
        self._marker_pub.publish(markers)

    def _marker(self, stamp, marker_id: int, kind: int, points: list[Point], leg: str) -> Marker:  # noqa: ANN001
        marker = Marker(ns=f"feet/{leg}", id=marker_id, type=kind, action=Marker.ADD)
        marker.header.frame_id = self._base_frame
        marker.header.stamp = stamp
        marker.pose.orientation.w = 1.0
        if kind == Marker.SPHERE:
            marker.pose.position = points[0]
            marker.scale.x = marker.scale.y = marker.scale.z = 0.04
        else:
            marker.points = points
            marker.scale.x = 0.015
        marker.color.r, marker.color.g, marker.color.b, marker.color.a = (0.1, 0.6, 1.0, 1.0)
        return marker

    def _publish_diagnostics(self) -> None:
        counts = self._tracker.counts
        received, feet = counts.messages, counts.feet
        rate_hz = (received - self._previous_counts[0]) / DIAGNOSTICS_PERIOD_S
        rejected_now = sum(counts.outcomes[r] for r in REJECTIONS) - self._previous_counts[1]
        self._previous_counts = (received, sum(counts.outcomes[r] for r in REJECTIONS))
        if self._diagnostics_pub.get_subscription_count() == 0:
            return
        outside = self._tracker.joints_outside_limits()
        level, summary = DiagnosticStatus.OK, "feet published"
        if not received:
            level, summary = DiagnosticStatus.WARN, "no joint_states received yet"
        elif rejected_now or outside or counts.non_finite_joints:
            level, summary = DiagnosticStatus.WARN, "some joint_states rejected or joints outside limits"
        if self._robot.topic_rejected:
            level, summary = DiagnosticStatus.WARN, f"robot description on {self._robot.topic_name} rejected"
        if self._verify_disagreed:
            level, summary = DiagnosticStatus.ERROR, "verify_fk: FK disagrees with PyBullet beyond the tolerance"
        values = {
            "messages_received": received,
            **{f"messages_{outcome}": n for outcome, n in sorted(counts.outcomes.items())},
            "non_finite_joint_values": counts.non_finite_joints,
            "feet_published": feet,
            "input_rate_hz": f"{rate_hz:.1f}",
            "joints_outside_limits": ",".join(outside) or "none",
            "messages_out_of_limits": counts.out_of_limit_messages,
            "unknown_joint_names": ",".join(sorted(counts.unknown_names)[:20]) or "none",
            "stamp_jumps_back": self._stamp_jumps_back,
            "last_verify": self._last_verify,
            "model": self._model.source,
            "robot_description_topic": f"{self._robot.topic_name or 'none'}: {self._robot.topic_status}",
        }
        hardware_id = self._model.quadruped.model.name
        self._diagnostics_pub.publish(ros_glue.diagnostics(self, "foot kinematics", level, summary, hardware_id, values))

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

    def _on_verify(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success, response.message = self._verify()
        self._last_verify = ("passed " if response.success else "failed ") + response.message
        return response

    def _verify(self) -> tuple[bool, str]:
        if not self._tracker.complete:
            missing = [name for name, a in zip(self._model.quadruped.joint_names, self._tracker.angles) if math.isnan(a)]
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

    def _value(self, name: str) -> object:
        return parameter_value(self, name)

    def _apply_settings(self) -> None:
        value = self._value
        self._base_frame = value("base_frame") or self._model.quadruped.base_frame
        self._publish_velocities = bool(value("publish_velocities"))
        self._publish_markers_enabled = bool(value("publish_markers"))
        self._marker_interval_s = 1.0 / value("marker_rate_hz")
        rate = value("max_publish_rate_hz")
        self._min_publish_interval_s = 1.0 / rate if rate > 0 else 0.0
        self._enable_verify = bool(value("enable_verify"))
        self._verify_tolerance_m = float(value("verify_tolerance_m"))

    def _set_frame_ids(self) -> None:
        for msg in (*self._position_msgs, *self._velocity_msgs):
            msg.header.frame_id = self._base_frame
        self._serialized = _SerializedStamped(self._base_frame)

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        problem = _invalid_setting({p.name: p.value for p in parameters})
        return SetParametersResult(successful=not problem, reason=problem)

    def _on_robot(self, config: RobotConfig) -> None:
        """Another robot was accepted (a parameter or the description topic): start over with it."""
        self._model = config
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


def _invalid_setting(changes: dict[str, object]) -> str:
    """Why a parameter change is unacceptable, or '' when it is fine."""
    for name in ("marker_rate_hz", "verify_tolerance_m"):
        if name in changes and not (isinstance(changes[name], float) and math.isfinite(changes[name]) and changes[name] > 0):
            return f"{name} must be a finite number > 0, got {changes[name]!r}"
    rate = changes.get("max_publish_rate_hz", 0.0)
    if not (isinstance(rate, float) and math.isfinite(rate) and rate >= 0):
        return f"max_publish_rate_hz must be a finite number >= 0, got {rate!r}"
    return ""


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk foot_fk_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node("foot_fk_node", FootFkNode, args)


if __name__ == "__main__":
    sys.exit(main())
