"""The state filter (a1_leg_fk.estimation.state_filter) on synthetic motion whose every quantity is
known by construction: a level base moving at a constant velocity, its stance feet giving
``e = v + w x r``, the accelerometer feeling gravity (plus a known bias)."""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.filter_model import LegMeasurement
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY

V = (0.4, -0.1, 0.0)  # [m/s] base frame = world frame (level, no turn)
FEET = ((0.18, -0.13, -0.3), (0.18, 0.13, -0.3), (-0.18, -0.13, -0.3), (-0.18, 0.13, -0.3))
LEVEL = (0.0, 0.0, 0.0, 1.0)
STEP_NS = 2_000_000
JJT = (0.05, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 0.05)


def legs(standing=(0, 3), extra=None):
    """Measurements of the standing feet; ``extra``: (leg, added velocity [m/s]) for a slip."""
    out: list[LegMeasurement | None] = [None] * 4
    for leg in standing:
        e = np.array(V, dtype=float)
        if extra and extra[0] == leg:
            e = e + np.array(extra[1])
        out[leg] = LegMeasurement(FootMotion(tuple(e), FEET[leg], 0.3), 0.99, JJT)
    return out


def run(state: StateFilter, seconds: float, start_ns: int = 0, bias=(0.0, 0.0, 0.0), **kw):
    """Step ``state`` for ``seconds``; the stamp after."""
    stamp = start_ns
    for k in range(round(seconds * 1e9 / STEP_NS)):
        stamp += STEP_NS
        force = (bias[0], bias[1], STANDARD_GRAVITY + bias[2])
        state.propagate(stamp, (0.0, 0.0, 0.0), force, LEVEL)
        pair = (0, 3) if (k // 100) % 2 == 0 else (1, 2)  # a trot's diagonals, 0.2 s each
        state.update(stamp, legs(pair, **kw), LEVEL)
    return stamp


def velocity(state: StateFilter) -> np.ndarray:
    return state.rotation.T @ state.velocity


def test_a_base_already_moving_is_taken_up_once_two_feet_agree() -> None:
    """The filter starts at rest (its velocity sigma 0.05 m/s); the first two standing feet say
    0.41 m/s together, which resets the gate at once (no foot was believed yet): followed."""
    state = StateFilter()
    run(state, 1.0)
    assert state.counts.gate_resets == 1
    assert np.abs(velocity(state) - V).max() < 1e-3
    assert abs(state.position[0] - 0.4 * 1.0) < 0.005  # moving from the first joint state


def lone_or_disagreeing(state: StateFilter, stamp: int, feet: dict[int, tuple], seconds: float):
    """Step with only ``feet`` standing (leg -> its velocity's offset from V [m/s]); the stamp."""
    for _ in range(round(seconds * 1e9 / STEP_NS)):
        stamp += STEP_NS
        state.propagate(stamp, (0.0, 0.0, 0.0), (0.0, 0.0, STANDARD_GRAVITY), LEVEL)
        standing = legs(tuple(feet))
        for leg, offset in feet.items():
            motion = standing[leg]
            assert motion is not None
            e = tuple(np.add(motion.motion.e, offset))
            standing[leg] = LegMeasurement(FootMotion(e, FEET[leg], 0.3), 0.99, JJT)
        state.update(stamp, standing, LEVEL)
    return stamp


def test_the_gate_resets_only_on_feet_that_agree() -> None:
    """A lone foot, or two that disagree, stay rejected however long (swinging feet taken for
    standing); two that agree are believed again after ``max_rejected_s``."""
    state = StateFilter()
    stamp = run(state, 1.0)
    stamp = lone_or_disagreeing(state, stamp, {0: (1.0, 0.0, 0.0)}, 0.6)
    stamp = lone_or_disagreeing(state, stamp, {0: (1.0, 0.0, 0.0), 3: (-1.0, 0.0, 0.0)}, 0.6)
    assert state.counts.gate_resets == 1  # the start's
    assert np.abs(velocity(state) - V).max() < 0.01  # the IMU alone: constant
    stamp = lone_or_disagreeing(state, stamp, {0: (0.5, 0.0, 0.0), 3: (0.52, 0.0, 0.0)}, 0.6)
    assert state.counts.gate_resets == 2
    assert abs(velocity(state)[0] - (V[0] + 0.51)) < 0.01


def test_a_slipping_foot_is_rejected_and_counted() -> None:
    state = StateFilter()
    stamp = run(state, 1.5)
    before = list(state.counts.rejected)
    run(state, 0.2, stamp, extra=(0, (0.0, 0.3, 0.0)))  # FR slides sideways at 0.3 m/s
    assert state.counts.rejected[0] - before[0] >= 40  # every FR sample of the 0.2 s
    assert sum(state.counts.rejected[1:]) == sum(before[1:])
    assert np.abs(velocity(state) - V).max() < 5e-3


def test_the_accelerometer_bias_is_estimated() -> None:
    bias = (0.05, -0.05, 0.05)
    state = StateFilter()
    run(state, 20.0, bias=bias)
    assert np.abs(state.accel_bias - bias).max() < 0.01
    assert np.abs(velocity(state) - V).max() < 2e-3


def test_the_covariance_shrinks_with_feet_and_grows_without() -> None:
    state = StateFilter()
    stamp = run(state, 2.0)
    standing = state.covariance[3:6, 3:6].trace()
    for _ in range(100):  # 0.2 s of flight: the IMU alone
        stamp += STEP_NS
        state.propagate(stamp, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), LEVEL)
        state.update(stamp, [None] * 4, LEVEL)
    assert state.covariance[3:6, 3:6].trace() > 2.0 * standing
    assert abs(velocity(state)[2] + STANDARD_GRAVITY * 0.2) < 1e-6  # free fall, exactly


def test_absurd_values_leave_the_state_finite() -> None:
    state = StateFilter()
    stamp = run(state, 0.5)
    for value in (1e300, -1e300, 1e-300):
        stamp += STEP_NS
        state.propagate(stamp, (0.0, 0.0, 0.0), (0.0, 0.0, STANDARD_GRAVITY), LEVEL)
        wild = [LegMeasurement(FootMotion((value,) * 3, FEET[0], 0.3), 0.99, JJT), None, None,
                None]  # fmt: skip
        state.update(stamp, wild, LEVEL)
    stamp -= 10 * STEP_NS  # stamps going back: no step
    state.propagate(stamp, (0.0, 0.0, 0.0), (0.0, 0.0, STANDARD_GRAVITY), LEVEL)
    sample = state.sample(stamp, (0,), ())
    values = sample.position + sample.linear + sample.pose_variance + sample.twist_variance
    assert all(math.isfinite(value) for value in values)
