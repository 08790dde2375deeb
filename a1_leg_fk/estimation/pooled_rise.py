"""A foot's liftoffs placed by its strides' pooled rise: where a leg's feet rise slowly from rest
(a walk's: ~0.002 mm/ms^2 t^2 for their first 10-12 ms, 0.03 mm at 4 ms) one lift-off's heights
in sensor noise (0.09 mm) cannot place it, but the leg's strides together can.

Pure numpy (no ROS, no file I/O); one leg, one gap-free run of samples: ``times`` (n,) [s],
``heights`` (n,) [m] above the ground plane, ``stance`` (n,) bool with each stance's edges
already placed (by :func:`a1_leg_fk.gait.edges.fit_edges` for ``gait``, by
:func:`a1_leg_fk.estimation.stance_edges.placed_edges` for the contact smoother).

* **Align.** Each interior stance that does not rise towards its liftoff (a soft foot unloading:
  :func:`~a1_leg_fk.estimation.stance_edges.lag`) is aligned where its foot first stands
  :data:`CROSSING_M` above the stance's level (within :data:`CROSSING_S` after the liftoff): in
  noise a millimetre's crossing time scatters by 0.3-1 ms, and a regular gait's foot reaches it
  the same time after it left, stride after stride (PyBullet's walks: within 0.3 ms).
* **Pool.** Their heights over the :data:`FIT_S` up to that crossing, less each stride's level
  (the median over :data:`LEVEL_S` before its crossing), are averaged: the noise shrinks by the
  square root of the strides.
* **Fit.** The mean rise is fitted, up to where it first stands :data:`FIT_TOP_M` up, as a
  stance (a level and a drift: a tilted base frame makes a standing foot's height drift) plus
  ``a (t - t0)^2`` after ``t0`` (:func:`pooled_onset`, ``t0`` scanned).
* **Place.** Where that rise is slow (it takes more than :data:`SLOW_S` to reach the edges'
  noise tolerance, and :data:`MIN_RISING` samples resolve it), each aligned stance ends at its
  crossing + ``t0``; a fast rise (a trot's), fewer than :data:`MIN_STRIDES` strides, fewer than
  :data:`MIN_SHARE` of the leg's interior stances, fewer samples than :data:`MIN_SAMPLES_SLOW`
  per :data:`SLOW_S`, or a noise tolerance as high as :data:`FIT_TOP_M` (a rise that noisy
  cannot be aligned, nor fitted), keep their edges.
"""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.stance_edges import (
    EDGE_NOISE_DEVIATIONS,
    EDGE_NOISE_FLOOR_M,
    MIN_WINDOW,
    lag,
    level,
    runs,
    stance_noise,
)

CROSSING_M = 0.001
"""[m] A liftoff's rise is aligned where the foot first stands this far above the stance's level
(0.8 and 1.2 mm met the same goals on the gait family: docs/gait.md)."""
CROSSING_S = 0.04
"""[s] That crossing is looked for this long after the stance's last sample."""
LEVEL_S = (0.07, 0.03)
"""[s] A stride's level is the median of its stance heights from this long to this long before
its crossing."""
FIT_S = 0.05
"""[s] The pooled rise is fitted from this long before the crossing (0.04 and 0.06 s: the same
goals met)."""
FIT_TOP_M = 0.0004
"""[m] ... up to where the pooled rise first stands this high (0.3 and 0.5 mm: the same goals
met); a walk's rise steepens some twentyfold past ~0.3-0.5 mm."""
ONSET_STEP_S = 0.0001
"""[s] The onset is scanned at this step, from :data:`MIN_STANCE_S` after the fit's start."""
MIN_STANCE_S = 0.004
"""[s] The fit keeps at least this much stance before the onset."""
SLOW_S = 0.004
"""[s] A rise that takes longer than this to reach the noise tolerance from its onset is slow
(6 ms: the same goals met)."""
MIN_SAMPLES_SLOW = 2.0
"""Pooled only where the samples (their median step) come at least this often per :data:`SLOW_S`
(500 Hz and faster): coarser ones cannot tell a slow rise's start from a fast one's."""
MIN_RISING = 2
"""A pooled rise is fitted only where at least this many of its samples stand between the mean's
noise tolerance (the edges' over the square root of the strides, at least
:data:`~a1_leg_fk.estimation.stance_edges.EDGE_NOISE_FLOOR_M`: noise-free heights, such as the
contact filter's of the lowest foot, exactly 0, have no noise to shrink) and :data:`FIT_TOP_M`:
a rise that crosses that band within one sample is a fast one, its onset not resolved."""
MIN_STRIDES = 3
"""A leg's liftoffs are pooled over at least this many strides."""
MIN_SHARE = 0.5
"""... and at least this share of its interior stances (a soft foot's, mostly left out, keeps
its own edges)."""


def pooled_liftoffs(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, tolerance_m: float
) -> np.ndarray:
    """``stance`` (n,) with the liftoffs of a leg whose feet rise slowly moved to their strides'
    pooled rise onset (module docstring); ``tolerance_m`` [m] is the edges' noise tolerance
    (at least :data:`EDGE_NOISE_FLOOR_M`), also what a soft stance rises by.
    """
    step = float(np.median(np.diff(times))) if times.size > 1 else math.inf
    tolerance_m = max(tolerance_m, EDGE_NOISE_FLOOR_M)
    if not poolable(step, tolerance_m):
        return stance
    strides = aligned_strides(times, heights, stance, tolerance_m)
    stances = sum(interior(stance, first, last, on) for first, last, on in runs(stance))
    onset = pool_onset(times, heights, strides, (grid_of(step), tolerance_m), stances)
    if onset is None:
        return stance
    placed = stance.copy()
    for stride in strides:
        place(placed, times, stride, onset)
    return placed


def recent_liftoffs(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, span_s: float, since: int = 0
) -> np.ndarray:
    """``stance`` (n,) with the liftoff of each stance that may end at sample ``since`` or later
    (its last sample at most :data:`CROSSING_S` before it) placed as :func:`pooled_liftoffs`
    places it over the samples from ``span_s`` [s] before its end to :data:`CROSSING_S` after
    it (the stances within, up to it), with those samples' noise tolerance
    (:data:`~a1_leg_fk.estimation.stance_edges.EDGE_NOISE_DEVIATIONS` of
    :func:`~a1_leg_fk.estimation.stance_edges.stance_noise`): the leg's recent strides, so a
    window that holds them gives what one pass does (the contact smoother's rule).
    """
    strides = crossing_strides(times, heights, stance)
    ends = [(first, last) for first, last, on in runs(stance) if interior(stance, first, last, on)]
    from_s = times[since] - CROSSING_S if since < times.size else math.inf
    placed = stance.copy()
    for stride, rise in strides:
        last = stride[1]
        if times[last] < from_s:
            continue
        begin = int(np.searchsorted(times, times[last] - span_s))
        recent = slice(begin, int(np.searchsorted(times, times[last] + CROSSING_S, "right")))
        step = float(np.median(np.diff(times[recent])))
        noise = stance_noise(heights[recent], stance[recent])
        tolerance_m = max(EDGE_NOISE_DEVIATIONS * noise, EDGE_NOISE_FLOOR_M)
        if not poolable(step, tolerance_m) or not stands(rise, tolerance_m):
            continue
        pool = [
            other
            for other, lift in strides
            if begin < other[0] and other[1] <= last and stands(lift, tolerance_m)
        ]
        stances = sum(begin < first and end <= last for first, end in ends)
        onset = pool_onset(times, heights, pool, (grid_of(step), tolerance_m), stances)
        if onset is not None:
            place(placed, times, stride, onset)
    return placed


def poolable(step_s: float, tolerance_m: float) -> bool:
    """Whether samples ``step_s`` [s] apart with a noise tolerance ``tolerance_m`` [m] can resolve
    a slow rise (:data:`MIN_SAMPLES_SLOW`, :data:`FIT_TOP_M`).
    """
    return round(SLOW_S / step_s, 6) >= MIN_SAMPLES_SLOW and tolerance_m < FIT_TOP_M


def grid_of(step_s: float) -> np.ndarray:
    """[s] The times, from the crossing, the pooled rise is sampled at: :data:`FIT_S` before it
    up to it, ``step_s`` [s] apart.
    """
    return np.arange(-round(FIT_S / step_s), 1) * step_s


def place(placed: np.ndarray, times: np.ndarray, stride: Stride, onset: float) -> None:
    """End the stance of ``stride`` in ``placed`` at its crossing + ``onset`` [s]: not before its
    middle sample, past its last where the onset comes later (an edge the heights put early).
    """
    first, last, _, at = stride
    end = int(np.searchsorted(times, at + onset, side="right")) - 1
    placed[first : last + 1] = False
    placed[first : max(end, (first + last) // 2) + 1] = True


def stands(rise: float | None, tolerance_m: float) -> bool:
    """Whether a stance that rose by ``rise`` [m] towards its liftoff (:func:`lag`; None: unknown)
    is no soft foot unloading: not more than ``tolerance_m`` [m].
    """
    return rise is None or not rise > tolerance_m


def interior(stance: np.ndarray, first: int, last: int, on: bool) -> bool:
    """Whether the run ``first``..``last`` of ``stance`` is a stance with both edges observed."""
    return on and first > 0 and last < stance.size - 1


Stride = tuple[int, int, float, float]
"""``(first, last, level [m], crossing [s])`` of an aligned stance (:func:`aligned_strides`)."""


def pool_onset(
    times: np.ndarray,
    heights: np.ndarray,
    pool: list[Stride],
    fit: tuple[np.ndarray, float],
    stances: int,
) -> float | None:
    """[s] The onset, from the crossing, of the mean rise of the strides ``pool`` (``fit``: the
    grid [s] it is sampled on and the edges' noise tolerance [m]), out of ``stances`` interior
    stances; None where it is not a slow rise that the pool resolves (module docstring).
    """
    grid, tolerance_m = fit
    if len(pool) < max(MIN_STRIDES, MIN_SHARE * stances):
        return None
    curves = [np.interp(at + grid, times, heights) - ground for *_, ground, at in pool]
    mean = np.mean(curves, axis=0)
    floor = max(tolerance_m / math.sqrt(len(pool)), EDGE_NOISE_FLOOR_M)
    resolved = (mean > floor) & (mean <= FIT_TOP_M)
    if np.count_nonzero(resolved) < MIN_RISING:  # not resolved, whatever the onset
        return None
    fitted = pooled_onset(grid, mean)
    if fitted is None or math.sqrt(tolerance_m / fitted[1]) <= SLOW_S:
        return None
    if np.count_nonzero(resolved & (grid > fitted[0])) < MIN_RISING:
        return None
    return fitted[0]


def aligned_strides(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray, tolerance_m: float
) -> list[Stride]:
    """The :func:`crossing_strides` whose foot does not rise towards its liftoff by more than
    ``tolerance_m`` [m] (:func:`stands`).
    """
    return [
        stride
        for stride, rise in crossing_strides(times, heights, stance)
        if stands(rise, tolerance_m)
    ]


def crossing_strides(
    times: np.ndarray, heights: np.ndarray, stance: np.ndarray
) -> list[tuple[Stride, float | None]]:
    """``(first, last, level [m], crossing [s])`` of each interior stance whose foot, within
    :data:`CROSSING_S` after it, first stands :data:`CROSSING_M` above the level next to its
    edge (the crossing, interpolated between samples), and what it rose by towards its liftoff
    (:func:`lag`); the level is the median of its heights within :data:`LEVEL_S` before the
    crossing (kept to the stance).
    """
    strides = []
    for first, last, on in runs(stance):
        if not interior(stance, first, last, on):
            continue
        stop = int(np.searchsorted(times, times[last] + CROSSING_S, side="right"))
        goal = level(times, heights, last, -1) + CROSSING_M
        up = np.flatnonzero(heights[last + 1 : stop] > goal)
        if not up.size or not heights[last] <= goal:  # none, or up already at the edge
            continue
        above = last + 1 + int(up[0])
        share = (goal - heights[above - 1]) / (heights[above] - heights[above - 1])
        at = float(times[above - 1] + share * (times[above] - times[above - 1]))
        window = (times >= at - LEVEL_S[0]) & (times <= at - LEVEL_S[1])
        window[:first] = False
        if window.sum() >= MIN_WINDOW:
            stride = (first, last, float(np.median(heights[window])), at)
            strides.append((stride, lag(times, heights, last, -1)))
    return strides


def pooled_onset(grid: np.ndarray, rise: np.ndarray) -> tuple[float, float] | None:
    """``(t0 [s], a [m/s^2])`` of the stance-then-rise that fits ``rise`` [m] at times ``grid``
    [s] best (least squares) up to where it first stands :data:`FIT_TOP_M` up: ``b + c t`` plus
    ``a (t - t0)^2`` after ``t0`` (``a > 0``), ``t0`` scanned at :data:`ONSET_STEP_S` from
    :data:`MIN_STANCE_S` after the first time; None without such a fit.
    """
    top = np.flatnonzero(rise > FIT_TOP_M)
    stop = int(top[0]) if top.size else grid.size
    times, heights = grid[:stop], rise[:stop]
    if stop < MIN_WINDOW:
        return None
    onsets = np.arange(times[0] + MIN_STANCE_S, times[-1], ONSET_STEP_S)
    if not onsets.size:
        return None
    rising = np.clip(times[None, :] - onsets[:, None], 0.0, None) ** 2
    shapes = np.stack(np.broadcast_arrays(np.ones_like(times), times, rising), axis=-1)
    coefficients = np.linalg.pinv(shapes, rcond=float(np.finfo(float).eps) * stop) @ heights
    errors = np.sum((shapes @ coefficients[:, :, None] - heights[:, None]) ** 2, axis=(1, 2))
    rises = coefficients[:, 2] > 0.0
    if not rises.any():
        return None
    best = int(np.flatnonzero(rises)[np.argmin(errors[rises])])
    return float(onsets[best]), float(coefficients[best, 2])
