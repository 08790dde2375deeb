"""The observer's lag undone for the causal filter (force_lag.py), by construction: a first-order
lag of 1 ms sampled every 2 ms keeps exp(-2) of the previous force per sample."""

from __future__ import annotations

import math

import numpy as np
import pytest

from a1_leg_fk.estimation.force_lag import LagTails, undo_lag
from a1_leg_fk.estimation.load_edges import unlagged

LAG_S, DT_S, HALF_N = 0.001, 0.002, 3.7
KEEP = math.exp(-DT_S / LAG_S)


def lagged(true: list[float]) -> list[float]:
    """The true forces [N] through the observer's first-order lag, from the first at rest."""
    out = [true[0]]
    for force in true[1:]:
        out.append(KEEP * out[-1] + (1.0 - KEEP) * force)
    return out


def test_a_foot_letting_go_of_its_load_shows_none_at_once() -> None:
    """A foot under PyBullet's position motors lets go of 88 N within a sample: the observer
    shows 88 x exp(-2) = 11.9 N, then 1.6 N (the filter's even odds: 3.7 N on the A1), so the
    filter held it standing 2-3 samples longer. The tail alone (11.9 N) is above even odds:
    undone, 0 N. The next sample's tail (1.6 N) is not: left as it is."""
    true = [88.0, 88.0, 0.0, 0.0, 0.0]
    observed = lagged(true)
    assert observed[2] == pytest.approx(11.91, abs=0.01)
    tails = LagTails(LAG_S, HALF_N)
    out = [tails.evidence(DT_S, [n, n, math.nan, 0.0])[0] for n in observed]
    assert out[:3] == pytest.approx([88.0, 88.0, 0.0], abs=1e-9)
    assert out[3:] == pytest.approx(observed[3:])


def test_small_forces_and_noise_pass_as_they_are() -> None:
    """A swing foot's force noise and a slow unloading tail (both under half / exp(-2) = 27 N
    before the sample) are not sharpened: undone, a 2 N noise would grow by 1.17x and a slow
    tail cross even odds early (the noisy pronk lost 0.2 point of agreement)."""
    rng = np.random.default_rng(3)
    forces = [*np.clip(rng.normal(0.0, 2.0, 50), -8.0, 8.0).tolist(), 20.0, 10.0, 5.0, 2.0]
    tails = LagTails(LAG_S, HALF_N)
    out = [tails.evidence(DT_S, [f, 0.0, 0.0, 0.0])[0] for f in forces]
    assert out == forces


def test_a_gap_a_missing_foot_and_no_lag_leave_the_forces_as_they_are() -> None:
    tails = LagTails(LAG_S, HALF_N)
    assert tails.evidence(DT_S, [90.0, math.nan, 90.0, 90.0]) == [90.0, math.nan, 90.0, 90.0]
    assert tails.evidence(0.0, [10.0] * 4) == [10.0] * 4  # no time passed
    out = tails.evidence(DT_S, [10.0, 10.0, 10.0, math.nan])
    assert out[1] == 10.0 and math.isnan(out[3])
    tails.reset()
    assert tails.evidence(DT_S, [0.0] * 4) == [0.0] * 4  # nothing before
    static = LagTails(0.0, HALF_N)
    static.evidence(DT_S, [90.0] * 4)
    assert static.evidence(DT_S, [0.0] * 4) == [0.0] * 4


def test_the_smoothers_loads_and_the_filter_undo_the_same_lag() -> None:
    """One rule: load_edges' loads over a recording are undo_lag's values."""
    stamps = np.arange(5) * DT_S
    normals = np.array(lagged([88.0, 88.0, 0.0, 0.0, 30.0]))[:, None] * np.ones(4)
    loads = unlagged(normals, stamps, LAG_S)
    assert loads[:, 0] == pytest.approx([88.0, 88.0, 0.0, 0.0, 30.0], abs=1e-9)
    assert loads[2, 0] == pytest.approx(undo_lag(normals[2, 0], normals[1, 0], KEEP), abs=1e-9)
