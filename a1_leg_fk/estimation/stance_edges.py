"""A foot's stance edges placed by its heights: where it stops coming down (a touchdown) and where
its rise starts (a liftoff). The one place of these rules for ``gait``'s own kinematic contacts
(:mod:`a1_leg_fk.gait.edges`, world heights above the ground plane) and the contact smoother
(:mod:`a1_leg_fk.estimation.contact_smoother`, the contact filter's heights above the lowest
foot along gravity).

Pure numpy (no ROS, no file I/O); one leg, one gap-free run of samples: ``times`` (n,) [s],
``heights`` (n,) [m], ``stance`` (n,) bool (:func:`against_standing`: every leg's, (n, legs)).

* **Rise** (:func:`rise_start`). A liftoff is moved back to where the foot's rise starts: the
  heights within :data:`RISE_S` after the stance, fitted as ``c (t - t0)^p`` (a foot that leaves
  fast, ``p = 1``, or from rest, ``p = 2``), give ``t0``; at most :data:`BACK_S` back (noise
  makes a foot rise three deviations before it is up; a walk's foot rises 0.1 mm only some 6 ms
  after it left).
* **Late rise** (:func:`late_rise`). A stance whose last sample already stands more than
  :data:`LIFT_M` above the stance's median height ended before it: the foot's rise leading up
  to it is fitted the same way and the stance ends at its onset (a walk's foot rises from rest,
  5 mm in 50 ms, before the contact filter's kinematic evidence turns to swing).
* **Landing** (:func:`landing_start`). A touchdown is moved later while the foot is still coming
  down: while some height within :data:`DESCENT_LOOK_S` after a stance sample lies lower than it
  at more than :data:`DESCENT_MPS` on average. The contact filter's heights are taken against
  the lowest foot, which steps and then settles by a millimetre as another foot lands (its
  contact sinks in under the impact): a level, as ``gait``'s edges take it, would follow that
  settling; the descent rate does not.
* **Against the standing feet** (:func:`against_standing`, the contact smoother's). Against the
  lowest foot, the lowest foot itself has a height of exactly 0 until it stands above the next
  one (a walk's hind foot, 1 mm below the others: 20 ms after it left), and a foot's height
  steps when another lands; against the mean height of the feet that stood throughout the
  stance's last :data:`STANCE_REFERENCE_S` it does neither. The late rise is also looked for in
  those heights, its onset no earlier than the last sample that still stands at the stance's
  height (:func:`still_level`: in noise a fitted power law may extrapolate 20 ms back), and
  the earlier end is kept.

:func:`placed_edges` applies them to every stance of a mask (the contact smoother's rule).
"""

from __future__ import annotations

import math

import numpy as np

EDGE_NOISE_DEVIATIONS = 3.0
"""A foot's heights' noise tolerance is this many deviations of their noise
(:func:`stance_noise`)."""
EDGE_NOISE_FLOOR_M = 0.0001
"""[m] A stance's edge tolerance is at least this (noise-free heights; chosen on the contact
family's tuned runs among 0.05, 0.1, 0.2, 0.5 mm, docs/gait.md)."""
EDGE_REFERENCE_S = 0.02
"""[s] A stance's level next to an edge is the median of its heights this close to it."""
RISE_S = 0.01
"""[s] A liftoff's rise is fitted over the heights this long after the stance's last sample."""
BACK_S = 0.01
"""[s] A liftoff is moved back by its rise's fit at most this far (a soft foot's slow rise)."""
RISE_POWERS = (1.0, 1.5, 2.0, 3.0)
"""The shapes a liftoff's rise is fitted with, ``(t - t0)^p``."""
MIN_WINDOW = 4
"""A level or a trend is taken over at least this many samples."""
LIFT_M = 0.0025
"""[m] A stance's last sample this far above the stance's median height is a foot already
rising (a soft foot unloading comes up ~1 mm, another foot's landing moves the lowest foot by
~1 mm; 2 and 3 mm met the same goals on the contact family's tuned runs, 1.5 mm did not:
docs/forces.md)."""
RISE_SPAN_S = 0.06
"""[s] A late rise is fitted over at most this long before the stance's last sample."""
DESCENT_MPS = 0.075
"""[m/s] A foot coming down faster than this towards a height ahead has not landed yet (0.05,
0.075 and 0.1 m/s met the same goals on the contact family's tuned runs; the middle kept,
docs/forces.md)."""
DESCENT_LOOK_S = 0.004
"""[s] How far ahead a stance sample's descent is looked for (at least the next sample)."""
LANDING_S = 0.1
"""[s] A touchdown is moved later by its descent at most this far (less than
:data:`CONTEXT_S`)."""
STANCE_REFERENCE_S = 0.2
"""[s] A stance's height, for a late rise, is the median of its heights this long before its
last sample."""
MAD_SIGMA = 1.4826
"""A normal distribution's standard deviation per median absolute deviation."""
CONTEXT_S = STANCE_REFERENCE_S
"""[s] How far back from a stance's last sample these rules look: with this much of the samples
before a window, its edges are those of one pass over every sample."""


def runs(mask: np.ndarray) -> list[tuple[int, int, bool]]:
    """``(first, last, value)`` of each run of equal values in ``mask`` (indices inclusive)."""
    cuts = np.flatnonzero(np.diff(mask.astype(np.int8))) + 1
    firsts = np.concatenate(([0], cuts))
    lasts = np.concatenate((cuts - 1, [mask.size - 1]))
    return [(int(a), int(b), bool(mask[a])) for a, b in zip(firsts, lasts)]


def placed_edges(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, against: np.ndarray | None = None
) -> np.ndarray:
    """``stance`` (n,) with each stance's touchdown moved later by :func:`landing_start` and its
    liftoff earlier by :func:`late_rise` (in ``heights`` or, where earlier, in ``against``: the
    foot's heights [m] against the standing feet, :func:`against_standing`), then
    :func:`rise_start` (with the tolerance :data:`EDGE_NOISE_FLOOR_M`), never past the stance's
    middle sample; the edges at the run's borders are not observed and stay. Heights [m] NaN
    near an edge leave it where it is.
    """
    placed = stance.copy()
    for first, last, value in runs(stance):
        if not value:
            continue
        middle = (first + last) // 2
        start, end = first, last
        if first > 0:
            start = landing_start(times, heights, first, middle)
        if last < stance.size - 1:
            end = late_rise(times, heights, (first, last), middle)
            if against is not None:
                risen = late_rise(times, against, (first, last), middle)
                end = min(end, max(risen, still_level(times, against, (first, last), middle)))
            end = rise_start(times, heights, end, middle, EDGE_NOISE_FLOOR_M)
        placed[first:start] = False
        placed[end + 1 : last + 1] = False
    return placed


def against_standing(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, leg: int
) -> np.ndarray:
    """(n,) [m] Foot ``leg``'s heights against the standing feet: on each of its stances in
    ``stance`` (n, legs) bool, its ``heights`` (n, legs) [m] less the mean of those of the other
    feet that stand throughout the stance's last :data:`STANCE_REFERENCE_S`; NaN elsewhere and
    on a stance without such feet (a trot's other pair lands as it leaves).
    """
    against = np.full(times.size, math.nan)
    others = [other for other in range(stance.shape[1]) if other != leg]
    for first, last, value in runs(stance[:, leg]):
        since = max(first, int(np.searchsorted(times, times[last] - STANCE_REFERENCE_S)))
        standing = [other for other in others if stance[since : last + 1, other].all()]
        if value and standing:
            rows = slice(first, last + 1)
            against[rows] = heights[rows, leg] - heights[rows][:, standing].mean(axis=1)
    return against


def landing_start(times: np.ndarray, heights: np.ndarray, first: int, limit: int) -> int:
    """A touchdown's first stance sample ``first`` moved later (not past ``limit``, nor more than
    :data:`LANDING_S`) while some height within :data:`DESCENT_LOOK_S` after it (at least the
    next) lies lower than it at more than :data:`DESCENT_MPS` on average: the foot has not
    landed yet.
    """
    start = first
    limit = min(limit, int(np.searchsorted(times, times[first] + LANDING_S, side="right")) - 1)
    while start < limit:
        stop = int(np.searchsorted(times, times[start] + DESCENT_LOOK_S, side="right"))
        ahead = slice(start + 1, max(stop, start + 2))
        with np.errstate(invalid="ignore", divide="ignore"):
            rates = (heights[start] - heights[ahead]) / (times[ahead] - times[start])
        if not (rates > DESCENT_MPS).any():  # NaN: no evidence of a descent
            break
        start += 1
    return start


def late_rise(times: np.ndarray, heights: np.ndarray, stance: tuple[int, int], limit: int) -> int:
    """The last sample of the stance on samples ``stance`` (first, last) moved back, where it
    stands more than :data:`LIFT_M` above the stance's height (the median over
    :data:`STANCE_REFERENCE_S` before it), to the onset of the rise that leads up to it: the
    samples before it (within :data:`RISE_SPAN_S`) more than half :data:`LIFT_M` above that
    height (not a soft foot's unloading millimetre), fitted by :func:`rise_onset`; not past
    ``limit``.
    """
    first, last = stance
    ground = stance_height(times, heights, first, last)
    if not heights[last] > ground + LIFT_M:  # NaN: unknown, kept
        return last
    begin = span_start(times, last, limit)
    start = last
    while start > begin and heights[start - 1] > ground + 0.5 * LIFT_M:
        start -= 1
    rising = slice(start, last + 1)
    if last - start < 2:
        return last
    onset = rise_onset(times[rising] - times[last], heights[rising] - ground)
    end = int(np.searchsorted(times, times[last] + onset, side="right")) - 1
    return min(max(end, limit), last)


def still_level(
    times: np.ndarray, heights: np.ndarray, stance: tuple[int, int], limit: int
) -> int:
    """The last sample within :data:`RISE_SPAN_S` before the end of the stance on samples
    ``stance`` (first, last), not before ``limit``, where the foot stands at or below the
    stance's height (:func:`stance_height`): it has not risen yet, whatever a fitted rise
    extrapolates back to; ``limit`` where there is none (NaN: unknown).
    """
    first, last = stance
    ground = stance_height(times, heights, first, last)
    begin = span_start(times, last, limit)
    level_samples = np.flatnonzero(heights[begin : last + 1] <= ground)
    return begin + int(level_samples[-1]) if level_samples.size else limit


def span_start(times: np.ndarray, last: int, limit: int) -> int:
    """The first sample within :data:`RISE_SPAN_S` before sample ``last``, not before ``limit``."""
    return max(limit, int(np.searchsorted(times, times[last] - RISE_SPAN_S, side="left")))


def stance_height(times: np.ndarray, heights: np.ndarray, first: int, last: int) -> float:
    """[m] The height of the stance on samples ``first`` to ``last``: the median of its heights
    within :data:`STANCE_REFERENCE_S` before its last sample.
    """
    since = max(first, int(np.searchsorted(times, times[last] - STANCE_REFERENCE_S)))
    return float(np.median(heights[since : last + 1]))


def rise_start(times: np.ndarray, heights: np.ndarray, end: int, limit: int, base_m: float) -> int:
    """A liftoff's last stance sample ``end`` moved back to where the foot's rise starts: a
    parabola fitted to the heights above the level next to the edge within :data:`RISE_S`
    after it (a foot that leaves fast or rises from rest) is extrapolated back to where it
    last reaches the level, or comes closest to it; not more than :data:`BACK_S` back, nor
    past ``limit``. Kept where the last sample already stands above the level + ``base_m``
    [m] (a soft foot rising as it unloads: the level lags), where fewer than three samples
    follow within :data:`RISE_S` (a low rate) and where a height there is not finite.
    """
    stop = int(np.searchsorted(times, times[end] + RISE_S, side="right"))
    after = np.arange(end + 1, stop)
    ground = level(times, heights, end, -1)
    if after.size < 3 or not heights[end] <= ground + base_m:
        return end
    lift = heights[after] - ground
    if not (lift > 0.0).all():
        return end
    start = times[end] + max(rise_onset(times[after] - times[end], lift), -BACK_S)
    return int(min(max(np.searchsorted(times, start, side="right") - 1, limit), end))


def rise_onset(dt: np.ndarray, lift: np.ndarray) -> float:
    """[s] When a rise ``lift`` [m] > 0 at times ``dt`` [s] started: the onset of the power law
    ``c (t - t0)^p`` (``p`` among :data:`RISE_POWERS`) that fits it best (least squares in
    height; ``p = 1``: a foot that leaves fast, ``p = 2``: from rest).
    """
    best = (math.inf, float(dt[0]))
    for power in RISE_POWERS:
        slope, intercept = np.polyfit(dt, lift ** (1.0 / power), 1)
        if slope <= 0.0:
            continue
        onset = -intercept / slope
        error = float(np.sum(((slope * np.clip(dt - onset, 0.0, None)) ** power - lift) ** 2))
        best = min(best, (error, float(onset)))
    return best[1]


def level(times: np.ndarray, heights: np.ndarray, edge: int, inward: int) -> float:
    """[m] The median height of the samples within :data:`EDGE_REFERENCE_S` of sample ``edge``
    towards ``inward`` (1: later samples, -1: earlier), ``edge`` included.
    """
    return float(np.median(heights[inwards(times, edge, inward, EDGE_REFERENCE_S)]))


def inwards(times: np.ndarray, edge: int, inward: int, span_s: float) -> slice:
    """The samples within ``span_s`` [s] of sample ``edge`` towards ``inward``, ``edge``
    included; at least :data:`MIN_WINDOW` where there are (a low rate).
    """
    if inward > 0:
        stop = int(np.searchsorted(times, times[edge] + span_s, side="right"))
        return slice(edge, max(stop, edge + MIN_WINDOW))
    begin = int(np.searchsorted(times, times[edge] - span_s, side="left"))
    return slice(max(min(begin, edge + 1 - MIN_WINDOW), 0), edge + 1)


def lag(times: np.ndarray, heights: np.ndarray, edge: int, inward: int) -> float | None:
    """[m] How much the level next to stance sample ``edge`` rose towards it from the level
    :data:`EDGE_REFERENCE_S` farther inwards; None where the stance is too short or the rate
    too low for more than :data:`MIN_WINDOW` samples in that span.
    """
    here = inwards(times, edge, inward, EDGE_REFERENCE_S)
    width = here.stop - here.start
    before = edge + inward * width
    if width <= MIN_WINDOW or not 0 <= before < heights.size:
        return None
    return level(times, heights, edge, inward) - level(times, heights, before, inward)


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
