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
off, so a foot rolling along a slope does not rise. What standing feet do while they stand
(they roll, give and unload, and the frame carried by them wanders a little) sets the scale:
the *spread* is the RMS of the standing feet's rises, averaged over :data:`SPREAD_TIME_S`.

A foot the filter holds in swing that has *landed* stands at its own level too: one whose
height has stayed within a band (the contact filter's even-odds rise) of where it was for
:data:`LANDED_S` has a rise of 0 (no foothold yet: that starts once the filter holds it
standing). A swing foot does not hover: at the top of its arc it passes through the A1's
1.5 mm band in under 10 ms (the family's trots), while a foot that landed on a higher tread
stays there for its stance (0.2 s); its height above the lowest foot, a tread's rise, is no
evidence of swing then.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
SPREAD_TIME_S = 0.5
"""[s] the time constant of the standing feet's mean squared rise (the spread)."""
LANDED_S = 0.02
"""[s] a foot held in swing whose height stays within the band this long has landed (measured:
4 ms called go2_slope_up_5's swing feet landed at the tops of their arcs, 0.6 point lost; 10
and 20 ms changed no run of the contact family and no slope)."""


class FootRise:
    """The feet's footholds, rises and the standing feet's spread (see the module text)."""

    def __init__(self) -> None:
        self.footholds = [math.nan] * LEGS
        """[m] each standing foot's foothold height in the frame (NaN: not standing)."""
        self.rises = [math.nan] * LEGS
        """[m] each standing foot's height above its foothold (NaN: not standing, unknown)."""
        self.spread_m = 0.0
        """[m] the standing feet's RMS rise, averaged over :data:`SPREAD_TIME_S`."""
        self._mean_square = 0.0
        self._levels = [math.nan] * LEGS
        """[m] where each foot held in swing last left its band (NaN: standing, unknown)."""
        self._level_s = [0.0] * LEGS
        """[s] how long each foot held in swing has stayed within the band of its level."""

    def update(
        self,
        dt_s: float,
        heights: Sequence[float],
        standing: Sequence[bool],
        band_m: float = 0.0,
    ) -> None:
        """A sample ``dt_s`` [s] on: the feet's ``heights`` [m] in the frame (NaN: unknown),
        ``standing`` which feet the filter held standing at the previous sample; ``band_m`` [m]
        how far a foot held in swing may move and still land (0: only a foot exactly still).
        """
        footholds, rises = self.footholds, self.rises
        squares = []
        for leg, height in enumerate(heights):
            if not (standing[leg] and math.isfinite(height)):
                footholds[leg] = rises[leg] = math.nan
                self._land(leg, height, max(dt_s, 0.0), band_m)
                continue
            self._levels[leg] = math.nan
            if not footholds[leg] <= height:  # a new foothold (NaN), or the foot gave
                footholds[leg] = height
            rises[leg] = rise = height - footholds[leg]
            squares.append(rise * rise)
        if squares:
            share = min(1.0, max(dt_s, 0.0) / SPREAD_TIME_S)
            self._mean_square += share * (sum(squares) / len(squares) - self._mean_square)
            self.spread_m = math.sqrt(self._mean_square)

    def half_m(self, floor_m: float, spread_factor: float) -> float:
        """The even-odds rise [m] above a foot's own foothold, within which a swing foot lands
        too: ``floor_m``, or ``spread_factor`` times the standing feet's spread if more.
        """
        return max(floor_m, spread_factor * self.spread_m)

    def _land(self, leg: int, height: float, dt_s: float, band_m: float) -> None:
        """A foot held in swing (or unknown: NaN) at ``height`` [m]: its time within
        ``band_m`` of its level, and a rise of 0 once that is :data:`LANDED_S`.
        """
        if not abs(height - self._levels[leg]) <= band_m:  # moved out of the band (NaN too)
            self._levels[leg], self._level_s[leg] = height, 0.0
            return
        self._level_s[leg] += dt_s
        if self._level_s[leg] >= LANDED_S:
            self.rises[leg] = 0.0
