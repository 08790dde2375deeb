"""The gait analysis (``a1-leg-fk gait``'s pipeline) on a contact-family run, scored against
PyBullet's contacts: the judge of test/gait/test_gait_family.py.

The feet are those the gait command reads: our FK of the joint angles, placed in the world by the
run's true base pose. The stance is the contact estimate's (``ContactEstimator``, probability >=
0.5) with the joints' efforts (``force``: what ``gait --contacts auto`` takes when they are
recorded) or without (``kinematic``), or the gait's own kinematic detector (``feet``: ``gait
--contacts kinematic``, and ``auto`` without efforts).

Truth is PyBullet's: a foot is in contact while its normal force is > 0. Every leg is scored over
its own complete true strides (first to last true touchdown of the gait proper; a bounce, a swing
shorter than ``contact_runs.BLIP_S``, is no touchdown). The gait report's duty factor is compared
with PyBullet's over that span, and with the estimate's own (the share of its samples with
probability >= 0.5 over the same span).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from contact_runs import BLIP_S, ContactRun
from contact_scoring import estimate, robot_of
from pybullet_sim import rotation_matrices

from a1_leg_fk.gait.analysis import Blips, GaitReport, detect_contacts, gait_metrics
from a1_leg_fk.gait.force_contacts import with_force_stance
from a1_leg_fk.model.legs import LEG_NAMES

REGULAR_STRIDE = 0.5
"""A true stride off the leg's median period by more than this fraction (the first step of a
walk from standing) is not scored: the gait report leaves such strides out of its duty factors."""
EVENT_MARGIN_S = 0.02
"""A report's stance counts in a true stride if it touches down at most this early [s]."""
FEET = "feet"
"""The gait's own kinematic contacts (heights and speeds of the world feet)."""


@dataclass(frozen=True)
class GaitScore:
    """One run under one evidence, per leg (FR, FL, RR, RL): duty factors (the gait report's,
    PyBullet's, the estimate's), the median touchdown and lift-off errors [ms] over the run's true
    events (every leg's together: the issue's goal, as test/contact_scoring.py scores the
    estimate's) and the worst leg's own median, the report's stances per true stride, and the
    blips the minimum-phase rule removed.
    """

    duty: np.ndarray
    true_duty: np.ndarray
    estimate_duty: np.ndarray | None  # None for FEET: no estimate
    touchdown_ms: float
    liftoff_ms: float
    worst_leg_ms: tuple[float, float]  # (touchdown, lift-off): the largest of the legs' medians
    stances_per_stride: float
    blips: tuple[Blips, ...]

    def row(self, name: str, evidence: str) -> str:
        """One line of the table."""
        versus = (
            "    - "
            if self.estimate_duty is None
            else f"{np.abs(self.duty - self.estimate_duty).max():6.3f}"
        )
        dropped = sum(b.dropped for b in self.blips)
        bridged = sum(b.bridged for b in self.blips)
        return (
            f"{name:22s} {evidence:9s} {np.abs(self.duty - self.true_duty).max():6.3f} {versus} "
            f"{self.touchdown_ms:6.1f} {self.liftoff_ms:6.1f} {self.worst_leg_ms[0]:6.1f} "
            f"{self.worst_leg_ms[1]:6.1f} {self.stances_per_stride:6.3f} "
            f"{dropped:5d} {bridged:5d}"
        )


HEADER = (
    f"{'run':22s} {'evidence':9s} {'|d-pb|':>6s} {'|d-e|':>6s} {'td ms':>6s} {'lo ms':>6s} "
    f"{'td leg':>6s} {'lo leg':>6s} "
    f"{'st/str':>6s} {'drop':>5s} {'bridg':>5s}"
)


def world_feet(run: ContactRun) -> np.ndarray:
    """(N, 4, 3) [m] the feet in the world: our FK placed by the run's true base pose."""
    base_feet = robot_of(run).fk_batch(run.angles)
    rotations = rotation_matrices(run.quaternions)
    return run.base_positions[:, None, :] + np.einsum("nij,nlj->nli", rotations, base_feet)


def gait_of(
    run: ContactRun, evidence: str, smoothed: bool = True
) -> tuple[GaitReport, np.ndarray | None, tuple]:
    """The gait report of the run under ``evidence``, the estimate's (N, 4) probabilities (None
    for :data:`FEET`) and the per-leg blips; the estimate ``smoothed`` over the run (``gait``'s
    default on a recording) or the causal filter's (``gait --causal``)."""
    contacts = detect_contacts(run.stamps_s, world_feet(run))
    probabilities = None
    if evidence != FEET:
        probabilities, _ = estimate(run, robot_of(run), evidence, smoothed=smoothed)
        contacts = with_force_stance(contacts, run.stamps_s, probabilities)
    return gait_metrics(contacts), probabilities, contacts.blips


def true_contacts(run: ContactRun, leg: int) -> np.ndarray:
    """(N,) bool: the leg's true contact with its bounces (swings shorter than ``BLIP_S``
    between two contacts) filled."""
    contact = run.contacts[:, leg].copy()
    edges = np.flatnonzero(np.diff(contact.astype(np.int8))) + 1
    for start, end in itertools.pairwise(edges):
        if not contact[start] and run.stamps_s[end] - run.stamps_s[start] < BLIP_S:
            contact[start:end] = True
    return contact


def events(times: np.ndarray, state: np.ndarray, rising: bool) -> np.ndarray:
    """Times [s] where ``state`` turns on (``rising``) or off, midway between the samples."""
    change = np.flatnonzero(np.diff(state.astype(np.int8)) == (1 if rising else -1)) + 1
    return 0.5 * (times[change - 1] + times[change])


def _errors_ms(true: list[float], found: list[float]) -> np.ndarray:
    """Per ``true`` event time [s], the distance to the nearest ``found`` [ms] (inf: none)."""
    if not found:
        return np.full(max(len(true), 1), np.inf)
    nearest = np.abs(np.subtract.outer(np.array(true), np.array(found))).min(axis=1)
    return 1000.0 * nearest


def _median(errors: np.ndarray) -> float:
    """The median [ms] of event errors (inf if any leg found none)."""
    return float(np.median(errors)) if np.isfinite(errors).all() else float("inf")


def score_gait(run: ContactRun, evidence: str, smoothed: bool = True) -> GaitScore:
    """The run's :class:`GaitScore` under ``evidence``: ``force``, ``kinematic`` or
    :data:`FEET`; the estimate ``smoothed`` (the default, as ``gait`` runs on a recording) or
    causal (``gait --causal``)."""
    report, probabilities, blips = gait_of(run, evidence, smoothed)
    times = run.stamps_s - run.stamps_s[0]
    gait = run.gait
    duty, true_duty, estimate_duty = np.zeros(4), np.zeros(4), np.zeros(4)
    touchdown_errors, liftoff_errors, stances, strides = [], [], 0, 0
    for leg, name in enumerate(LEG_NAMES):
        metrics = report.legs[name]
        duty[leg] = np.nan if metrics.duty_factor is None else metrics.duty_factor
        truth = true_contacts(run, leg)
        downs = events(times[gait], truth[gait], rising=True)
        ups = events(times[gait], truth[gait], rising=False)
        periods = np.diff(downs)
        regular = np.abs(periods / np.median(periods) - 1.0) <= REGULAR_STRIDE
        span = np.zeros(times.size, dtype=bool)
        for start, end in zip(downs[:-1][regular], downs[1:][regular]):
            span |= (times >= start) & (times < end)
        true_duty[leg] = run.contacts[span, leg].mean()
        if probabilities is not None:  # over the strides the report's duty is computed from
            used = np.zeros(times.size, dtype=bool)
            for start, end in metrics.strides_s:
                used |= (times >= start) & (times < end)
            estimate_duty[leg] = (probabilities[used, leg] >= 0.5).mean()
        ons = [a for a, _ in metrics.stance_s]
        offs = [b for _, b in metrics.stance_s]
        touchdown_errors.append(_errors_ms(downs.tolist(), ons))
        inside = (ups > downs[0]) & (ups < downs[-1])
        liftoff_errors.append(_errors_ms(ups[inside].tolist(), offs))
        for start, end in zip(downs[:-1][regular], downs[1:][regular]):
            stances += sum(start - EVENT_MARGIN_S <= a < end - EVENT_MARGIN_S for a in ons)
        strides += int(regular.sum())
    return GaitScore(
        duty,
        true_duty,
        None if probabilities is None else estimate_duty,
        _median(np.concatenate(touchdown_errors)),
        _median(np.concatenate(liftoff_errors)),
        (
            max(_median(errors) for errors in touchdown_errors),
            max(_median(errors) for errors in liftoff_errors),
        ),
        stances / strides,
        blips,
    )
