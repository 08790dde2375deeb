"""The synthetic trots' geometry (test/estimation/test_foot_give.py, test_foot_impact.py,
test_foot_jolt.py): a level base moving at a constant horizontal velocity over four feet, an exact
IMU, 500 Hz joint states; the truth known by construction."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from a1_leg_fk.estimation.filter_model import LegMeasurement
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY

V = (0.4, -0.1, 0.0)
"""[m/s] the base's velocity, base frame = world frame (level, no turn); no vertical motion."""
FEET = ((0.18, -0.13, -0.3), (0.18, 0.13, -0.3), (-0.18, -0.13, -0.3), (-0.18, 0.13, -0.3))
"""[m] the feet's contact points in the base frame, FR, FL, RR, RL."""
LEVEL = (0.0, 0.0, 0.0, 1.0)
"""The base's orientation (x, y, z, w): level."""
STEP_NS = 2_000_000
"""[ns] the joint states' interval."""
JJT = (0.05, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 0.05)
"""Each leg's J Jᵀ [m²/rad²], row-major."""


def vertical_errors(
    state: StateFilter, seconds: float, legs_at: Callable[[int], list[LegMeasurement | None]],
    settle_s: float, axis: int = 2,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Run ``state`` over ``seconds`` of joint states (the IMU exact: level, still, 1 g), the
    ``k``-th joint state's legs ``legs_at(k)``; the filter's velocity error [m/s] and its
    reported sigma [m/s] on ``axis`` (world = base; 2: vertical) after every joint state from
    ``settle_s`` [s] on."""
    errors, sigmas = [], []
    stamp = 0
    for k in range(round(seconds * 1e9 / STEP_NS)):
        stamp += STEP_NS
        state.propagate(stamp, (0.0, 0.0, 0.0), (0.0, 0.0, STANDARD_GRAVITY), LEVEL)
        state.update(stamp, legs_at(k), LEVEL)
        if stamp >= settle_s * 1e9:
            errors.append(float(state.velocity[axis]) - V[axis])
            sigmas.append(math.sqrt(state.covariance[3 + axis, 3 + axis]))
    return np.array(errors), np.array(sigmas)


def sigma_scores(error: np.ndarray, sigma: np.ndarray) -> tuple[float, float, float]:
    """A run's mean reported sigma [m/s], that over its RMS ``error`` [m/s], and the share of
    samples whose error lies within 3 ``sigma``."""
    rms = math.sqrt(float((error**2).mean()))
    mean = float(sigma.mean())
    return mean, mean / rms, float((np.abs(error) <= 3.0 * sigma).mean())
