"""``leg_odometry_node``: sensor_msgs/JointState (+ sensor_msgs/Imu) in, nav_msgs/Odometry out,
and the local ground under the base (geometry_msgs/PoseWithCovarianceStamped on ``ground``).

Thin ROS glue over :mod:`a1_leg_fk.estimation.odometry_feed`, the pipeline ``a1-leg-fk odom``
runs on bags. The robot comes from :class:`~a1_leg_fk.ros.robot_source.RobotSource` and joint
states follow :class:`~a1_leg_fk.tracking.FootTracker`'s rules, as in ``foot_fk_node``. Each
accepted joint state with velocities gives one ``leg_odometry`` message, stamped with the joint
state's stamp: pose in ``odom_frame``, twist in the base frame (``child_frame_id``). An IMU sample
is paired with a joint state by stamp (the latest at or before it, :class:`ImuBuffer`); a joint
state stamped after the newest IMU sample waits for its own (parameter ``imu_wait_s``, at most
:data:`~a1_leg_fk.estimation.imu_pairing.WALL_WAIT_S` of wall time: :class:`ImuPairing`).

The estimate is the state filter's (:mod:`a1_leg_fk.estimation.state_filter`: IMU-propagated,
gated leg velocities) while IMU samples carry an accelerometer, else the legs alone. Contacts
(parameter ``contacts``): the contact filter's probabilities from the efforts' foot forces and the
feet's kinematics (``auto``, ``force``) or the kinematics alone (``kinematic``), as in ``a1-leg-fk
odom`` (:data:`~a1_leg_fk.estimation.odometry_feed.CONTACT_SOURCES`).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Sequence
from typing import Unpack

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Imu

from a1_leg_fk.estimation.filter_model import GROUND_MODELS
from a1_leg_fk.estimation.ground_outputs import plane_pose
from a1_leg_fk.estimation.imu import MAX_ANGULAR_RATE_RADPS, imu_reading
from a1_leg_fk.estimation.imu_pairing import WALL_WAIT_S, ImuPairing
from a1_leg_fk.estimation.odometry import OdometrySample, OdometrySettings
from a1_leg_fk.estimation.odometry_feed import (
    CONTACT_SOURCES,
    KINEMATIC,
    Foot,
    OdometryFeed,
)
from a1_leg_fk.kinematics.robot_config import RobotConfig
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.ros import glue as ros_glue
from a1_leg_fk.ros.correction_choice import with_corrections
from a1_leg_fk.ros.diagnostics import PeriodCounter
from a1_leg_fk.ros.glue import JOINT_STATES_QOS, OUTPUT_QOS
from a1_leg_fk.ros.guarded_input import GuardedInputs, read_imu
from a1_leg_fk.ros.joint_input import LOWSTATE_TOPIC, MissingMessages, joint_input
from a1_leg_fk.ros.odometry_diagnostics import OdometryReport, odometry_status
from a1_leg_fk.ros.odometry_parameters import PARAMETERS
from a1_leg_fk.ros.odometry_wire import SerializedOdometry
from a1_leg_fk.ros.robot_source import ParameterChoiceError, RobotSource
from a1_leg_fk.tracking import REJECTIONS, FootTracker
from a1_leg_fk.wire.imu import ImuFields
from a1_leg_fk.wire.joint_state import WireFields, doubles

NODE_NAME = "leg_odometry"
DIAGNOSTICS_PERIOD_S = 1.0


class LegOdometryNode(Node):
    """Publishes the base's leg odometry for every joint state with velocities."""

    def __init__(self, **node_options: Unpack[ros_glue.NodeOptions]) -> None:
        super().__init__(NODE_NAME, **node_options)
        for spec in PARAMETERS:
            spec.declare(self)
        message, topic, self._decoder = joint_input(self)  # before any output: a usage error
        self._inputs = GuardedInputs(self)
        self._robot = RobotSource(self, self._on_robot, self._inputs)
        self._warnings = ros_glue.WarnThrottle(self)
        self._period = PeriodCounter()
        self._no_stance_before = 0
        self._without_velocities = 0
        self._msg = Odometry()
        self._values = [0.0] * SerializedOdometry.DOUBLES
        self._contacts = str(self.get_parameter("contacts").value)
        if self._contacts not in CONTACT_SOURCES:
            raise LegFkError(
                f"parameter contacts must be {', '.join(CONTACT_SOURCES)}: {self._contacts!r}"
            )
        self._ground = str(self.get_parameter("ground").value)
        if self._ground not in GROUND_MODELS:
            raise LegFkError(
                f"parameter ground must be {', '.join(GROUND_MODELS)}: {self._ground!r}"
            )
        self._start(self._robot.config)
        self._publisher = self.create_publisher(Odometry, "leg_odometry", OUTPUT_QOS)
        self._ground_pub = self.create_publisher(PoseWithCovarianceStamped, "ground", OUTPUT_QOS)
        self._ground_msg = PoseWithCovarianceStamped()
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", OUTPUT_QOS)
        self._inputs.subscribe(
            message,
            topic,
            self._decoder.fields,
            self._on_joint_state,
            JOINT_STATES_QOS,
            qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        )
        self._imu_topic = self.resolve_topic_name("imu")
        if bool(self._setting("use_imu")) and topic != LOWSTATE_TOPIC:  # a LowState has its IMU
            self._inputs.subscribe(
                Imu,
                "imu",
                read_imu,
                self._on_imu_fields,
                JOINT_STATES_QOS,
                qos_overriding_options=QoSOverridingOptions.with_default_policies(),
            )
        self.create_timer(DIAGNOSTICS_PERIOD_S, self._publish_diagnostics)
        self.create_timer(WALL_WAIT_S / 2, self._expire)
        self.add_post_set_parameters_callback(self._after_set_parameters)
        self.get_logger().info(
            f"leg odometry of {self._config.source} from {self.resolve_topic_name(topic)}"
            + (f" and {self._imu_topic}" if bool(self._setting("use_imu")) else " (legs alone)")
            + f" to {self.resolve_topic_name('leg_odometry')}"
            + f" in frame '{self._msg.header.frame_id}'"
        )

    def _start(self, config: RobotConfig) -> None:
        """(Re)start the estimate with a robot: fresh tracker and odometry, pose at the origin."""
        self._config = config
        self._tracker = FootTracker(config.quadruped)
        radius = self._setting("foot_radius_m")
        self._feed, self._corrections_refused = with_corrections(
            self,
            lambda corrections: OdometryFeed(
                config.quadruped,
                OdometrySettings(
                    slip_threshold_mps=self._setting("slip_threshold_mps"),
                    stance_band_m=self._setting("stance_band_m"),
                ),
                radius if radius >= 0.0 else None,
                self._setting("imu_timeout_s"),
                use_imu=bool(self._setting("use_imu")),
                contacts=self._contacts,
                ground=self._ground,
                model_corrections=corrections,
            ),
        )
        separate_imu = self._decoder.imu is None  # a LowState's IMU comes with its joint state
        wait_s = self._setting("imu_wait_s") if separate_imu else 0.0
        self._pairing = ImuPairing(self._feed, wait_s)
        if self._feed.note and self._contacts != KINEMATIC:
            self.get_logger().warn(f"no foot forces, kinematic stance: {self._feed.note}")
        self._no_stance_before = 0
        self._ground_revision = 0
        self._apply_frames()

    # --- per message ---------------------------------------------------------------------

    def _on_imu_fields(self, fields: ImuFields) -> None:
        """One Imu's fields (an Imu message's, read by :func:`read_imu`, or a LowState's own)
        into the odometry; one whose angular velocity is not finite or beyond
        :data:`MAX_ANGULAR_RATE_RADPS` is counted as ``rejected_imu_gyro_out_of_range`` (a
        LowState's: ``rejected_lowstate_gyro_out_of_range``).
        """
        reading = imu_reading(*fields[1:])
        stamp = fields[0]
        if reading is None:
            topic = "imu" if self._decoder.imu is None else LOWSTATE_TOPIC
            self._inputs.reject(
                topic,
                "gyro_out_of_range",
                f"angular velocity not finite or beyond {MAX_ANGULAR_RATE_RADPS:g} rad/s",
            )
        self._output(self._pairing.imu(stamp or self.get_clock().now().nanoseconds, reading))

    def _on_joint_state(self, fields: WireFields) -> None:
        """One joint state's fields, read from its bytes by the input's decoder (as the bag tools
        read them; a message that cannot be read never gets here: :class:`GuardedInputs`); then
        :class:`FootTracker`'s rules and the odometry.
        """
        stamp_ns, _, order, position_bytes, velocity_bytes, effort_bytes = fields
        names: Sequence[str] = self._decoder.names
        positions = doubles(position_bytes, order)
        velocities = doubles(velocity_bytes, order)
        efforts = doubles(effort_bytes, order)
        if self._decoder.imu is not None:  # a LowState's own IMU, stamped as its motors
            self._on_imu_fields(self._decoder.imu)
        tracker = self._tracker
        feet = tracker.update(names, positions, velocities, efforts)
        if tracker.new_unknown_names:
            names = tracker.take_new_unknown_names()
            self.get_logger().warn(
                f"ignoring joint names not in the model (warned once per name): {names[:20]}"
            )
        if tracker.last_problem:
            self._report_problem()
        if not feet:
            return
        legs: list[Foot | None] = [None] * len(LEG_NAMES)
        for foot in feet:
            if foot.velocity is not None:
                legs[foot.leg_slot] = (foot.position, foot.velocity)
        if all(leg is None for leg in legs):
            self._without_velocities += 1
            self._warnings.warn(
                "no_velocities", "joint_states without joint velocities: no odometry from them"
            )
            return
        self._output(
            self._pairing.joint(
                stamp_ns or self.get_clock().now().nanoseconds,
                legs,
                list(tracker.angles),
                list(tracker.rates),
                list(tracker.efforts),
                time.monotonic_ns(),
            )
        )

    def _expire(self) -> None:
        """The wall-clock bound: the joint states held longer than :data:`WALL_WAIT_S`."""
        if self._pairing.holding:
            self._output(self._pairing.expire(time.monotonic_ns() - round(WALL_WAIT_S * 1e9)))

    def _output(self, samples: Iterable[OdometrySample]) -> None:
        """Publish each released sample, and the ground when its footholds changed."""
        for sample in samples:
            self._publish(sample)
            if self._feed.ground.revision != self._ground_revision:
                self._ground_revision = self._feed.ground.revision
                self._publish_ground(sample)

    def _publish_ground(self, sample: OdometrySample) -> None:
        """The local ground under the base on ``ground`` (in the odom frame, stamped as the
        joint state): sent when its footholds change (a touchdown, a liftoff, an expiry).
        """
        plane = self._feed.ground_plane(sample)
        if plane is None:
            return
        position, orientation, covariance = plane_pose(plane, *sample.position[:2])
        msg = self._ground_msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(sample.stamp_ns, 1_000_000_000)
        msg.header.frame_id = self._msg.header.frame_id
        pose = msg.pose.pose
        pose.position.x, pose.position.y, pose.position.z = position
        o = pose.orientation
        o.x, o.y, o.z, o.w = orientation
        msg.pose.covariance = covariance
        self._ground_pub.publish(msg)

    def _publish(self, sample: OdometrySample) -> None:
        values = self._values  # pose 7, its covariance 36, twist 6, its covariance 36
        values[0:3] = sample.position
        values[3:7] = sample.orientation
        values[43:46] = sample.linear
        values[46:49] = sample.angular
        pose_variance, twist_variance = sample.pose_variance, sample.twist_variance
        for index in range(6):  # the diagonals; the rest stays zero
            values[7 + 7 * index] = pose_variance[index]
            values[49 + 7 * index] = twist_variance[index]
        if self._serialized is not None:
            self._publisher.publish(self._serialized.serialized(sample.stamp_ns, values))
            return
        pose_covariance, twist_covariance = values[7:43], values[49:85]
        msg = self._msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(sample.stamp_ns, 1_000_000_000)
        pose, twist = msg.pose.pose, msg.twist.twist
        pose.position.x, pose.position.y, pose.position.z = sample.position
        o = pose.orientation
        o.x, o.y, o.z, o.w = sample.orientation
        twist.linear.x, twist.linear.y, twist.linear.z = sample.linear
        twist.angular.x, twist.angular.y, twist.angular.z = sample.angular
        msg.pose.covariance = pose_covariance
        msg.twist.covariance = twist_covariance
        self._publisher.publish(msg)

    def _report_problem(self) -> None:
        tracker = self._tracker
        outcome = tracker.last_outcome
        kind = outcome if outcome in REJECTIONS else "non_finite_position"
        self._warnings.warn(
            kind, f"joint_states: {outcome.replace('_', ' ')}: {tracker.last_problem}"
        )

    # --- diagnostics and parameters -----------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        received, rejected = self._period.take(self._tracker.counts)
        inputs_rejected = self._inputs.rejected_since()
        counts = self._feed.odometry.counts
        no_stance, self._no_stance_before = (
            counts.no_stance - self._no_stance_before,
            counts.no_stance,
        )
        if self._diagnostics_pub.get_subscription_count() == 0:
            return
        robot = self._robot
        level, summary, values = odometry_status(
            OdometryReport(
                tracker=self._tracker.counts,
                odometry=counts,
                received_in_period=received,
                rejected_in_period=rejected,
                no_stance_in_period=no_stance,
                period_s=DIAGNOSTICS_PERIOD_S,
                imu_topic=self._imu_topic
                if bool(self._setting("use_imu"))
                else "none (use_imu false)",
                imu_received=self._feed.imu.received,
                samples_with_imu=self._feed.samples_with_imu,
                imu_pairing=(self._pairing.held, self._pairing.released_by_wait),
                without_velocities=self._without_velocities,
                contacts=self._contacts,
                contact_counts=self._feed.counts,
                contacts_note=self._feed.note,
                corrections=self._feed.corrections,
                corrections_refused=self._corrections_refused,
                filtered=self._feed.samples_filtered,
                filter=self._feed.filter.counts,
                biases=(
                    tuple(self._feed.filter.gyro_bias.tolist()),
                    tuple(self._feed.filter.accel_bias.tolist()),
                ),
                noise_scales=self._feed.filter.gate.scales,
                distance_m=self._feed.distance_m,
                model=self._config.source,
                description_topic=robot.topic_name,
                description_status=robot.topic_status,
                description_rejected=robot.topic_rejected,
                inputs_rejected_in_period=inputs_rejected,
                inputs_rejected=self._inputs.values(),
            )
        )
        self._diagnostics_pub.publish(
            ros_glue.diagnostics(
                self, "leg odometry", level, summary, self._config.quadruped.model.name, values
            )
        )

    def _setting(self, name: str) -> float:
        """A declared double or bool parameter's value (rclpy has checked its type and range)."""
        return float(self.get_parameter(name).value)

    def _apply_frames(self) -> None:
        """Set the frames, and serialize the probe message that output is patched into."""
        msg = self._msg
        msg.header.frame_id = str(self.get_parameter("odom_frame").value)
        msg.child_frame_id = self._robot.base_frame({})
        probe = Odometry(child_frame_id=msg.child_frame_id)
        probe.header.frame_id = msg.header.frame_id
        probe.header.stamp.sec, probe.header.stamp.nanosec = SerializedOdometry.PROBE_STAMP
        values = SerializedOdometry.probe_values()
        pose, twist = probe.pose.pose, probe.twist.twist
        pose.position.x, pose.position.y, pose.position.z = values[0:3]
        o = pose.orientation
        o.x, o.y, o.z, o.w = values[3:7]
        probe.pose.covariance = values[7:43]
        twist.linear.x, twist.linear.y, twist.linear.z = values[43:46]
        twist.angular.x, twist.angular.y, twist.angular.z = values[46:49]
        probe.twist.covariance = values[49:85]
        writer = SerializedOdometry(serialize_message(probe))
        self._serialized = writer if writer.usable else None

    def _on_robot(self, config: RobotConfig) -> None:
        """Another robot was accepted: start over with it (the pose restarts at the origin)."""
        self._period.new_tracker(self._tracker.counts)
        self._start(config)

    def _after_set_parameters(self, _parameters: list[Parameter]) -> None:
        self._apply_frames()

    def destroy_node(self) -> None:
        """Ctrl-C, SIGTERM: the joint states still held are published first."""
        self._output(self._pairing.flush())
        super().destroy_node()  # type: ignore[no-untyped-call]


def main(args: Sequence[str] | None = None) -> int:
    """Entry point of ``ros2 run a1_leg_fk leg_odometry_node``; exits 0 on Ctrl-C/SIGTERM."""
    return ros_glue.run_node(
        "leg_odometry_node", LegOdometryNode, args, (MissingMessages, ParameterChoiceError)
    )


if __name__ == "__main__":
    sys.exit(main())
