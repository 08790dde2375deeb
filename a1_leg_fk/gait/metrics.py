"""Gait metrics from foot contacts: per-leg stride metrics, touchdown phases vs FR, the gait's
name.

Pure numpy (no ROS, no file I/O); the input is :func:`a1_leg_fk.gait.contacts.detect_contacts`'s
:class:`~a1_leg_fk.gait.contacts.Contacts`.

Metrics (:func:`gait_metrics`): per leg the stance intervals, duty factor (stance time over stride
time of the complete strides; strides off the leg's median period by more than half, such as a
pause to stand, are left out and counted as irregular), stride period and frequency (touchdown to
touchdown), step length (horizontal distance between consecutive touchdown positions, each the
median position of its stance), swing clearance (peak height of each complete swing above the
ground plane), the blips the phase rule removed (stances dropped, swings bridged); for the
robot, each leg's touchdown phase relative to FR's strides (0..1, circular mean, with its
consistency ``R`` in 0..1) and the gait named from the phases and the duty factor in Hildebrand's
terms (:mod:`a1_leg_fk.gait.naming`: limb phase, region, fit).
Times are in seconds from the first stamp.
"""

from __future__ import annotations

import itertools
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from a1_leg_fk.gait.contacts import Contacts, GroundPlane
from a1_leg_fk.gait.naming import GaitName, name_gait
from a1_leg_fk.gait.phases import Blips
from a1_leg_fk.gait.thresholds import ContactThresholds
from a1_leg_fk.model.legs import LEG_NAMES

USED_THRESHOLDS = ("height_on_m", "height_off_m", "speed_on_mps", "speed_off_mps")
"""The per-leg thresholds a report gives (derived from the data when adaptive)."""
IRREGULAR_STRIDE = 0.5
"""A stride longer or shorter than the leg's median by more than this fraction (a pause, a stumble)
is left out of the stride metrics and the phases, and counted as irregular."""


@dataclass(frozen=True)
class LegMetrics:
    """One leg's stride metrics; ``None`` where the data cannot give a value (``reason`` says
    why).
    """

    leg: str
    status: str  # "ok", "no data", "never touches down", "never lifts", "too few strides"
    stance_s: tuple[tuple[float, float], ...]
    strides: int  # complete, regular strides the metrics are computed from
    # touchdown-to-touchdown spans off the median period by more than half (e.g. a pause)
    irregular_strides: int
    duty_factor: float | None
    stride_period_s: float | None
    stride_frequency_hz: float | None
    step_length_m: float | None
    clearance_m: float | None
    reason: str | None = None
    # runs shorter than min_phase_s the phase rule removed: stances dropped, swings bridged
    blips_dropped: int = 0
    blips_bridged: int = 0
    # the regular strides the metrics are computed from: (touchdown, next touchdown) [s]
    strides_s: tuple[tuple[float, float], ...] = ()


@dataclass(frozen=True)
class GaitReport:
    """The gait of a recording: name, fit, per-leg metrics, phases, and what they were computed
    with.
    """

    gait: str
    gait_fit: float  # 0..1: template match x phase consistency
    gait_reason: str
    candidates: dict[str, float]  # fit of each gait name
    legs: dict[str, LegMetrics]
    phase_vs_fr: dict[str, float | None]  # touchdown phase of FL, RR, RL in FR's stride, 0..1
    phase_consistency: dict[str, float | None]
    duty_factor: float | None  # mean over legs with one
    ground: GroundPlane
    thresholds: ContactThresholds  # as configured
    notes: tuple[str, ...] = field(default=())
    naming: GaitName | None = None  # region, limb phase, symmetry (gait_naming)
    leg_thresholds: tuple[ContactThresholds, ...] = ()  # what each leg was judged by

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict without NaN or infinity (missing values are ``None`` with a
        ``reason``).
        """
        legs = {}
        for leg, metrics in self.legs.items():
            entry = {key: value for key, value in asdict(metrics).items() if key != "leg"}
            for key in ("stance_s", "strides_s"):
                entry[key] = [[round(a, 6), round(b, 6)] for a, b in getattr(metrics, key)]
            if entry["reason"] is None:
                del entry["reason"]
            legs[leg] = entry
        return {
            "gait": self.gait,
            "gait_fit": self.gait_fit,
            "gait_reason": self.gait_reason,
            "gait_candidates": self.candidates,
            "duty_factor": self.duty_factor,
            "legs": legs,
            "phase_vs_FR": self.phase_vs_fr,
            "phase_consistency": self.phase_consistency,
            "ground_level_m": self.ground.level_m,
            "ground_plane": {
                "origin_xy_m": list(self.ground.origin_xy),
                "slope_dz_dxy": list(self.ground.slope),
                "slope_deg": self.ground.slope_deg,
            },
            "thresholds": asdict(self.thresholds),
            "thresholds_used": {
                leg: {key: getattr(used, key) for key in USED_THRESHOLDS}
                for leg, used in zip(LEG_NAMES, self.leg_thresholds)
            },
            "gait_region": self.naming.region if self.naming else "",
            "gait_symmetric": self.naming.symmetric if self.naming else None,
            "limb_phase": self.naming.limb_phase if self.naming else None,
            "limb_phase_left": self.naming.limb_phase_left if self.naming else None,
            "limb_phase_right": self.naming.limb_phase_right if self.naming else None,
            "notes": list(self.notes),
        }


# --- metrics -----------------------------------------------------------------------------------


def _leg_metrics(contacts: Contacts, slot: int) -> tuple[LegMetrics, list[tuple[float, float]]]:
    """The leg's metrics and its complete strides ``(touchdown, next touchdown)`` [s]."""
    leg = LEG_NAMES[slot]
    stances = contacts.stances[slot]
    intervals = tuple((s.t_on, s.t_off) for s in stances)
    valid = contacts.valid[:, slot]
    in_stance = contacts.stance[:, slot] & valid

    blips = contacts.blips[slot] if contacts.blips else Blips()

    def without_strides(
        status: str,
        reason: str,
        duty_factor: float | None = None,
        clearance_m: float | None = None,
    ) -> LegMetrics:
        return LegMetrics(
            leg,
            status,
            intervals,
            0,
            0,
            duty_factor,
            None,
            None,
            None,
            clearance_m,
            reason,
            blips.dropped,
            blips.bridged,
        )

    if not valid.any():
        return without_strides("no data", "no finite position of this foot"), []
    if not in_stance.any():
        return without_strides(
            "never touches down", "the foot is never near the ground and still", duty_factor=0.0
        ), []
    if not (valid & ~in_stance).any():
        return without_strides(
            "never lifts", "the foot is in stance in every sample", duty_factor=1.0
        ), []
    strides, stance_times, steps, clearances = [], [], [], []
    footholds = [  # horizontal, world frame [m]
        np.median(contacts.positions_m[s.first : s.last + 1, slot, :2], axis=0) for s in stances
    ]
    for (this, following), (start, end) in zip(
        itertools.pairwise(stances), itertools.pairwise(footholds)
    ):
        if this.segment != following.segment:
            continue
        clearances.append(float(np.max(contacts.heights_m[this.last + 1 : following.first, slot])))
        if this.touchdown_observed:
            strides.append((this.t_on, following.t_on))
            stance_times.append(this.t_off - this.t_on)
            steps.append(float(np.linalg.norm(end - start)))
    clearance = float(np.mean(clearances)) if clearances else None
    if not strides:
        return without_strides(
            "too few strides",
            "fewer than two touchdowns in one gap-free stretch",
            clearance_m=clearance,
        ), []
    durations = np.array([b - a for a, b in strides])
    regular = np.abs(durations / np.median(durations) - 1.0) <= IRREGULAR_STRIDE
    kept = [stride for stride, keep in zip(strides, regular) if keep]
    if not kept:  # an even count of strides can leave none near its median (0.5 s and 1.5 s)
        return without_strides(
            "irregular strides",
            f"no stride within {IRREGULAR_STRIDE:.0%} of the median stride period",
            clearance_m=clearance,
        ), []
    stride_time = float(durations[regular].sum())
    period = stride_time / len(kept)
    metrics = LegMetrics(
        leg,
        "ok",
        intervals,
        len(kept),
        int((~regular).sum()),
        float(np.array(stance_times)[regular].sum() / stride_time),
        period,
        1.0 / period,
        float(np.array(steps)[regular].mean()),
        clearance,
        None,
        blips.dropped,
        blips.bridged,
        tuple(kept),
    )
    return metrics, kept


def _circular_mean(phases: list[float]) -> tuple[float, float]:
    """(mean phase in [0, 1), consistency R in [0, 1]) of phases in cycles."""
    vector = np.exp(2j * np.pi * np.asarray(phases)).mean()
    return float(np.angle(vector) / (2 * np.pi) % 1.0), float(abs(vector))


def relative_phases(
    contacts: Contacts, fr_strides: list[tuple[float, float]]
) -> tuple[dict[str, float | None], dict[str, float | None]]:
    """Touchdown phase of FL, RR, RL within FR's strides (0..1) and its consistency R, ``None``
    without data.
    """
    phases: dict[str, float | None] = {}
    consistency: dict[str, float | None] = {}
    starts = np.array([a for a, _ in fr_strides])
    for slot, leg in enumerate(LEG_NAMES[1:], start=1):
        found = []
        for stance in contacts.stances[slot]:
            if not stance.touchdown_observed or not fr_strides:
                continue
            k = int(np.searchsorted(starts, stance.t_on, side="right")) - 1
            if k >= 0 and stance.t_on < fr_strides[k][1]:
                a, b = fr_strides[k]
                found.append((stance.t_on - a) / (b - a))
        phases[leg], consistency[leg] = _circular_mean(found) if found else (None, None)
    return phases, consistency


def gait_metrics(contacts: Contacts) -> GaitReport:
    """Per-leg metrics, phases vs FR and the gait's name from :func:`detect_contacts`'s result."""
    results = [_leg_metrics(contacts, slot) for slot in range(len(LEG_NAMES))]
    legs = {metrics.leg: metrics for metrics, _ in results}
    duties = [
        m.duty_factor for m in legs.values() if m.status == "ok" and m.duty_factor is not None
    ]
    duty = float(np.mean(duties)) if duties else None
    phases, consistency = relative_phases(contacts, results[0][1])
    naming = name_gait(phases, consistency, duty)
    return GaitReport(
        naming.name,
        naming.fit,
        naming.reason,
        naming.candidates,
        legs,
        phases,
        consistency,
        duty,
        contacts.ground,
        contacts.thresholds,
        contacts.notes,
        naming,
        contacts.leg_thresholds,
    )
