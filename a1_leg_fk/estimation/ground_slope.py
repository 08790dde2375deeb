"""The ground's slope from the feet that stand at the same time (:class:`GroundSlope`): each
pair's height difference over its horizontal offset, in odom. The base's position is common to
every foot of a sample, so its drift cancels out of the differences (and so does the load of a
trot's diagonal pair, both feet equally loaded): the slope is measured, not integrated. The
pairs' sums decay with a time constant (the ground under the robot changes), each sample weighted
by its interval, one stance counting as one measurement per ``correlation_s``; a Gaussian prior
(level, standard deviation ``prior``) keeps a direction no pair spans level and uncertain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Point = tuple[float, float, float]

MAX_STEP_S = 0.1
"""[s] the longest sample interval a sample weighs (a gap counts as this)."""


class GroundSlope:
    """The decaying sums of the standing feet's pairwise differences and the slope they give
    (see the module text): ``time_s`` [s] the sums' time constant, ``sigma_m`` [m] a contact
    point's height noise, ``correlation_s`` [s] the span one measurement covers, ``prior`` the
    slopes' prior standard deviation (dz/dx, dz/dy).
    """

    def __init__(self, time_s: float, sigma_m: float, correlation_s: float, prior: float) -> None:
        self.time_s = time_s
        self.weight = 1.0 / (sigma_m**2 * correlation_s)
        self.prior = 1.0 / prior**2
        self._sums = [0.0] * 5
        """dx², dx dy, dy², dx dz, dy dz [m² s], decaying."""
        self._stamp_s: float | None = None

    def add(self, stamp_s: float, points: Sequence[Point]) -> None:
        """Decay the sums to ``stamp_s`` [s] and add the pairwise differences of the standing
        feet's contact ``points`` [m, odom], weighted by the interval since the last sample.
        """
        last, self._stamp_s = self._stamp_s, stamp_s
        dt = 0.0 if last is None else min(max(stamp_s - last, 0.0), MAX_STEP_S)
        decay = math.exp(-dt / self.time_s)
        sums = [value * decay for value in self._sums]
        for i, (xi, yi, zi) in enumerate(points):
            for xj, yj, zj in points[i + 1 :]:
                dx, dy, dz = xj - xi, yj - yi, zj - zi
                sums[0] += dt * dx * dx
                sums[1] += dt * dx * dy
                sums[2] += dt * dy * dy
                sums[3] += dt * dx * dz
                sums[4] += dt * dy * dz
        self._sums = sums

    def gradient(self) -> tuple[tuple[float, float], tuple[float, float, float]]:
        """The slope (dz/dx, dz/dy) and its covariance (xx, xy, yy); level with the prior's
        variance before any pair.
        """
        weight = self.weight
        xx, xy, yy, xz, yz = self._sums
        a, b, d = xx * weight + self.prior, xy * weight, yy * weight + self.prior
        det = a * d - b * b
        cxx, cxy, cyy = d / det, -b / det, a / det
        u, v = xz * weight, yz * weight
        return (cxx * u + cxy * v, cxy * u + cyy * v), (cxx, cxy, cyy)
