"""Each foot's height above the local ground, for the contact filter's kinematic evidence (plain
floats, per sample: the node runs it for every joint state).

A flat-floor rule reads a foot's height against the lowest foot along gravity: on a slope, a foot
on the higher side stands while it is "high" (a 5° slope lifts the A1's front feet 3 cm above its
rear ones, twice the filter's even-odds height). Here the ground's slope is the plane through the
recent footholds at their measured heights, fitted by the odometry's own rule
(:class:`~a1_leg_fk.estimation.ground.LocalGround` with ``anchored=False``: the odometry's anchors
snap a touchdown to a level or lagging prediction, which flattens a ramp's footholds: 0.123
instead of 0.141 on an 8° one), in a frame the contact estimate keeps by itself, without the
odometry:

- gravity-levelled: z up (minus ``down``), x the base's x along the horizontal, turned by a
  heading ``psi`` [rad] integrated from the gyro's rate about z;
- carried by the standing feet: the base moves by the mean displacement, in that frame, of the
  standing feet (a standing foot is still) whose speed is within :data:`CARRY_GATE_MPS` of the
  base's at the previous sample (a foot the estimate still holds while it lifts, or already
  holds while it lands, moves differently: left out), else of the one closest to it; with none
  standing (a flight), at the previous speed. The footholds left behind stay put.

A slope within :data:`SIGNIFICANT` standard deviations of level (the plane's own covariance) is
taken for level: on a flat floor the rule is the flat-floor rule, exactly. A foot's height [m] is
then its contact point's height with the slope taken off (``z - gx x - gy y``), above the lowest
foot's: the slope comes from the footholds, the heights from the feet now, so that the frame's
slow vertical drift does not bias them. Before the first foothold there is no slope: None.
The standing feet's heights in the frame, the slope taken off (level before there is one), also
give each its rise above its own foothold and each foot its height over the tread under it, the
highest of the other standing feet's footholds not above it, where those are on two levels
(:mod:`a1_leg_fk.estimation.foot_rise`): where that is lower, it is the foot's height (no plane
fits a staircase's treads; a foot on a higher tread than the lowest foot's stands on it beside
another foot).
Absurd input is kept out: a contact point farther than :data:`MAX_REACH_M` from the base is
unknown, and a frame carried beyond :data:`MAX_FRAME_M` starts anew.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.estimation.foot_rise import FootRise, averaged_square
from a1_leg_fk.estimation.ground import LocalGround
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
Vector = tuple[float, float, float]
SIGNIFICANT = 2.0
"""A slope smaller than this many of its standard deviations is taken for level."""
MAX_REACH_M = 10.0
"""[m] a contact point farther than this from the base along any axis is no foot (absurd input):
unknown."""
MAX_FRAME_M = 1.0e6
"""[m] a frame whose base has gone farther (a gap of hours, absurd speeds) starts anew."""
CARRY_GATE_MPS = 0.1
"""[m/s] a standing foot carries the frame while its speed is this close to the base's."""


class FootGround:
    """The frame, the base's place in it, the footholds and the plane (see the module text)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """A new frame: no footholds, the base at its origin, still."""
        self.ground = LocalGround(anchored=False)
        self.psi = 0.0
        """[rad] the heading of the levelled frame, from the gyro."""
        self.base: list[float] = [0.0, 0.0, 0.0]
        """[m] the base's origin in the frame, carried by the standing feet."""
        self._offsets: list[Vector | None] = [None] * LEGS
        self._velocity: Vector = (0.0, 0.0, 0.0)
        """[m/s] the base's velocity in the frame at the previous sample."""
        self._stamp_s = 0.0
        self._slope: tuple[int, float, float] | None = None
        """(the footholds' revision, dz/dx, dz/dy) of the plane last fitted."""
        self.height_spread_m = math.inf
        """[m] the standing feet's RMS height (as :meth:`heights` returns it), averaged over
        :data:`~a1_leg_fk.estimation.foot_rise.SPREAD_TIME_S` (inf: no standing foot yet)."""
        self._height_square = math.inf
        self.one_level = True
        """Whether the standing feet's footholds were on one level at the latest sample (not
        farther apart than ``step_m``; before a foothold: True)."""
        self.rise = FootRise()
        """The standing feet's rises above their own footholds (level while there is no
        slope yet)."""

    def heights(
        self,
        dt_s: float,
        feet: Sequence[FootMotion | None],
        down: Vector,
        omega: Sequence[float],
        standing: Sequence[bool],
        band_m: float = 0.0,
        step_m: float = math.inf,
    ) -> list[float] | None:
        """Each foot's contact point's height [m] above the lowest one's, the local ground's
        slope taken off, or over the tread under it where lower (NaN: unknown foot), after a
        sample ``dt_s`` [s] on: ``feet`` their motions (base frame), ``down`` gravity's unit
        direction and ``omega`` the base's angular velocity [rad/s] (base frame), ``standing``
        which feet stood at the previous sample (the filter's estimate), ``band_m`` [m] the band
        within which a foot held in swing lands and a foot below a tread is on it,
        ``step_m`` [m] how far apart the standing feet's footholds are on two levels
        (:meth:`FootRise.update`, :meth:`FootRise.over_treads`; inf: never). None before the
        first foothold.
        """
        dx, dy, dz = down
        ux, uy, uz = -dx, -dy, -dz  # up
        psi = self.psi + dt_s * (omega[0] * ux + omega[1] * uy + omega[2] * uz)
        self.psi = psi if math.isfinite(psi) else self.psi  # a gyro's NaN: the heading kept
        # x_L: the base's x made horizontal
        ax, ay, az = 1.0 - ux * ux, -ux * uy, -ux * uz
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / norm, ay / norm, az / norm
        bx, by, bz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax  # y_L = z_L x x_L
        cos, sin = math.cos(self.psi), math.sin(self.psi)
        offsets: list[Vector | None] = []
        for foot in feet:
            if foot is None:
                offsets.append(None)
                continue
            rx, ry, rz = foot.r
            if not (abs(rx) <= MAX_REACH_M and abs(ry) <= MAX_REACH_M and abs(rz) <= MAX_REACH_M):
                offsets.append(None)  # NaN too
                continue
            x, y = ax * rx + ay * ry + az * rz, bx * rx + by * ry + bz * rz
            offsets.append((cos * x - sin * y, sin * x + cos * y, ux * rx + uy * ry + uz * rz))
        dt_s = max(dt_s, 0.0)
        base = self._carry(offsets, standing, dt_s)
        px, py, pz = base
        if not (abs(px) <= MAX_FRAME_M and abs(py) <= MAX_FRAME_M and abs(pz) <= MAX_FRAME_M):
            self.reset()
            return None
        self._stamp_s += dt_s
        self.ground.update(
            self._stamp_s,
            [
                (leg, (px + o[0], py + o[1], pz + o[2]))
                for leg, o in enumerate(offsets)
                if o is not None and standing[leg]
            ],
        )
        slope = self._slope
        if slope is None or slope[0] != self.ground.revision:
            slope = self._fitted()
        gx, gy = (0.0, 0.0) if slope is None else slope[1:]
        points = [None if o is None else (px + o[0], py + o[1], pz + o[2]) for o in offsets]
        self.rise.update(dt_s, points, (gx, gy), standing, band_m)
        if slope is None:
            return None
        level = [math.nan if o is None else o[2] - gx * o[0] - gy * o[1] for o in offsets]
        lowest = min([value for value in level if value == value], default=math.nan)  # noqa: PLR0124 (NaN)
        over = self.rise.over_treads(points, (gx, gy), band_m, step_m)
        self.one_level = over is None
        if over is None:  # the standing feet on one level: the lowest foot's
            out = [value - lowest for value in level]
        else:
            out = [
                min(value - lowest, tread)  # NaN (no tread under it): the lowest's
                for value, tread in zip(level, over, strict=True)
            ]
        self._spread(dt_s, out, standing)
        return out

    def _spread(self, dt_s: float, heights: Sequence[float], standing: Sequence[bool]) -> None:
        """:attr:`height_spread_m` after a sample ``dt_s`` [s] on: the ``standing`` feet's
        ``heights`` [m] (NaN: unknown, left out); the first sample with one sets it.
        """
        squares = [h * h for h, on in zip(heights, standing, strict=True) if on and h == h]  # noqa: PLR0124 (NaN)
        if not squares:
            return
        self._height_square = averaged_square(self._height_square, squares, dt_s)
        self.height_spread_m = math.sqrt(self._height_square)

    def _carry(
        self, offsets: list[Vector | None], standing: Sequence[bool], dt_s: float
    ) -> list[float]:
        """The base moved by the standing feet that move as it did (see the module text);
        :attr:`base`.
        """
        previous, self._offsets = self._offsets, offsets
        base = self.base
        if dt_s <= 0.0:
            return base
        vx, vy, vz = self._velocity
        moves: list[tuple[float, Vector]] = []
        for leg, now in enumerate(offsets):
            before = previous[leg]
            if now is not None and before is not None and standing[leg]:
                mx, my, mz = (
                    (before[0] - now[0]) / dt_s,
                    (before[1] - now[1]) / dt_s,
                    (before[2] - now[2]) / dt_s,
                )
                off = (mx - vx) * (mx - vx) + (my - vy) * (my - vy) + (mz - vz) * (mz - vz)
                moves.append((off, (mx, my, mz)))
        if moves:
            gate = CARRY_GATE_MPS * CARRY_GATE_MPS
            kept = [move for off, move in moves if off <= gate] or [min(moves)[1]]
            sx = sy = sz = 0.0  # summed in order, as sum() does
            for mx, my, mz in kept:
                sx += mx
                sy += my
                sz += mz
            count = len(kept)
            vx, vy, vz = self._velocity = (sx / count, sy / count, sz / count)
        base[0] += vx * dt_s
        base[1] += vy * dt_s
        base[2] += vz * dt_s
        return base

    def _fitted(self) -> tuple[int, float, float] | None:
        """The plane's slope, fitted again only when its footholds changed (None: none yet)."""
        ground = self.ground
        if self._slope is None or self._slope[0] != ground.revision:
            plane = ground.plane(self.base[0], self.base[1])
            if plane is None:
                self._slope = None
                return None
            gx, gy = plane.gradient
            variance = plane.covariance[1][1] + plane.covariance[2][2]  # roll's and pitch's
            if gx * gx + gy * gy <= SIGNIFICANT * SIGNIFICANT * variance:
                gx, gy = 0.0, 0.0  # level, as far as the footholds can tell
            self._slope = (ground.revision, gx, gy)
        return self._slope
