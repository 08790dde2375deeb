"""The local ground under the robot, from its recent footholds: a plane z = a + b (x - x₀) +
c (y - y₀) [m, odom frame] fitted by least squares to where the stance feet touched, with its
covariance; the height under the base, the plane's normal and its tilt (what a model-predictive
controller plans on).

A foothold is one foot's stance: the mean of its contact points (the foot's centre less its
rolling radius, straight down) over the samples it stood, in odom. :class:`LocalGround` keeps the
footholds of the last ``window_s`` seconds, at most ``max_footholds`` of them, and fits the plane
about the point asked for (x₀, y₀), with a Gaussian prior on the slopes (zero, standard deviation
``slope_prior``): where the footholds are fewer than three or in a line, the slope across them
stays level with a large variance instead of being made up. The fit's noise is the footholds'
residual RMS (corrected for the three parameters fitted), at least ``min_sigma_m``: feet that
agree exactly still give the sink and roll of a real foot's contact.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from typing import NamedTuple

import numpy as np

Point = tuple[float, float, float]

DEFAULT_WINDOW_S = 2.0
"""[s] how long a foothold counts after its stance ended."""
DEFAULT_MAX_FOOTHOLDS = 8
"""The footholds kept (a trot's last two strides of four feet)."""
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


class Foothold(NamedTuple):
    """One foot's stance: its mean contact point [m, odom], the samples averaged and the stamp
    [s] of the last.
    """

    point: Point
    samples: int
    stamp_s: float


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
    data = np.asarray(points, dtype=float)
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
    return _plane(solution, covariance, len(data))


def _plane(solution: np.ndarray, covariance: np.ndarray, count: int) -> GroundPlane:
    """The :class:`GroundPlane` of (a, b, c) and their covariance."""
    a, b, c = (float(value) for value in solution)
    norm = math.sqrt(1.0 + b * b + c * c)
    along = math.sqrt(1.0 + b * b)
    roll, pitch = math.atan2(c, along), -math.atan(b)
    # d(height, roll, pitch) / d(a, b, c)
    jacobian = np.array(
        [
            [1.0, 0.0, 0.0],
            [0.0, -b * c / (norm * norm * along), along / (norm * norm)],
            [0.0, -1.0 / (1.0 + b * b), 0.0],
        ]
    )
    tilted = jacobian @ covariance @ jacobian.T
    return GroundPlane(
        a,
        (b, c),
        (-b / norm, -c / norm, 1.0 / norm),
        roll,
        pitch,
        tuple((float(row[0]), float(row[1]), float(row[2])) for row in tilted),
        count,
    )


class LocalGround:
    """The footholds of the recent stances and the plane through them (see the module text)."""

    def __init__(
        self,
        window_s: float = DEFAULT_WINDOW_S,
        max_footholds: int = DEFAULT_MAX_FOOTHOLDS,
        slope_prior: float = DEFAULT_SLOPE_PRIOR,
        min_sigma_m: float = DEFAULT_MIN_SIGMA_M,
    ) -> None:
        if window_s <= 0.0 or max_footholds < 1 or slope_prior <= 0.0 or min_sigma_m <= 0.0:
            raise ValueError("window_s, max_footholds, slope_prior and min_sigma_m must be > 0")
        self.window_s = window_s
        self.slope_prior = slope_prior
        self.min_sigma_m = min_sigma_m
        self.footholds: deque[Foothold] = deque(maxlen=max_footholds)
        """The ended stances, oldest first."""
        self._open: dict[int, tuple[Point, int]] = {}
        """Per standing leg: the sum of its contact points [m] and their count."""

    def update(self, stamp_s: float, contacts: Iterable[tuple[int, Point]]) -> None:
        """One sample [s]: the standing legs (slot) and their contact points [m, odom]. A leg
        not among them ends its stance: its foothold is kept.
        """
        standing = dict(contacts)
        for leg in [leg for leg in self._open if leg not in standing]:
            total, count = self._open.pop(leg)
            mean = (total[0] / count, total[1] / count, total[2] / count)
            self.footholds.append(Foothold(mean, count, stamp_s))
        for leg, point in standing.items():
            total, count = self._open.get(leg, ((0.0, 0.0, 0.0), 0))
            summed = (total[0] + point[0], total[1] + point[1], total[2] + point[2])
            self._open[leg] = (summed, count + 1)
        while self.footholds and stamp_s - self.footholds[0].stamp_s > self.window_s:
            self.footholds.popleft()

    def points(self) -> list[Point]:
        """The footholds kept and the standing feet's (their mean so far) [m, odom]."""
        standing = [
            (total[0] / count, total[1] / count, total[2] / count)
            for total, count in self._open.values()
        ]
        return [foothold.point for foothold in self.footholds] + standing

    def plane(self, x: float, y: float) -> GroundPlane | None:
        """The plane at (x, y) [m, odom]; None before the first stance."""
        return fit_plane(self.points(), (x, y), self.slope_prior, self.min_sigma_m)


def contact_points(
    position: Point,
    rotation: Sequence[Sequence[float]],
    feet: Sequence[Point | None],
    radii: Sequence[float],
    legs: Iterable[int],
) -> list[tuple[int, Point]]:
    """The contact points [m, odom] of the feet of ``legs``: the base at ``position`` [m] turned
    by ``rotation`` (3×3, base to odom), each foot's centre ``feet[leg]`` [m, base frame] less
    its rolling radius ``radii[leg]`` [m] straight down; legs without a foot are left out.
    """
    points = []
    for leg in legs:
        foot = feet[leg]
        if foot is None:
            continue
        world = [
            position[row] + sum(rotation[row][k] * foot[k] for k in range(3)) for row in range(3)
        ]
        points.append((leg, (world[0], world[1], world[2] - radii[leg])))
    return points
