"""Whether a touchdown takes the ground's prediction (:class:`TouchdownGate`): the anchoring's
decision (:mod:`a1_leg_fk.estimation.ground`), a step or the same ground, from the noise of the
touchdown's own height, which depends on where that height comes from.

- **Against the standing feet** (their anchors plus the contact points' height differences, both
  from one pose): the estimate's height error cancels, and what is left is the feet's relative
  error, ``min_sigma_m``. The run's scatter of touchdown offsets no longer widens it: on a
  staircase most touchdowns are steps, and the offsets the gate took widened the gate that
  took them until a 24-32 mm step passed for noise and its foot was anchored on the wrong
  tread (a1_stairs_down_4cm with noise: the scatter 5 -> 15-19 mm, vertical drift 0.73 %;
  Unitree's Aliengo down a 4 cm staircase, clean: 1.24 %).
- **Alone** (no foot stands to take it against: after a flight, at the start): the height is
  the estimate's own, as uncertain as the estimate's height, whose variance each sample brings
  (``height_variance``, the state filter's: go2_slope_up_5 with noise starts with four feet
  landing alone 19 mm off the first footholds after the robot's drop). Where the ground is
  level, the touchdowns' robust scatter about confident predictions (:meth:`TouchdownGate.count`:
  the offsets the gate took, and every lone one's) where larger: an IMU the filter's model
  does not describe (a retargeted walk's, linearly interpolated: accelerations that jump at
  every frame) lands its lone feet 5-23 mm off the prediction while the filter's vertical sigma
  stays 0.7-4.8 mm. Where the ground slopes a lone touchdown off by more than its own noise is
  a step (the run's scatter took a lone 32 mm step for the tread below).

Where the ground slopes, the ground's prediction is either the slope's or the level one (a
tread): a staircase is no ramp, and its slope's prediction lies between its treads, so a foot that
lands one tread down may pass for the slope's (Unitree's Aliengo down 4 cm steps with noise: a
foot 39 mm below the level prediction, 14.5 mm below the slope's, took the slope's, 20 mm above
its tread, and the next feet took it on: 0.72 % of the path). Which of the two the ground is, the
touchdowns measured against the standing feet tell (:meth:`TouchdownGate.compare`): each that
agrees with the nearer of two predictions apart by more than its noise votes for it; where more
of the last :data:`SCATTER_TOUCHDOWNS` votes are the level one's and those measure the treads as
the base noise says (their robust scatter about the level prediction within ``min_sigma_m``:
1-2.5 mm on the Aliengo's), the ground is treads (:meth:`TouchdownGate.treads`) and the slope's
prediction is not offered. Where they scatter more (the A1's feet on 4 cm steps, landing early
on the nosings: 7.5-8.5 mm), the steps' own heights are no better, and the slope's prediction,
right on the staircase's average, stays offered (without that condition a1_stairs_down_4cm's
noisy kinematic vertical drift was 0.24 -> 0.81 %).

No count depends on the scatter any more, so it cannot widen the gate that feeds it: a
touchdown against the standing feet counts where it is within the base noise's gate, a lone one
on level ground taken or not, and on sloped ground the scatter is no part of the gate.
"""

from __future__ import annotations

import math
from collections import deque

SCATTER_TOUCHDOWNS = 16
"""The touchdowns whose offsets from a confident prediction give their scatter."""
NORMAL_QUARTILE = 0.3186
"""The lower quartile of a normal variable's absolute value, in sigmas."""


class TouchdownGate:
    """A touchdown's noise [m] by where its height comes from, and its test against the ground's
    prediction (module text): within ``step_gate`` sigmas of it, the touchdown takes it.
    """

    def __init__(self, min_sigma_m: float, step_gate: float) -> None:
        self.min_sigma_m = min_sigma_m
        """[m] the touchdowns' height noise against the standing feet, and its least alone."""
        self.step_gate = step_gate
        self._offsets: deque[float] = deque(maxlen=SCATTER_TOUCHDOWNS)
        """The last counted touchdowns' absolute offsets from a confident prediction [m]."""
        self._pending: list[float] = []
        """This sample's counted offsets [m], kept out of its own touchdowns' noise."""
        self._votes: deque[bool] = deque(maxlen=SCATTER_TOUCHDOWNS)
        """The last votes of touchdowns against the standing feet: True, the slope's prediction
        was the nearer (:meth:`compare`)."""
        self._pending_votes: list[bool] = []
        """This sample's votes, kept out of its own touchdowns' judgement."""
        self._tread_offsets: deque[float] = deque(maxlen=SCATTER_TOUCHDOWNS)
        """The last votes for the level prediction: their absolute offsets from it [m]."""
        self._pending_tread_offsets: list[float] = []
        """This sample's, kept out of its own touchdowns' judgement."""

    def sigma_m(self, alone: bool, sloped: bool, height_variance: float) -> float:
        """[m] the noise of a touchdown's height: ``min_sigma_m`` against the standing feet;
        ``alone`` (no foot to take it against), the estimate's own, ``height_variance`` [m²]
        its vertical position's, and where the ground is not ``sloped``, the touchdowns'
        :meth:`scatter_m` where larger.
        """
        if not alone:
            return self.min_sigma_m
        own = math.sqrt(self.min_sigma_m**2 + max(height_variance, 0.0))
        return own if sloped else max(own, self.scatter_m())

    def agrees(self, offset_m: float, variance: float, sigma_m: float) -> bool:
        """Whether a touchdown ``offset_m`` [m] off a prediction of variance ``variance`` [m²]
        is within ``step_gate`` sigmas of it, its own noise ``sigma_m`` [m] (:meth:`sigma_m`).
        """
        return offset_m * offset_m <= self.step_gate**2 * (variance + sigma_m * sigma_m)

    def count(self, offset_m: float) -> None:
        """Count a touchdown's offset [m] from a confident prediction (one that took it, or a
        lone one, but a step where the ground slopes), from the next sample on
        (:meth:`close_sample`).
        """
        self._pending.append(abs(offset_m))

    def compare(self, height_m: float, sloped: tuple[float, float], level: float) -> None:
        """Count the vote of a touchdown at ``height_m`` [m] measured against the standing feet,
        between the slope's prediction (height [m], variance [m²]) and the level one [m]: for
        the nearer, where the two are more than ``min_sigma_m`` apart (the touchdown can tell
        them apart) and it agrees with it (:meth:`agrees`; a step votes for neither), from the
        next sample on (:meth:`close_sample`).
        """
        if abs(sloped[0] - level) <= self.min_sigma_m:
            return
        slope_nearer = abs(height_m - sloped[0]) < abs(height_m - level)
        offset, variance = (
            (height_m - sloped[0], sloped[1]) if slope_nearer else (height_m - level, 0.0)
        )
        if self.agrees(offset, variance, self.min_sigma_m):
            self._pending_votes.append(slope_nearer)
            if not slope_nearer:
                self._pending_tread_offsets.append(abs(offset))

    def treads(self) -> bool:
        """Whether the sloped ground is a staircase's treads whose touchdowns measure as well as
        the base noise says: more of the last votes (:meth:`compare`) went to the level
        prediction than to the slope's, and the level votes' robust scatter about it
        (:func:`quartile_sigma_m`) is within ``min_sigma_m``.
        """
        sigma = quartile_sigma_m(self._tread_offsets)
        fits = sigma is not None and sigma <= self.min_sigma_m
        return fits and 2 * sum(self._votes) < len(self._votes)

    def close_sample(self) -> None:
        """The sample's touchdowns are judged: its counted offsets and votes join the rest."""
        self._offsets.extend(self._pending)
        self._pending.clear()
        self._votes.extend(self._pending_votes)
        self._pending_votes.clear()
        self._tread_offsets.extend(self._pending_tread_offsets)
        self._pending_tread_offsets.clear()

    def scatter_m(self) -> float:
        """[m] the touchdowns' robust scatter: ``min_sigma_m``, or where larger
        :func:`quartile_sigma_m` of the last :data:`SCATTER_TOUCHDOWNS` counted offsets.
        """
        sigma = quartile_sigma_m(self._offsets)
        return self.min_sigma_m if sigma is None else max(self.min_sigma_m, sigma)


def quartile_sigma_m(offsets: deque[float]) -> float | None:
    """[m] a robust sigma of absolute ``offsets`` [m]: their lower quartile over a normal
    sigma's (:data:`NORMAL_QUARTILE`), from half of :data:`SCATTER_TOUCHDOWNS` on; None before.
    """
    if 2 * len(offsets) < SCATTER_TOUCHDOWNS:
        return None
    return sorted(offsets)[len(offsets) // 4] / NORMAL_QUARTILE
