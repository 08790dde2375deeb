"""The online model corrections (a1_leg_fk/estimation/model_corrections.py): friction recovered
from residuals made by construction, the learning frozen in stance, and the estimator's option.

The family of robots that differ from their URDF (test/mismatch_runs.py) is scored in
test/estimation/test_mismatch_family.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from a1_leg_fk.estimation.contact_estimator import ContactEstimator
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.model_corrections import CorrectionSettings, ModelCorrections
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError

STEP_S = 0.002
SWING = [0.0, 1.0, 1.0, 1.0]
"""Stance probabilities: FR in swing, the others standing."""
FEET = [FootMotion((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), depth) for depth in (0.20, 0.3, 0.3, 0.3)]
"""FR 0.1 m above the others: the kinematics agree it is in the air."""


def friction(rate: float, bias: float, viscous: float, coulomb: float) -> float:
    """A joint's unmodelled torque [N m] at ``rate`` [rad/s]: bias, viscous and Coulomb
    friction (an exact sign, as PyBullet's joint friction), the residual a swinging leg shows."""
    return bias - viscous * rate - coulomb * float(np.sign(rate))


def test_friction_is_recovered_from_a_swinging_leg() -> None:
    """FR's three joints swing sinusoidally (as a trotting leg's, up to 6 rad/s) with known
    friction and 0.3 N m of noise on the residual; after 10 s of swing (the forgetting's time
    constant) every joint's bias, viscous and Coulomb coefficients are fitted within 20 % (bias
    within 0.05 N m) of the truth,
    and the terms taken off are within 20 % where they are large (the thigh's and calf's: the
    hip's 0.05 N m s/rad at 1.5 rad/s is within a few standard deviations of the noise, and
    shrunk by them)."""
    rng = np.random.default_rng(3)
    truth = [(0.3, 0.05, 0.2), (-0.2, 0.2, 0.6), (0.1, 0.1, 0.4)]
    corrections = ModelCorrections()
    for n in range(5000):
        t = n * STEP_S
        for joint, (amplitude, hz) in enumerate(((1.5, 2.5), (6.0, 3.0), (4.0, 3.7))):
            rate = amplitude * math.sin(2.0 * math.pi * hz * t + joint)
            residual = friction(rate, *truth[joint]) + rng.normal(0.0, 0.3)
            corrections.correct(joint, residual, rate)
        corrections.learn(STEP_S, SWING, FEET, 0.05)
    fits = list(enumerate(corrections.fit[:3])) + list(enumerate(corrections.parameters[:3]))[1:]
    for joint, (bias, viscous, coulomb) in fits:
        b, v, c = truth[joint]
        assert abs(bias - b) <= 0.05, (joint, bias)
        assert abs(viscous - v) <= 0.2 * v, (joint, viscous)
        assert abs(coulomb - c) <= 0.2 * c, (joint, coulomb)
    assert corrections.parameters[3:] == [(0.0, 0.0, 0.0)] * 9  # the standing legs: frozen
    fitted = corrections.correct(1, friction(2.0, *truth[1]), 2.0)
    assert abs(fitted) <= 0.2 * abs(friction(2.0, *truth[1]))  # the friction taken off


def test_a_joint_without_friction_gets_no_correction() -> None:
    """The exact robot's blocker, by construction: a calf swinging as a walk's does (rate of one
    sign for its first 35 samples, up to 12 rad/s), its residual the observer's few hundredths
    of a N m of integration error, or with 0.5 N m of sensor noise. Nothing the data do not show
    is taken off: every term stays below 0.05 N m of torque at any rate, at every sample (the
    clipped fit of before drove bias and Coulomb to +-1.2 N m on such a start)."""
    rng = np.random.default_rng(5)
    for noise in (0.0, 0.5):
        corrections = ModelCorrections()
        worst = 0.0
        for n in range(5000):
            rate = -12.0 * math.sin(2.0 * math.pi * 3.0 * n * STEP_S + 0.1)
            residual = 0.02 * math.sin(7.0 * n * STEP_S) + rng.normal(0.0, noise)
            corrections.correct(2, residual, rate)
            corrections.learn(STEP_S, SWING, FEET, 0.05)
            bias, viscous, coulomb = corrections.parameters[2]
            worst = max(worst, abs(bias) + 12.0 * viscous + coulomb)
        assert worst <= 0.05, (noise, worst)


@pytest.mark.parametrize(
    ("probabilities", "feet"),
    [
        ([0.2, 1.0, 1.0, 1.0], FEET),  # the filter not confident of the swing
        (SWING, [FEET[1]] * 4),  # the foot as low as the others: the kinematics disagree
        (SWING, [None] * 4),  # no kinematics
    ],
)
def test_learning_is_frozen_unless_the_foot_is_surely_in_the_air(probabilities, feet) -> None:
    corrections = ModelCorrections()
    for n in range(500):
        corrections.correct(0, 1.0, math.sin(n * 0.1))
        corrections.learn(STEP_S, probabilities, feet, 0.05)
    assert corrections.learnt_samples == 0
    assert corrections.parameters[0] == (0.0, 0.0, 0.0)


def test_the_estimates_stay_within_their_bounds() -> None:
    """A residual far outside anything friction makes (50 N m, against the rate) saturates the
    bounds; friction never turns into a motor (viscous and Coulomb stay >= 0)."""
    settings = CorrectionSettings(bounds=(3.0, 0.5, 1.5))
    corrections = ModelCorrections(settings)
    for n in range(3000):
        rate = 5.0 * math.sin(n * 0.01)
        corrections.correct(0, 50.0 + 50.0 * rate, rate)
        corrections.learn(STEP_S, SWING, FEET, 0.05)
    bias, viscous, coulomb = corrections.parameters[0]
    assert bias <= 3.0 and viscous == 0.0 and 0.0 <= coulomb <= 1.5


@pytest.mark.parametrize(
    "settings", [{"forget_s": 0.0}, {"smooth_rate": math.nan}, {"bounds": (1.0, -1.0, 1.0)}]
)
def test_absurd_settings_are_refused(settings) -> None:
    with pytest.raises(LegFkError, match="model corrections"):
        CorrectionSettings(**settings)


def test_the_estimator_takes_online_off_or_a_file() -> None:
    a1_quadruped = Quadruped.from_urdf()
    assert ContactEstimator(a1_quadruped, model_corrections="online").corrections is not None
    assert ContactEstimator(a1_quadruped).corrections is not None  # the default
    assert ContactEstimator(a1_quadruped, model_corrections="off").corrections is None
    with pytest.raises(LegFkError, match="corrections file onlin: cannot be read"):
        ContactEstimator(a1_quadruped, model_corrections="onlin")  # neither mode nor a file


def test_the_samples_taken_in_at_once_are_the_forgotten_least_squares() -> None:
    """700 swing samples of FR's three joints (residual 0.3 - 0.1 q̇ - 0.4 tanh(q̇/0.1) N m with
    noise), forgetting 0.5 s so it weighs: the fit equals the weighted least squares written
    out by hand, weights exp(-(T - t_i) / 0.5 s), prior information (0.5/3)², (0.5/0.5)²,
    (0.5/1.5)² (the noise over each bound, squared); the samples counted as they come."""
    corrections = ModelCorrections(CorrectionSettings(forget_s=0.5))
    rng = np.random.default_rng(3)
    rates = rng.uniform(-5.0, 5.0, 700)
    sign = np.tanh(rates / 0.1)
    residuals = 0.3 - 0.1 * rates - 0.4 * sign + rng.normal(0.0, 0.05, 700)
    for count, (residual, rate) in enumerate(zip(residuals.tolist(), rates.tolist()), 1):
        for joint in range(3):
            corrections.correct(joint, residual, rate)
        corrections.learn(STEP_S, SWING, FEET, 0.05)
        assert corrections.learnt_samples == 3 * count
    corrections.solve()
    theta = forgotten_least_squares(rates, residuals)
    for joint in range(3):
        bias, viscous, coulomb = corrections.fit[joint]
        assert np.allclose([bias, -viscous, -coulomb], theta, rtol=1e-9, atol=1e-12)
    assert np.allclose(theta, [0.3, -0.1, -0.4], atol=0.02)


def forgotten_least_squares(rates: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """Bias, viscous and Coulomb terms fitted to one joint's samples written out by hand: weights
    exp(-(T - t_i) / 0.5 s) with t_i = i x 2 ms (its own learning time), prior information
    (0.5/3)², (0.5/0.5)², (0.5/1.5)² (the noise over each bound, squared)."""
    count = len(rates)
    weights = np.exp(-(count - np.arange(1, count + 1)) * STEP_S / 0.5)
    regressors = np.stack([np.ones(count), rates, np.tanh(rates / 0.1)], axis=1)
    information = regressors.T @ (weights[:, None] * regressors)
    information += np.diag([(0.5 / 3.0) ** 2, (0.5 / 0.5) ** 2, (0.5 / 1.5) ** 2])
    theta: np.ndarray = np.linalg.solve(information, regressors.T @ (weights * residuals))
    return theta


def test_a_joints_missing_or_non_finite_samples_are_skipped_and_stop_its_clock_alone() -> None:
    """FR's three joints swing 700 samples; the knee's residual is NaN every 5th sample, the
    hip's rate infinite every 3rd, the thigh never corrected every 4th (no sample): each joint's
    fit is the forgotten least squares of its own finite samples alone, its learning time
    advancing only with them (the others unaffected), and the samples counted as they come."""
    corrections = ModelCorrections(CorrectionSettings(forget_s=0.5))
    rng = np.random.default_rng(5)
    rates = rng.uniform(-5.0, 5.0, (700, 3))
    residuals = 0.3 - 0.1 * rates - 0.4 * np.tanh(rates / 0.1) + rng.normal(0.0, 0.05, (700, 3))
    kept = np.ones((700, 3), bool)
    kept[::3, 0], kept[::4, 1], kept[::5, 2] = False, False, False
    count = 0
    for n in range(700):
        for joint in range(3):
            rate, residual = float(rates[n, joint]), float(residuals[n, joint])
            if joint == 0 and not kept[n, 0]:
                rate = math.inf
            if joint == 2 and not kept[n, 2]:
                residual = math.nan
            if joint != 1 or kept[n, 1]:
                corrections.correct(joint, residual, rate)
        corrections.learn(STEP_S, SWING, FEET, 0.05)
        count += int(kept[n].sum())
        assert corrections.learnt_samples == count
    corrections.solve()
    for joint in range(3):
        mine = kept[:, joint]
        theta = forgotten_least_squares(rates[mine, joint], residuals[mine, joint])
        bias, viscous, coulomb = corrections.fit[joint]
        assert np.allclose([bias, -viscous, -coulomb], theta, rtol=1e-9, atol=1e-12), joint
