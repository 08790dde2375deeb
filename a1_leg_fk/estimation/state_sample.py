"""The error-state filter's state as the odometry's output (:class:`OdometrySample`), for the
filter itself and for a smoother's states alike: the twist in the base frame, the pose in odom,
and the diagonals of their covariances (no ROS).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_model import GYRO_BIAS, POSITION, FilterSettings
from a1_leg_fk.estimation.odometry import OdometrySample
from a1_leg_fk.estimation.so3 import quaternion_of
from a1_leg_fk.kinematics.frames import Vector

ONES_6 = np.ones(6)
"""Sums the rows of a 6-column matrix (a product with it costs less than a sum)."""


def floats_of(
    rotation: np.ndarray, nominal: np.ndarray
) -> tuple[list[list[float]], Vector, list[float]]:
    """The rotation's rows, the velocity in the base frame ``Rᵀ v`` [m/s] and the nominal
    velocity, position and gyro bias (9 values), in floats.
    """
    (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = rows = rotation.tolist()
    values = nominal[0:9].tolist()
    vx, vy, vz = values[0:3]
    local = (r0 * vx + r3 * vy + r6 * vz, r1 * vx + r4 * vy + r7 * vz,
             r2 * vx + r5 * vy + r8 * vz)  # fmt: skip
    return rows, local, values


def state_sample(
    stamp_ns: int,
    state: tuple[np.ndarray, np.ndarray, np.ndarray],
    gyro: tuple[Vector, Vector],
    settings: FilterSettings,
    legs: tuple[Sequence[int], Sequence[int]],
) -> OdometrySample:
    """A state (rotation, nominal, covariance: the filter's or a smoother's) as an
    :class:`OdometrySample` (twist in the base frame, pose in odom) with the diagonals of its
    covariances; ``gyro``: the gyro's sample [rad/s] and the gate's doubt [m²/s²], ``legs``: the
    stance and used legs.
    """
    rotation, nominal, covariance = state
    rows_of_rotation, (lx, ly, lz), values = floats_of(rotation, nominal)
    (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = rows_of_rotation
    _, _, _, px, py, pz, bx, by, bz = values
    # the twist's rows d(Rᵀ v) / d(dθ, dv) over the attitude's (R, 0): both variances at once
    rows = np.array(
        ((0.0, -lz, ly, r0, r3, r6), (lz, 0.0, -lx, r1, r4, r7), (-ly, lx, 0.0, r2, r5, r8),
         (r0, r1, r2, 0.0, 0.0, 0.0), (r3, r4, r5, 0.0, 0.0, 0.0), (r6, r7, r8, 0.0, 0.0, 0.0))
    )  # fmt: skip
    variances = (rows.dot(covariance[:6, :6]) * rows).dot(ONES_6).tolist()
    diagonal = covariance.diagonal().tolist()
    gyro_noise = settings.gyro_sample_noise_radps**2
    (wx, wy, wz), (dx, dy, dz) = gyro
    return OdometrySample(
        stamp_ns,
        (px, py, pz),
        quaternion_of(rows_of_rotation),
        (lx, ly, lz),
        (wx - bx, wy - by, wz - bz),
        tuple(diagonal[POSITION] + variances[3:6]),
        (
            variances[0] + dx,
            variances[1] + dy,
            variances[2] + dz,
            *(value + gyro_noise for value in diagonal[GYRO_BIAS]),
        ),
        tuple(legs[0]),
        tuple(legs[1]),
        False,
    )
