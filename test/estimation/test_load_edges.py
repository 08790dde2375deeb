"""Where the smoothed contacts of a foot with force evidence end, on loads built by construction
(issue #39): a slow unloading ramp whose zero is known, a dip to half a newton inside a stance,
and a step to zero seen through the momentum observer's first-order lag. The evidence is the
contact filter's model written out (force log-ratio ``(N - 3 % W) / (0.5 % W)`` within +-4,
the transition's switch probability), so the right answer is the load's own zero.
"""

from __future__ import annotations

import numpy as np
import pytest

from a1_leg_fk.estimation.contact_filter import ContactFilter
from a1_leg_fk.estimation.contact_model import ContactModel
from a1_leg_fk.estimation.contact_smoother import EvidenceRows, FixedLagSmoother
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.load_edges import loaded_stance, unlagged

LEGS, STEP_S, WEIGHT_N = 4, 0.002, 120.0
HALF_N, SCALE_N = 0.03 * WEIGHT_N, 0.005 * WEIGHT_N
OBSERVER_LAG_S = 0.001


def rows_of(loads: np.ndarray, kinematic: np.ndarray) -> EvidenceRows:
    """The filter's evidence of (N, 4) normal forces [N] and kinematic log-ratios, 500 Hz (the
    feet's heights unknown)."""
    count = len(loads)
    force = np.clip((loads - HALF_N) / SCALE_N, -4.0, 4.0)
    switch = np.full(count, 1.0 - np.exp(-STEP_S / 0.1))
    forced = np.ones((count, LEGS), dtype=bool)
    heights = np.full((count, LEGS), np.nan)
    stamps = np.arange(count) * STEP_S
    return EvidenceRows(stamps, switch, kinematic, forced, kinematic + force, loads, heights)


def stance_of(rows: EvidenceRows, force_lag_s: float = 0.0) -> np.ndarray:
    """(N, 4) bool: the smoother's stance (probability >= 0.5) over the whole run."""
    smoother = FixedLagSmoother(force_lag_s=force_lag_s)
    smoother.add(rows)
    return smoother.take(len(rows)) >= 0.5


def liftoffs(stance: np.ndarray) -> np.ndarray:
    """Rows where a stance has ended (the first row of swing)."""
    return np.flatnonzero(stance[:-1] & ~stance[1:]) + 1


def gait_loads(
    rng: np.random.Generator, ramp_n_per_ms: float, cliff_n: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) loads [N] of 20 strides (200 ms stance at 30 N ending in a linear ramp of
    ``ramp_n_per_ms`` down to ``cliff_n``, then zero; 200 ms of swing at 0) plus 2 N of sensor
    noise, and the rows where each true load reaches zero (the first row without load)."""
    stride = np.zeros(200)
    ramp_rows = int(np.ceil((30.0 - cliff_n) / (ramp_n_per_ms * 2.0)))
    stride[:100] = 30.0
    stride[100 - ramp_rows : 100] = 30.0 - ramp_n_per_ms * 2.0 * np.arange(1, ramp_rows + 1)
    stride[:100] = np.maximum(stride[:100], max(cliff_n, 0.0))
    true = np.tile(stride, 20)
    zeros = np.flatnonzero((true[:-1] > 0.0) & (true[1:] <= 0.0)) + 1
    loads = true[:, None] + rng.normal(0.0, 2.0, (true.size, LEGS))
    return loads, zeros


def test_a_slow_unloading_ramp_lifts_off_where_it_reaches_zero() -> None:
    """A pronk's push-off: the kinematics say swing through the stance's end (-3.5, the foot
    moving), the load falls at 1.1 N/ms. Evidence at even odds at 3.6 N ends the stance ~3 ms
    early; the ramp's zero is the liftoff: median error within one sample on every foot."""
    loads, zeros = gait_loads(np.random.default_rng(39), 1.1)
    kinematic = np.full(loads.shape, -3.5)
    stance = stance_of(rows_of(loads, kinematic))
    for leg in range(LEGS):
        found = liftoffs(stance[:, leg])
        errors = [int(found[np.abs(found - z).argmin()]) - z for z in zeros]
        assert abs(np.median(errors)) <= 1, (leg, errors)


def test_a_load_that_falls_off_a_cliff_is_not_carried_on_by_its_ramp() -> None:
    """A soft trotting foot's end: the load falls at 2 N/ms to 6 N, then to zero in one sample,
    with 2 N of noise. The ramp's line would reach zero a sample after the cliff; the sample's
    own load (near zero) weighs against it: the median liftoff on the cliff, fewer than half of
    them a sample late (36 of 80; the line alone: median one sample late, 46 of 80)."""
    loads, zeros = gait_loads(np.random.default_rng(39), 2.0, cliff_n=6.0)
    stance = stance_of(rows_of(loads, np.full(loads.shape, -3.5)))
    errors = []
    for leg in range(LEGS):
        found = liftoffs(stance[:, leg])
        errors += [int(found[np.abs(found - z).argmin()]) - z for z in zeros]
    assert np.median(errors) == 0, errors
    assert sum(e > 0 for e in errors) < len(errors) // 2, errors


def test_a_dip_that_never_unloads_is_bridged_and_a_swing_is_kept() -> None:
    """Clean loads (0.02 N of noise): stances at 30 N, one dipping to 0.5 N for 40 ms
    (a foot that never leaves the ground, below the evidence's 3.6 N), swings at 0 N. The dip
    stands; every swing stays a swing from its second sample on."""
    rng = np.random.default_rng(7)
    true = np.tile(np.r_[np.full(100, 30.0), np.zeros(100)], 10)
    dip = slice(430, 450)  # inside the third stance
    true[dip] = 0.5
    loads = (true + rng.normal(0.0, 0.02, true.size))[:, None].repeat(LEGS, axis=1)
    stance = stance_of(rows_of(loads, np.zeros(loads.shape)))
    assert stance[dip].all()
    swing = (true == 0.0)[:, None].repeat(LEGS, axis=1)
    swing[np.flatnonzero(np.diff(true == 0.0, prepend=False))] = False  # each swing's first
    assert not (stance & swing).any()


def dip_loads() -> tuple[np.ndarray, np.ndarray, slice, slice]:
    """(N, 4) loads [N] with 0.06 N of noise (the floor 8 x 0.06 = 0.48 N): stances at 30 N,
    one dipping from 3 N down to 0.4 N and back over 50 ms (under the floor for its middle 10
    ms, never at zero: the foot stands), another the same but at zero for two samples in its
    middle (the foot left); the true loads (N,), the dip's rows and the rows at zero."""
    rng = np.random.default_rng(36)
    true = np.tile(np.r_[np.full(100, 30.0), np.zeros(100)], 10)
    dip, touched, left = slice(430, 455), slice(630, 655), slice(641, 643)
    true[dip] = true[touched] = 0.4 + 2.6 * np.abs(np.linspace(-1.0, 1.0, 25))
    true[left] = 0.0
    loads = (true + rng.normal(0.0, 0.06, true.size))[:, None].repeat(LEGS, axis=1)
    return loads, true, dip, left


def test_a_dip_under_the_floor_that_never_reaches_zero_is_bridged() -> None:
    """go2_walk's first stride, built (:func:`dip_loads`): the dip stands; the other keeps its
    swing on the samples at zero, as every swing keeps its own from its second sample on."""
    loads, true, dip, left = dip_loads()
    stance = stance_of(rows_of(loads, np.zeros(loads.shape)))
    assert stance[dip].all()
    assert not stance[left].any()
    swing = (true == 0.0)[:, None].repeat(LEGS, axis=1)
    swing[np.flatnonzero(np.diff(true == 0.0, prepend=False))] = False  # each swing's first
    assert not (stance & swing).any()


def test_the_observers_lag_is_no_load() -> None:
    """A load stepping from 30 N to 0 seen through the observer's lag (1 ms: 4.1, 0.55, 0.07 N
    on the samples after the step) with 0.02 N of noise: the lag undone, the stance ends at most
    one sample after the step (the filter's own), not carried on by the decaying lag."""
    rng = np.random.default_rng(5)
    true = np.tile(np.r_[np.full(100, 30.0), np.zeros(100)], 10)
    lagged = np.empty_like(true)
    keep, value = np.exp(-STEP_S / OBSERVER_LAG_S), 30.0
    for k, load in enumerate(true):
        value = keep * value + (1.0 - keep) * load
        lagged[k] = value
    loads = (lagged + rng.normal(0.0, 0.02, true.size))[:, None].repeat(LEGS, axis=1)
    stance = stance_of(rows_of(loads, np.zeros(loads.shape)), OBSERVER_LAG_S)
    steps = np.flatnonzero((true[:-1] > 0.0) & (true[1:] == 0.0)) + 1
    for leg in range(LEGS):
        found = liftoffs(stance[:, leg])
        assert all(0 <= found[np.abs(found - s).argmin()] - s <= 1 for s in steps), found


def test_unlagged_inverts_a_first_order_lag() -> None:
    """Any load through the lag's exact discretization, then undone: the load again."""
    rng = np.random.default_rng(3)
    stamps = np.cumsum(rng.uniform(0.001, 0.003, 200))
    load = rng.uniform(0.0, 50.0, (200, LEGS))
    lagged = load.copy()
    for k in range(1, 200):
        keep = np.exp(-(stamps[k] - stamps[k - 1]) / OBSERVER_LAG_S)
        lagged[k] = keep * lagged[k - 1] + (1.0 - keep) * load[k]
    np.testing.assert_allclose(unlagged(lagged, stamps, OBSERVER_LAG_S)[1:], load[1:], atol=1e-9)


@pytest.mark.parametrize("case", ["ramps", "dips"])
def test_windows_give_the_whole_pass_with_loads(case: str) -> None:
    """Blocks of 7 rows through the fixed-lag smoother against one pass over every row, on
    noisy loads with ramps, and on loads with dips (:func:`dip_loads`): the loads' rules see the
    same rows (their history kept, their look ahead within the lag), the same stance on every
    row."""
    if case == "ramps":
        loads = gait_loads(np.random.default_rng(11), 1.1)[0]
        rows = rows_of(loads, np.full(loads.shape, -3.5))
    else:
        loads = dip_loads()[0]
        rows = rows_of(loads, np.zeros(loads.shape))
    whole = stance_of(rows, OBSERVER_LAG_S)
    smoother, parts = FixedLagSmoother(force_lag_s=OBSERVER_LAG_S), []
    for start in range(0, len(rows), 7):  # a block's end lands inside many stances' ends
        smoother.add(rows[start : start + 7])
        parts.append(smoother.take(smoother.final_rows()))
    parts.append(smoother.take(len(smoother.pending)))
    np.testing.assert_array_equal(np.concatenate(parts) >= 0.5, whole)


def test_a_trotting_foots_liftoff_smoothed_is_no_later_than_the_filters() -> None:
    """A trot's clean liftoffs (a1_trot_soft's RL at 1.7 s: the load ramping down 2.9 N a
    sample to 8.2 N, then nothing; 0.05 N of noise, the floor 0.4 N), the feet low and still
    throughout: the causal filter (no low-and-still stance beside a force that says swing) lets
    go on the first sample without load. The smoother, run on the filter's own evidence, lets
    go there too: the unloading ramp's line (8.0 N at the stance's last sample, reaching zero
    5.7 ms after it, far above the floor) would carry the stance two samples past the cliff,
    where the samples' own loads say none."""
    rng = np.random.default_rng(46)
    ramp = [25.1, 22.2, 19.3, 16.4, 13.6, 10.6, 8.2]
    stride = np.r_[np.full(100 - len(ramp), 30.0), ramp, np.zeros(100)]
    true = np.stack([np.roll(np.tile(stride, 10), shift) for shift in (0, 100, 100, 0)], axis=1)
    loads = np.abs(true + rng.normal(0.0, 0.05, true.shape))
    still = FootMotion((0.0, 0.0, 0.0), (0.0, 0.0, -0.3), 0.3)
    contacts = ContactFilter(ContactModel.for_robot(WEIGHT_N, 0.4))
    causal, kept = np.empty(true.shape), []
    for k, row in enumerate(loads.tolist()):
        causal[k] = contacts.update(STEP_S, [still] * LEGS, ((0.0, 0.0, 0.0), None), row)
        kept.append(contacts.evidence)
    switch, kinematic, forced, total, heights = (np.array(c) for c in zip(*kept, strict=True))
    stamps = np.arange(len(loads)) * STEP_S
    rows = EvidenceRows(stamps, switch, kinematic, forced, total, loads, heights)
    smoothed = stance_of(rows)
    for leg in range(LEGS):
        zeros = np.flatnonzero((true[:-1, leg] > 0.0) & (true[1:, leg] == 0.0)) + 1
        assert liftoffs(causal[:, leg] >= 0.5).tolist() == zeros.tolist(), leg
        assert liftoffs(smoothed[:, leg]).tolist() == zeros.tolist(), leg


def carried_past(ramp: list[float], next_n: float) -> bool:
    """Whether the loads' rules (:func:`~a1_leg_fk.estimation.load_edges.loaded_stance`, the
    stance's odds given) carry a stance one sample past its end: every foot's swing load
    alternates +-2 N (the noise's robust spread 2.97 N: the floor's rules stay off), the first
    foot stands at 30 N for 40 samples ending in the five ``ramp`` loads [N], its first swing
    sample reading ``next_n`` [N]."""
    count = 200
    loads = np.where(np.arange(count)[:, None] % 2, 2.0, -2.0) * np.ones((1, LEGS))
    odds = np.full((count, LEGS), -5.0)
    loads[60:95, 0] = 30.0
    loads[95:100, 0] = ramp
    loads[100, 0] = next_n
    odds[60:100, 0] = 5.0
    stamps = np.arange(count) * STEP_S
    forced = np.ones((count, LEGS), dtype=bool)
    return bool(loaded_stance(odds, stamps, loads, forced)[100, 0] >= 0.0)


def test_the_ramp_carries_a_sample_only_at_one_and_a_half_standard_errors() -> None:
    """A trotting foot's last loads, noisy (19.5, 13.5, 12, 10.5, 4.5 N: the line 5.4 N at the
    stance's last sample, -1650 N/s, its residuals' variance 2.7 N^2), then a cliff to zero
    (truth: swing) whose first sample reads 1 N of noise. Written out: the line's 2.1 N there
    (variance 1.1 x 2.7 N^2) and the sample's 1 N (2.7 N^2) weighted by their inverse
    variances give 1.52 N within 1.19 N, 1.28 standard errors: at one standard error the ramp
    would carry it; at 1.5 it is swing, as the truth. Reading 2 N (2.05 N within 1.19 N, 1.72
    standard errors), it is carried."""
    ramp = [19.5, 13.5, 12.0, 10.5, 4.5]
    assert not carried_past(ramp, 1.0)
    assert carried_past(ramp, 2.0)
