"""The standing feet's give (a1_leg_fk.estimation.foot_give) in the state filter, on a synthetic
trot whose truth is known by construction: a level base moving at a constant horizontal velocity,
an exact IMU, and each diagonal pair's feet sinking into the ground as they load and rising as
they unload (the feet's vertical velocity off by ``A sin(π t / T)`` over each stance, both feet
of the pair alike: a compliant foot, as PyBullet's mat-soft toes, sinking more under load than
at its touchdown)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from synthetic_trot import FEET, JJT, V, vertical_errors

from a1_leg_fk.estimation.filter_model import FLAT, FilterSettings, LegMeasurement
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.state_filter import StateFilter

STANCE_STEPS = 75  # 0.15 s per diagonal pair
GIVE_MPS = 0.08
"""The give's amplitude [m/s]: a 7.6 mm sink over a 0.15 s stance (PyBullet's mat-soft toes: the
feet's vertical error 0.05 m/s RMS, this 0.057)."""
GIVE = FilterSettings()
"""The give modelled (the default: ``give_s`` 0.02, the mat-soft toes' correlation time)."""
OFF = FilterSettings(give_s=0.0)
"""The give left out: the filter as it was before the term."""
FLICKER = (30, 40)
"""The steps of a stance [joint states] a swing foot is taken for standing (20 ms)."""
SETTLE_S = 2.0
"""[s] not scored: the filter's start and the give's average (``give_average_s`` 1 s)."""


def trot(
    settings: FilterSettings, give_mps: float, seconds: float = 8.0, flicker: bool = False
) -> tuple[np.ndarray, np.ndarray, StateFilter]:
    """The filter's vertical velocity error [m/s] and reported sigma [m/s] after every joint
    state past :data:`SETTLE_S`, and the filter; ``flicker``: the standing feet exact, but over
    :data:`FLICKER` of each stance a flight with one swing foot taken for standing, its vertical
    velocity off by ``give_mps`` (kinematic contacts calling a foot that descends to a lower step
    standing)."""
    state = StateFilter(settings, FLAT)  # the floor is flat and known: the feet's heights hold z

    def legs_at(k: int) -> list[LegMeasurement | None]:
        pair = (0, 3) if (k // STANCE_STEPS) % 2 == 0 else (1, 2)
        phase = (k % STANCE_STEPS) / STANCE_STEPS
        sink = 0.0 if flicker else give_mps * math.sin(math.pi * phase)
        legs: list[LegMeasurement | None] = [None] * 4
        for leg in pair:
            motion = FootMotion((V[0], V[1], sink), FEET[leg], 0.3)
            legs[leg] = LegMeasurement(motion, 0.99, JJT)
        if flicker and FLICKER[0] <= k % STANCE_STEPS < FLICKER[1]:  # a flight: one foot down
            swing = 1 if pair == (0, 3) else 0
            motion = FootMotion((V[0], V[1], give_mps), FEET[swing], 0.3)
            legs = [None] * 4
            legs[swing] = LegMeasurement(motion, 0.99, JJT)
        return legs

    errors, sigmas = vertical_errors(state, seconds, legs_at, SETTLE_S)
    return errors, sigmas, state


def test_a_foot_sinking_under_load_is_inside_the_reported_sigma() -> None:
    """The issue's goals on the vertical velocity: the error within 3 sigma on >= 95 % of the
    samples and sigma <= 5x its RMS, with the give modelled (the default). Without it (``give_s``
    0) the filter follows the feet and stays confident: the same trot's error leaves its 3
    sigma on most samples."""
    error, sigma, _ = trot(GIVE, GIVE_MPS)
    rms = math.sqrt(float((error**2).mean()))
    inside = float((np.abs(error) <= 3.0 * sigma).mean())
    print(f"give: RMS {rms:.4f} m/s, sigma {sigma.mean():.4f}, within 3 sigma {inside:.3f}")
    assert inside >= 0.95 and sigma.mean() <= 5.0 * rms
    assert rms < GIVE_MPS / math.sqrt(2.0) / 2.0  # the IMU believed over the give: half its RMS
    old_error, old_sigma, _ = trot(OFF, GIVE_MPS)
    old_inside = float((np.abs(old_error) <= 3.0 * old_sigma).mean())
    print(f"without: RMS {math.sqrt(float((old_error**2).mean())):.4f} m/s, "
          f"sigma {old_sigma.mean():.4f}, within 3 sigma {old_inside:.3f}")  # fmt: skip
    assert old_inside < 0.95


def test_the_give_is_measured_against_the_imu() -> None:
    """The give's mean square is the half-sines' variance about their mean, ``A² (1/2 - 4/π²)``
    (the stance feet's vertical velocity the IMU does not confirm, high-passed: their mean, a
    steady sink, is left to the height rows), less what the feet's white vertical noise, matched
    to their innovations, already holds: between half of it and all of it (+10 %). Feet that agree
    with the IMU have none, and the filter then gives what it gave without the term."""
    _, _, state = trot(GIVE, GIVE_MPS, seconds=4.0)
    expected = GIVE_MPS**2 * (0.5 - 4.0 / math.pi**2)
    assert 0.5 * expected < state.give.square < 1.1 * expected, (state.give.square, expected)
    exact, exact_sigma, rigid = trot(GIVE, 0.0, seconds=3.0)
    assert rigid.give.square <= 0.0
    without, without_sigma, _ = trot(OFF, 0.0, seconds=3.0)
    assert np.allclose(exact, without, atol=1e-9) and np.allclose(exact_sigma, without_sigma)


def test_a_swing_foot_taken_for_standing_is_no_give() -> None:
    """A swing foot taken for standing for 20 ms of every stance, sinking at 0.3 m/s (kinematic
    contacts on a step down: a foot still descending to the lower tread), the other feet exact:
    no stance lasts that short, so it is no give (counted only once a stance has lasted
    ``give_after_s``, 0.1 s) and the filter is the one without the term. Counted from every
    touchdown (``give_after_s`` 0), the same flickers read as a give and loosen the feet."""
    flicker = 0.3
    error, sigma, gated = trot(GIVE, flicker, seconds=4.0, flicker=True)
    assert gated.give.square <= 0.0
    without, without_sigma, _ = trot(OFF, flicker, seconds=4.0, flicker=True)
    assert np.allclose(error, without, atol=1e-9) and np.allclose(sigma, without_sigma)
    _, counted_sigma, counted = trot(
        replace(GIVE, give_after_s=0.0), flicker, seconds=4.0, flicker=True
    )
    assert counted.give.square > 0.0 and counted_sigma.mean() > 1.2 * sigma.mean()
