"""A foot's stance edges placed by its heights: where it leaves the ground and where it lands.

Pure numpy (no ROS, no file I/O); one leg, one gap-free run of samples: ``times`` (n,) [s],
``heights`` (n,) [m] above the ground plane, ``stance`` (n,) bool from the speeds' hysteresis.
A foot unloads before it moves measurably and may slide while it pushes off, so the speeds place
edges late or early; the heights place them (:func:`fit_edges`):

* **Gross trim.** A stance's edge samples higher than its median height + the gross tolerance
  (the noise tolerance plus the stance's own spread beyond the noise: a stance may sink and
  bob) are moved to swing.
* **Settle** (:func:`settle`). Each edge is then moved inwards while its sample stands higher
  than the stance's level next to it (the median of the heights within :data:`EDGE_REFERENCE_S`
  inwards) + the edge tolerance, and then outwards over the neighbours within that tolerance of
  the level: the stance ends where the foot starts to rise and begins where it stops coming
  down. The edge tolerance is the noise tolerance (:data:`EDGE_NOISE_DEVIATIONS` of the
  heights' noise, robust, from consecutive stance samples; at least :data:`EDGE_NOISE_FLOOR_M`)
  plus what the level lags a stance rising towards the edge by (its rise over the previous
  :data:`EDGE_REFERENCE_S`, at most the drift): a stance that comes up to its edge faster than
  the noise, standing above its median there (a soft foot unloading), is allowed its whole
  drift; one that bobs up and comes down to its edge (the demo's) nothing, so its first
  millimetres of swing are swing.
* **Ramp** (:func:`follow_ramp`). A liftoff whose stance comes up towards it faster than the
  noise tolerance (its level rose by more over the previous :data:`EDGE_REFERENCE_S`: a soft
  foot unloading, ~1 mm over its last 40 ms, which the settle stops partway up) is carried on
  along that stance's line (fitted over the same span, refitted as the edge moves) while the
  heights stay within the noise tolerance of it: the stance ends where the foot's rise leaves
  the ramp.
* **Rise** (:func:`~a1_leg_fk.estimation.stance_edges.rise_start`, the rule the contact
  smoother shares). A liftoff is moved back to where the foot's rise starts, fitted as
  ``c (t - t0)^p`` over the heights just after the stance.
"""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.stance_edges import (
    EDGE_NOISE_DEVIATIONS,
    EDGE_NOISE_FLOOR_M,
    EDGE_REFERENCE_S,
    MAD_SIGMA,
    inwards,
    lag,
    level,
    rise_start,
    runs,
)


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
        bounds = ((start + end) // 2, float(np.median(heights[inside])))
        start = settle(times, heights, start, 1, slack, bounds)
        end = settle(times, heights, end, -1, slack, bounds)
        end = follow_ramp(times, heights, end, base)
        end = rise_start(times, heights, end, bounds[0], base)
        fitted[inside] = False
        fitted[start : end + 1] = True
    return fitted


def follow_ramp(times: np.ndarray, heights: np.ndarray, end: int, noise_m: float) -> int:
    """A liftoff's last stance sample ``end`` moved later while the next sample's height [m]
    stays within the noise tolerance ``noise_m`` [m] above :func:`on_line` (the line through
    the heights of the :data:`EDGE_REFERENCE_S` up to the edge, refitted at each step); only
    where the stance rises towards ``end`` by more than that tolerance over that span
    (:func:`lag`: a soft foot unloading), else kept.
    """
    rise = lag(times, heights, end, -1)
    if rise is None or not rise > noise_m:  # NaN: unknown, kept
        return end
    ahead = end
    while ahead + 1 < heights.size and (
        heights[ahead + 1] <= on_line(times, heights, ahead) + noise_m
    ):
        ahead += 1
    return ahead


def on_line(times: np.ndarray, heights: np.ndarray, edge: int) -> float:
    """[m] The height at the sample after ``edge`` of the straight line fitted to the heights
    within :data:`EDGE_REFERENCE_S` up to ``edge``.
    """
    ramp = inwards(times, edge, -1, EDGE_REFERENCE_S)
    slope, at_edge = np.polyfit(times[ramp] - times[edge], heights[ramp], 1)
    return float(at_edge + slope * (times[edge + 1] - times[edge]))


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
    bounds: tuple[int, float],
) -> int:
    """The stance edge sample from ``edge`` (``inward`` 1: a touchdown's, -1: a liftoff's):
    moved inwards (not past ``limit``) while it stands higher than :func:`ceiling`, then
    outwards over the neighbours no higher (``slack``: the noise tolerance and the stance's
    drift [m]; ``bounds``: the sample not to move past and the stance's median height [m]). A
    stance that comes up towards ``edge`` (a soft foot as it unloads, faster and faster) is
    allowed its whole drift at every step: its level there stands above its median and rose by
    more than the noise tolerance over :data:`EDGE_REFERENCE_S` (a stance that bobs up and comes
    down to its edge does not); so is any stance at a rate too low to tell.
    """
    noise_m, drift_m = slack
    limit, median_m = bounds
    rise = lag(times, heights, edge, inward)
    soft = rise is None or (level(times, heights, edge, inward) > median_m and rise > noise_m)
    allowance = (drift_m, drift_m) if soft else (0.0, drift_m)
    while edge != limit and (
        heights[edge] > ceiling(times, heights, edge + inward, inward, noise_m, allowance)
    ):
        edge += inward
    outward = edge - inward
    while 0 <= outward < heights.size and (
        heights[outward] <= ceiling(times, heights, edge, inward, noise_m, allowance)
    ):
        edge, outward = outward, outward - inward
    return edge


def ceiling(
    times: np.ndarray,
    heights: np.ndarray,
    edge: int,
    inward: int,
    noise_m: float,
    allowance: tuple[float, float],
) -> float:
    """[m] The highest a foot stands next to stance sample ``edge`` (on its side away from
    ``inward``): the level there + the noise tolerance ``noise_m`` [m] + what the level lags a
    stance rising towards the edge by (:func:`lag`), within ``allowance`` (least, most [m]).
    """
    least, most = allowance
    behind = min(max(lag(times, heights, edge, inward) or 0.0, least), most)
    return level(times, heights, edge, inward) + noise_m + behind
