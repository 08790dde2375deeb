"""How far each standing foot has risen above its own foothold, and how much standing feet do
while they stand (plain floats, per sample: the contact filter's kinematic evidence of a
liftoff).

A foot's height above the lowest foot or the local ground's plane says "low" for a foot that
left a dip or a lower tread until it is well up (the contact filter's even-odds height is 4 %
of a leg, 16 mm on the A1: a lifting foot 6-10 mm up was still "low" 14-18 ms after its
liftoff). Its height against the foothold it stands on does not depend on the terrain: while
the filter holds a foot standing, its *foothold* is the lowest height it has had since (a
loaded foot sinks into a soft toe or ground: the lowest follows it down), and its *rise* is its
height now above that. A foot the filter holds in swing has neither (NaN): a touchdown on a
higher tread is no rise.

The heights are the contact points' along gravity, in the contact estimate's own carried frame
(:class:`~a1_leg_fk.estimation.foot_ground.FootGround`), with the local ground's slope taken
off, so a foot rolling along a slope does not rise; a foothold is kept as a point and the rise
taken from it with today's slope, so that a slope fitted anew does not move a standing foot (on
stairs the plane through footholds on two treads jumps by degrees: taken off about the frame's
origin, metres away, it lifted standing feet by centimetres, and the spread of a1_stairs_down_4cm
grew to 5 mm, at times 27). What standing feet do while they stand
(they roll, give and unload, and the frame carried by them wanders a little) sets the scale:
the *spread* is the RMS of the standing feet's rises, averaged over :data:`SPREAD_TIME_S`.

A foot has *landed* where it came down to and stayed: its height within a band (the contact
filter's least even-odds rise, 1.5 mm on the A1) of the level it came down to, for
:data:`LANDED_S`, whether the filter holds it standing or not; the contact filter then takes its
height above the other feet for no evidence of swing (a foot on a staircase's higher tread). A
swing foot does not hover where it came down to; the top of its arc, where a foot trotting in
place is still for 40 ms and more (Unitree's Aliengo at 2-2.5 Hz in PyBullet), is a level it
came *up* to. A standing foot that gives under load comes down to its level too.

A foot's height *over the tread under it* is taken over the highest of the other standing feet's
footholds at most the band above it (a foot the band below a tread is on it), while those
footholds are on more than one level (farther apart than the contact filter's even-odds
height): on a staircase the feet stand on two treads, the lowest foot's and a higher one, and
a foot on the higher one stands beside another (a trot's rear pair), which no plane through
footholds on both treads fits. Its own foothold is no tread: a foot lifting from it would
stand while it rises (the rise says that). On one level there are no treads: there the
footholds differ by a foot's give and the sensors' noise, and a foot lifting at a trot's
handover was taken over a foothold just placed above the lowest foot (the contact family's
noisy and soft-toed trots lost 0.1-0.2 point).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
Vector = tuple[float, float, float]
SPREAD_TIME_S = 0.5
"""[s] the time constant of the standing feet's mean squared rise (the spread)."""
LANDED_S = 0.02
"""[s] a foot that stays within the band of the level it came down to this long has landed (ten
500 Hz samples, chosen before measuring; measured after: 4 and 10 ms gain the staircases
0.1-0.8 point, 40 ms loses 0.1-1.1, no run of the contact family or the slopes moves)."""


class FootRise:
    """The feet's footholds, rises and the standing feet's spread (see the module text)."""

    def __init__(self) -> None:
        self.footholds: list[Vector | None] = [None] * LEGS
        """[m] each standing foot's foothold, a point in the frame (None: not standing)."""
        self.rises = [math.nan] * LEGS
        """[m] each standing foot's height above its foothold (NaN: not standing, unknown)."""
        self.spread_m = 0.0
        """[m] the standing feet's RMS rise, averaged over :data:`SPREAD_TIME_S`."""
        self._mean_square = 0.0
        self.landed = [False] * LEGS
        """Whether each foot has stayed where it came down to for :data:`LANDED_S`."""
        self._levels: list[Vector | None] = [None] * LEGS
        """[m] where each foot last left its band (None: unknown)."""
        self._level_s = [0.0] * LEGS
        """[s] how long each foot has stayed within the band of its level."""
        self._down = [False] * LEGS
        """Whether each foot came down to its level (rather than up)."""

    def update(
        self,
        dt_s: float,
        points: Sequence[Vector | None],
        slope: tuple[float, float],
        standing: Sequence[bool],
        band_m: float = 0.0,
    ) -> None:
        """A sample ``dt_s`` [s] on: the feet's contact ``points`` [m] in the frame (None:
        unknown), the local ground's ``slope`` (dz/dx, dz/dy; 0, 0: level), ``standing`` which
        feet the filter held standing at the previous sample; ``band_m`` [m] how far a foot held
        in swing may move and still land (0: only a foot exactly still). Heights are taken
        between a foot's two points with today's slope: a slope fitted anew (on stairs it jumps
        by degrees) does not move a standing foot, however far the frame's origin.
        """
        footholds, rises, levels, level_s = self.footholds, self.rises, self._levels, self._level_s
        gx, gy = slope
        dt_s = max(dt_s, 0.0)
        squares = []
        for leg, point in enumerate(points):
            if point is None:
                levels[leg], footholds[leg], rises[leg] = None, None, math.nan
                self.landed[leg] = self._down[leg] = False
                continue
            x, y, z = point
            level = levels[leg]  # where it came to, the slope taken off (inlined: per sample)
            above = (
                math.nan
                if level is None
                else z - level[2] - gx * (x - level[0]) - gy * (y - level[1])
            )
            if not abs(above) <= band_m:  # moved out of the band
                levels[leg], level_s[leg] = point, 0.0
                self._down[leg] = above < 0.0  # came down to it (not: rose to the top of an arc)
            else:
                level_s[leg] += dt_s
            self.landed[leg] = self._down[leg] and level_s[leg] >= LANDED_S
            if not standing[leg]:
                footholds[leg], rises[leg] = None, math.nan
                continue
            rise = _above(point, footholds[leg], slope)
            if not rise >= 0.0:  # a new foothold (NaN), or the foot gave
                footholds[leg], rise = point, 0.0
            rises[leg] = rise
            squares.append(rise * rise)
        if squares:
            self._mean_square = averaged_square(self._mean_square, squares, dt_s)
            self.spread_m = math.sqrt(self._mean_square)

    def over_treads(
        self,
        points: Sequence[Vector | None],
        slope: tuple[float, float],
        band_m: float,
        step_m: float,
    ) -> list[float] | None:
        """[m] each foot's height over the tread under it (see the module text): above the
        highest of the *other* standing feet's footholds at most ``band_m`` above it (heights
        with the ``slope`` taken off; NaN: none, or an unknown foot); None while the standing
        feet's footholds are within ``step_m`` of each other (one level). ``points`` as
        :meth:`update`'s, after it.
        """
        gx, gy = slope
        treads = [math.nan] * LEGS
        low, high = math.inf, -math.inf
        for leg, foothold in enumerate(self.footholds):
            if foothold is not None:
                tread = treads[leg] = foothold[2] - gx * foothold[0] - gy * foothold[1]
                low, high = min(low, tread), max(high, tread)
        if not high - low > step_m:  # one level, or none (inf - inf: NaN)
            return None
        over = [math.nan] * LEGS
        for leg, point in enumerate(points):
            if point is None:
                continue
            z = point[2] - gx * point[0] - gy * point[1]
            for other, tread in enumerate(treads):  # the highest within reach: inlined max()
                if other != leg and tread <= z + band_m:  # NaN: no foothold
                    below = z - tread
                    if not below >= over[leg]:  # NaN: the first
                        over[leg] = below
        return over


def averaged_square(previous: float, squares: Sequence[float], dt_s: float) -> float:
    """[m²] a running mean square over :data:`SPREAD_TIME_S`: ``previous`` moved toward the mean
    of this sample's ``squares`` [m²] (at least one) by ``dt_s`` [s] over :data:`SPREAD_TIME_S`,
    at most all the way; from ``previous`` inf (none yet), the sample's mean.
    """
    mean = sum(squares) / len(squares)
    if previous == math.inf:
        return mean
    return previous + min(1.0, dt_s / SPREAD_TIME_S) * (mean - previous)


def _above(point: Vector, base: Vector | None, slope: tuple[float, float]) -> float:
    """[m] how far ``point`` is above ``base`` (None: NaN) with the ``slope`` taken off."""
    if base is None:
        return math.nan
    gx, gy = slope
    return point[2] - base[2] - gx * (point[0] - base[0]) - gy * (point[1] - base[1])
