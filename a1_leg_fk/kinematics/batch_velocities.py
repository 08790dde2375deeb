"""Foot velocities of rows of joint states where some legs are unknown: the bag tools' batch form
of :meth:`~a1_leg_fk.kinematics.quadruped.Quadruped.foot_velocities_batch`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES

if TYPE_CHECKING:
    from a1_leg_fk.kinematics.quadruped import Quadruped

LEGS = len(LEG_NAMES)


def velocities_of(
    quadruped: Quadruped, angles: np.ndarray, known: np.ndarray, rates: np.ndarray
) -> np.ndarray:
    """(N, 4, 3) J(q)·q̇ [m/s], base frame, for (N, 12) angles [rad] and rates [rad/s]; NaN for
    legs not ``known`` (N, 4), legs whose rates are not all finite, and overflowed results.
    """
    out = np.full((angles.shape[0], LEGS, 3), math.nan)
    usable = known & np.isfinite(rates).reshape(-1, LEGS, JOINTS_PER_LEG).all(axis=2)
    rows = usable.any(axis=1)
    if rows.any():
        velocity = quadruped.foot_velocities_batch(
            np.nan_to_num(angles[rows]), np.nan_to_num(rates[rows])
        )
        with np.errstate(invalid="ignore"):
            velocity[~usable[rows] | ~np.isfinite(velocity).all(axis=2)] = math.nan
        out[rows] = velocity
    return out
