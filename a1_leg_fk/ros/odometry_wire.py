"""``leg_odometry_node``'s messages as bytes: sensor_msgs/Imu read from its CDR without building a
message object (:func:`a1_leg_fk.wire.imu.imu_fields`), nav_msgs/Odometry written by patching a
pre-serialized probe. At 1 kHz each of
the two would otherwise cost about as much as the odometry itself (rclpy's conversion between
message objects and C, with numpy arrays for every covariance).

:func:`imu_sample` turns an Imu's fields into what the foot forces and contacts take. No ROS
imports: :class:`SerializedOdometry` takes the probe's bytes from the caller.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from a1_leg_fk.estimation.contact_estimator import ImuSample
from a1_leg_fk.estimation.imu import has_orientation, measured_vector
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, down_direction, unit_quaternion
from a1_leg_fk.wire.imu import LENGTH as _LENGTH
from a1_leg_fk.wire.imu import STAMP as _STAMP
from a1_leg_fk.wire.imu import ImuFields


def imu_message_fields(msg: Any) -> ImuFields:
    """:func:`imu_fields` of a deserialized sensor_msgs/msg/Imu."""
    q, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    return (
        msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec,
        (q.x, q.y, q.z, q.w),
        tuple(msg.orientation_covariance),
        (w.x, w.y, w.z),
        tuple(msg.angular_velocity_covariance),
        (a.x, a.y, a.z),
        tuple(msg.linear_acceleration_covariance),
    )


def imu_sample(fields: ImuFields) -> ImuSample:
    """What an Imu's fields tell the foot forces and contacts (an IMU aligned with the base):
    gravity [m/s^2] from its orientation, angular velocity [rad/s] and specific force [m/s^2],
    each None where the message has none (``*_covariance[0] == -1``, a zero quaternion, values
    not finite).
    """
    _, orientation, orientation_covariance, gyro, gyro_covariance, accel, accel_covariance = fields
    gravity = None
    if has_orientation(orientation_covariance[0], orientation):
        unit = unit_quaternion(orientation)
        if unit is not None:
            gravity = [STANDARD_GRAVITY * v for v in down_direction(unit)]
    return ImuSample(
        gravity,
        measured_vector(gyro, gyro_covariance[0]),
        measured_vector(accel, accel_covariance[0], zero_is_none=True),
    )


class SerializedOdometry:
    """A nav_msgs/msg/Odometry serialized once (``probe``: the bytes of one whose 85 doubles are
    :meth:`probe_values`); :meth:`serialized` patches the stamp and the 85 doubles (pose 7, its
    covariance 36, twist 6, its covariance 36), which CDR keeps contiguous after the frame names.
    ``usable`` is False unless the probe is little-endian CDR laid out so.
    """

    DOUBLES = 85
    VALUES = struct.Struct(f"<{DOUBLES}d")

    def __init__(self, probe: bytes) -> None:
        self._offset = probe.find(self.VALUES.pack(*self.probe_values()))
        self.usable = (
            probe[:4] == b"\x00\x01\x00\x00"
            and _STAMP.unpack_from(probe, 4) == self.PROBE_STAMP
            and self._offset > 12
            and self._offset + self.VALUES.size == len(probe)
        )
        self._buffer = bytearray(probe)
        if self.usable:  # zero the padding before the values (a serializer may leave junk)
            child = (12 + _LENGTH.unpack_from(probe, 12)[0] + 3) & -4  # relative to the data
            text_end = 4 + child + 4 + _LENGTH.unpack_from(probe, 4 + child)[0]
            self._buffer[text_end : self._offset] = bytes(self._offset - text_end)

    PROBE_STAMP = (7, 9)

    @staticmethod
    def probe_values() -> list[float]:
        """The 85 distinct values the probe message carries, in CDR order."""
        return [1.0 + index / 128.0 for index in range(SerializedOdometry.DOUBLES)]

    def serialized(self, stamp_ns: int, values: Sequence[float]) -> bytes:
        """The message's bytes with this stamp [ns] and these 85 values."""
        buffer = self._buffer
        _STAMP.pack_into(buffer, 4, *divmod(stamp_ns, 1_000_000_000))
        self.VALUES.pack_into(buffer, self._offset, *values)
        return bytes(buffer)
