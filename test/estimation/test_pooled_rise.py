"""A leg's liftoffs placed by its strides' pooled rise (a1_leg_fk.estimation.pooled_rise), on rises
built here: the fit's onset against the constructed one, and a fast rise (a trot's) that keeps
the edges the heights gave it. The walk-like slow rise in noise, end to end, is
test/gait/test_gait_edges.py's ``test_a_slow_rise_in_noise_is_placed_at_its_start``.
"""

from __future__ import annotations

import numpy as np
import pytest

from a1_leg_fk.estimation.pooled_rise import pooled_liftoffs, pooled_onset

STEP_S = 0.002  # 500 Hz, the contact family's rate


@pytest.mark.parametrize("drift_mps", [0.0, 0.002, -0.002])
def test_the_onset_of_a_slow_rise_from_a_drifting_stance(drift_mps) -> None:
    # A stance whose height drifts by 2 mm/s (a base frame tilted by 0.3 degrees over a trotting
    # body: 0.09 mm over a stance), then a rise from rest of 2 m/s^2 (t - t0)^2 (a walk's first
    # 10 ms: 0.2 mm), 15.3 ms before the crossing at the grid's end; off the 2 ms grid.
    grid = np.arange(-25, 1) * STEP_S
    onset = -0.0153
    rise = 0.00001 + drift_mps * (grid - grid[0]) + 2.0 * np.clip(grid - onset, 0.0, None) ** 2
    fitted = pooled_onset(grid, rise)
    assert fitted is not None
    assert abs(fitted[0] - onset) <= 0.0002
    assert fitted[1] == pytest.approx(2.0, rel=0.05)


def test_a_fast_rise_keeps_its_edges() -> None:
    # A trot's foot leaves at 0.5 m/s (0.06 m sin over a 0.2 s swing), stance 0.2 s, in 0.09 mm
    # of noise: its rise reaches the noise tolerance within a sample, not slow: nothing moves.
    times = np.arange(0.0, 6.0, STEP_S)
    since = np.mod(times, 0.4)
    stance = since < 0.2
    swing = np.clip((since - 0.2) / 0.2, 0.0, 1.0)
    heights = np.where(stance, 0.0, 0.06 * np.sin(np.pi * swing))
    heights = heights + np.random.default_rng(5).normal(0.0, 0.00009, times.size)
    assert np.array_equal(pooled_liftoffs(times, heights, stance, 3 * 0.00009), stance)


def test_coarse_or_noisy_samples_keep_their_edges() -> None:
    # At 250 Hz a slow rise's first 4 ms hold one sample; a noise tolerance of 0.4 mm or more
    # hides the rise the fit needs: both keep the edges they were given.
    for step, tolerance in ((0.004, 0.0003), (STEP_S, 0.0004)):
        times = np.arange(0.0, 6.0, step)
        after = np.clip(np.mod(times, 0.6) - 0.45, 0.0, None)
        stance = np.mod(times, 0.6) < 0.45
        heights = 2.0 * after**2 + 24.0 * np.clip(after - 0.01, 0.0, None) ** 2
        shifted = stance & (np.mod(times, 0.6) < 0.44)  # liftoffs 10 ms early
        assert np.array_equal(pooled_liftoffs(times, heights, shifted, tolerance), shifted)
