"""The stance edges placed by a foot's heights (a1_leg_fk.estimation.stance_edges), on feet
built by construction: where they leave and land is known exactly."""

from __future__ import annotations

import numpy as np
import pytest

from a1_leg_fk.estimation.stance_edges import placed_edges

STEP_S = 0.002
LIFTOFF_S = 0.3001
"""[s] The foot's true liftoff, off the 500 Hz grid: its last stance sample is at 0.300 s."""


@pytest.mark.parametrize("late_ms", [8, 12, 16])
def test_a_soft_foot_unloading_is_not_its_rise(late_ms: int) -> None:
    """A soft foot comes up 1 mm over the 40 ms before it leaves (it unloads), then leaves at
    0.5 m/s; a stance that the posterior ends ``late_ms`` after the liftoff (the foot 5-9 mm
    up, three samples or more of its rise to fit) ends within a sample of the true one: the
    unloading's millimetre is not the rise."""
    times = np.arange(0.0, 0.45, STEP_S)
    unloading = np.clip((times - (LIFTOFF_S - 0.04)) / 0.04, 0.0, 1.0) * 0.001
    heights = np.where(times < LIFTOFF_S, unloading, 0.001 + 0.5 * (times - LIFTOFF_S))
    stance = times < LIFTOFF_S + late_ms / 1000.0
    placed = placed_edges(times, heights, stance)
    last = times[np.flatnonzero(placed)[-1]]
    assert abs(last - 0.300) <= STEP_S + 1e-9


def test_unknown_heights_leave_the_edges() -> None:
    """NaN heights (a foot not known) move no edge."""
    times = np.arange(0.0, 0.5, STEP_S)
    stance = (times > 0.1) & (times < 0.3)
    placed = placed_edges(times, np.full(times.size, np.nan), stance)
    np.testing.assert_array_equal(placed, stance)
