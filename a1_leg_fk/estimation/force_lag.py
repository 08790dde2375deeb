"""The momentum observer's first-order lag, undone: one rule for the loads the contact smoother's
load edges read over a recording (:func:`a1_leg_fk.estimation.load_edges.unlagged`) and for the
causal contact filter's force evidence where a loaded foot lets go (:class:`LagTails`); without
ROS.

The observer's normal force ``n`` follows the true one through a first-order lag of time constant
``1 / K`` (1 ms at its default gain): between samples ``dt`` apart ``n_k = a n_(k-1) + (1 - a)
N_k``, ``a = exp(-dt K)``, so ``N_k = (n_k - a n_(k-1)) / (1 - a)``. Undoing it amplifies the
force's noise (by ``sqrt(1 + a^2) / (1 - a)``, 1.17 at 500 Hz), which near the force at even odds
turns noise into evidence: on the contact family's noisy pronk the feet's slow unloading tails
were called swing early (98.58 -> 98.37 % with efforts). The causal filter therefore undoes it
only where the lag's tail alone, ``a n_(k-1)``, is above the force at even odds: a foot that let
go of a load at least ``half / a`` (27 N on the A1 at 500 Hz), which the observer would otherwise
show standing one sample longer (a foot bouncing off the ground under PyBullet's position
motors, or unloading for 5-10 ms mid-stance: 88 N, then 12 and 2 N where none is left).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TypeVar

import numpy as np

Values = TypeVar("Values", float, np.ndarray)


def undo_lag(current: Values, previous: Values, keep: Values) -> Values:
    """``current`` [N] with a first-order lag undone, ``(current - keep previous) / (1 - keep)``,
    ``keep`` the share of ``previous`` [N] the lag keeps over the step, ``exp(-dt / lag)``
    (floats, or numpy arrays elementwise).
    """
    undone: Values = (current - keep * previous) / (1.0 - keep)
    return undone


class LagTails:
    """Per foot, the causal filter's force evidence [N]: the observer's normal forces with the
    lag's tail taken off where it alone is above the force at even odds (the module text),
    stepped with each sample in time order.
    """

    def __init__(self, lag_s: float, half_n: float) -> None:
        """``lag_s`` [s]: the observer's lag (0: none, the forces pass as they are);
        ``half_n`` [N]: the filter's force at even odds.
        """
        self.lag_s, self.half_n = lag_s, half_n
        self.previous: tuple[float, ...] = ()
        """The latest sample's normal forces [N] as the observer gave them (none yet: empty)."""
        self._keep = (math.nan, 0.0)  # (dt [s], exp(-dt / lag)) of the latest step

    def reset(self) -> None:
        """Forget the previous sample (a new pass over a recording)."""
        self.previous = ()

    def evidence(self, dt_s: float, normals: Sequence[float]) -> Sequence[float]:
        """The forces [N] the filter takes from ``normals`` [N] (NaN: none), ``dt_s`` [s]
        after the previous sample (no positive step: as they are; ``normals`` itself where
        nothing is undone).
        """
        previous, self.previous = self.previous, tuple(normals)
        if not (previous and self.lag_s > 0.0 and dt_s > 0.0):
            return normals
        if self._keep[0] != dt_s:
            self._keep = (dt_s, math.exp(-dt_s / self.lag_s))
        keep, half = self._keep[1], self.half_n
        out = normals
        for leg, before in enumerate(previous):
            if keep * before > half:  # the tail alone above even odds
                undone = undo_lag(normals[leg], before, keep)
                if undone < half:
                    out = list(out)
                    out[leg] = undone
        return out
