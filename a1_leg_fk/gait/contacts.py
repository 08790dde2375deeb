"""Foot contacts from world-frame feet: ground plane, speeds, hysteresis, minimum phase, edges.

Pure numpy (no ROS, no file I/O); :func:`detect_contacts` takes ``stamps_s`` (N,) [s] and
``world_feet`` (N, 4, 3) [m] as described in :mod:`a1_leg_fk.gait.analysis`. A foot is in stance
when it is near the ground and nearly still:

* **Thresholds** per foot, derived from its own speed and height distributions
  (:mod:`a1_leg_fk.gait.thresholds`; the configured values are bounds), or as configured with
  ``adaptive=False``.
* **Ground.** A plane ``z = level + gx (x - x0) + gy (y - y0)`` fitted to the samples where a foot
  is still (speed below its ``speed_on_mps``): least squares, then refitted on the lower half of
  the residuals three times (so a still swing apex does not lift it), and finally shifted to the
  ``ground_percentile`` percentile of the residuals of all still samples. The level is that of the
  *foot frame* in stance (ground + foot radius), so neither the floor height nor the foot radius
  need be known; a slope of a few degrees is followed. Heights are ``z - plane(x, y)``.
* **Speed** [m/s] comes from central differences over the stamps (no constant rate assumed): the
  difference quotient over a span of at least ``speed_window_s`` (at least one sample interval),
  the central-difference velocity at the span's middle. A sample's speed is the smaller of the
  span that ends at it and the span that starts at it: a foot just landed is still over the span
  ahead, a foot about to lift is still over the span behind, so the spans do not shorten stances.
* **Hysteresis.** Swing -> stance when height < ``height_on_m`` and speed < ``speed_on_mps``;
  stance -> swing when height > ``height_off_m`` or speed > ``speed_off_mps`` (the foot's own
  thresholds).
* **Minimum phase.** Interior stances and swings shorter than ``min_phase_s`` (blips) are removed,
  shortest first (:mod:`a1_leg_fk.gait.phases`: a stance blip dropped, a swing blip bridged).
* **Edges** (:func:`a1_leg_fk.gait.edges.fit_edges`). The speeds place edges late or early (a
  foot unloads before it moves, may slide as it pushes off); the heights place them: a stance
  ends where the foot starts to rise above the stance's level next to the edge and begins where
  it stops coming down. A leg whose feet rise slowly from rest (a walk's) has its liftoffs
  placed by its strides' pooled rise (:func:`a1_leg_fk.estimation.pooled_rise.pooled_liftoffs`: one
  liftoff's heights cannot place such a rise in sensor noise). An edge time is the midpoint
  between the last sample of one phase and the first of the next (unbiased on a sampling grid);
  at the start/end of the data or of a gap it is that sample's time and the edge is not observed.

Times are in seconds from the first stamp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.estimation.pooled_rise import pooled_liftoffs
from a1_leg_fk.estimation.stance_edges import EDGE_NOISE_DEVIATIONS, stance_noise
from a1_leg_fk.gait.edges import fit_edges
from a1_leg_fk.gait.phases import Blips, Stance, apply_min_phase, segment_slices, stances_of
from a1_leg_fk.gait.thresholds import ContactThresholds, height_thresholds, speed_thresholds
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

MIN_SAMPLES = 5
"""Fewer valid rows than this cannot give a speed window and a phase on each side."""
PLANE_REFITS = 3
SLOPE_RCOND = 0.01
"""Slopes along directions in which the still feet spread less than ~1 cm are not fitted (set
0)."""


@dataclass(frozen=True)
class GroundPlane:
    """``z = level_m + slope[0] (x - origin[0]) + slope[1] (y - origin[1])`` [m], world frame."""

    level_m: float
    origin_xy: tuple[float, float]
    slope: tuple[float, float]

    @property
    def slope_deg(self) -> float:
        """The plane's inclination from horizontal [deg]."""
        return math.degrees(math.atan(math.hypot(*self.slope)))

    def height_of(self, points: np.ndarray) -> np.ndarray:
        """Height [m] of ``points`` (..., 3) above the plane, along z."""
        x0, y0 = self.origin_xy
        gx, gy = self.slope
        return points[..., 2] - (
            self.level_m + gx * (points[..., 0] - x0) + gy * (points[..., 1] - y0)
        )


@dataclass(frozen=True)
class Contacts:
    """Per-sample contact states and the stance phases of each leg (arrays sorted by time)."""

    times_s: np.ndarray  # (N,) [s] from the first stamp
    positions_m: np.ndarray  # (N, 4, 3) world frame
    valid: np.ndarray  # (N, 4) bool: finite position
    heights_m: np.ndarray  # (N, 4) above the ground plane; NaN where not valid
    speeds_mps: np.ndarray  # (N, 4); NaN where not valid or no neighbour
    stance: np.ndarray  # (N, 4) bool
    stances: tuple[tuple[Stance, ...], ...]  # per leg
    ground: GroundPlane
    thresholds: ContactThresholds  # as configured (floors and ceilings when adaptive)
    notes: tuple[str, ...] = ()
    # the thresholds each foot was judged by (derived from the data when adaptive), per leg
    leg_thresholds: tuple[ContactThresholds, ...] = ()
    blips: tuple[Blips, ...] = ()  # per leg: what the minimum-phase rule dropped and bridged
    blip_samples: np.ndarray | None = None  # (N, 4) bool: the samples it changed (None: none)


# --- input -------------------------------------------------------------------------------------


def prepare(
    stamps_s: np.ndarray, world_feet: np.ndarray, unsorted: str = "sort"
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(stamps, feet, notes)`` checked, sorted by time (``unsorted="sort"``) or refused
    (``"reject"``).

    Rows with a repeated stamp keep the first; the notes say what was sorted or dropped.
    """
    stamps = np.asarray(stamps_s, dtype=float)
    feet = np.asarray(world_feet, dtype=float)
    if stamps.ndim != 1 or feet.shape != (stamps.size, len(LEG_NAMES), 3):
        raise LegFkError(
            f"expected stamps (N,) and world feet (N, 4, 3), got {stamps.shape} and {feet.shape}"
        )
    if not np.isfinite(stamps).all():
        raise LegFkError(f"{int((~np.isfinite(stamps)).sum())} stamps are not finite")
    notes: list[str] = []
    backwards = int((np.diff(stamps) < 0).sum())
    if backwards:
        if unsorted == "reject":
            first = int(np.argmax(np.diff(stamps) < 0)) + 1
            raise LegFkError(
                f"stamps not increasing: {backwards} go back in time (first at row {first}); "
                "rejected"
            )
        order = np.argsort(stamps, kind="stable")
        stamps, feet = stamps[order], feet[order]
        notes.append(f"stamps not increasing: {backwards} rows went back in time; sorted by stamp")
    repeated = np.concatenate(([False], np.diff(stamps) == 0))
    if repeated.any():
        if unsorted == "reject":
            raise LegFkError(
                f"stamps not increasing: {int(repeated.sum())} repeat the previous stamp; rejected"
            )
        stamps, feet = stamps[~repeated], feet[~repeated]
        notes.append(f"{int(repeated.sum())} rows repeated a stamp; the first of each was kept")
    valid_rows = int(np.isfinite(feet).all(axis=2).any(axis=1).sum())
    if valid_rows < MIN_SAMPLES:
        raise LegFkError(
            f"too few samples: {valid_rows} rows with a finite foot, need at least {MIN_SAMPLES}"
        )
    return stamps, feet, notes


# --- contacts ----------------------------------------------------------------------------------


def still_speeds(times: np.ndarray, points: np.ndarray, window_s: float) -> np.ndarray:
    """(n,) speed [m/s] of one gap-free run: the smaller of the spans ending and starting at each
    sample.

    A span reaches the nearest sample at least ``window_s`` away (at least the neighbour), or the
    run's end; its difference quotient is the central-difference velocity at the span's middle.
    """
    n = times.size
    index = np.arange(n)
    back = np.clip(np.searchsorted(times, times - window_s, side="right") - 1, 0, None)
    back = np.where(back == index, index - 1, back)
    ahead = np.clip(np.searchsorted(times, times + window_s, side="left"), None, n - 1)
    ahead = np.where(ahead == index, index + 1, ahead)
    speeds = np.full((2, n), np.inf)
    for row, other in enumerate((back, ahead)):
        ok = (other >= 0) & (other < n)
        partner = other[ok]
        distance = np.linalg.norm(points[partner] - points[index[ok]], axis=1)
        speeds[row, ok] = distance / np.abs(times[partner] - times[index[ok]])
    speed = speeds.min(axis=0)
    return np.where(np.isfinite(speed), speed, np.nan)


def fit_ground(points: np.ndarray, percentile: float) -> GroundPlane:
    """The ground plane under still feet ``points`` (M, 3) [m]: see the module docstring."""
    if points.shape[0] < 3:
        raise LegFkError(f"too few still foot samples ({points.shape[0]}) to find the ground")
    origin = points[:, :2].mean(axis=0)
    design = np.column_stack((np.ones(points.shape[0]), points[:, :2] - origin))
    keep = np.ones(points.shape[0], dtype=bool)
    for _ in range(PLANE_REFITS + 1):
        # Unscaled columns (1, dx [m], dy [m]): a singular value relative to the first is about the
        # feet's spread [m] in that direction, so rcond drops slopes the feet cannot determine.
        coefficients = np.linalg.lstsq(design[keep], points[keep, 2], rcond=SLOPE_RCOND)[0]
        residuals = points[:, 2] - design @ coefficients
        keep = residuals <= np.median(residuals)
    level = coefficients[0] + float(np.percentile(residuals, percentile))
    return GroundPlane(
        float(level),
        (float(origin[0]), float(origin[1])),
        (float(coefficients[1]), float(coefficients[2])),
    )


def hysteresis(heights: np.ndarray, speeds: np.ndarray, t: ContactThresholds) -> np.ndarray:
    """(n,) stance mask of one gap-free run from its heights [m] and speeds [m/s]."""
    with np.errstate(invalid="ignore"):
        enter = (heights < t.height_on_m) & (speeds < t.speed_on_mps)
        leave = (heights > t.height_off_m) | (speeds > t.speed_off_mps) | np.isnan(speeds)
    events = np.where(enter | leave)[0]
    if events.size == 0:
        # Never past either threshold: the whole run lies between on and off.
        return np.full(heights.size, bool(heights[0] < t.height_off_m))
    last = np.maximum.accumulate(np.where(enter | leave, np.arange(heights.size), -1))
    state: np.ndarray = np.where(last >= 0, enter[np.clip(last, 0, None)], leave[events[0]])
    return state.astype(bool)


def detect_contacts(
    stamps_s: np.ndarray,
    world_feet: np.ndarray,
    thresholds: ContactThresholds = ContactThresholds(),
    unsorted: str = "sort",
) -> Contacts:
    """Stance/swing of each foot from world-frame feet; see the module docstring for the method.

    ``stamps_s`` (N,) [s], ``world_feet`` (N, 4, 3) [m] world frame, z up, NaN rows = gaps.
    ``unsorted``: ``"sort"`` (default; noted) or ``"reject"`` (:class:`LegFkError`) for stamps that
    go back.
    """
    stamps, feet, notes = prepare(stamps_s, world_feet, unsorted)
    times = stamps - stamps[0]
    valid = np.isfinite(feet).all(axis=2)
    legs = len(LEG_NAMES)
    segments = [segment_slices(valid[:, slot]) for slot in range(legs)]
    speeds = np.full(valid.shape, np.nan)
    for slot in range(legs):
        for rows in segments[slot]:
            if rows.stop - rows.start >= 2:
                speeds[rows, slot] = still_speeds(
                    times[rows], feet[rows, slot], thresholds.speed_window_s
                )
    per_leg = speed_thresholds(speeds, thresholds)
    with np.errstate(invalid="ignore"):
        still = valid & (speeds < np.array([leg.speed_on_mps for leg in per_leg]))
    if still.sum() < 3:
        gate = max(leg.speed_on_mps for leg in per_leg)
        raise LegFkError(
            f"no foot is ever still (speed < {gate:.3g} m/s in {int(still.sum())} samples): "
            "cannot find the ground; are these world-frame feet?"
        )
    ground = fit_ground(feet[still], thresholds.ground_percentile)
    heights = np.where(valid, ground.height_of(np.where(valid[..., None], feet, 0.0)), np.nan)
    per_leg = height_thresholds(heights, speeds, per_leg)
    raw = np.zeros(valid.shape, dtype=bool)
    for slot in range(legs):
        for rows in segments[slot]:
            raw[rows, slot] = hysteresis(heights[rows, slot], speeds[rows, slot], per_leg[slot])
    stance, blips = apply_min_phase(times, raw, segments, thresholds.min_phase_s)
    blip_samples = stance != raw
    for slot in range(legs):
        for rows in segments[slot]:
            noise = stance_noise(heights[rows, slot], stance[rows, slot])
            fitted = fit_edges(times[rows], heights[rows, slot], stance[rows, slot], noise)
            stance[rows, slot] = pooled_liftoffs(
                times[rows], heights[rows, slot], fitted, EDGE_NOISE_DEVIATIONS * noise
            )
    stances = tuple(stances_of(times, stance[:, slot], segments[slot]) for slot in range(legs))
    gaps = int((~valid.all(axis=1)).sum())
    if gaps:
        notes.append(
            f"{gaps} rows with a missing foot (no pose there, a gap): phases are split at them"
        )
    return Contacts(
        times,
        feet,
        valid,
        heights,
        speeds,
        stance,
        stances,
        ground,
        thresholds,
        tuple(notes),
        tuple(per_leg),
        blips,
        blip_samples,
    )
