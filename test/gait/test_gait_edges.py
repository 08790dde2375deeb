"""Stance edges placed by the feet's heights (a1_leg_fk.gait.edges.fit_edges), on gaits built
here with known touchdowns and liftoffs: a foot that rises slowly (a walk's rolling liftoff: 1 mm
up only ~16 ms after it left), a foot that slides as it pushes off (a pronk's), a soft foot that
sinks in stance and comes up as it unloads. 500 Hz, four feet stepping in place in a trot's
pattern, no noise (the family's noisy runs are test/gait/test_gait_family.py's), a stance that
bobs up and down (the demo's), and liftoffs in 0.1 mm of height noise.
"""

from __future__ import annotations

import numpy as np
import pytest
from shared import known
from synthetic_gaits import slow_rise_walk

from a1_leg_fk.gait.analysis import analyze_gait

RATE_HZ, PERIOD_S, STANCE_S, CLEARANCE_M = 500.0, 0.4, 0.2, 0.06
OFFSETS = (0.0, 0.5, 0.5, 0.0)  # a trot's touchdowns [cycles]


def stepping(
    swing: str,
    slide_mps: float = 0.0,
    sink_m: float = 0.0,
    seconds: float = 6.0,
    unload_m: float = 0.0,
):
    """(stamps [s], world feet (N, 4, 3) [m], true (touchdown, liftoff) times [s] per leg). In
    swing the foot rises as ``sin`` (fast: leaves at 0.5 m/s) or ``sin2`` (slowly, from rest);
    in its last 40 ms of stance it slides forward at ``slide_mps`` [m/s] at ground level and
    comes up steadily by ``unload_m`` [m] (a soft foot unloading: the swing starts there and
    comes back down to the ground); in stance it sinks up to ``sink_m`` [m] and comes back (a
    soft foot)."""
    stamps = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    feet = np.zeros((stamps.size, 4, 3))
    truth = []
    for leg, offset in enumerate(OFFSETS):
        since = np.mod(stamps - offset * PERIOD_S, PERIOD_S)
        standing = since < STANCE_S
        s = (since - STANCE_S) / (PERIOD_S - STANCE_S)
        lift = np.sin(np.pi * s) if swing == "sin" else np.sin(np.pi * s) ** 2
        sliding = np.clip(since - (STANCE_S - 0.04), 0.0, 0.04)
        height = np.where(
            standing,
            unload_m * sliding / 0.04 - sink_m * np.sin(np.pi * since / STANCE_S),
            unload_m * (1.0 - s) + CLEARANCE_M * lift,
        )
        x = 0.2 * (leg < 2) + np.where(standing, slide_mps * sliding, slide_mps * 0.04 * (1 - s))
        feet[:, leg] = np.column_stack((x, np.full(stamps.size, 0.1 * (-1) ** leg), height))
        downs = np.arange(-1, seconds / PERIOD_S + 1) * PERIOD_S + offset * PERIOD_S
        truth.append([(on, on + STANCE_S) for on in downs if on > 0.1 and on + STANCE_S < seconds])
    return stamps, feet, truth


def edge_errors(stamps, feet, truth) -> tuple[float, float, float]:
    """The largest |touchdown| and |liftoff| error [ms] over the legs' interior stances, and the
    largest duty factor error."""
    contacts, report = analyze_gait(stamps, feet)
    worst_on = worst_off = 0.0
    for leg, stances in enumerate(contacts.stances):
        ons = np.array([s.t_on for s in stances if s.touchdown_observed])
        offs = np.array([s.t_off for s in stances if s.liftoff_observed])
        for on, off in truth[leg]:
            worst_on = max(worst_on, 1000 * float(np.abs(ons - on).min()))
            worst_off = max(worst_off, 1000 * float(np.abs(offs - off).min()))
    duty = max(abs(known(m.duty_factor) - STANCE_S / PERIOD_S) for m in report.legs.values())
    return worst_on, worst_off, duty


@pytest.mark.parametrize(
    ("case", "options"),
    [("slow rise", {"swing": "sin2"}), ("slide at push-off", {"swing": "sin", "slide_mps": 0.8})],
)
def test_liftoff_where_the_foot_rises(case, options) -> None:
    # The issue's goals (events within 4 ms, duty within 0.02). Before, the edges were 9 ms off
    # on the slow rise (duty 0.045) and the slide ended its stance 33 ms early (duty 0.08).
    on_ms, off_ms, duty = edge_errors(*stepping(**options))
    assert on_ms <= 4.0 and off_ms <= 4.0, case
    assert duty <= 0.02, case


def test_a_sinking_soft_foot_stands_to_its_edges() -> None:
    # A foot 1.5 mm into soft ground mid-stance: its edges are 1.5 mm above its median height.
    on_ms, off_ms, duty = edge_errors(*stepping("sin", sink_m=0.0015))
    assert on_ms <= 4.0 and off_ms <= 4.0
    assert duty <= 0.01


@pytest.mark.parametrize(
    ("sink_m", "unload_m"),
    [
        (0.001, 0.0006),
        (0.0015, 0.0008),
        pytest.param(
            0.0015,
            0.0012,
            marks=pytest.mark.xfail(
                strict=True,
                reason="lift-off 31 ms early (duty 0.075): the ramp starts at a kink, 0.03 mm/ms "
                "steeper than the sinking stance, which the line over the 20 ms before the edge "
                "lags by more than the noise tolerance",
            ),
        ),
    ],
)
def test_an_unloading_soft_foot_stands_to_its_rise(sink_m, unload_m) -> None:
    # A soft foot (the soft-toe run's, a1_trot_soft) sinks in stance, then comes up steadily
    # over its last 40 ms as it unloads, before the swing's rise. The stance is carried along
    # that ramp while the heights follow its line; before, the edge stopped partway up it
    # (lift-off 21 ms early with a 1 mm sink and 0.6 mm of ramp, 29 ms with 1.5 and 0.8; duty
    # 0.027 and 0.05 off).
    on_ms, off_ms, duty = edge_errors(*stepping("sin", sink_m=sink_m, unload_m=unload_m))
    assert on_ms <= 4.0 and off_ms <= 4.0
    assert duty <= 0.02


@pytest.mark.parametrize(
    "bob_m",
    [
        0.001,
        pytest.param(
            0.003,
            marks=pytest.mark.xfail(
                strict=True,
                reason="touchdown 5 ms early (lift-off 3 ms, duty 0.020): the level next to "
                "an edge is a median over 20 ms, which lags a stance coming down to its edge",
            ),
        ),
    ],
)
def test_a_bobbing_stance_ends_where_the_foot_rises(bob_m) -> None:
    # The demo's stance (docs/gait.md): the foot rises mid-stance and comes back down before it
    # lifts as sin^2. A tolerance grown by the stance's spread took the first millimetres of each
    # swing as stance (before: edges 9 ms off, duty 0.045 with a 1 mm bob; 15 ms, 0.075 with 3).
    on_ms, off_ms, duty = edge_errors(*stepping("sin2", sink_m=-bob_m))
    assert on_ms <= 4.0 and off_ms <= 4.0
    assert duty <= 0.02


@pytest.mark.parametrize("swing", ["sin", "sin2"])
def test_liftoff_where_the_rise_starts_in_noise(swing) -> None:
    # 0.1 mm of height noise: a foot must rise 3 deviations before it is up, so the lift-off is
    # placed where its rise, fitted as c (t - t0)^p, starts: from rest (sin2: before, median
    # 5 ms late, duty 0.025 off) or leaving fast (sin: a square-root-only fit put it 5 ms early).
    stamps, feet, truth = stepping(swing, seconds=10.0)
    feet = feet + np.random.default_rng(3).normal(0.0, 0.0001, feet.shape)
    contacts, report = analyze_gait(stamps, feet)
    errors = []
    for leg, stances in enumerate(contacts.stances):
        offs = np.array([s.t_off for s in stances if s.liftoff_observed])
        errors += [1000 * float(np.abs(offs - off).min()) for _, off in truth[leg]]
    assert np.median(errors) <= 4.0
    duty = max(abs(known(m.duty_factor) - STANCE_S / PERIOD_S) for m in report.legs.values())
    assert duty <= 0.02


@pytest.mark.parametrize("seed", [3, 1, 2])
def test_a_slow_rise_in_noise_is_placed_at_its_start(seed) -> None:
    """A walk's feet rise 2 m/s^2 t^2 for 10 ms (0.2 mm: two deviations of the 0.09 mm noise),
    then ~20x steeper (test/synthetic_gaits.py ``slow_rise``): every leg's median liftoff within
    the issue's 4 ms of the constructed one, on three noise draws. One liftoff's heights cannot
    place it (per-leg medians 3.6-7.6 ms late on these seeds); the leg's strides pooled
    (a1_leg_fk.estimation.pooled_rise) place it 0.3-3.0 ms off."""
    stamps, feet, liftoffs = slow_rise_walk(0.00009, seed=seed)
    contacts, _ = analyze_gait(stamps, feet)
    for leg, stances in enumerate(contacts.stances):
        offs = np.array([s.t_off for s in stances if s.liftoff_observed])
        errors = [1000 * float(np.abs(offs - off).min()) for off in liftoffs[leg]]
        assert np.median(errors) <= 4.0
