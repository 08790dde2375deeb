"""The local ground under the robot, from its recent footholds: a plane z = a + b (x - x₀) +
c (y - y₀) [m, odom] fitted by least squares to where the stance feet touched, with its
covariance; the height under the base, the plane's normal and tilt (what an MPC plans on).

A foothold is one foot's stance: the mean (x, y) of its contact points (the foot's centre less its
rolling radius, straight down) in odom, at its anchored height there (a rolling foot's point moves
a few mm over a stance: its touchdown's anchor carried along the slope it landed on).
:class:`LocalGround` keeps the footholds of the last ``window_s`` seconds, at most
``max_footholds``, and fits the plane with a Gaussian prior on the slopes (zero,
``slope_prior``): footholds fewer than three or in a line leave the slope across them level and
uncertain. The fit's noise is the residual RMS, at least ``min_sigma_m``
(:mod:`a1_leg_fk.estimation.ground_plane`). The plane reported (:meth:`LocalGround.reported`: the
node's ``ground``, the odom CSV's and plot's) leaves out the stances shorter than
:data:`MIN_FOOTHOLD_S`; the one a landing foot is held to (:meth:`LocalGround.plane`) takes them.
On a staircase either samples the treads where the feet landed: a plane, not the treads.

The heights are anchored, not the drifting estimate's (``ground: footholds``, the default): a
touchdown within ``step_gate`` sigmas of the ground's prediction takes it (a flat floor, a tread,
an even slope: no error carried from stance to stance), one off it keeps its own height (a step);
its sigma is its own height's, by where that comes from
(:mod:`a1_leg_fk.estimation.touchdown_gate`).
The prediction is the nearest foothold's height carried along the slope (measured between feet
standing at the same time, :mod:`a1_leg_fk.estimation.ground_slope`; level below
:data:`LEVEL_SLOPE`) or level (a tread), the nearer; a touchdown's own height is taken against
the feet standing in the same sample, so the estimate's drift cancels out of it.
``anchored=False`` keeps the measured heights instead (each foothold at its stance's mean contact
point, no slope measured): the plane fitted to them is the raw footholds' (the contact filter's,
:mod:`a1_leg_fk.estimation.foot_ground`, whose frame is not the odometry's).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from typing import NamedTuple

import numpy as np

from a1_leg_fk.estimation import ground_plane
from a1_leg_fk.estimation.ground_plane import (
    DEFAULT_MIN_SIGMA_M,
    DEFAULT_SLOPE_PRIOR,
    Covariance,
    GroundPlane,
    Point,
    fit,
    moved,
    plane_of,
)
from a1_leg_fk.estimation.ground_slope import GroundSlope
from a1_leg_fk.estimation.touchdown_gate import TouchdownGate
from a1_leg_fk.kinematics.frames import Quaternion, rotate

DEFAULT_WINDOW_S = 2.0
"""[s] how long a foothold counts after its stance ended."""
DEFAULT_MAX_FOOTHOLDS = 8
"""The footholds kept (a trot's last two strides of four feet)."""
DEFAULT_STEP_GATE = 3.0
"""A touchdown this many standard deviations off the anchored ground's prediction is a step."""
DEFAULT_SLOPE_TIME_S = 2.0
"""[s] the time constant over which the standing feet's height differences are summed."""
LEVEL_SLOPE = math.tan(math.radians(1.0))
"""Slopes below this are level: an IMU's mounting error (0.3°) tilts the feet's differences."""
CORRELATION_S = 0.2
"""[s] the span one stance's height differences count as one measurement over."""
MIN_FOOTHOLD_S = 0.05
"""[s] the shortest stance the reported plane takes for a foothold (:meth:`LocalGround.reported`):
a shorter one is the contact estimate's flicker as a foot lands or scuffs (a trot's stance lasts
0.2-0.3 s), and its point, taken before the foot settled, tilted the plane (go2_slope_up_5: 0.92°
off the 5° slope with it, 0.01° without)."""


class Foothold(NamedTuple):
    """One foot's stance: its mean contact point [m, odom], the samples averaged and the stamp
    [s] of the last.
    """

    point: Point
    samples: int
    stamp_s: float


Grade = tuple[float, float]
"""A ground's slope (dz/dx, dz/dy)."""
LEVEL: Grade = (0.0, 0.0)


def _sloped(grade: Grade) -> bool:
    """Whether a ground of slope ``grade`` (dz/dx, dz/dy) slopes: above :data:`LEVEL_SLOPE`."""
    return grade[0] * grade[0] + grade[1] * grade[1] > LEVEL_SLOPE**2


def _carried(anchor: Point, grade: Grade, point: Sequence[float]) -> float:
    """The height [m] of the ground a stance landed on at ``anchor`` [m, odom] with slope
    ``grade``, under ``point`` (x, y) [m, odom]: a rolling foot's contact point moves along the
    stance (a few mm on a trot), and on a slope its ground's height with it.
    """
    return anchor[2] + grade[0] * (point[0] - anchor[0]) + grade[1] * (point[1] - anchor[1])


class LocalGround:
    """The recent footholds, their anchored heights and the plane through them (module text).

    A standing foot counts at its touchdown point until it lifts, then at its stance's: the
    points change only at touchdowns, liftoffs and expiries, and the plane is fitted again only
    then (about the points' centre), and moved to the point asked for by :meth:`plane`.
    """

    def __init__(
        self,
        window_s: float = DEFAULT_WINDOW_S,
        max_footholds: int = DEFAULT_MAX_FOOTHOLDS,
        slope_prior: float = DEFAULT_SLOPE_PRIOR,
        min_sigma_m: float = DEFAULT_MIN_SIGMA_M,
        step_gate: float = DEFAULT_STEP_GATE,
        slope_time_s: float = DEFAULT_SLOPE_TIME_S,
        anchored: bool = True,
    ) -> None:
        if min(window_s, max_footholds, slope_prior, min_sigma_m, step_gate, slope_time_s) <= 0:
            raise ValueError("LocalGround's settings must be > 0")
        self.window_s = window_s
        self.anchored = anchored
        """False: the footholds keep their measured heights (module text)."""
        self.slope_prior = slope_prior
        self.min_sigma_m = min_sigma_m
        self.footholds: deque[Foothold] = deque(maxlen=max_footholds)
        """The ended stances, oldest first."""
        self.settled: deque[Foothold] = deque(maxlen=max_footholds)
        """The ended stances of at least :data:`MIN_FOOTHOLD_S`, oldest first."""
        self._open: dict[int, tuple[Point, Grade, list[float], int, Point, float]] = {}
        """Per standing leg: its touchdown point [m] (at its anchored height), the slope it landed
        on (:meth:`_carried`), the sums of its contact points' x, y and z, their count, its
        contact point's last [m] and its touchdown's stamp [s]."""
        self._fit: tuple[int, Fit | None] | None = None
        """:meth:`plane`'s fit and the :attr:`revision` it was made at."""
        self._reported: tuple[int, Fit | None] | None = None
        """:meth:`reported`'s fit and the :attr:`revision` it was made at."""
        self.gate = TouchdownGate(min_sigma_m, step_gate)
        """A touchdown's noise and its test against the prediction (:meth:`_nearest`)."""
        self._height_variance = 0.0
        """[m²] the estimate's vertical position variance in the last :meth:`update`."""
        self.slope = GroundSlope(slope_time_s, min_sigma_m, CORRELATION_S, slope_prior)
        self.revision = 0
        """Counts the changes of the points (touchdowns, liftoffs, expiries): the plane changes
        only with it, and with the point asked for."""

    def update(
        self, stamp_s: float, contacts: Iterable[tuple[int, Point]], height_variance: float = 0.0
    ) -> None:
        """One sample [s]: the standing legs (slot) and their contact points [m, odom], placed
        by an estimate whose vertical position has variance ``height_variance`` [m²] (a lone
        touchdown's height noise: :class:`TouchdownGate`). A leg not among them ends its
        stance: its foothold is kept, at its stance's mean (x, y) and its anchored height (or
        mean height); a leg new among them is anchored (:meth:`_touchdown`) or kept at its own
        height.
        """
        standing = dict(contacts)
        self._height_variance = height_variance
        if self.anchored:
            self.slope.add(stamp_s, list(standing.values()))
        lifted = {}
        for leg in [leg for leg in self._open if leg not in standing]:
            touchdown, grade, total, count, last, since = self._open.pop(leg)
            lifted[leg] = (last[2], _carried(touchdown, grade, last))
            mean = (total[0] / count, total[1] / count, total[2] / count)
            if self.anchored:
                mean = (mean[0], mean[1], _carried(touchdown, grade, mean))
            self.footholds.append(Foothold(mean, count, stamp_s))
            if stamp_s - since >= MIN_FOOTHOLD_S:
                self.settled.append(Foothold(mean, count, stamp_s))
            self.revision += 1
        opened_now = self._open
        landed = []
        for leg, point in standing.items():  # the stances that go on: their sums
            opened = opened_now.get(leg)
            if opened is None:
                landed.append((leg, point))
                continue
            total = opened[2]
            total[0] += point[0]
            total[1] += point[1]
            total[2] += point[2]
            opened_now[leg] = (opened[0], opened[1], total, opened[3] + 1, point, opened[5])
        if landed:
            self._land(stamp_s, landed, standing, lifted)
        while self.footholds and stamp_s - self.footholds[0].stamp_s > self.window_s:
            self.footholds.popleft()
            self.revision += 1
        while self.settled and stamp_s - self.settled[0].stamp_s > self.window_s:
            self.settled.popleft()
            self.revision += 1

    def _land(
        self,
        stamp_s: float,
        landed: list[tuple[int, Point]],
        standing: dict[int, Point],
        lifted: dict[int, tuple[float, float]],
    ) -> None:
        """Open the stances of the ``landed`` legs (slot, contact point [m, odom]) at ``stamp_s``
        [s], anchored (:meth:`_touchdown`) against the feet that stood before this sample and
        stand on (``standing``, not ``landed``), else the ``lifted`` ones; or at their own heights.
        The feet landing in one sample are judged together, against the ground and the noise
        known before it (two feet landing alone, one judged after the other had widened the
        noise, took heights 21 mm apart: the retargeted walk's).
        """
        kept = {leg: (point[2], _carried(self._open[leg][0], self._open[leg][1], point))
                for leg, point in standing.items() if leg in self._open}  # fmt: skip
        anchors = [
            self._touchdown(point, kept or lifted) if self.anchored else (point[2], LEVEL)
            for _, point in landed
        ]
        self.gate.close_sample()
        for (leg, point), (own, grade) in zip(landed, anchors):
            self._open[leg] = ((point[0], point[1], own), grade, list(point), 1, point, stamp_s)
            self.revision += 1

    def _touchdown(
        self, point: Point, others: dict[int, tuple[float, float]]
    ) -> tuple[float, Grade]:
        """The anchored height [m] and slope of a foot landing at ``point`` [m, odom]:
        :meth:`_anchor` of its height against the ``others``' anchors (per other foot its contact
        point's height now or as it lifted, and its anchor carried there [m]: the estimate's
        offset cancels), or its own.
        """
        if not others:
            return self._anchor(point, alone=True)
        height = sum(anchor + point[2] - z for z, anchor in others.values()) / len(others)
        return self._anchor((point[0], point[1], height), alone=False)

    def gradient(self) -> tuple[tuple[float, float], tuple[float, float, float]]:
        """The ground's slope (dz/dx, dz/dy) and its covariance (xx, xy, yy), from the feet that
        stood at the same time (:class:`~a1_leg_fk.estimation.ground_slope.GroundSlope`).
        """
        return self.slope.gradient()

    def predicted(self, x: float, y: float) -> list[tuple[float, float, Grade]]:
        """The anchored ground's heights at (x, y) [m, odom], their variances [m²] and slopes
        (dz/dx, dz/dy) from the nearest anchored foothold (per foothold, so a staircase's treads
        stay apart), carried along :meth:`gradient` (a slope) and level (a tread); none before
        the first foothold.
        """
        anchors = self.points()
        if not anchors:
            return []
        px, py, pz = min(anchors, key=lambda p: (p[0] - x) ** 2 + (p[1] - y) ** 2)
        (gx, gy), (cxx, cxy, cyy) = self.gradient()
        if not _sloped((gx, gy)):
            return [(pz, 0.0, LEVEL)]
        dx, dy = x - px, y - py
        spread = cxx * dx * dx + 2.0 * cxy * dx * dy + cyy * dy * dy
        return [(pz + gx * dx + gy * dy, spread, (gx, gy)), (pz, 0.0, LEVEL)]

    def _anchor(self, point: Point, alone: bool) -> tuple[float, Grade]:
        """The anchored height [m] of a touchdown at ``point`` [m, odom] and the slope its stance
        stands on: the prediction nearer to it, where it agrees (:meth:`_nearest`); its own
        where neither does (a step, a tread: level), or with no prediction. ``alone``: no foot
        to take its height against (the estimate's own). Its offset from a confident prediction
        counts toward the touchdowns' scatter (:meth:`TouchdownGate.count`) where it took it,
        and alone where it is no step (a lone touchdown off a sloped ground's prediction).
        """
        nearest = self._nearest(point, alone)
        if nearest is None:
            return point[2], LEVEL
        height, variance, grade, agrees = nearest
        if variance <= self.min_sigma_m**2 and (agrees or (alone and not self._a_step(agrees))):
            self.gate.count(point[2] - height)
        return (height, grade) if agrees else (point[2], LEVEL)

    def lands_on_a_step(self, point: Point) -> bool:
        """Whether a touchdown at ``point`` [m, odom] with no foot to take its height against
        is a step: where the ground slopes (a staircase), off the prediction by more than
        ``step_gate`` of its noise (:meth:`_nearest`).
        """
        nearest = self._nearest(point, alone=True)
        return nearest is not None and self._a_step(nearest[3])

    def _a_step(self, agrees: bool) -> bool:
        """Whether a lone touchdown that ``agrees`` with the prediction or not is a step: off
        it where the ground slopes.
        """
        return not agrees and _sloped(self.gradient()[0])

    def _nearest(self, point: Point, alone: bool) -> tuple[float, float, Grade, bool] | None:
        """The prediction nearer to ``point`` [m, odom] (height [m], variance [m²], slope; on
        treads the level one, :meth:`TouchdownGate.treads`) and whether ``point`` agrees with it
        (:meth:`TouchdownGate.agrees`: its noise by where its height comes from, against the
        standing feet or ``alone``, the estimate's own; against them it votes between the two,
        :meth:`TouchdownGate.compare`); None: no foothold yet.
        """
        predictions = self.predicted(point[0], point[1])
        if not predictions:
            return None
        if not alone and len(predictions) > 1:  # the slope's and the level one
            self.gate.compare(point[2], predictions[0][:2], predictions[1][0])
        if self.gate.treads():  # a staircase's: the level prediction alone
            predictions = predictions[-1:]
        height, variance, grade = min(predictions, key=lambda p: abs(point[2] - p[0]))
        sigma = self.gate.sigma_m(alone, _sloped(self.gradient()[0]), self._height_variance)
        return height, variance, grade, self.gate.agrees(point[2] - height, variance, sigma)

    def under(
        self, feet: Iterable[tuple[int, Point]], legs: int
    ) -> list[tuple[float, float] | None]:
        """Per leg of ``legs``, the ground's height [m, odom] under its foot and its variance
        [m²] (what the state filter holds a stance foot to, ``ground: footholds``): a standing
        foot's anchor carried to its contact point (no variance: the anchor is the ground), else
        the plane's under its contact point in ``feet`` (leg, point [m, odom]); None: no foot, or
        no ground yet.
        """
        grounds: list[tuple[float, float] | None] = [None] * legs
        for leg, (x, y, _) in feet:
            opened = self._open.get(leg)
            if opened is not None:
                grounds[leg] = (_carried(opened[0], opened[1], (x, y)), 0.0)
                continue
            plane = self.plane(x, y)
            if plane is not None:
                grounds[leg] = (plane.height_m, plane.covariance[0][0])
        return grounds

    def points(self) -> list[Point]:
        """The footholds kept and the standing feet's touchdowns [m, odom], anchored."""
        standing = [opened[0] for opened in self._open.values()]
        return [foothold.point for foothold in self.footholds] + standing

    def plane(self, x: float, y: float) -> GroundPlane | None:
        """The plane through :meth:`points` at (x, y) [m, odom] (what :meth:`under` holds a
        landing foot to, and the contacts' slope); None before the first stance.
        """
        if self._fit is None or self._fit[0] != self.revision:
            self._fit = (self.revision, self._fitted(self.points()))
        return _at(self._fit[1], x, y)

    def reported(
        self, x: float, y: float, orientation: Quaternion | None = None
    ) -> GroundPlane | None:
        """The local ground reported at (x, y) [m, odom] (the node's ``ground``, the odom CSV's
        columns): the plane through the :attr:`settled` footholds and the standing feet's
        touchdowns, the stances shorter than :data:`MIN_FOOTHOLD_S` left out unless they are all
        there is (the ground once known stays known); None before the first stance. Given the
        base's ``orientation`` (x, y, z, w: base to odom), anchored, its slope across the base's
        heading is :meth:`gradient`'s (:meth:`_across`).
        """
        if self._reported is None or self._reported[0] != self.revision:
            standing = [opened[0] for opened in self._open.values()]
            points = [foothold.point for foothold in self.settled] + standing
            self._reported = (self.revision, self._fitted(points or self.points()))
        fitted = self._reported[1]
        if orientation is None or not self.anchored or fitted is None:
            return _at(fitted, x, y)
        centre, solution, covariance, count = fitted
        there, spread = moved(solution, covariance, x - centre[0], y - centre[1])
        return plane_of(*self._across(there, spread, orientation), count)

    def _across(
        self, solution: Sequence[float], covariance: Covariance, orientation: Quaternion
    ) -> tuple[tuple[float, float, float], Covariance]:
        """The plane (a, b, c) and covariance at a point, its slope across the heading of a base
        turned by ``orientation`` (its x axis in odom) :meth:`gradient`'s, its height there and
        its slope along kept (:func:`ground_plane.with_slope_across`): across, the feet that
        stand together span the track at every instant, while the footholds' left and right
        feet land at different places on a staircase's treads and tilt the plane (2.0-3.7° on the
        family's staircases, level across; :meth:`gradient` 0.5-1.2°). Unchanged for a base
        facing straight up or down, and where :meth:`gradient` is below :data:`LEVEL_SLOPE`
        (the footholds are anchored level then: a flat floor's plane stays level).
        """
        forward = rotate(orientation, (1.0, 0.0, 0.0))
        norm = math.hypot(forward[0], forward[1])
        (gx, gy), (cxx, cxy, cyy) = self.gradient()
        if norm < 1e-6 or not _sloped((gx, gy)):  # level: as the anchoring takes it
            return (solution[0], solution[1], solution[2]), covariance
        ux, uy = forward[0] / norm, forward[1] / norm
        variance = uy * uy * cxx - 2.0 * ux * uy * cxy + ux * ux * cyy
        return ground_plane.with_slope_across(
            solution, covariance, (ux, uy), ux * gy - uy * gx, variance
        )

    def _fitted(self, points: list[Point]) -> Fit | None:
        """The plane through ``points`` [m, odom] about their centre; None without points."""
        if not points:
            return None
        data = np.asarray(points, dtype=float)
        centre = (float(data[:, 0].mean()), float(data[:, 1].mean()))
        solution, covariance = fit(data, centre, self.slope_prior, self.min_sigma_m)
        return centre, solution, covariance, len(points)


Fit = tuple[tuple[float, float], tuple[float, float, float], Covariance, int]
"""A plane's centre (x, y) [m], (a, b, c) there, their covariance and the points fitted."""


def _at(fitted: Fit | None, x: float, y: float) -> GroundPlane | None:
    """The ``fitted`` plane moved to (x, y) [m, odom]; None without one."""
    if fitted is None:
        return None
    centre, solution, covariance, count = fitted
    there, spread = moved(solution, covariance, x - centre[0], y - centre[1])
    return plane_of(there, spread, count)
