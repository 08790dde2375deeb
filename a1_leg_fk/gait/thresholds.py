"""Contact thresholds derived from the recording itself: each foot's stance is the low, slow mode
of its own height and speed distributions.

Pure numpy (no ROS, no file I/O). Fixed thresholds fail on real data: a retargeted or a slipping
stance foot moves at 0.2-0.4 m/s, and a foot can stand a centimetre higher than the others. So,
for each foot (legs in :data:`a1_leg_fk.model.legs.LEG_NAMES` order):

* **Speed.** The foot's speeds [m/s] split into a slow mode (stance) and a fast one (swing) by
  Otsu's method on ``log(speed)`` -- the split that maximises the variance between the two modes,
  found in one pass over the sorted values. The foot's ``speed_on_mps`` is the top of the slow
  mode (its ``SLOW_PERCENTILE`` percentile times ``SPEED_MARGIN``; at most the split), so a landing
  foot still decelerating does not count as down; it is kept within the configured
  ``speed_on_mps`` (floor) and ``speed_on_max_mps`` (ceiling); ``speed_off_mps`` keeps the
  configured gap above on.
* **Height** [m] above the ground plane, over the foot's slow samples (mostly stance; a still swing
  apex is a minority): their median plus ``HEIGHT_SPREAD`` robust deviations (1.4826 MAD) is the
  foot's ``height_on_m``, within the configured ``height_on_m`` (floor) and ``height_on_max_m``
  (ceiling); ``height_off_m`` keeps the configured gap above ``on``.

A foot with fewer than ``MIN_SAMPLES`` finite samples keeps the floors. With
``ContactThresholds(adaptive=False)`` every foot uses the configured values as they are.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from a1_leg_fk.estimation.stance_edges import MAD_SIGMA
from a1_leg_fk.model.urdf import LegFkError

MIN_SAMPLES = 20
"""Fewer finite samples of a foot than this give no distribution to split: the floors are used."""
SPEED_FLOOR_MPS = 1e-3
"""Speeds below this [m/s] count as this in the log-speed split (a foot still to the last bit)."""
SLOW_PERCENTILE = 90.0
SPEED_MARGIN = 1.5
"""The slow mode's top: this percentile of its speeds, times this margin [m/s]."""
HEIGHT_SPREAD = 4.0
"""Robust deviations of the slow samples' heights above their median that still count as down."""


def otsu_split(values: np.ndarray) -> float:
    """The value splitting ``values`` (1-D, finite, at least 2) into two modes with the largest
    variance between them (Otsu's method): the midpoint between the last value of the lower mode
    and the first of the upper one.
    """
    ordered = np.sort(np.asarray(values, dtype=float))
    n = ordered.size
    below = np.arange(1, n)  # candidate splits: the first k values are the lower mode
    sums = np.cumsum(ordered)[:-1]
    mean_low = sums / below
    mean_high = (ordered.sum() - sums) / (n - below)
    between = below * (n - below) * (mean_high - mean_low) ** 2
    k = int(np.argmax(between)) + 1
    return float(0.5 * (ordered[k - 1] + ordered[k]))


def slow_top(speeds: np.ndarray) -> float | None:
    """The top [m/s] of one foot's slow mode: below the split from the fast mode (Otsu on
    ``log(speed)``), :data:`SPEED_MARGIN` times its :data:`SLOW_PERCENTILE` percentile; ``None``
    with fewer than :data:`MIN_SAMPLES` finite speeds.
    """
    finite = speeds[np.isfinite(speeds)]
    if finite.size < MIN_SAMPLES:
        return None
    split = float(np.exp(otsu_split(np.log(np.maximum(finite, SPEED_FLOOR_MPS)))))
    slow = finite[finite <= split]
    return min(split, SPEED_MARGIN * float(np.percentile(slow, SLOW_PERCENTILE)))


def height_top(heights: np.ndarray) -> float | None:
    """The top [m] of one foot's stance heights ``heights`` (its slow samples): median plus
    :data:`HEIGHT_SPREAD` robust deviations, or ``None`` with fewer than :data:`MIN_SAMPLES`.
    """
    finite = heights[np.isfinite(heights)]
    if finite.size < MIN_SAMPLES:
        return None
    median = float(np.median(finite))
    deviation = MAD_SIGMA * float(np.median(np.abs(finite - median)))
    return median + HEIGHT_SPREAD * deviation


def speed_thresholds(speeds: np.ndarray, bounds: ContactThresholds) -> list[ContactThresholds]:
    """Per foot: ``bounds`` with ``speed_on_mps``/``speed_off_mps`` from that foot's speeds (N, 4)
    [m/s] (NaN: unknown), see the module docstring; ``bounds`` itself when not adaptive.
    """
    out = []
    for slot in range(speeds.shape[1]):
        top = slow_top(speeds[:, slot]) if bounds.adaptive else None
        if top is None:
            out.append(bounds)
            continue
        on = min(max(top, bounds.speed_on_mps), bounds.speed_on_max_mps)
        gap = bounds.speed_off_mps - bounds.speed_on_mps
        out.append(replace(bounds, speed_on_mps=on, speed_off_mps=on + gap))
    return out


def height_thresholds(
    heights: np.ndarray, speeds: np.ndarray, per_leg: list[ContactThresholds]
) -> list[ContactThresholds]:
    """Per foot: ``per_leg[slot]`` with ``height_on_m``/``height_off_m`` from that foot's heights
    (N, 4) [m] where its speed (N, 4) [m/s] is below its ``speed_on_mps``; see the module
    docstring.
    """
    out = []
    for slot, leg in enumerate(per_leg):
        with np.errstate(invalid="ignore"):
            slow = speeds[:, slot] < leg.speed_on_mps
        top = height_top(heights[slow, slot]) if leg.adaptive else None
        if top is None:
            out.append(leg)
            continue
        on = min(max(top, leg.height_on_m), leg.height_on_max_m)
        out.append(
            replace(leg, height_on_m=on, height_off_m=on + leg.height_off_m - leg.height_on_m)
        )
    return out


@dataclass(frozen=True)
class ContactThresholds:
    """The contact detector's settings; defaults for the A1 at 20..1000 Hz (README: why these).
    ``adaptive``: each foot's on/off values derived from the data, these as bounds
    (:mod:`a1_leg_fk.gait.thresholds`); else every foot uses them as given.
    """

    height_on_m: float = 0.02
    height_off_m: float = 0.035
    speed_on_mps: float = 0.15
    speed_off_mps: float = 0.3
    min_phase_s: float = 0.04
    ground_percentile: float = 5.0
    speed_window_s: float = 0.02
    height_on_max_m: float = 0.05
    speed_on_max_mps: float = 0.6
    adaptive: bool = True

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not math.isfinite(value) or value < 0:
                raise LegFkError(
                    f"contact threshold {name} must be a finite number >= 0, got {value}"
                )
        if self.height_off_m < self.height_on_m or self.speed_off_mps < self.speed_on_mps:
            raise LegFkError(
                f"hysteresis needs off >= on: height {self.height_on_m} / {self.height_off_m} m, "
                f"speed {self.speed_on_mps} / {self.speed_off_mps} m/s"
            )
        if self.height_on_max_m < self.height_on_m or self.speed_on_max_mps < self.speed_on_mps:
            raise LegFkError(
                f"bounds need max >= on: height {self.height_on_m} / {self.height_on_max_m} m, "
                f"speed {self.speed_on_mps} / {self.speed_on_max_mps} m/s"
            )
        if self.ground_percentile > 100:
            raise LegFkError(f"ground_percentile must be in 0..100, got {self.ground_percentile}")
