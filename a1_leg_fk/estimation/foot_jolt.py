"""The standing feet's horizontal jolt at each touchdown, measured on its own first samples
(:mod:`a1_leg_fk.estimation.state_filter`): the horizontal twin of
:mod:`~a1_leg_fk.estimation.foot_impact`, shared by every standing foot.

A foot that lands while others stand pushes the base sideways through its leg: the feet already
standing slip with it, all alike, for tens of milliseconds, so no foot's innovation stands out
and the gate lets them through. Under PyBullet's position motors (a1_position_flat, clean) the
standing feet's sideways velocities are 0.04-0.05 m/s off (RMS) in the first 25 ms after a
touchdown (a landing or a bounce), 0.02 in the next 25, 0.004 later, against a foot's horizontal
innovation sigma of 0.014 m/s: the estimate followed them, and most of its samples outside 3
sigma were these handovers.

So each touchdown while another foot stood (a landing after a flight, or the filter's first feet,
jolts no one) starts a jolt ``a² d(t)``, ``d(t) = exp(-2 t / τ)`` (``τ`` ``touchdown_s``, ``t``
seconds since that touchdown), on every standing foot's horizontal velocity, per axis: until
measured the last touchdown's ``a²`` (``touchdown_noise_mps²`` before any); from the touchdown's
first update on its own: the least-squares fit of ``a² d(t)`` to the accepted feet's excesses
``(r_h² - s₀) / 2`` within ``impact_window_s`` (``r_h`` a foot's innovation across world up, ``s₀``
that innovation's variance across up), at least 0. A fit, not the largest excess (foot_impact's
rule for one foot's landing): the excesses of white noise alone average 0, where the largest of
tens of them is several times their variance (with the largest, go2_slope_up_5's clean sigma went
from 4.97 to 5.47x its error, a1_rigid_toes' 4.38 to 5.11x). As the landing's vertical transient,
one offset shared by the samples that follow: the white noise of the same low-frequency power, ``a²
2τ / dt``, never more than ``touchdown_noise_mps²``. The filter adds it to the feet the gate
accepted, after the gate (with it in, a landing foot sliding 0.1 m/s passed and pulled the
estimate), and matches the feet's noise scales with it (it is no white noise the scales should take
up).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_model import FilterSettings
from a1_leg_fk.estimation.foot_give import quadratic
from a1_leg_fk.estimation.foot_impact import colored, decay

SPAN = 5.0
"""A jolt is over this many ``touchdown_s`` after its touchdown: its variance then below
``e^-10`` of its start (at most ``(0.7 mm/s)²``, under any foot's white noise), so the filter
adds nothing between touchdowns."""


class FootJolt:
    """The last touchdown's horizontal jolt: :meth:`land` at a foot's touchdown while others
    stood, :meth:`variance` for the accepted feet's horizontal noise, :meth:`observe` with every
    update's accepted feet.
    """

    def __init__(self, settings: FilterSettings) -> None:
        self.settings = settings
        self.square: float | None = None
        """The last touchdown's measured ``a²`` [m²/s², per horizontal axis] (None: not yet)."""
        self._sums = (0.0, 0.0)
        """Its least-squares fit's sums: the excesses times ``d(t)``, and ``d(t)²``."""
        self.previous: float | None = None
        """The touchdown's before it (None: none measured)."""
        self.landed_ns: int | None = None
        """The last touchdown [ns] (None: none yet)."""
        self.interval_s = 0.0
        """The time between the last two updates with accepted feet [s]."""
        self._stamp_ns: int | None = None

    def land(self, stamp_ns: int) -> None:
        """A foot's touchdown at ``stamp_ns`` [ns]: a new jolt, its size the last one's until
        measured.
        """
        if self.square is not None:
            self.previous = self.square
        self.square, self.landed_ns, self._sums = None, stamp_ns, (0.0, 0.0)

    def variance(self, stamp_ns: int) -> float:
        """Each standing foot's extra horizontal variance [m²/s², per axis] at ``stamp_ns`` [ns]
        (0 before any touchdown, :data:`SPAN` after it, or with ``impact_window_s`` or
        ``touchdown_noise_mps`` 0).
        """
        s = self.settings
        if self.landed_ns is None or not (s.impact_window_s > 0.0 and s.touchdown_noise_mps > 0.0):
            return 0.0
        seconds = (stamp_ns - self.landed_ns) / 1e9
        if not seconds <= SPAN * s.touchdown_s:
            return 0.0
        square = self.square if self.square is not None else self.previous
        return colored(square, self.interval_s, s) * decay(seconds, s)

    def sideways(self, stamp_ns: int, up: Sequence[float]) -> np.ndarray | None:
        """The :meth:`variance` at ``stamp_ns`` [ns] across world ``up`` (base frame), 3 x 3
        [m²/s²] (None: 0).
        """
        variance = self.variance(stamp_ns)
        return variance * (np.eye(3) - np.outer(up, up)) if variance else None

    def observe(
        self,
        stamp_ns: int,
        residuals: Sequence[tuple[float, float, float]],
        up: Sequence[float],
        innovation: np.ndarray,
        rows: Sequence[int],
    ) -> None:
        """One update's accepted feet at ``stamp_ns`` [ns]: their innovations [m/s, base frame],
        world ``up`` in the base frame, the update's ``innovation`` covariance [m²/s²] (the jolt
        not in it) and each foot's first row in it: the jolt measured within ``impact_window_s``
        of its touchdown.
        """
        s = self.settings
        previous, self._stamp_ns = self._stamp_ns, stamp_ns
        if previous is not None:
            self.interval_s = min(max((stamp_ns - previous) / 1e9, 0.0), s.max_step_s)
        if self.landed_ns is None:
            return
        age = (stamp_ns - self.landed_ns) / 1e9
        if not age <= s.impact_window_s:
            return
        ux, uy, uz = up
        share, (products, squares) = decay(age, s), self._sums
        for (x, y, z), row in zip(residuals, rows):
            along = ux * x + uy * y + uz * z
            across = x * x + y * y + z * z - along * along
            block = innovation[row : row + 3, row : row + 3].ravel().tolist()
            spread = block[0] + block[4] + block[8] - quadratic(up, block)
            products += (across - spread) / 2.0 * share
            squares += share * share
        self._sums = (products, squares)
        if squares > 0.0:
            self.square = max(products / squares, 0.0)
