"""A foot's stance edges placed by its heights: where it leaves the ground and where it lands.

Pure numpy (no ROS, no file I/O); one leg, one gap-free run of samples: ``times`` (n,) [s],
``heights`` (n,) [m] above the ground plane, ``stance`` (n,) bool from the speeds' hysteresis.
A foot unloads before it moves measurably and may slide while it pushes off, so the speeds place
edges late or early; the heights place them (:func:`fit_edges`):

* **Gross trim.** A stance's edge samples higher than its median height + the gross tolerance
  (the noise tolerance plus the stance's own spread beyond the noise: a stance may sink and
  bob) are moved to swing.
* **Settle.** Each edge is then moved inwards while its sample stands higher than the stance's
  level next to it (the median of the heights within :data:`EDGE_REFERENCE_S` inwards) + the
  edge tolerance, and then outwards over the neighbours within that tolerance of the level: the
  stance ends where the foot starts to rise and begins where it stops coming down. The edge
  tolerance is the noise tolerance (:data:`EDGE_NOISE_DEVIATIONS` of the heights' noise, robust,
  from consecutive stance samples; at least :data:`EDGE_NOISE_FLOOR_M`), plus the stance's drift
  (its spread beyond the noise) only where its heights rise towards the edge (the median of
  their steps within :data:`TREND_S`): a soft foot coming up out of the ground as it unloads
  stands, while a stance that comes down to its edge (a bobbing body's) gets no allowance and
  its first millimetres of swing are swing.
"""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.gait.phases import runs

EDGE_NOISE_DEVIATIONS = 3.0
EDGE_NOISE_FLOOR_M = 0.0001
"""[m] A stance's edge tolerance is at least this (noise-free heights; chosen on the contact
family's tuned runs among 0.05, 0.1, 0.2, 0.5 mm, docs/gait.md)."""
EDGE_REFERENCE_S = 0.02
"""[s] A stance's level next to an edge is the median of its heights this close to it."""
TREND_S = 0.04
"""[s] Whether a stance rises towards an edge is judged over its heights this close to it."""
MIN_WINDOW = 4
"""A level or a trend is taken over at least this many samples."""
MAD_SIGMA = 1.4826
"""A normal distribution's standard deviation per median absolute deviation."""


def stance_noise(heights: np.ndarray, stance: np.ndarray) -> float:
    """[m] The noise of a foot's stance heights: robust, from the differences of consecutive
    stance samples away from the edges (so that neither a stance's slow drift, nor the levels of
    different stances, nor its touchdowns and liftoffs count); 0 without such samples.
    """
    interior = stance[1:-2] & stance[2:-1] & stance[:-3] & stance[3:]  # no edge sample
    steps = np.diff(heights)[1:-1][interior]
    if not steps.size:
        return 0.0
    return MAD_SIGMA * float(np.median(np.abs(steps - np.median(steps)))) / math.sqrt(2.0)


def fit_edges(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, noise_m: float
) -> np.ndarray:
    """``stance`` (n,) with each stance's edges placed by the ``heights`` [m] (module docstring;
    ``times`` [s], the heights' ``noise_m`` [m]).
    """
    fitted = stance.copy()
    base = max(EDGE_NOISE_DEVIATIONS * noise_m, EDGE_NOISE_FLOOR_M)
    for first, last, value in runs(stance):
        if not value:
            continue
        inside = slice(first, last + 1)
        interior = np.abs(times[inside] - times[inside].mean()) < (
            0.5 * (times[last] - times[first]) - EDGE_REFERENCE_S
        )
        slack = (base, drift(heights[inside][interior], noise_m))
        low = np.flatnonzero(heights[inside] <= np.median(heights[inside]) + sum(slack))
        start, end = first + int(low[0]), first + int(low[-1])
        middle = (start + end) // 2
        start = settle(times, heights, start, 1, slack, middle)
        end = settle(times, heights, end, -1, slack, middle)
        fitted[inside] = False
        fitted[start : end + 1] = True
    return fitted


def drift(levels: np.ndarray, noise_m: float) -> float:
    """[m] A stance's spread beyond the heights' noise ``noise_m`` [m]: the robust deviation of
    its interior heights ``levels`` [m] (a soft foot sinks, a body bobs); 0 from fewer than
    three.
    """
    if levels.size < 3:
        return 0.0
    spread = MAD_SIGMA * float(np.median(np.abs(levels - np.median(levels))))
    return math.sqrt(max(spread**2 - noise_m**2, 0.0))


def settle(
    times: np.ndarray,
    heights: np.ndarray,
    edge: int,
    inward: int,
    slack: tuple[float, float],
    limit: int,
) -> int:
    """The stance edge sample from ``edge`` (``inward`` 1: a touchdown's, -1: a liftoff's):
    moved inwards (not past ``limit``) while it stands higher than :func:`ceiling`, then
    outwards over the neighbours no higher (``slack``: the noise tolerance and the stance's
    drift [m]).
    """
    while edge != limit and heights[edge] > ceiling(times, heights, edge + inward, inward, slack):
        edge += inward
    outward = edge - inward
    while 0 <= outward < heights.size and (
        heights[outward] <= ceiling(times, heights, edge, inward, slack)
    ):
        edge, outward = outward, outward - inward
    return edge


def ceiling(
    times: np.ndarray, heights: np.ndarray, edge: int, inward: int, slack: tuple[float, float]
) -> float:
    """[m] The highest a foot stands next to stance sample ``edge`` (on its side away from
    ``inward``): the level there + the noise tolerance + the stance's drift if it rises towards
    the edge (``slack``: those two [m]).
    """
    noise_m, drift_m = slack
    return (
        level(times, heights, edge, inward)
        + noise_m
        + (
            drift_m
            if rises_towards(heights, _inwards(times, edge, inward, TREND_S), inward)
            else 0.0
        )
    )


def rises_towards(heights: np.ndarray, window: slice, inward: int) -> bool:
    """Whether the ``heights`` in ``window`` mostly rise towards its end away from ``inward``:
    the median of their steps (robust to a few swing samples at the edge).
    """
    steps = np.diff(heights[window])
    return bool(steps.size) and -inward * float(np.median(steps)) > 0.0


def level(times: np.ndarray, heights: np.ndarray, edge: int, inward: int) -> float:
    """[m] The median height of the samples within :data:`EDGE_REFERENCE_S` of sample ``edge``
    towards ``inward`` (1: later samples, -1: earlier), ``edge`` included.
    """
    return float(np.median(heights[_inwards(times, edge, inward, EDGE_REFERENCE_S)]))


def _inwards(times: np.ndarray, edge: int, inward: int, span_s: float) -> slice:
    """The samples within ``span_s`` [s] of sample ``edge`` towards ``inward``, ``edge``
    included; at least :data:`MIN_WINDOW` where there are (a low rate).
    """
    if inward > 0:
        stop = int(np.searchsorted(times, times[edge] + span_s, side="right"))
        return slice(edge, max(stop, edge + MIN_WINDOW))
    begin = int(np.searchsorted(times, times[edge] - span_s, side="left"))
    return slice(max(min(begin, edge + 1 - MIN_WINDOW), 0), edge + 1)
