"""The force a swing foot reads: the root mean square of the normal forces [N] of the feet the
contact filter held in swing over the last :data:`WINDOW_S`, without ROS (plain floats, per
sample).

A foot in the air bears no load, so what its estimated normal force reads there is the force
estimate's own error: sensor noise (2-3 N on the contact family's noisy runs), or torques the
observer's model does not explain (a swing foot under PyBullet's position motors reads a median
23 N on Unitree's Aliengo). The contact filter's force evidence is at even odds at 3 % of the
weight; a force a swing foot may read is no proof that a foot presses, so the filter's fade of a
sliding foot's speed (:mod:`a1_leg_fk.estimation.contact_filter`) starts this RMS above it.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence

WINDOW_S = 1.0
"""[s] The past the swing feet's forces are pooled over (a slow walk's two strides)."""
EDGE_S = 1e-6
"""[s] A sample this much older than :data:`WINDOW_S` still counts: samples on a regular grid
reach the window's edge exactly, and a stamp rounded to whole nanoseconds (a bag's) must not
move one across it."""
MAX_SQUARE_N2 = 1e12
"""[N^2] A force's square counts at most this much (a million newtons: absurd values stay
finite in the sums)."""


class SwingForce:
    """The RMS normal force [N] of the feet held in swing over the last :data:`WINDOW_S`,
    stepped with each sample in time order (0 until a swing foot's force is seen).
    """

    def __init__(self) -> None:
        self._samples: deque[tuple[float, float, int]] = deque()  # (time [s], sum N^2, count)
        self._time_s = 0.0  # the time since the first sample [s]
        self._sum, self._count = 0.0, 0

    def update(self, dt_s: float, normals: Sequence[float], swing: Sequence[bool]) -> float:
        """The RMS [N] after a sample ``dt_s`` [s] after the previous one, its ``normals`` [N]
        (NaN: none) of the feet held in ``swing`` (the filter's previous state) taken in.
        """
        self._time_s += max(dt_s, 0.0)
        squares, count = 0.0, 0
        for normal, up in zip(normals, swing, strict=True):
            if up and math.isfinite(normal):
                squares += min(normal * normal, MAX_SQUARE_N2)  # absurd forces: bounded
                count += 1
        self._samples.append((self._time_s, squares, count))
        self._sum += squares
        self._count += count
        oldest = self._time_s - WINDOW_S - EDGE_S
        while self._samples[0][0] < oldest:
            _, gone, number = self._samples.popleft()
            self._sum -= gone
            self._count -= number
        if self._count == 0:
            self._sum = 0.0  # no drift carried past an empty window
            return 0.0
        return math.sqrt(max(self._sum, 0.0) / self._count)
