"""The RMS force of the feet held in swing (the contact filter's fade margin), against sums
written out by hand."""

from __future__ import annotations

import math

import pytest

from a1_leg_fk.estimation.swing_force import WINDOW_S, SwingForce


def test_the_rms_pools_the_swing_feet_over_the_last_second() -> None:
    """0 before a swing foot is seen; standing feet and unknown forces (NaN) left out; then
    sqrt(mean of squares) over every swing foot-sample of the last second, the older ones gone."""
    swing = SwingForce()
    assert swing.update(0.002, [30.0, 30.0, 30.0, 30.0], [False] * 4) == 0.0
    assert swing.update(0.002, [3.0, 4.0, 50.0, math.nan], [True, True, False, True]) == (
        pytest.approx(math.sqrt((9.0 + 16.0) / 2.0))
    )
    assert swing.update(0.5, [0.0, -12.0, 0.0, 0.0], [False, True, False, False]) == (
        pytest.approx(math.sqrt((9.0 + 16.0 + 144.0) / 3.0))
    )
    # 0.6 s on the first two samples are more than WINDOW_S old: the -12 N alone is left
    assert WINDOW_S == 1.0
    assert swing.update(0.6, [0.0] * 4, [False] * 4) == pytest.approx(12.0)
    assert swing.update(1.2, [0.0] * 4, [False] * 4) == 0.0  # an empty window: none


def test_absurd_forces_stay_finite() -> None:
    """A square counts at most 1e12 N^2; an infinite force is no force (left out)."""
    swing = SwingForce()
    value = swing.update(0.002, [1e300, -math.inf, 2.0, 0.0], [True] * 4)
    assert math.isfinite(value) and value == pytest.approx(math.sqrt((1e12 + 4.0) / 3.0))


def test_a_stamps_rounding_moves_no_sample_across_the_windows_edge() -> None:
    """A 500 Hz grid reaches the window's edge exactly: the same forces with each dt off by
    up to 0.4 ns (a bag's stamps rounded to whole nanoseconds) give the same RMS, sample by
    sample, to 1e-9 N."""
    exact, rounded = SwingForce(), SwingForce()
    for k in range(1500):
        forces = [float(k % 7), -float(k % 5), 0.5 * (k % 3), 1.0]
        swing = [k % 2 == 0, True, k % 3 == 0, False]
        a = exact.update(0.002, forces, swing)
        b = rounded.update(0.002 + (4e-10 if k % 2 else -4e-10), forces, swing)
        assert a == pytest.approx(b, abs=1e-9), k
