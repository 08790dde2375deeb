"""A plane z = a + b (x - x₀) + c (y - y₀) [m, odom] through points, by least squares with a
Gaussian prior on its slopes (zero, ``slope_prior``): few points or points in a line leave the
slope across them level and uncertain; the noise is the residual RMS, at least ``min_sigma_m``.
As :class:`GroundPlane`: the height, the normal and tilt an MPC plans on, and their covariance;
moved to another point without fitting again (:func:`moved`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

Point = tuple[float, float, float]
Covariance = tuple[tuple[float, float, float], ...]
DEFAULT_SLOPE_PRIOR = math.tan(math.radians(30.0))
"""The slopes' prior standard deviation (dz/dx, dz/dy): a 30° incline is one sigma."""
DEFAULT_MIN_SIGMA_M = 0.005
"""[m] the footholds' height noise at least (a compliant foot's sink, the contact's roll)."""


class GroundPlane(NamedTuple):
    """The local ground at a point (x₀, y₀) [m, odom]: ``height_m`` its z there, ``gradient``
    (dz/dx, dz/dy), ``normal`` the unit normal (up), ``roll`` and ``pitch`` [rad] the tilt that
    turns odom's z onto the normal (R = Ry(pitch) Rx(roll)), ``covariance`` the 3×3 covariance of
    (height [m], roll, pitch [rad]) and ``footholds`` how many were fitted.
    """

    height_m: float
    gradient: tuple[float, float]
    normal: Point
    roll: float
    pitch: float
    covariance: tuple[tuple[float, float, float], ...]
    footholds: int

    @property
    def slope_deg(self) -> float:
        """The inclination [deg]: the normal's angle from odom's z."""
        return math.degrees(math.atan(math.hypot(*self.gradient)))


def fit_plane(
    points: Sequence[Point],
    at: tuple[float, float],
    slope_prior: float = DEFAULT_SLOPE_PRIOR,
    min_sigma_m: float = DEFAULT_MIN_SIGMA_M,
) -> GroundPlane | None:
    """The plane through ``points`` [m] (least squares with the slope prior, see the module text)
    at ``at`` (x₀, y₀) [m]; None without points.
    """
    if not points:
        return None
    solution, covariance = fit(np.asarray(points, dtype=float), at, slope_prior, min_sigma_m)
    return plane_of(solution, covariance, len(points))


def fit(
    data: np.ndarray, at: tuple[float, float], slope_prior: float, min_sigma_m: float
) -> tuple[tuple[float, float, float], Covariance]:
    """(a, b, c) of the plane through (n, 3) ``data`` about ``at`` and their covariance."""
    design = np.column_stack([np.ones(len(data)), data[:, 0] - at[0], data[:, 1] - at[1]])
    heights = data[:, 2]
    prior = np.diag([0.0, 1.0, 1.0]) / slope_prior**2
    sigma2 = min_sigma_m**2
    for _ in range(2):  # the residuals' variance, then the fit with it
        information = design.T @ design / sigma2 + prior
        solution = np.linalg.solve(information, design.T @ heights / sigma2)
        residual = heights - design @ solution
        freedom = max(len(data) - 3, 1)
        sigma2 = max(float(residual @ residual) / freedom, min_sigma_m**2)
    covariance = np.linalg.inv(design.T @ design / sigma2 + prior)
    a, b, c = (float(value) for value in solution)
    return (a, b, c), tuple((float(r[0]), float(r[1]), float(r[2])) for r in covariance)


def plane_of(solution: Sequence[float], covariance: Covariance, count: int) -> GroundPlane:
    """The :class:`GroundPlane` of (a, b, c) and their 3×3 covariance (plain floats: the bag
    tool asks for one per row).
    """
    a, b, c = solution
    norm2 = 1.0 + b * b + c * c
    norm, along = math.sqrt(norm2), math.sqrt(1.0 + b * b)
    # d(height, roll, pitch) / d(a, b, c): rows (1, 0, 0), (0, j11, j12), (0, j21, 0)
    j11, j12, j21 = -b * c / (norm2 * along), along / norm2, -1.0 / (1.0 + b * b)
    (s00, s01, s02), (_, s11, s12), (_, _, s22) = covariance
    t01, t02 = j11 * s01 + j12 * s02, j21 * s01
    t11 = j11 * j11 * s11 + 2.0 * j11 * j12 * s12 + j12 * j12 * s22
    t12, t22 = j21 * (j11 * s11 + j12 * s12), j21 * j21 * s11
    return GroundPlane(
        a,
        (b, c),
        (-b / norm, -c / norm, 1.0 / norm),
        math.atan2(c, along),
        -math.atan(b),
        ((s00, t01, t02), (t01, t11, t12), (t02, t12, t22)),
        count,
    )


def moved(
    solution: Sequence[float], covariance: Covariance, dx: float, dy: float
) -> tuple[tuple[float, float, float], Covariance]:
    """(a, b, c) and their covariance of the same plane about a point (dx, dy) [m] away."""
    a, b, c = solution
    (s00, s01, s02), (_, s11, s12), (_, _, s22) = covariance
    m01, m02 = s01 + dx * s11 + dy * s12, s02 + dx * s12 + dy * s22
    m00 = s00 + dx * (s01 + m01) + dy * (s02 + m02)
    return (a + b * dx + c * dy, b, c), ((m00, m01, m02), (m01, s11, s12), (m02, s12, s22))


def with_slope_across(
    solution: Sequence[float],
    covariance: Covariance,
    along: tuple[float, float],
    slope: float,
    variance: float,
) -> tuple[tuple[float, float, float], Covariance]:
    """(a, b, c) and their covariance of the plane turned about its point (x₀, y₀) so that its
    slope across the unit direction ``along`` (x, y) [odom] is ``slope`` (dz per m, to the left
    of ``along``) with ``variance``, independent of the rest; its height there and its slope
    along are kept.
    """
    (ux, uy), (a, b, c) = along, solution
    (s00, s01, s02), (_, s11, s12), (_, _, s22) = covariance
    kept = ux * b + uy * c
    with_a = ux * s01 + uy * s02  # the covariance of the height and the slope along
    spread = ux * ux * s11 + 2.0 * ux * uy * s12 + uy * uy * s22  # the slope along's variance
    return (a, ux * kept - uy * slope, uy * kept + ux * slope), (
        (s00, ux * with_a, uy * with_a),
        (ux * with_a, ux * ux * spread + uy * uy * variance, ux * uy * (spread - variance)),
        (uy * with_a, ux * uy * (spread - variance), uy * uy * spread + ux * ux * variance),
    )
