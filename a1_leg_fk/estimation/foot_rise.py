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
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
SPREAD_TIME_S = 0.5
"""[s] the time constant of the standing feet's mean squared rise (the spread)."""


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

    def update(self, dt_s: float, heights: Sequence[float], standing: Sequence[bool]) -> None:
        """A sample ``dt_s`` [s] on: the feet's ``heights`` [m] in the frame (NaN: unknown),
        ``standing`` which feet the filter held standing at the previous sample.
        """
        footholds, rises = self.footholds, self.rises
        squares = []
        for leg, height in enumerate(heights):
            if not (standing[leg] and math.isfinite(height)):
                footholds[leg] = rises[leg] = math.nan
                continue
            if not footholds[leg] <= height:  # a new foothold (NaN), or the foot gave
                footholds[leg] = height
            rises[leg] = rise = height - footholds[leg]
            squares.append(rise * rise)
        if squares:
            share = min(1.0, max(dt_s, 0.0) / SPREAD_TIME_S)
            self._mean_square += share * (sum(squares) / len(squares) - self._mean_square)
            self.spread_m = math.sqrt(self._mean_square)
