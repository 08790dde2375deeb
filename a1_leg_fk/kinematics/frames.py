"""Rotations between the world and the base frame, no ROS: the one rule for gravity's direction in
the base frame from the base's orientation (an IMU's), used by the foot forces and the leg
odometry, in a scalar form (one sample, plain floats) and an array form (a recording).

Quaternions are (x, y, z, w), unit, rotating base-frame vectors into a z-up world frame (as
``sensor_msgs/Imu.orientation`` with the IMU aligned with the base).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Vector = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]

STANDARD_GRAVITY = 9.80665
"""[m/s^2]"""
DOWN: Vector = (0.0, 0.0, -1.0)
"""Gravity's unit direction in a level base's frame."""


def down_direction(orientation: Quaternion | None) -> Vector:
    """Gravity's unit direction (world -z) in the base frame for a base orientation; :data:`DOWN`
    (a level base) without one. The third row of the base's rotation matrix, negated.
    """
    if orientation is None:
        return DOWN
    x, y, z, w = orientation
    return (2.0 * (w * y - x * z), -2.0 * (y * z + w * x), 2.0 * (x * x + y * y) - 1.0)


def gravity_in_base(quaternions: np.ndarray) -> np.ndarray:
    """(M, 3) world gravity ``(0, 0, -g)`` [m/s^2] in the frame of a base at (M, 4) unit
    quaternions: :func:`down_direction` on arrays, times standard gravity.
    """
    x, y, z, w = quaternions.T
    down = np.stack([2 * (w * y - x * z), -2 * (y * z + w * x), 2 * (x * x + y * y) - 1], axis=1)
    result: np.ndarray = STANDARD_GRAVITY * down
    return result


def rotate(q: Quaternion, v: Vector) -> Vector:
    """``v`` rotated by the unit quaternion ``q``: base frame -> world frame."""
    x, y, z, w = q
    tx, ty, tz = (
        2.0 * (y * v[2] - z * v[1]),
        2.0 * (z * v[0] - x * v[2]),
        2.0 * (x * v[1] - y * v[0]),
    )
    return (
        v[0] + w * tx + y * tz - z * ty,
        v[1] + w * ty + z * tx - x * tz,
        v[2] + w * tz + x * ty - y * tx,
    )


def unit_quaternion(q: Sequence[float]) -> Quaternion | None:
    """``q`` normalised, or ``None`` where it is no rotation (zero, NaN or far from unit)."""
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    if not (math.isfinite(norm) and norm > 0.5):
        return None
    return (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm)
