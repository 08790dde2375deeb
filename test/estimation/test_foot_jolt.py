"""The standing feet's horizontal jolt at each touchdown (a1_leg_fk.estimation.foot_jolt): the
measurement by hand, and the state filter on a synthetic trot whose truth is known by
construction (a level base at a constant horizontal velocity, an exact IMU, the diagonal pairs
overlapping 8 ms at each handover, every standing foot's sideways velocity off by ``A exp(-t /
τ)`` after each touchdown, all alike, plus a seeded white noise): the slip PyBullet's position
motors show (a1_position_flat: 0.04-0.05 m/s in the first 25 ms) and a gentle trot's."""

from __future__ import annotations

import math

import numpy as np
from synthetic_trot import FEET, JJT, STEP_NS, V, sigma_scores, vertical_errors

from a1_leg_fk.estimation.filter_model import FLAT, FilterSettings, LegMeasurement
from a1_leg_fk.estimation.foot_jolt import FootJolt
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.state_filter import StateFilter

NOISE_MPS = 0.002
"""Each foot's white noise [m/s] per axis (seeded)."""
STANCE_STEPS = 100
"""A diagonal pair's stance [joint states]: 0.2 s, the next pair landing 4 joint states before it
lifts."""
OVERLAP_STEPS = 4
SETTLE_S = 2.0
"""[s] not scored: the filter's start and its noise scales' first seconds."""
WITHOUT = FilterSettings(impact_window_s=0.0)
"""No landing measured: no jolt either (the filter before it)."""


def test_a_jolt_starts_at_the_last_ones_size_and_then_is_its_own() -> None:
    """Hand numbers (updates 2 ms apart: a measured ``a²`` counts ``2τ / dt`` = 30 times): none
    before a touchdown; the first one ``0.1²`` (the setting) decaying as ``e^{-2t/τ}``; a
    standing foot 0.03 m/s off sideways (0.02, 0.0224 in x and y), its innovation's variance
    0.0002 per horizontal axis, measures ``(0.03² - 0.0004) / 2``; a second one, 0.04 m/s off a
    sample later on a tilted base (the along-up part of the residual and of its variance left
    out), makes it the least-squares fit of ``a² d(t)`` to both excesses; the next touchdown
    starts at that size until it measures its own; a sample past ``impact_window_s`` measures
    nothing."""
    settings = FilterSettings()
    tau, dt = settings.touchdown_s, 0.002
    jolt = FootJolt(settings)
    assert jolt.variance(0) == 0.0
    jolt.observe(0, [(0.5, 0.5, 0.5)], (0.0, 0.0, 1.0), np.eye(3), [0])  # no touchdown yet
    assert jolt.square is None
    jolt.land(2_000_000)
    assert math.isclose(jolt.variance(2_000_000 + 15_000_000), 0.01 * math.exp(-1.0))
    innovation = np.diag([0.0002, 0.0002, 0.5])
    jolt.observe(2_000_000, [(0.02, math.sqrt(0.0005), 0.3)], (0.0, 0.0, 1.0), innovation, [0])
    measured = (0.03**2 - 0.0004) / 2.0
    assert jolt.square is not None and math.isclose(jolt.square, measured, rel_tol=1e-9)
    assert math.isclose(jolt.variance(2_000_000), measured * 2.0 * tau / dt, rel_tol=1e-9)
    tilted = (0.0, math.sin(0.3), math.cos(0.3))
    block = np.eye(3) * 0.0002 + np.outer(tilted, tilted) * 0.5
    residual = np.array([0.0, math.cos(0.3), -math.sin(0.3)]) * 0.04 + np.array(tilted) * 0.7
    jolt.observe(4_000_000, [tuple(residual)], tilted, block, [0])
    share = math.exp(-2.0 * dt / tau)  # the fit of a² d(t) to both excesses
    later = (measured + (0.04**2 - 0.0004) / 2.0 * share) / (1.0 + share * share)
    assert math.isclose(jolt.square, later, rel_tol=1e-9)
    jolt.land(10_000_000)
    assert math.isclose(jolt.variance(10_000_000), 0.01, rel_tol=1e-9)  # capped: the setting
    jolt.observe(10_000_000 + 31_000_000, [(1.0, 1.0, 0.0)], (0.0, 0.0, 1.0), innovation, [0])
    assert jolt.square is None and math.isclose(jolt.previous or 0.0, later, rel_tol=1e-9)


def trot(settings: FilterSettings, slip_mps: float, seconds: float = 10.0):
    """The filter's sideways (y) velocity error [m/s] and its reported sigma [m/s] after every
    joint state past :data:`SETTLE_S`: after each touchdown every standing foot's y velocity off
    by ``slip_mps exp(-t / touchdown_s)``, all alike, every foot's by a white noise."""
    rng = np.random.default_rng(7)
    tau = settings.touchdown_s

    def legs_at(k: int) -> list[LegMeasurement | None]:
        phase = k % STANCE_STEPS
        pairs = [(0, 3) if (k // STANCE_STEPS) % 2 == 0 else (1, 2)]
        if phase >= STANCE_STEPS - OVERLAP_STEPS:  # the next pair has landed
            pairs.append((1, 2) if pairs[0] == (0, 3) else (0, 3))
            since_s = (phase - (STANCE_STEPS - OVERLAP_STEPS)) * STEP_NS / 1e9
        else:
            since_s = (phase + OVERLAP_STEPS) * STEP_NS / 1e9
        slip = slip_mps * math.exp(-since_s / tau)
        legs: list[LegMeasurement | None] = [None] * 4
        for leg in (leg for pair in pairs for leg in pair):
            x, y, z = NOISE_MPS * rng.normal(size=3)
            motion = FootMotion((V[0] + x, V[1] + slip + y, V[2] + z), FEET[leg], 0.3)
            legs[leg] = LegMeasurement(motion, 0.99, JJT)
        return legs

    return vertical_errors(StateFilter(settings, FLAT), seconds, legs_at, SETTLE_S, axis=1)


def scores(settings: FilterSettings, slip_mps: float) -> tuple[float, float, float]:
    """The trot's mean sideways sigma [m/s], that over its RMS error, and the share of samples
    within 3 sigma."""
    return sigma_scores(*trot(settings, slip_mps))


def test_the_standing_feet_slipping_at_each_touchdown_stay_inside_the_reported_sigma() -> None:
    """Every standing foot 0.04 m/s off sideways at each touchdown (a1_position_flat's handovers),
    decaying over ``touchdown_s``: each touchdown's jolt measured, the error stays within 3 sigma
    on >= 95 % of the samples with sigma <= 5x its RMS; without it (no landing measured) the
    filter follows the feet (fewer than 90 % within 3 sigma)."""
    measured, without = scores(FilterSettings(), 0.04), scores(WITHOUT, 0.04)
    print(f"sigma [m/s], sigma / error, within 3 sigma: measured {measured}, without {without}")
    assert measured[2] >= 0.95 and measured[1] <= 5.0
    assert without[2] < 0.90


def test_a_gentle_trots_touchdowns_cost_it_little() -> None:
    """Touchdowns that jolt the standing feet by 1 mm/s (below their 2 mm/s white noise): the
    sideways sigma within 25 % of the filter's without the jolt, the goals met."""
    measured, without = scores(FilterSettings(), 0.001), scores(WITHOUT, 0.001)
    print(f"sigma [m/s], sigma / error, within 3 sigma: measured {measured}, without {without}")
    assert abs(measured[0] / without[0] - 1.0) <= 0.25
    assert measured[1] <= 5.0 and measured[2] >= 0.95


def test_feet_landing_after_a_flight_jolt_no_one() -> None:
    """A touchdown while no foot stood (a start, a flight's landing) starts no jolt: the feet
    landing then are the impact's (foot_impact), not a jolt of feet already standing."""
    state = StateFilter(FilterSettings(), FLAT)
    motion = FootMotion(V, FEET[0], 0.3)
    legs: list[LegMeasurement | None] = [LegMeasurement(motion, 0.99, JJT), None, None, None]
    state.propagate(STEP_NS, (0.0, 0.0, 0.0), (0.0, 0.0, 9.80665), (0.0, 0.0, 0.0, 1.0))
    state.update(STEP_NS, legs, (0.0, 0.0, 0.0, 1.0))
    assert state.jolt.landed_ns is None
    legs[3] = LegMeasurement(FootMotion(V, FEET[3], 0.3), 0.99, JJT)
    state.propagate(2 * STEP_NS, (0.0, 0.0, 0.0), (0.0, 0.0, 9.80665), (0.0, 0.0, 0.0, 1.0))
    state.update(2 * STEP_NS, legs, (0.0, 0.0, 0.0, 1.0))
    assert state.jolt.landed_ns == 2 * STEP_NS
