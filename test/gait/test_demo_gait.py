"""The demo gait (pure, no ROS): inside the URDF limits, analytic rates, diagonal-pair timing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shared import known

from a1_leg_fk.gait.demo_gait import Gait, GaitParameters, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

ROBOT = Quadruped.from_urdf()
GAIT = Gait(limits_of(ROBOT))
# Stand-up, fade-in and several trot cycles, sampled densely (1 ms).
TIMES = np.arange(-0.5, GAIT.periodic_from_s + 4 * GAIT.period_s, 0.001)


def angles_over(times: np.ndarray) -> np.ndarray:
    return np.array([GAIT.angles(float(t)) for t in times])


def test_every_angle_stays_inside_the_urdf_limits() -> None:
    angles = angles_over(TIMES)
    lower = np.array([joint.lower for joint in ROBOT.joints])
    upper = np.array([joint.upper for joint in ROBOT.joints])
    assert angles.shape == (len(TIMES), 12)
    assert (angles >= lower).all() and (angles <= upper).all()
    # ...and with the robot's own limit report, at every sample.
    assert not any(ROBOT.joints_outside_limits(row) for row in angles[::7])


def test_stands_up_from_a_crouch_then_trots() -> None:
    knee_lower = min(known(joint.lower) for joint in ROBOT.joints[2::3])
    knee_upper = max(known(joint.upper) for joint in ROBOT.joints[2::3])
    crouch, stood = np.array(GAIT.angles(0.0)), np.array(GAIT.angles(GAIT.trot_start_s))
    # Crouched: knees in the most-bent 10 % of their range; standing: the A1's usual pose.
    assert (crouch[2::3] < knee_lower + 0.1 * (knee_upper - knee_lower)).all()
    np.testing.assert_allclose(stood.reshape(4, 3), [[0.0, 0.8, -1.5]] * 4, atol=1e-12)
    # The body rises: every foot ends lower relative to the trunk (z more negative) than it
    # started.
    assert (ROBOT.fk(stood)[:, 2] < ROBOT.fk(crouch)[:, 2] - 0.05).all()
    # Crouch: each foot roughly under its hip-pitch joint.
    for leg in ROBOT.legs:
        points = leg.joint_points(crouch[:3])
        assert abs(points[3, 0] - points[1, 0]) < 0.02
    # Periodic after the fade-in, at ~2 Hz.
    assert 1.5 <= 1.0 / GAIT.period_s <= 2.5
    later = GAIT.periodic_from_s + np.linspace(0, 3 * GAIT.period_s, 200)
    np.testing.assert_allclose(
        angles_over(later), angles_over(later + 5 * GAIT.period_s), atol=1e-9
    )


def test_velocities_match_finite_differences() -> None:
    step = 1e-7  # small: the swing's sin**2 lift has a kink in its second derivative at lift-off
    for t in TIMES[::13]:
        t = float(t)
        numeric = (np.array(GAIT.angles(t + step)) - np.array(GAIT.angles(t - step))) / (2 * step)
        np.testing.assert_allclose(GAIT.velocities(t), numeric, atol=1e-5, err_msg=f"t={t}")


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=-1.0, max_value=60.0))
def test_velocities_match_finite_differences_anywhere(t: float) -> None:
    step = 1e-7
    numeric = (np.array(GAIT.angles(t + step)) - np.array(GAIT.angles(t - step))) / (2 * step)
    np.testing.assert_allclose(GAIT.velocities(t), numeric, atol=1e-5)


def test_velocities_are_continuous_and_nonzero_while_trotting() -> None:
    rates = np.array([GAIT.velocities(float(t)) for t in TIMES])
    # No jumps (1 ms steps): the largest change is bounded by the peak acceleration (the knee's
    # 2 * knee_lift * omega**2 ~ 160 rad/s**2 at 2 Hz, i.e. 0.16 rad/s per ms), never a step.
    assert np.abs(np.diff(rates, axis=0)).max() < 0.2
    trotting = rates[GAIT.periodic_from_s < TIMES]
    assert np.abs(trotting).max(axis=0).min() > 0.05  # every joint moves
    np.testing.assert_allclose(GAIT.velocities(-0.2), 0.0)


def test_diagonal_pairs_alternate() -> None:
    times = GAIT.periodic_from_s + np.linspace(0, 2 * GAIT.period_s, 2001)
    angles = angles_over(times).reshape(len(times), 4, 3)
    slot = {leg: i for i, leg in enumerate(LEG_NAMES)}
    # Diagonal partners move identically...
    np.testing.assert_allclose(angles[:, slot["FR"]], angles[:, slot["RL"]], atol=1e-12)
    np.testing.assert_allclose(angles[:, slot["FL"]], angles[:, slot["RR"]], atol=1e-12)
    # ...and the other pair does the same half a cycle later.
    half = np.array(angles_over(times + GAIT.period_s / 2)).reshape(len(times), 4, 3)
    np.testing.assert_allclose(angles[:, slot["FR"]], half[:, slot["FL"]], atol=1e-9)
    # Never both pairs in the air at once; each pair swings about half the time.
    for t in times:
        swinging = {leg for leg in LEG_NAMES if GAIT.swinging(float(t), leg)}
        assert swinging in (set(), {"FR", "RL"}, {"FL", "RR"})
    fr_swing = np.mean([GAIT.swinging(float(t), "FR") for t in times])
    assert 0.45 < fr_swing < 0.55
    # In swing the knee bends more (the foot lifts): the FR foot is highest while FR swings.
    feet = ROBOT.fk_batch(angles.reshape(len(times), 12))
    fr_z = feet[:, slot["FR"], 2]
    top = int(np.argmax(fr_z))
    assert GAIT.swinging(float(times[top]), "FR") and not GAIT.swinging(float(times[top]), "FL")
    assert fr_z.max() - fr_z.min() > 0.03  # a visible step (> 3 cm)


def test_small_hip_roll() -> None:
    rolls = angles_over(TIMES)[:, 0::3]
    assert 0.0 < np.abs(rolls).max() <= 0.1


def test_limits_come_from_the_model() -> None:
    limits = limits_of(ROBOT)
    assert limits == [(joint.lower, joint.upper) for joint in ROBOT.joints]
    # A robot whose knees cannot bend as far gets a shallower crouch, still inside its limits.
    narrower = [
        (lo, hi) if slot % 3 != 2 else (known(lo) + 0.5, hi)
        for slot, (lo, hi) in enumerate(limits)
    ]
    gait = Gait(narrower)
    assert min(gait.angles(0.0)[2::3]) >= known(limits[2][0]) + 0.5
    # Limits that cannot hold the gait are refused with a message naming the joint.
    with pytest.raises(LegFkError, match="slot 1"):
        Gait([(lo, hi) if slot != 1 else (0.0, 0.9) for slot, (lo, hi) in enumerate(limits)])
    with pytest.raises(LegFkError):
        Gait(limits[:11])
    with pytest.raises(LegFkError):
        Gait(limits, GaitParameters(trot_hz=0.0))


def test_custom_frequency() -> None:
    gait = Gait(limits_of(ROBOT), GaitParameters(trot_hz=1.0))
    t = gait.periodic_from_s + 0.3
    np.testing.assert_allclose(gait.angles(t), gait.angles(t + 1.0), atol=1e-12)
    assert not math.isclose(gait.angles(t)[1], gait.angles(t + 0.5)[1])
