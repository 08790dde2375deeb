"""The standing feet's give (:mod:`a1_leg_fk.estimation.state_filter`): the part of their vertical
velocity the IMU does not confirm, measured over the last strides, as the feet's vertical noise.

A compliant foot (or ground) sinks as it loads and rises as it unloads, and rolls on a radius
smaller than its URDF sphere: the legs see the base move vertically by that much, every standing
foot alike (a trot's pair loads together), for tens of milliseconds at a time. No foot's innovation
shows it while they agree, so no constant fitted to one contact model holds on another. The IMU
does see it: over a fraction of a second its integrated vertical acceleration is exact to
millimetres per second, and the accepted feet's mean vertical velocity (weighted by their vertical
noises, as the filter weighs them: a landing foot's transient counts little) less it, high-passed
over ``give_window_s``, is the give (plus the IMU's own noise). Its mean square over
``give_average_s``, ``σ²``, is a colored noise of correlation time ``give_s`` ``τ`` shared by the
``n`` standing feet: each foot's sample ``dt`` apart is given the white noise of the same low
frequency power, ``n σ² 2τ / dt`` (the feet's fused measurement keeps the give's ``σ²`` over ``τ``,
not ``σ²/n`` at every sample).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_model import ACCEL_BIAS, FilterSettings

CLIP = 4.0
"""A sample's squared give counts up to this times the variance so far (the give's and the white
noise's: 2 sigma), so one impact, a step down's landings or a start in motion do not hold the feet
loose for seconds (at 9x, 3 sigma, go2_stairs_down_6cm's landings did: within 3 sigma 92.4 %
clean with efforts); a softer ground is taken up over a fraction of a second (the mean may grow
by that factor per ``give_average_s``)."""


class FootGive:
    """The give's running estimate: :meth:`observe` at every update with standing feet,
    :meth:`variance` for each standing foot's vertical noise.
    """

    def __init__(self, settings: FilterSettings) -> None:
        self.settings = settings
        self.square = 0.0
        """The give's mean square [m²/s²] (``σ²``), the feet's white noise taken off (below 0:
        none)."""
        self._stamp_ns: int | None = None
        self._corrections_ms = 0.0
        """The sum of the updates' corrections to the filter's vertical velocity [m/s]: the
        filter's velocity less it is the IMU's alone."""
        self._slow: float | None = None
        """The feet's vertical velocity less the IMU's, low-passed over ``give_window_s``."""
        self._trend = 0.0
        """Its rate [m/s²]: an IMU bias not yet learnt makes the difference a ramp."""
        self.interval_s = 0.0
        """The time between the last two updates with standing feet [s]."""
        self._landed_ns: int | None = None
        """The accepted feet's last touchdown [ns]: the stance being measured."""
        self._kept: list[tuple[float, float, float]] = []
        """Its samples (seconds since the last, squared give, white noise's variance) while it
        may yet be no stance (shorter than ``give_after_s``: a swing foot taken for standing)."""

    def corrected(self, correction_ms: float) -> None:
        """One update's correction to the filter's vertical velocity [m/s, world up]."""
        self._corrections_ms += correction_ms

    def observe(
        self,
        stamp_ns: int,
        up: list[float],
        residuals: list[tuple[float, float, float]],
        noises: list[tuple[float, ...]],
        transients: list[float],
        covariance: np.ndarray,
        landed_ns: int,
    ) -> None:
        """One update's accepted feet (none, or ``give_s`` 0: nothing): their ``residuals`` [m/s,
        base frame] against the filter's velocity before the update, their ``noises``, each its
        3 x 3 row-major covariance [m²/s²], and ``transients``, the part of each one's variance
        along up that is no white noise (the touchdown's and the give's); world ``up`` in the base
        frame. The residuals' mean
        along ``up``, weighted as the filter weighs them (a landing foot little), plus the
        corrections so far is the feet's vertical velocity less the IMU's; that mean's white noise,
        ``Σ w² v / (Σ w)²``, is no give. While the accelerometer's bias (its block of the filter's
        ``covariance``, [m²/s⁴], base frame) is not known to that noise over
        ``give_window_s`` (the filter's first seconds), the IMU's velocity is not the reference
        yet: nothing is measured. A stance (since the accepted feet's last touchdown ``landed_ns``
        [ns]) counts from its touchdown on once it has lasted ``give_after_s``: a shorter one (a
        swing foot taken for standing for a few joint states, a bounce) is no give.
        """
        if not (residuals and self.settings.give_s > 0.0):
            return
        along = total = white = 0.0
        for (x, y, z), noise, transient in zip(residuals, noises, transients):
            variance = quadratic(up, noise)
            if not variance > 0.0:
                return
            weight = 1.0 / variance
            along += weight * (up[0] * x + up[1] * y + up[2] * z)
            total += weight
            white += weight * weight * max(variance - transient, 0.0)
        white /= total * total
        if _bias_along(up, covariance) * self.settings.give_window_s**2 > white:
            self._slow = None
            return
        self._observe(stamp_ns, along / total, white, landed_ns)

    def _observe(self, stamp_ns: int, residual_ms: float, white: float, landed_ns: int) -> None:
        """The feet's weighted mean vertical residual [m/s] and its white noise's variance
        [m²/s²] to the high-pass and, once the stance since ``landed_ns`` has lasted
        ``give_after_s``, to the mean square (its samples kept until then).
        """
        s = self.settings
        previous, self._stamp_ns = self._stamp_ns, stamp_ns
        difference = residual_ms + self._corrections_ms
        seconds = (stamp_ns - previous) / 1e9 if previous is not None else math.inf
        if self._slow is None or not seconds <= s.give_window_s:  # the first, or after a gap
            self._slow, self._trend = difference, 0.0
            return
        seconds = min(max(seconds, 0.0), s.max_step_s)
        self.interval_s = seconds
        share = _share(seconds, s.give_window_s)
        give = difference - self._slow - self._trend * seconds
        self._slow += self._trend * seconds + 2.0 * share * give
        self._trend += share * share / max(seconds, 1e-9) * give
        if landed_ns != self._landed_ns:  # a new stance: the last one's samples, if kept, dropped
            self._landed_ns = landed_ns
            self._kept.clear()
        if stamp_ns - landed_ns < s.give_after_s * 1e9:  # no stance yet: kept
            self._kept.append((seconds, give * give, white))
            return
        if self._kept:  # a stance now: its first samples are give
            for kept in self._kept:
                self._count(*kept)
            self._kept.clear()
        self._count(seconds, give * give, white)

    def _count(self, seconds: float, square: float, white: float) -> None:
        """One sample ``seconds`` [s] after the last, its squared give [m²/s²] clipped at
        :data:`CLIP` times the variance so far and its white noise's variance ``white`` taken off,
        to the give's mean square.
        """
        counted = min(square, CLIP * (max(self.square, 0.0) + white)) - white
        self.square += _share(seconds, self.settings.give_average_s) * (counted - self.square)

    def variance(self, feet: int) -> float:
        """Each of ``feet`` standing feet's vertical variance for the give [m²/s²], ``n σ² 2τ /
        dt`` (0 before two updates, or while the feet's scatter is all their white noise).
        """
        if not (self.interval_s > 0.0 and self.square > 0.0):
            return 0.0
        return feet * self.square * 2.0 * self.settings.give_s / self.interval_s


def quadratic(up: Sequence[float], matrix: Sequence[float]) -> float:
    """``uᵀ M u`` for a symmetric 3 x 3 ``matrix`` (row-major) and ``up`` ``u``."""
    ux, uy, uz = up
    a, b, c, _, d, e, _, _, f = matrix
    return (
        a * ux * ux + d * uy * uy + f * uz * uz + 2.0 * (b * ux * uy + c * ux * uz + e * uy * uz)
    )


def _bias_along(up: list[float], covariance: np.ndarray) -> float:
    """The accelerometer bias' variance along ``up`` [m²/s⁴] in the filter's ``covariance``
    (read entry by entry: cheaper than a copy of its block).
    """
    i = ACCEL_BIAS.start
    item = covariance.item
    a, b, c = item(i, i), item(i, i + 1), item(i, i + 2)
    d, e, f = item(i + 1, i + 1), item(i + 1, i + 2), item(i + 2, i + 2)
    return quadratic(up, (a, b, c, b, d, e, c, e, f))


def _share(seconds: float, time_constant: float) -> float:
    """A running mean's step: ``seconds`` over its ``time_constant`` (0: the last value), <= 1."""
    return min(seconds / time_constant, 1.0) if time_constant > 0.0 else 1.0
