"""The state filter's noise model (a1_leg_fk.estimation.filter_model), written out in floats,
against numpy's matrices and hand derivations."""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.filter_model import (
    FilterSettings,
    doubt,
    inverse_square,
    scaled,
    scattered,
)

RNG = np.random.default_rng(27)


def symmetric() -> np.ndarray:
    """A random symmetric positive-definite 3 x 3 [m²/s²]."""
    a = RNG.normal(size=(3, 3)) * 0.05
    return a @ a.T + 1e-4 * np.eye(3)


def test_inverse_square_is_numpys() -> None:
    for _ in range(100):
        m, r = symmetric(), RNG.normal(size=3)
        expected = r @ np.linalg.solve(m, r)
        got = inverse_square(m[0, 0], m[0, 1], m[0, 2], m[1, 1], m[1, 2], m[2, 2], *r)
        assert math.isclose(got, expected, rel_tol=1e-9)


def test_scaled_is_the_shaped_matrix() -> None:
    """``S N S + i u uᵀ`` with ``S = h I + (v - h) u uᵀ``, by numpy."""
    for _ in range(100):
        n, u = symmetric(), RNG.normal(size=3)
        u /= np.linalg.norm(u)
        h, v, impact = RNG.uniform(0.05, 1.0), RNG.uniform(0.05, 1.0), RNG.uniform(0.0, 0.01)
        shape = h * np.eye(3) + (v - h) * np.outer(u, u)
        expected = shape @ n @ shape + impact * np.outer(u, u)
        got = np.array(scaled(tuple(n.ravel()), (h, v), tuple(u), impact)).reshape(3, 3)
        assert np.abs(got - expected).max() < 1e-15
        # across up scaled by h², along it by v² (plus the impact)
        assert math.isclose(u @ got @ u, v * v * (u @ n @ u) + impact, rel_tol=1e-12)


def test_feet_that_agree_within_their_noise_are_not_scattered() -> None:
    noise = tuple((1e-4 * np.eye(3)).ravel())  # 0.01 m/s per axis
    assert scattered([(0.01, 0.0, 0.0), (-0.01, 0.0, 0.0)], [noise, noise], 16.27) == 0.0
    assert scattered([(0.5, 0.0, 0.0)], [noise], 16.27) == 0.0  # one foot: no scatter


def test_feet_that_disagree_add_their_sample_variance() -> None:
    """Deviations ±0.05 m/s on x against 0.01 m/s noise: χ² 50 > 16.27; the sample variance per
    axis, ``(2 x 0.05²) / (3 (2 - 1))``."""
    noise = tuple((1e-4 * np.eye(3)).ravel())
    spread = scattered([(0.06, 0.0, 0.0), (-0.04, 0.0, 0.0)], [noise, noise], 16.27)
    assert math.isclose(spread, 2 * 0.05**2 / 3, rel_tol=1e-12)


def test_doubt_is_the_two_hypotheses_mixture() -> None:
    """Two rejected feet agreeing on δ = (0.2, -0.1, 0): ``w (1 - w) δ²`` per axis; feet that
    disagree, or one alone, raise none."""
    settings = FilterSettings()
    noise = tuple((1e-4 * np.eye(3)).ravel())
    w = settings.lost_weight
    got = doubt([(0.2, -0.1, 0.0), (0.2, -0.1, 0.0)], [noise, noise], [30.0, 40.0], settings)
    assert np.allclose(got, [w * (1 - w) * 0.04, w * (1 - w) * 0.01, 0.0], rtol=1e-12)
    far = doubt([(0.2, 0.0, 0.0), (-0.2, 0.0, 0.0)], [noise, noise], [30.0, 40.0], settings)
    assert far == (0.0, 0.0, 0.0)
    assert doubt([(0.2, 0.0, 0.0)], [noise], [30.0], settings) == (0.0, 0.0, 0.0)
