"""Contacts estimated on a simulated run, scored against PyBullet's: the judge of the contact
tests (test/estimation/test_contact_family.py) and of ``bench/contact_family.py``.

Truth has one definition: a foot is in contact while PyBullet's normal force on it is > 0
(``ContactRun.contacts``). Only the gait proper is scored (``ContactRun.gait``), not the settling
before it. The estimates run through :class:`~a1_leg_fk.estimation.contact_estimator.
ContactEstimator`, the pipeline of the node and the bag tools; the old rule (quasi-static forces
through the fixed-threshold hysteresis) is scored beside it on the same samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from contact_runs import ContactRun
from pybullet_sim import rotation_matrices

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.estimation.contact_smoother import EvidenceRows, FixedLagSmoother
from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_forces
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped

FORCE, KINEMATIC, OLD_RULE = "force", "kinematic", "old rule"


@dataclass(frozen=True)
class Score:
    """One run under one evidence: shares of the gait's foot-samples [%], event delays [ms],
    the normal force's RMS error in stance [% of the weight] and each foot's duty factor,
    estimated and true.
    """

    agree_pct: float
    swing_as_stance_pct: float
    stance_as_swing_pct: float
    touchdown_ms: float
    liftoff_ms: float
    stance_force_pct: float
    duty: np.ndarray
    true_duty: np.ndarray

    def row(self, name: str, evidence: str) -> str:
        """One line of the table."""
        return (
            f"{name:22s} {evidence:9s} {self.agree_pct:6.2f} {self.swing_as_stance_pct:6.2f} "
            f"{self.stance_as_swing_pct:6.2f} {self.touchdown_ms:6.1f} {self.liftoff_ms:6.1f} "
            f"{self.stance_force_pct:6.2f} {np.abs(self.duty - self.true_duty).max():6.3f}"
        )


HEADER = (
    f"{'run':22s} {'evidence':9s} {'agree%':>6s} {'sw>st%':>6s} {'st>sw%':>6s} {'td ms':>6s} "
    f"{'lo ms':>6s} {'F rms%':>6s} {'duty':>6s}"
)


def robot_of(run: ContactRun) -> Quadruped:
    """The run's robot, loaded from the description PyBullet simulated."""
    return Quadruped.from_urdf(run.urdf_path)


def estimate(
    run: ContactRun,
    quadruped: Quadruped,
    evidence: str,
    smoothed: bool = False,
    **options: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) probabilities of stance and normal forces [N] of one evidence over the run: the
    causal filter's, or ``smoothed`` over the whole run (the filter's evidence through
    :class:`~a1_leg_fk.estimation.contact_smoother.FixedLagSmoother` in one block, as
    ``a1-leg-fk bag`` does it);
    ``options``: the estimator's keywords.
    """
    rotations = rotation_matrices(run.quaternions)
    gravity = np.einsum("nji,j->ni", rotations, [0.0, 0.0, -STANDARD_GRAVITY])
    if evidence == OLD_RULE:
        statics = FootForces(quadruped)
        normal = normal_forces(
            statics.estimate_batch(run.angles, run.torques, gravity).forces, gravity
        )
        rule = ContactRule(ContactThresholds.for_weight(statics.total_mass_kg * STANDARD_GRAVITY))
        return rule.update_batch(normal), normal
    estimator = ContactEstimator(quadruped, **options)
    feet = quadruped.fk_batch(run.angles)
    velocities = quadruped.foot_velocities_batch(run.angles, run.rates)
    probabilities, normals = np.empty((len(run.stamps_s), 4)), np.empty((len(run.stamps_s), 4))
    kept = []
    for n, stamp in enumerate(run.stamps_s.tolist()):
        step = estimator.step(
            stamp,
            (run.angles[n].tolist(), run.rates[n].tolist(),
             run.torques[n].tolist() if evidence == FORCE else None),
            [(feet[n, leg].tolist(), velocities[n, leg].tolist()) for leg in range(4)],
            ImuSample(gravity[n].tolist(), run.gyro[n].tolist(), run.specific_force[n].tolist()),
        )  # fmt: skip
        probabilities[n], normals[n] = step.probabilities, step.normals
        kept.append(estimator.filter.evidence)
    if smoothed:
        switch, kinematic, forced, total, heights = (np.array(c) for c in zip(*kept, strict=True))
        rows = EvidenceRows(run.stamps_s, switch, kinematic, forced, total, normals, heights)
        smoother = FixedLagSmoother(force_lag_s=estimator.force_lag_s)
        smoother.add(rows)
        probabilities = smoother.take(len(run.stamps_s))
    return probabilities, normals


def score(
    run: ContactRun, probabilities: np.ndarray, normals: np.ndarray, weight_n: float
) -> Score:
    """The :class:`Score` of (N, 4) probabilities of stance and normal forces [N]."""
    gait = run.gait
    truth, stance = run.contacts[gait], probabilities[gait] >= 0.5
    stamps = run.stamps_s[gait]
    in_stance = truth & np.isfinite(normals[gait])
    error = normals[gait][in_stance] - run.normal_forces[gait][in_stance]
    return Score(
        100.0 * float((stance == truth).mean()),
        100.0 * float((stance & ~truth).mean()),
        100.0 * float((~stance & truth).mean()),
        _median_delay_ms(stamps, truth, stance, rising=True),
        _median_delay_ms(stamps, truth, stance, rising=False),
        100.0 * float(np.sqrt(np.mean(error**2))) / weight_n if error.size else math.nan,
        stance.mean(axis=0),
        truth.mean(axis=0),
    )


def _median_delay_ms(
    stamps: np.ndarray, truth: np.ndarray, stance: np.ndarray, rising: bool
) -> float:
    """The median over true touchdowns (``rising``) or liftoffs of the time [ms] from the true
    event to the estimate's nearest same event (either side); inf if there is none.
    """
    delays: list[float] = []
    for leg in range(truth.shape[1]):
        true_events = _events(stamps, truth[:, leg], rising)
        estimated = _events(stamps, stance[:, leg], rising)
        if not estimated.size:
            return math.inf
        delays.extend(np.abs(estimated - event).min() for event in true_events)
    return 1000.0 * float(np.median(delays)) if delays else math.nan


def _events(stamps: np.ndarray, state: np.ndarray, rising: bool) -> np.ndarray:
    """Stamps [s] where ``state`` turns on (``rising``) or off."""
    change = np.flatnonzero(np.diff(state.astype(np.int8)) == (1 if rising else -1)) + 1
    return stamps[change]
