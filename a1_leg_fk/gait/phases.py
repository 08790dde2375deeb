"""Per-sample stance masks -> phases: the minimum-phase rule and the stance intervals, the one
place both the kinematic contacts and an estimate's (forces, foot sensors) become phases.

Pure numpy (no ROS, no file I/O). Times are in seconds from the first stamp; a mask is one leg's
(n,) bool stance over one gap-free run of samples.

**Minimum phase.** An interior run of equal values (a stance or a swing, not the first or last of
the run of samples) shorter than ``min_phase_s`` is a *blip*. Blips are removed shortest first:
the shortest is flipped and so merged with its two neighbours, then the shortest of what is left,
until every interior phase lasts at least ``min_phase_s`` (on a tie, a stance goes before a
swing). A stance blip is *dropped* (set to swing), a swing blip is *bridged* (set to stance).
Each flip changes the leg's stance time by exactly the blip's own duration, and a blip is never
longer than either neighbour at the time it is flipped: a 2 ms false touchdown 14 ms before the
real one is dropped (it is the shorter), instead of the 14 ms gap being bridged into 16 ms of
stance; a 2 ms false lift-off inside a stance is bridged; a real swing or stance is kept.

**Edges.** A phase's edge time is the midpoint between its border sample and the neighbour's (no
bias on a sampling grid); at the start or end of the run of samples it is the border sample's own
time, and the edge is not observed.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.estimation.stance_edges import runs


@dataclass(frozen=True)
class Stance:
    """One stance phase [s from the first stamp]; an edge at the data's or a gap's border is not
    observed.
    """

    t_on: float
    t_off: float
    first: int  # sample indices, inclusive
    last: int
    touchdown_observed: bool
    liftoff_observed: bool
    segment: int  # index of the gap-free run of samples it lies in


@dataclass(frozen=True)
class Blips:
    """What the minimum-phase rule removed from one leg: stance blips ``dropped`` (set to swing)
    and swing blips ``bridged`` (set to stance), each a count of runs.
    """

    dropped: int = 0
    bridged: int = 0

    def __add__(self, other: Blips) -> Blips:
        return Blips(self.dropped + other.dropped, self.bridged + other.bridged)


def segment_slices(valid: np.ndarray) -> list[slice]:
    """The gap-free runs of one leg's (N,) validity mask, in time order, as row slices."""
    return [slice(first, last + 1) for first, last, value in runs(valid) if value]


def phase_span(times: np.ndarray, first: int, last: int) -> tuple[float, float]:
    """``(start, end)`` [s] of the phase on samples ``first..last`` of a gap-free run's ``times``:
    each edge midway between the phase's border sample and its neighbour, or the border sample's
    own time at the run's start or end (an edge not observed).
    """
    start = times[first] if first == 0 else 0.5 * (times[first - 1] + times[first])
    end = times[last] if last == times.size - 1 else 0.5 * (times[last] + times[last + 1])
    return float(start), float(end)


def drop_blips(
    times: np.ndarray, stance: np.ndarray, min_phase_s: float
) -> tuple[np.ndarray, Blips]:
    """``stance`` (n,) of one gap-free run with its blips removed, shortest first (see the module
    docstring), and how many were dropped and bridged.
    """
    found = runs(stance)
    first = [a for a, _, _ in found]
    last = [b for _, b, _ in found]
    value = [v for _, _, v in found]
    left = list(range(-1, len(found) - 1))  # the neighbouring runs of each run; -1: none
    right = [*range(1, len(found)), -1]
    version = [0] * len(found)  # bumped when a run grows; older heap entries are stale

    def push(run: int) -> None:
        if left[run] != -1 and right[run] != -1:  # interior: neither the first run nor the last
            start, end = phase_span(times, first[run], last[run])
            if end - start < min_phase_s:  # a stance goes first on a tie, then the earlier
                key = (end - start, not value[run], first[run], version[run], run)
                heapq.heappush(heap, key)

    heap: list[tuple[float, bool, int, int, int]] = []
    for run in range(len(found)):
        push(run)
    out, dropped, bridged = stance.copy(), 0, 0
    while heap:
        _, _, _, seen, run = heapq.heappop(heap)
        if seen != version[run]:
            continue
        before, after = left[run], right[run]
        out[first[run] : last[run] + 1] = not value[run]
        dropped, bridged = dropped + value[run], bridged + (not value[run])
        last[before], right[before] = last[after], right[after]  # all three are now ``before``
        if right[after] != -1:
            left[right[after]] = before
        version[run] = version[after] = -1
        version[before] += 1
        push(before)
    return out, Blips(dropped, bridged)


def apply_min_phase(
    times: np.ndarray, stance: np.ndarray, segments: list[list[slice]], min_phase_s: float
) -> tuple[np.ndarray, tuple[Blips, ...]]:
    """(N, legs) ``stance`` with each leg's blips removed within each of its gap-free runs
    ``segments[leg]`` (:func:`drop_blips`), and each leg's count of them; ``times`` (N,) [s].
    """
    out = stance.copy()
    counts = []
    for slot, rows_of_leg in enumerate(segments):
        total = Blips()
        for rows in rows_of_leg:
            out[rows, slot], found = drop_blips(times[rows], stance[rows, slot], min_phase_s)
            total += found
        counts.append(total)
    return out, tuple(counts)


def stances_of(times: np.ndarray, stance: np.ndarray, segments: list[slice]) -> tuple[Stance, ...]:
    """One leg's stance phases from its (N,) stance mask, within each gap-free run ``segments``."""
    out = []
    for segment, rows in enumerate(segments):
        local = times[rows]
        for first, last, value in runs(stance[rows]):
            if not value:
                continue
            t_on, t_off = phase_span(local, first, last)
            out.append(
                Stance(
                    t_on,
                    t_off,
                    rows.start + first,
                    rows.start + last,
                    first > 0,
                    last < local.size - 1,
                    segment,
                )
            )
    return tuple(out)
