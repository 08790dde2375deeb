"""IMU samples for the odometry: what a ``sensor_msgs/msg/Imu`` says, and which sample goes with a
joint state. One rule each, shared by the node and the bag tool (no ROS types here).

- :func:`imu_reading`: the orientation counts unless ``orientation_covariance[0] == -1`` (the
  message's convention for "no orientation") or it is not a rotation (a zero quaternion); the
  angular velocity always, unless it is not finite or faster than :data:`MAX_ANGULAR_RATE_RADPS`
  (a corrupt message: no gyro comes near it). An all-zero covariance means "unknown" (REP 145,
  sensor_msgs): its variances are then left to the odometry's defaults.
- :class:`ImuBuffer`: a joint state stamped ``t`` takes the latest IMU sample stamped at or before
  ``t``, if it is at most ``timeout_s`` older; else none.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence

from a1_leg_fk.estimation.odometry import ImuReading

NO_ORIENTATION = -1.0
"""``orientation_covariance[0]`` of an IMU without orientation (sensor_msgs/msg/Imu)."""
DEFAULT_IMU_TIMEOUT_S = 0.1
MAX_ANGULAR_RATE_RADPS = 1e3
"""[rad/s] A faster angular velocity is no measurement (a corrupt message), as a NaN is not: MEMS
gyros saturate near 35 rad/s; and it keeps the odometry's sums of squares far from overflow."""
MAX_SPECIFIC_FORCE_MPS2 = 1e3
"""[m/s^2] A larger specific force is no measurement (MEMS accelerometers saturate near 160)."""
BUFFER_SAMPLES = 256
"""IMU samples kept for matching: ~0.25 s at 1 kHz, far more than a joint state's lag."""


def has_orientation(covariance_0: float, quaternion: Sequence[float]) -> bool:
    """Whether an Imu message's orientation may be used: its ``orientation_covariance[0]`` is not
    -1 (the message's "no orientation") and the quaternion is a rotation (finite, not near zero;
    it is normalised where used). The one rule of the foot forces and the odometry, live and from
    bags.
    """
    x, y, z, w = quaternion
    norm2 = x * x + y * y + z * z + w * w
    return covariance_0 != NO_ORIENTATION and math.isfinite(norm2) and norm2 > 0.25


def measured_vector(
    vector: Sequence[float], covariance_0: float, zero_is_none: bool = False
) -> tuple[float, float, float] | None:
    """An Imu message's angular velocity [rad/s] or linear acceleration [m/s^2] if it was
    measured: not when its ``covariance[0]`` is -1 (the message's "not measured"), when it is
    not finite, or (``zero_is_none``, for the accelerometer, which always feels gravity unless
    falling freely) when it is exactly zero, as drivers without one fill it. The one rule of the
    node and the bag tools.
    """
    x, y, z = float(vector[0]), float(vector[1]), float(vector[2])
    if covariance_0 == NO_ORIENTATION or not math.isfinite(x + y + z):
        return None
    if zero_is_none and x == y == z == 0.0:
        return None
    return (x, y, z)


def imu_reading(
    orientation: Sequence[float],
    orientation_covariance: Sequence[float],
    angular_velocity: Sequence[float],
    angular_velocity_covariance: Sequence[float],
    linear_acceleration: Sequence[float] = (0.0, 0.0, 0.0),
    linear_acceleration_covariance: Sequence[float] = (0.0,) * 9,
) -> ImuReading | None:
    """The :class:`ImuReading` of an Imu message's fields (quaternion x, y, z, w; 3x3 row-major
    covariances [rad^2], [(rad/s)^2], [(m/s^2)^2]; angular velocity [rad/s]; linear acceleration
    [m/s^2], the specific force: :func:`measured_vector`'s rule, all zero is none), or None when
    its angular velocity is not finite or faster than :data:`MAX_ANGULAR_RATE_RADPS` on some axis.
    """
    gyro = (float(angular_velocity[0]), float(angular_velocity[1]), float(angular_velocity[2]))
    fastest = MAX_ANGULAR_RATE_RADPS
    if not (abs(gyro[0]) <= fastest and abs(gyro[1]) <= fastest and abs(gyro[2]) <= fastest):
        return None  # also NaN
    x, y, z, w = (float(orientation[0]), float(orientation[1]), float(orientation[2]),
                  float(orientation[3]))  # fmt: skip
    usable = has_orientation(float(orientation_covariance[0]), (x, y, z, w))
    force = measured_vector(
        linear_acceleration, float(linear_acceleration_covariance[0]), zero_is_none=True
    )
    if force is not None and not max(map(abs, force)) <= MAX_SPECIFIC_FORCE_MPS2:
        force = None
    return ImuReading(
        (x, y, z, w) if usable else None,
        gyro,
        _diagonal(orientation_covariance) if usable else None,
        _diagonal(angular_velocity_covariance),
        force,
    )


def _diagonal(covariance: Sequence[float]) -> tuple[float, float, float] | None:
    """The diagonal of a 3x3 row-major covariance; None when unknown (all zero) or unusable."""
    a, b, c = float(covariance[0]), float(covariance[4]), float(covariance[8])
    if not any(covariance) or not (math.isfinite(a + b + c) and min(a, b, c) >= 0.0):
        return None
    return (a, b, c)


class ImuBuffer:
    """The latest IMU samples by stamp [ns], to pair with joint states (see the module's rule)."""

    def __init__(self, timeout_s: float = DEFAULT_IMU_TIMEOUT_S) -> None:
        self.timeout_ns = round(timeout_s * 1e9)
        self._stamps: list[int] = []
        self._readings: list[ImuReading] = []
        self.received = 0

    def add(self, stamp_ns: int, reading: ImuReading) -> None:
        """Keep a sample (they may come out of order; the oldest beyond the buffer are dropped)."""
        self.received += 1
        index = bisect.bisect_right(self._stamps, stamp_ns)
        self._stamps.insert(index, stamp_ns)
        self._readings.insert(index, reading)
        if len(self._stamps) > BUFFER_SAMPLES:
            del self._stamps[0], self._readings[0]

    def at(self, stamp_ns: int) -> ImuReading | None:
        """The sample for a joint state stamped ``stamp_ns``, or None."""
        index = bisect.bisect_right(self._stamps, stamp_ns) - 1
        if index < 0 or stamp_ns - self._stamps[index] > self.timeout_ns:
            return None
        return self._readings[index]
