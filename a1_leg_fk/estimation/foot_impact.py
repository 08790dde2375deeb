"""Each landing's vertical transient measured on its own first samples
(:mod:`a1_leg_fk.estimation.state_filter`): a gentle landing is believed as such, in place of one
fixed size for every landing.

A landing foot's vertical velocity is off by the impact (the ground and the foot compressed, then
springing back), decaying exponentially over ``touchdown_s`` ``τ``: its extra variance
``a² d(t)``, ``d(t) = exp(-2 t / τ)`` at ``t`` seconds since its touchdown. How large ``a`` is
depends on the landing: 35-40 mm/s on a flying trot's landings, a fraction of a millimetre per
second for PyBullet's position motors, whose stiff feet touch down without a give the legs can
see. One fixed ``a`` (``touchdown_noise_mps``, 0.1 m/s) holds the vertical velocity loose after
every touchdown where the feet say it is known: on a1_position_flat the reported vertical sigma
was 8x its error.

So a landing's first joint state in stance gets ``touchdown_noise_mps`` (the largest landing the
filter assumes), and from then on its own measured size: the largest ``(r² - s₀) / d(t)`` over
its accepted samples within ``impact_window_s`` of its touchdown (``r`` its innovation along
world up, ``s₀`` that innovation's variance without the impact: the state's and the foot's white
noise). The transient is no white noise but one offset decaying over ``τ``, shared by the
samples that follow (and, a pair landing together, by its feet): as the feet's give
(:mod:`~a1_leg_fk.estimation.foot_give`), it is given the white noise of the same low-frequency
power, ``a² 2τ / dt`` (``dt`` the updates' interval); with ``a²`` alone the filter followed a hard
landing's offset (a synthetic trot's landings 0.08 m/s off: within 3 sigma 91.5 %). Never more
than ``touchdown_noise_mps²``: the measurement only believes a landing more than the fixed size
did (a flying trot's landings, ``a²`` 30x at 500 Hz, keep the fixed size's noise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_model import LEGS, FilterSettings
from a1_leg_fk.estimation.foot_give import quadratic


class FootImpact:
    """Each leg's landing amplitude: :meth:`land` at its touchdown, :meth:`variance` for its
    vertical noise, :meth:`observe` with every update's accepted feet.
    """

    def __init__(self, settings: FilterSettings) -> None:
        self.settings = settings
        self.squares: list[float | None] = [None] * LEGS
        """Per leg its landing's measured ``a²`` [m²/s²] (None: not measured yet)."""
        self.interval_s = 0.0
        """The time between the last two updates with accepted feet [s]."""
        self._stamp_ns: int | None = None

    def land(self, leg: int) -> None:
        """``leg``'s touchdown: a new landing, its size unknown."""
        self.squares[leg] = None

    def variance(self, leg: int, seconds: float) -> float:
        """``leg``'s extra vertical velocity variance [m²/s²] ``seconds`` after its touchdown
        (its first joint state in stance): ``A² exp(-2 t / τ)``, ``A²`` its landing's measured
        ``a² 2τ / dt`` (at most ``touchdown_noise_mps²``), ``touchdown_noise_mps²`` until
        measured (0 with ``touchdown_noise_mps`` 0).
        """
        s = self.settings
        if not s.touchdown_noise_mps > 0.0:
            return 0.0
        return colored(self.squares[leg], self.interval_s, s) * decay(seconds, s)

    def observe(
        self,
        stamp_ns: int,
        feet: tuple[Sequence[int], Sequence[float], Sequence[tuple[float, float, float]]],
        transients: Sequence[float],
        up: Sequence[float],
        innovation: np.ndarray,
        rows: Sequence[int],
    ) -> None:
        """One update's accepted feet at ``stamp_ns`` [ns] (``feet``: their legs, each one's time
        since its touchdown [s] and its innovation [m/s, base frame]; ``transients``: the part of
        each one's vertical variance that is the touchdown's or the give's [m²/s²]), world ``up``
        in the base frame, the update's ``innovation`` covariance [m²/s²] and each foot's first
        row in it: the landings within ``impact_window_s`` measured (0: none).
        """
        s = self.settings
        if not s.impact_window_s > 0.0:
            return
        previous, self._stamp_ns = self._stamp_ns, stamp_ns
        if previous is not None:
            self.interval_s = min(max((stamp_ns - previous) / 1e9, 0.0), s.max_step_s)
        for leg, age, (x, y, z), transient, row in zip(*feet, transients, rows):
            if not age <= s.impact_window_s:
                continue
            along = up[0] * x + up[1] * y + up[2] * z
            spread = quadratic(up, innovation[row : row + 3, row : row + 3].ravel().tolist())
            white = max(spread - transient, 0.0)
            measured = max(along * along - white, 0.0) * growth(age, s)
            self.squares[leg] = max(self.squares[leg] or 0.0, measured)


def colored(square: float | None, interval_s: float, settings: FilterSettings) -> float:
    """A transient's white noise [m²/s²] at its start: its measured ``a²`` [m²/s²] as the white
    noise of the same low-frequency power, ``a² 2τ / dt`` (``interval_s`` ``dt`` [s]), at most
    ``touchdown_noise_mps²``, which it is until measured (``square`` None, or no interval yet).
    """
    largest = settings.touchdown_noise_mps**2
    if square is None or not interval_s > 0.0:
        return largest
    return min(square * 2.0 * settings.touchdown_s / interval_s, largest)


def decay(seconds: float, settings: FilterSettings) -> float:
    """A transient's variance ``seconds`` after its touchdown over its start's, ``exp(-2 t / τ)``
    (``τ`` ``touchdown_s``).
    """
    return math.exp(-2.0 * seconds / max(settings.touchdown_s, 1e-9))


def growth(seconds: float, settings: FilterSettings) -> float:
    """``1 / decay``: a transient's variance at its start over its part ``seconds`` later."""
    return math.exp(2.0 * seconds / max(settings.touchdown_s, 1e-9))
