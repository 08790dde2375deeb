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

from a1_leg_fk.kinematics.frames import Quaternion, rotate

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
    solution, covariance = _fit(np.asarray(points, dtype=float), at, slope_prior, min_sigma_m)
    return _plane(solution, covariance, len(points))


def _fit(
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


Covariance = tuple[tuple[float, float, float], ...]


def _plane(solution: Sequence[float], covariance: Covariance, count: int) -> GroundPlane:
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


def _moved(
    solution: Sequence[float], covariance: Covariance, dx: float, dy: float
) -> tuple[tuple[float, float, float], Covariance]:
    """(a, b, c) and their covariance of the same plane about a point (dx, dy) [m] away."""
    a, b, c = solution
    (s00, s01, s02), (_, s11, s12), (_, _, s22) = covariance
    m01, m02 = s01 + dx * s11 + dy * s12, s02 + dx * s12 + dy * s22
    m00 = s00 + dx * (s01 + m01) + dy * (s02 + m02)
    return (a + b * dx + c * dy, b, c), ((m00, m01, m02), (m01, s11, s12), (m02, s12, s22))


class LocalGround:
    """The footholds of the recent stances and the plane through them (see the module text).

    A standing foot counts at its touchdown point until it lifts, then at its stance's mean: the
    points change only at touchdowns, liftoffs and expiries, and the plane is fitted again only
    then (about the points' centre), and moved to the point asked for by :meth:`plane`.
    """

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
        self._open: dict[int, tuple[Point, list[float], int]] = {}
        """Per standing leg: its touchdown point [m], the sum of its contact points and count."""
        self._fit: tuple[tuple[float, float], Point, Covariance, int] | None = None
        """The plane's centre (x, y) [m], (a, b, c) there, their covariance, the points fitted."""
        self._changed = False
        self.revision = 0
        """Counts the changes of the points (touchdowns, liftoffs, expiries): the plane changes
        only with it, and with the point asked for."""

    def update(self, stamp_s: float, contacts: Iterable[tuple[int, Point]]) -> None:
        """One sample [s]: the standing legs (slot) and their contact points [m, odom]. A leg
        not among them ends its stance: its foothold is kept.
        """
        standing = dict(contacts)
        for leg in [leg for leg in self._open if leg not in standing]:
            _, total, count = self._open.pop(leg)
            mean = (total[0] / count, total[1] / count, total[2] / count)
            self.footholds.append(Foothold(mean, count, stamp_s))
            self._changed = True
            self.revision += 1
        for leg, point in standing.items():
            opened = self._open.get(leg)
            if opened is None:
                self._open[leg] = (point, [point[0], point[1], point[2]], 1)
                self._changed = True
                self.revision += 1
            else:
                total = opened[1]
                total[0] += point[0]
                total[1] += point[1]
                total[2] += point[2]
                self._open[leg] = (opened[0], total, opened[2] + 1)
        while self.footholds and stamp_s - self.footholds[0].stamp_s > self.window_s:
            self.footholds.popleft()
            self._changed = True
            self.revision += 1

    def points(self) -> list[Point]:
        """The footholds kept and the standing feet's touchdown points [m, odom]."""
        standing = [touchdown for touchdown, _, _ in self._open.values()]
        return [foothold.point for foothold in self.footholds] + standing

    def plane(self, x: float, y: float) -> GroundPlane | None:
        """The plane at (x, y) [m, odom]; None before the first stance."""
        if self._changed or self._fit is None:
            self._changed = False
            points = self.points()
            if not points:
                self._fit = None
                return None
            data = np.asarray(points, dtype=float)
            centre = (float(data[:, 0].mean()), float(data[:, 1].mean()))
            solution, covariance = _fit(data, centre, self.slope_prior, self.min_sigma_m)
            self._fit = (centre, solution, covariance, len(points))
        centre, solution, covariance, count = self._fit
        moved, spread = _moved(solution, covariance, x - centre[0], y - centre[1])
        return _plane(moved, spread, count)


def contact_points(
    position: Point,
    orientation: Quaternion,
    feet: Sequence[Sequence[float] | None],
    radii: Sequence[float],
    legs: Iterable[int],
) -> list[tuple[int, Point]]:
    """The contact points [m, odom] of the feet of ``legs``: the base at ``position`` [m] turned
    by ``orientation`` (x, y, z, w: base to odom), each foot's centre ``feet[leg]`` [m, base
    frame] less its rolling radius ``radii[leg]`` [m] straight down; legs without a foot are
    left out.
    """
    points = []
    for leg in legs:
        foot = feet[leg]
        if foot is None:
            continue
        x, y, z = rotate(orientation, (foot[0], foot[1], foot[2]))
        points.append((leg, (position[0] + x, position[1] + y, position[2] + z - radii[leg])))
    return points


GROUND_COLUMNS = (
    "ground_height_m",
    "ground_normal_x",
    "ground_normal_y",
    "ground_normal_z",
    "ground_var_height",
    "ground_var_roll",
    "ground_var_pitch",
)
"""The local ground's values as the odom CSV names them (:func:`ground_values`)."""


def ground_values(plane: GroundPlane | None) -> tuple[float, ...]:
    """``plane`` as :data:`GROUND_COLUMNS`: its height [m, odom], unit normal and the variances
    of the height [m²], roll and pitch [rad²]; NaN each before the first stance (None).
    """
    if plane is None:
        return (math.nan,) * len(GROUND_COLUMNS)
    covariance = plane.covariance
    return (
        plane.height_m,
        *plane.normal,
        covariance[0][0],
        covariance[1][1],
        covariance[2][2],
    )


def plane_pose(
    plane: GroundPlane, x: float, y: float
) -> tuple[Point, tuple[float, float, float, float], list[float]]:
    """``plane`` at (x, y) [m, odom] as a pose with covariance (geometry_msgs'): the point on it
    there [m], the tilt as a quaternion (x, y, z, w; R = Ry(pitch) Rx(roll), no yaw) and the
    6×6 covariance, row-major (x, y, z, rotation about x, y, z): the height's and the tilt's,
    zero for x, y and yaw (the point is under the base by construction, a plane has no yaw).
    """
    half_roll, half_pitch = plane.roll / 2.0, plane.pitch / 2.0
    cr, sr, cp, sp = (
        math.cos(half_roll),
        math.sin(half_roll),
        math.cos(half_pitch),
        math.sin(half_pitch),
    )
    quaternion = (cp * sr, sp * cr, -sp * sr, cp * cr)  # qy(pitch) ⊗ qx(roll)
    covariance = [0.0] * 36
    for row, axis in enumerate((2, 3, 4)):  # z, roll, pitch
        for column, other in enumerate((2, 3, 4)):
            covariance[6 * axis + other] = plane.covariance[row][column]
    return (x, y, plane.height_m), quaternion, covariance
