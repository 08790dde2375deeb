"""The fields of a serialized little-endian CDR ``sensor_msgs/msg/Imu``, read without building a
message object (at 1 kHz, rclpy's conversion would cost about as much as the odometry itself).
No ROS here.
"""

from __future__ import annotations

import struct

IMU_DOUBLES = struct.Struct("<37d")
"""An Imu's fields after its header: orientation (4), its covariance (9), angular velocity (3),
its covariance (9), linear acceleration (3), its covariance (9)."""
STAMP = struct.Struct("<iI")
LENGTH = struct.Struct("<I")
LITTLE_ENDIAN_CDR = b"\x00\x01"

Values = tuple[float, ...]
ImuFields = tuple[int, Values, Values, Values, Values, Values, Values]
"""(stamp [ns], orientation x y z w, orientation covariance (9), angular velocity [rad/s] (3),
its covariance (9), linear acceleration [m/s^2] (3), its covariance (9))."""


def imu_fields(raw: bytes) -> ImuFields | None:
    """The fields of a serialized little-endian CDR sensor_msgs/msg/Imu, or None (another
    encoding, or malformed: the caller then deserializes it the ordinary way).
    """
    if len(raw) < 16 or raw[:2] != LITTLE_ENDIAN_CDR:
        return None
    sec, nanosec = STAMP.unpack_from(raw, 4)
    text_end = 12 + LENGTH.unpack_from(raw, 12)[0]  # relative to the data, after 4 bytes
    start = 4 + ((text_end + 7) & -8)
    if start + IMU_DOUBLES.size != len(raw):
        return None
    values = IMU_DOUBLES.unpack_from(raw, start)
    return (
        sec * 1_000_000_000 + nanosec,
        values[0:4],
        values[4:13],
        values[13:16],
        values[16:25],
        values[25:28],
        values[28:37],
    )
