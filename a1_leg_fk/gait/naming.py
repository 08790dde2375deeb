"""The gait's name from the legs' touchdown phases and duty factor, as biomechanics names gaits.

Pure Python (no ROS, no numpy). The input is each leg's touchdown phase within FR's stride (FR at
0; FL, RR, RL in 0..1 cycles, see :func:`a1_leg_fk.gait.metrics.relative_phases`), how consistent
each phase is (mean resultant length R, 0..1) and the mean duty factor (0..1).

**Symmetric gaits** (Hildebrand 1965, 1976, 1989): the left and right feet of each pair touch down
half a cycle apart (fore FL - FR and hind RL - RR both 0.5 +- :data:`SYMMETRY_TOLERANCE`). Such a
gait is a point in Hildebrand's plane: the duty factor against the *limb phase*, the fraction of
the stride by which each fore foot touches down after the hind foot of its own side (the mean of
the left and the right side's). The plane's regions (limb-phase bands at its eighths,
:data:`LIMB_PHASE_BANDS`):

* limb phase 0 +- 0.125 (hind and fore of a side nearly together): **pace**;
* 0.5 +- 0.125 (diagonal feet nearly together): **trot**;
* 0.125..0.375 lateral sequence, 0.625..0.875 diagonal sequence (the feet one after the other):
  **walk** when the duty factor is above 0.5 (each foot down more than half the time), else
  **amble** (a running walk);
* a pace or trot with a duty factor above 0.5 keeps its name, its region says "walking".

**Asymmetric gaits** (Hildebrand 1977), by how each pair's feet are paired: a pair is *in unison*
when its two touchdowns are within :data:`UNISON_TOLERANCE` cycles. Both pairs in unison: **pronk**
when the fore and hind pairs are together too, else **bound**; one pair in unison: **half-bound**;
neither (and not symmetric): **gallop**, *transverse* when the fore and hind pairs lead with the
same side (the lead foot is the pair's second to touch down), else *rotary*.

Anything else -- phases missing, not consistent (R < :data:`MIN_CONSISTENCY`), or a pattern between
the regions -- is **unknown**. The fit (0..1) is the smallest R times how closely the pattern holds
the region's defining pairing: ``1 - deviation / NO_MATCH_DEVIATION``, the deviation being the
largest [cycles] of the pairs' offsets from 0.5 (symmetric) or of the unison pairs' lags from 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

SYMMETRY_TOLERANCE = 0.1
"""Largest deviation [cycles] of a pair's left-right offset from half a cycle (symmetric gait)."""
UNISON_TOLERANCE = 0.1
"""Largest lag [cycles] between the two feet of a pair that still counts as in unison."""
NO_MATCH_DEVIATION = 0.25
"""A deviation [cycles] of a quarter cycle or more fits a region not at all (fit 0)."""
MIN_CONSISTENCY = 0.6
"""Phase consistency R (mean resultant length) below this names no gait (phases drift)."""
WALK_MIN_DUTY = 0.5
"""Above this duty factor a symmetric gait walks (every foot down more than half the time)."""
LIMB_PHASE_BANDS: tuple[tuple[float, float, str], ...] = (
    (0.0, 0.125, "pace"),
    (0.125, 0.375, "lateral-sequence"),
    (0.375, 0.625, "trot"),
    (0.625, 0.875, "diagonal-sequence"),
    (0.875, 1.0, "pace"),
)
"""``(from, to, band)`` of limb phase [cycles] in Hildebrand's plane (edges at its eighths)."""
GAIT_NAMES = ("walk", "amble", "trot", "pace", "bound", "half-bound", "gallop", "pronk")
"""Every name :func:`name_gait` gives besides ``unknown``."""


@dataclass(frozen=True)
class GaitName:
    """A gait's name, its region in Hildebrand's scheme, how well it fits, and the phases used."""

    name: str  # one of GAIT_NAMES or "unknown"
    region: str  # e.g. "lateral-sequence walk", "walking trot", "transverse gallop"; "" if unknown
    fit: float  # 0..1
    reason: str
    limb_phase: float | None  # [cycles] fore after hind of the same side, mean of both sides
    limb_phase_left: float | None
    limb_phase_right: float | None
    symmetric: bool | None  # left-right offsets of both pairs near half a cycle; None: unknown
    candidates: dict[str, float] = field(default_factory=dict)  # fit of every name


def circular_distance(a: float, b: float) -> float:
    """The distance [cycles, 0..0.5] between phases ``a`` and ``b`` on the unit circle."""
    d = abs(a - b) % 1.0
    return min(d, 1.0 - d)


def circular_mean(a: float, b: float) -> float:
    """The mean [cycles, 0..1) of two phases along the shorter arc between them."""
    d = (b - a) % 1.0
    return (a + (d if d <= 0.5 else d - 1.0) / 2.0) % 1.0


def _fit(deviation: float, consistency: float) -> float:
    return round(max(0.0, 1.0 - deviation / NO_MATCH_DEVIATION) * consistency, 4)


def _band(limb_phase: float) -> str:
    for low, high, band in LIMB_PHASE_BANDS:
        if low <= limb_phase < high:
            return band
    return "pace"  # limb_phase == 1.0 after rounding


def _symmetric_name(limb_phase: float, duty: float | None) -> tuple[str, str]:
    """``(name, region)`` of a symmetric gait at ``limb_phase`` [cycles] and ``duty`` (0..1)."""
    band = _band(limb_phase)
    walking = duty is not None and duty > WALK_MIN_DUTY
    if band in ("pace", "trot"):
        return band, f"walking {band}" if walking else band
    if walking:
        return "walk", f"{band} walk"
    return "amble", f"{band} run"


def _asymmetric_name(fr: float, fl: float, rr: float, rl: float) -> tuple[str, str, float] | None:
    """``(name, region, deviation [cycles])`` of an asymmetric pattern, or ``None`` between
    regions.
    """
    fore_lag, hind_lag = circular_distance(fl, fr), circular_distance(rl, rr)
    fore_unison, hind_unison = fore_lag <= UNISON_TOLERANCE, hind_lag <= UNISON_TOLERANCE
    if fore_unison and hind_unison:
        apart = circular_distance(circular_mean(fr, fl), circular_mean(rr, rl))
        if apart <= UNISON_TOLERANCE:
            return "pronk", "pronk", max(fore_lag, hind_lag, apart)
        return "bound", "bound", max(fore_lag, hind_lag)
    if fore_unison or hind_unison:
        split = "fore" if hind_unison else "hind"
        return "half-bound", f"half-bound ({split} pair split)", min(fore_lag, hind_lag)
    if max(fore_lag, hind_lag) >= 0.5 - SYMMETRY_TOLERANCE:
        return None  # one pair alternates, the other is split: between the regions
    # The lead foot of a pair is its second to touch down: FL leads when it follows FR within
    # half a cycle.
    fore_lead_left = (fl - fr) % 1.0 < 0.5
    hind_lead_left = (rl - rr) % 1.0 < 0.5
    kind = "transverse" if fore_lead_left == hind_lead_left else "rotary"
    return "gallop", f"{kind} gallop", 0.0


def name_gait(
    phases: dict[str, float | None], consistency: dict[str, float | None], duty: float | None
) -> GaitName:
    """The gait from the touchdown phases of FL, RR, RL within FR's stride [cycles], their
    consistency R and the mean duty factor; see the module docstring.
    """
    fl, rr, rl = (phases.get(leg) for leg in ("FL", "RR", "RL"))
    if fl is None or rr is None or rl is None:
        missing = [leg for leg in ("FL", "RR", "RL") if phases.get(leg) is None]
        return GaitName(
            "unknown",
            "",
            0.0,
            f"no touchdown phase for {', '.join(missing)} (needs strides of FR and touchdowns of "
            "each leg)",
            None,
            None,
            None,
            None,
        )
    fr = 0.0
    r = min(value for value in consistency.values() if value is not None)
    left, right = (fl - rl) % 1.0, (fr - rr) % 1.0
    limb_phase = circular_mean(left, right)
    offsets = circular_distance((fl - fr) % 1.0, 0.5), circular_distance((rl - rr) % 1.0, 0.5)
    symmetric = max(offsets) <= SYMMETRY_TOLERANCE
    candidates = dict.fromkeys(GAIT_NAMES, 0.0)
    if symmetric:
        name, region = _symmetric_name(limb_phase, duty)
        deviation = max(offsets)
        found: tuple[str, str, float] | None = (name, region, deviation)
    else:
        found = _asymmetric_name(fr, fl, rr, rl)
    if found is not None:
        candidates[found[0]] = _fit(found[2], r)

    def named(name: str, region: str, fit: float, reason: str) -> GaitName:
        return GaitName(name, region, fit, reason, limb_phase, left, right, symmetric, candidates)

    if r < MIN_CONSISTENCY:
        return named(
            "unknown",
            "",
            0.0,
            f"touchdown phases are not consistent (R = {r:.2f} < {MIN_CONSISTENCY})",
        )
    if found is None:
        return named(
            "unknown",
            "",
            0.0,
            "no region fits: one pair alternates while the other is split "
            f"(fore FL - FR {(fl - fr) % 1.0:.2f}, hind RL - RR {(rl - rr) % 1.0:.2f} cycles)",
        )
    name, region, _ = found
    if symmetric:
        reason = (
            f"symmetric, limb phase {limb_phase:.2f} (left {left:.2f}, right {right:.2f}), "
            f"duty {'-' if duty is None else format(duty, '.2f')}: {region}"
        )
    else:
        reason = (
            f"asymmetric, fore pair lag {circular_distance(fl, fr):.2f}, hind pair lag "
            f"{circular_distance(rl, rr):.2f} cycles: {region}"
        )
    return named(name, region, candidates[name], reason)
