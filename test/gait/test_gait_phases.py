"""The minimum-phase rule (a1_leg_fk.gait.phases) on stance sequences built by hand: a blip is
removed by flipping it, never by growing a phase over a real gap (issue #39), and the count of
what was dropped and bridged is right."""

from __future__ import annotations

import numpy as np
import pytest

from a1_leg_fk.estimation.stance_edges import runs
from a1_leg_fk.gait.analysis import Blips, ContactThresholds
from a1_leg_fk.gait.phases import drop_blips

STEP_S = 0.002  # 500 Hz, as the runs
MIN_PHASE_S = ContactThresholds().min_phase_s


def mask_of(spans: list[tuple[float, float]], end_s: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(times [s], stance) on a 500 Hz grid: stance on the samples in each ``[on, off)`` [s]."""
    times = np.arange(round(end_s / STEP_S)) * STEP_S
    stance = np.zeros(times.size, dtype=bool)
    for on, off in spans:
        stance[(times >= on - 1e-9) & (times < off - 1e-9)] = True
    return times, stance


@pytest.mark.parametrize(
    ("spans", "expected", "blips"),
    [
        pytest.param(  # the FR: today's rule gave [0.263, 0.455]
            [(0.264, 0.266), (0.280, 0.456), (0.564, 0.566), (0.580, 0.756)],
            [(0.280, 0.456), (0.580, 0.756)],
            Blips(dropped=2, bridged=0),
            id="a_blip_before_a_gap_is_dropped_not_bridged",
        ),
        pytest.param(  # a chattering touchdown (6 ms stance, 2 ms swing) keeps its first contact
            [(0.1, 0.2), (0.204, 0.3), (0.4, 0.406), (0.408, 0.6)],
            [(0.1, 0.3), (0.4, 0.6)],
            Blips(dropped=0, bridged=2),
            id="a_false_liftoff_inside_a_stance_is_bridged_a_real_swing_kept",
        ),
    ],
)
def test_blips_are_flipped_never_grown_over(spans, expected, blips) -> None:
    """The issue's FR (2 ms of stance at 0.264 s, 14 ms of swing, the real touchdown at 0.280 s)
    keeps only the stance [0.280, 0.456); 4 ms of swing inside a stance is bridged and a 100 ms
    swing (a real step) kept."""
    times, stance = mask_of(spans)
    out, found = drop_blips(times, stance, MIN_PHASE_S)
    np.testing.assert_array_equal(out, mask_of(expected)[1])
    assert found == blips


def test_runs_at_the_data_edges_are_kept() -> None:
    """The first and last runs are not interior: a 4 ms stance at the start stays."""
    times, stance = mask_of([(0.0, 0.004), (0.5, 0.6)])
    out, blips = drop_blips(times, stance, MIN_PHASE_S)
    np.testing.assert_array_equal(out, stance)
    assert blips == Blips()


@pytest.mark.parametrize("seed", range(20))
def test_only_blips_change_and_none_survive(seed: int) -> None:
    """Random flickering sequences: every changed sample lay in a run shorter than the minimum
    phase (a phase never grows past the blips it absorbs), no interior run shorter than it is
    left, and the counts match the stance runs removed."""
    rng = np.random.default_rng(seed)
    lengths = rng.choice([1, 2, 3, 5, 8, 12, 19, 25, 40, 60, 90], size=60)
    stance = np.repeat(np.arange(lengths.size) % 2 == 1, lengths)
    times = np.cumsum(rng.uniform(0.5, 1.5, stance.size)) * STEP_S  # jittered stamps
    out, blips = drop_blips(times, stance, MIN_PHASE_S)
    short = np.zeros(stance.size, dtype=bool)
    for first, last, _ in runs(stance):
        start = 0.5 * (times[max(first - 1, 0)] + times[first])
        end = 0.5 * (times[last] + times[min(last + 1, times.size - 1)])
        short[first : last + 1] = end - start < MIN_PHASE_S
    assert not (out != stance)[~short].any()
    found = runs(out)
    for first, last, _ in found[1:-1]:
        assert 0.5 * (times[last] + times[last + 1] - times[first - 1] - times[first]) >= (
            MIN_PHASE_S - 1e-12
        )
    # a dropped stance joins two swings, a bridged swing two stances: one stance run less each
    stance_runs = sum(value for *_, value in runs(stance))
    assert sum(value for *_, value in found) == stance_runs - blips.dropped - blips.bridged
