"""The contact filter's kinematic evidence against the local ground (estimation/foot_ground.py),
on synthetic trots whose truth is by construction: a level trunk carried at a constant speed
over a ground ``z = ground(x)``, each foot still on its foothold while it stands and on an arc
between two footholds while it swings. No efforts: the kinematics alone decide.

A flat-floor rule reads a foot against the lowest one: on an 8° ramp the A1's front feet stand
5 cm above its rear ones (the filter's even odds: 1.6 cm), so it calls them swing; against the
footholds' slope they stand.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.estimation.foot_ground import FootGround
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped

HIPS = ((0.18, -0.13), (0.18, 0.13), (-0.18, -0.13), (-0.18, 0.13))
"""[m] the feet's places under the hips (FR, FL, RR, RL), base frame: the A1's."""
HEIGHT_M, SPEED_MPS, PERIOD_S, DUTY, LIFT_M, RADIUS_M = 0.28, 0.3, 0.4, 0.6, 0.06, 0.02
STEP_S = 0.002
RAMP_DEG = 8.0


def ramp(x: float) -> float:
    """[m] flat to x = 0.3 m, then up at :data:`RAMP_DEG`."""
    return max(x - 0.3, 0.0) * math.tan(math.radians(RAMP_DEG))


def step_up(x: float) -> float:
    """[m] flat, then a 4 cm step at x = 0.6 m."""
    return 0.04 if x >= 0.6 else 0.0


def foot_world(leg: int, t: float, ground: Callable[[float], float]) -> tuple[np.ndarray, bool]:
    """Leg ``leg``'s foot centre [m, world] at ``t`` [s] and whether it stands: a trot (FR+RL,
    then FL+RR), each touchdown half a stance ahead of its hip."""
    stance_s = DUTY * PERIOD_S
    phase = 0.0 if leg in (0, 3) else PERIOD_S / 2
    k = math.floor((t - phase) / PERIOD_S)
    start = phase + k * PERIOD_S

    def foothold(n: int) -> np.ndarray:
        x = HIPS[leg][0] + SPEED_MPS * (phase + n * PERIOD_S + stance_s / 2)
        return np.array([x, HIPS[leg][1], ground(x) + RADIUS_M])

    if t - start < stance_s:
        return foothold(k), True
    s = (t - start - stance_s) / (PERIOD_S - stance_s)
    a, b = foothold(k), foothold(k + 1)
    point = a + s * (b - a)
    point[2] += LIFT_M * math.sin(math.pi * s)
    return point, False


def walk(
    ground: Callable[[float], float], seconds: float, estimator: ContactEstimator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(N, 4) stance truth, probabilities and feet's x [m, world] of a trot over ``ground``."""
    imu = ImuSample((0.0, 0.0, -STANDARD_GRAVITY), (0.0, 0.0, 0.0), (0.0, 0.0, STANDARD_GRAVITY))
    truth, probabilities, xs = [], [], []
    zeros = [0.0] * 12
    for t in np.arange(0.0, seconds, STEP_S):

        def base(at: float) -> np.ndarray:
            x = SPEED_MPS * at
            return np.array([x, 0.0, ground(x) + HEIGHT_M])

        feet, stands, row_x = [], [], []
        for leg in range(4):
            here, standing = foot_world(leg, t, ground)
            ahead, _ = foot_world(leg, t + 1e-5, ground)
            behind, _ = foot_world(leg, t - 1e-5, ground)
            velocity = ((ahead - base(t + 1e-5)) - (behind - base(t - 1e-5))) / 2e-5
            if standing:  # still in the world: only the base moves
                velocity = -np.array([SPEED_MPS, 0.0, 0.0])
            feet.append(((here - base(t)).tolist(), velocity.tolist()))
            stands.append(standing)
            row_x.append(here[0])
        step = estimator.step(float(t), (zeros, zeros, None), feet, imu)
        truth.append(stands)
        probabilities.append(step.probabilities)
        xs.append(row_x)
    return np.array(truth), np.array(probabilities), np.array(xs)


@pytest.fixture(scope="module")
def a1() -> Quadruped:
    from pybullet_sim import A1_URDF

    return Quadruped.from_urdf(str(A1_URDF))


def test_a_stance_foot_on_the_high_side_of_a_ramp_stands(a1: Quadruped) -> None:
    """Onto an 8° ramp without efforts: once the whole robot is on it, at least 95 % of the
    foot-samples agree with the truth, and the front feet's stance samples are called stance as
    often as the rear feet's, within 2 points (the filter's touchdown delay is the same for
    both: about 90 %); the flat-floor rule calls the front feet swing, 5 cm above the rear."""
    truth, probabilities, xs = walk(ramp, 7.0, ContactEstimator(a1))
    on_ramp = xs.min(axis=1) > 0.5  # every foot on the ramp
    assert on_ramp.sum() > 1000
    called = probabilities[on_ramp] >= 0.5
    true = truth[on_ramp]
    front, rear = called[:, :2][true[:, :2]].mean(), called[:, 2:][true[:, 2:]].mean()
    print(f"agree {100 * (called == true).mean():.2f} %, stance called stance: front "
          f"{100 * front:.2f} %, rear {100 * rear:.2f} %")  # fmt: skip
    assert (called == true).mean() >= 0.95
    assert front >= rear - 0.02


def test_a_swing_foot_over_a_step_is_not_called_stance(a1: Quadruped) -> None:
    """Up a 4 cm step without efforts: while a front foot swings over the step's edge (within
    5 cm of it along x, at most 5 cm above the tread it will land on), it is called swing on at
    least 95 % of its samples: the footholds' slope (two heights, a step between them) does not
    pull it down to the stance feet."""
    truth, probabilities, xs = walk(step_up, 4.0, ContactEstimator(a1))
    near = np.abs(xs[:, :2] - 0.6) < 0.05
    swinging = near & ~truth[:, :2]
    assert swinging.sum() > 20
    called_swing = probabilities[:, :2][swinging] < 0.5
    print(f"swing over the edge called swing {100 * called_swing.mean():.1f} %")
    assert called_swing.mean() >= 0.95


def staircase(rise_m: float) -> Callable[[float], float]:
    """[m] flat, then eight steps of ``rise_m`` (down if negative) every 0.3 m from x = 0.45 m
    (test/terrain_specs.py's staircases)."""

    def ground(x: float) -> float:
        return rise_m * min(8, math.floor((x - 0.45) / 0.3) + 1) if x >= 0.45 else 0.0

    return ground


@pytest.mark.parametrize(
    ("rise_m", "agree_goal", "held_goal"), [(0.04, 0.99, 0.975), (-0.06, 0.995, 0.99)]
)
def test_each_foot_stands_on_its_own_tread(
    a1: Quadruped, rise_m: float, agree_goal: float, held_goal: float
) -> None:
    """Up 4 cm steps and down 6 cm ones without efforts, every foot on the flight, kinematics
    exact: the foot-samples agree with the truth as on a level floor (at least 99 %; down, where
    the rear feet stand on a tread above the front ones, 99.5 %), and the feet standing on a
    higher tread than the lowest foot's are called stance on at least 97.5 / 99 % of their
    samples (the touchdown's delay aside): their height is taken over the tread under them (the
    other standing feet's footholds), not only over the lowest foot or a plane no staircase fits
    (measured: 99.30 / 98.07 % up, 99.76 / 99.48 % down; before, 94.89 / 88.93 and 99.28 /
    97.97 %)."""
    ground = staircase(rise_m)
    truth, probabilities, xs = walk(ground, 6.0, ContactEstimator(a1))
    on = (xs.min(axis=1) > 0.5) & (xs.max(axis=1) < 0.45 + 8 * 0.3)  # every foot on the flight
    treads = np.vectorize(ground)(xs[on])
    higher = truth[on] & (treads > treads.min(axis=1, keepdims=True) + 0.01)
    called = probabilities[on] >= 0.5
    assert higher.sum() > 300
    agree, held = (called == truth[on]).mean(), called[higher].mean()
    print(f"agree {100 * agree:.2f} %, stance on a higher tread called stance {100 * held:.2f} %")
    assert agree >= agree_goal
    assert held >= held_goal


def test_a_level_floor_reads_as_the_lowest_foot() -> None:
    """On footholds at one height the slope is level: each foot's height is its contact point's
    above the lowest one, exactly (the flat-floor rule), whatever the trunk's tilt."""
    ground = FootGround()
    tilt = math.radians(10.0)
    down = (math.sin(tilt), 0.0, -math.cos(tilt))  # the base pitched nose-up by 10°
    heights_up = [0.0, 0.0, 0.0, 0.03]  # world heights of the four contact points [m]
    xs = [0.2, 0.2, -0.2, -0.2]
    ys = [-0.13, 0.13, -0.13, 0.13]
    feet = []
    for x, y, z in zip(xs, ys, heights_up, strict=True):
        # world (x, y, z - 0.3) seen from a base pitched by ``tilt`` about y
        wz = z - 0.3
        bx, bz = x * math.cos(tilt) - wz * math.sin(tilt), x * math.sin(tilt) + wz * math.cos(tilt)
        r = (bx, y, bz)
        feet.append(FootMotion((0.0, 0.0, 0.0), r, down[0] * bx + down[2] * bz))
    standing = [True, True, True, False]
    for _ in range(10):
        heights = ground.heights(0.002, feet, down, (0.0, 0.0, 0.0), standing)
    assert heights is not None
    assert heights == pytest.approx([0.0, 0.0, 0.0, 0.03], abs=1e-9)


def test_absurd_feet_and_stamps_give_probabilities_not_errors(a1: Quadruped) -> None:
    """Positions of 1e300 m or NaN, infinite gyro rates, stamps that leap by 1e300 s: every
    step gives four probabilities in [0, 1], and no numpy warning (the footholds' fit is never
    fed a point it cannot solve for)."""
    import random
    import warnings

    rng = random.Random(1)
    values = [0.0, 1e300, -1e300, 1e-300, 3.0, -2.0, math.inf, math.nan, 1e154]
    zeros = [0.0] * 12
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        estimator = ContactEstimator(a1)
        for _ in range(40):
            estimator.reset()
            for n in range(40):
                feet = [
                    ((rng.choice(values), rng.choice(values), rng.choice(values)),
                     (rng.choice(values), 0.0, 0.0)) if rng.random() < 0.8 else None
                    for _ in range(4)
                ]  # fmt: skip
                gravity = (rng.choice(values), rng.choice(values), -9.8)
                imu = ImuSample(
                    gravity if rng.random() < 0.7 else None,
                    (rng.choice(values), 0.0, rng.choice(values)),
                    (0.0, 0.0, 9.8),
                )
                stamp = n * STEP_S if rng.random() < 0.9 else rng.choice([1e300, -5.0, 0.0])
                efforts = None if rng.random() < 0.5 else zeros
                step = estimator.step(stamp, (zeros, zeros, efforts), feet, imu)
                assert all(0.0 <= p <= 1.0 for p in step.probabilities)
