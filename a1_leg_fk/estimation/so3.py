"""Rotations for the state filter: SO(3)'s exponential, the rotation vector between a rotation
matrix and a quaternion, and the conversions between rotation matrices and (x, y, z, w) unit
quaternions (numpy 3 x 3, or their rows in floats).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from a1_leg_fk.kinematics.frames import Quaternion


def exp_so3(w: Sequence[float]) -> np.ndarray:
    """The rotation matrix of the rotation vector ``w`` [rad] (:func:`exp_so3_rows`)."""
    return np.array(exp_so3_rows(w))


def exp_so3_rows(w: Sequence[float]) -> tuple[tuple[float, float, float], ...]:
    """The rows of the rotation matrix of the rotation vector ``w`` [rad] (Rodrigues, written
    out, in floats).
    """
    x, y, z = float(w[0]), float(w[1]), float(w[2])
    angle2 = x * x + y * y + z * z
    if angle2 < 1e-12:  # the series to second order
        a, b = 1.0 - angle2 / 6.0, 0.5 - angle2 / 24.0
    else:
        angle = math.sqrt(angle2)
        a, b = math.sin(angle) / angle, (1.0 - math.cos(angle)) / angle2
    return (
        (1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y),
        (b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x),
        (b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)),
    )


def rotation_between(rows: Sequence[Sequence[float]], q: Quaternion) -> tuple[float, float, float]:
    """``Log(Rᵀ R_q)`` [rad]: the rotation vector (angles below π) from the rotation whose
    ``rows`` are given to that of the unit quaternion ``q`` (x, y, z, w), in the first's frame.
    """
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = rows
    x, y, z, w = q
    b00, b01, b02 = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)
    b10, b11, b12 = 2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)
    b20, b21, b22 = 2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)
    trace = (a00 * b00 + a01 * b01 + a02 * b02 + a10 * b10 + a11 * b11 + a12 * b12
             + a20 * b20 + a21 * b21 + a22 * b22)  # fmt: skip
    angle = math.acos(max(-1.0, min(1.0, (trace - 1.0) / 2.0)))
    scale = 0.5 if angle < 1e-8 else angle / (2.0 * math.sin(angle))
    return (
        scale * (a02 * b01 + a12 * b11 + a22 * b21 - a01 * b02 - a11 * b12 - a21 * b22),
        scale * (a00 * b02 + a10 * b12 + a20 * b22 - a02 * b00 - a12 * b10 - a22 * b20),
        scale * (a01 * b00 + a11 * b10 + a21 * b20 - a00 * b01 - a10 * b11 - a20 * b21),
    )


def matrix_of(q: Quaternion) -> np.ndarray:
    """The rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_of(rows: Sequence[Sequence[float]]) -> Quaternion:
    """The unit quaternion (x, y, z, w, w >= 0) of a rotation matrix given by its ``rows``
    (Shepperd's method).
    """
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = rows
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, s / 4)
    elif m00 > m11 and m00 > m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        q = (s / 4, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        q = ((m01 + m10) / s, s / 4, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
        q = ((m02 + m20) / s, (m12 + m21) / s, s / 4, (m10 - m01) / s)
    sign = -1.0 if q[3] < 0.0 else 1.0
    return (sign * q[0], sign * q[1], sign * q[2], sign * q[3])


def exp_so3_batch(w: np.ndarray) -> np.ndarray:
    """The rotation matrices (N, 3, 3) of the rotation vectors ``w`` (N, 3) [rad] (Rodrigues,
    the series to second order below 1e-6 rad, as :func:`exp_so3_rows`).
    """
    angle2 = np.einsum("ni,ni->n", w, w)
    small = angle2 < 1e-12
    angle = np.sqrt(np.where(small, 1.0, angle2))
    a = np.where(small, 1.0 - angle2 / 6.0, np.sin(angle) / angle)
    b = np.where(small, 0.5 - angle2 / 24.0, (1.0 - np.cos(angle)) / np.where(small, 1.0, angle2))
    x, y, z = w[:, 0], w[:, 1], w[:, 2]
    zero = np.zeros_like(x)
    skew = np.stack([zero, -z, y, z, zero, -x, -y, x, zero], axis=1).reshape(-1, 3, 3)
    rotations: np.ndarray = np.eye(3) + a[:, None, None] * skew + b[:, None, None] * (skew @ skew)
    return rotations


def log_so3_batch(rotations: np.ndarray) -> np.ndarray:
    """The rotation vectors (N, 3) [rad, angles below π] of the rotation matrices (N, 3, 3)."""
    trace = np.einsum("nii->n", rotations)
    angle = np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0))
    small = angle < 1e-8
    scale = np.where(small, 0.5, angle / (2.0 * np.sin(np.where(small, 1.0, angle))))
    vee = np.stack(
        [
            rotations[:, 2, 1] - rotations[:, 1, 2],
            rotations[:, 0, 2] - rotations[:, 2, 0],
            rotations[:, 1, 0] - rotations[:, 0, 1],
        ],
        axis=1,
    )
    vectors: np.ndarray = scale[:, None] * vee
    return vectors
