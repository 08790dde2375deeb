"""Foot forces and contacts one joint state at a time, the pass that the node (``foot_fk_node``'s
``foot_forces/<leg>`` and ``foot_contacts``) and the bag tools (``a1-leg-fk bag --forces
--contacts``, ``gait``, through :class:`~a1_leg_fk.recording.forces.RecordingForces`) share:
:class:`~a1_leg_fk.estimation.contact_estimator.ContactEstimator` fed a JointState's angles, rates
and efforts by joint name, with the counts the summaries and diagnostics report.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.estimation.contact_estimator import (
    DYNAMIC,
    FILTER,
    ContactEstimator,
    ContactStep,
    ImuSample,
)
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.model.legs import JOINT_COUNT

if TYPE_CHECKING:
    from a1_leg_fk.kinematics.quadruped import Quadruped


@dataclass
class ForceCounts:
    """Legs of the rows of a pass: with a force, without (efforts missing or not finite, or a
    JointState whose effort array does not match its names), near-singular.
    """

    estimated: int = 0
    missing: int = 0
    singular: int = 0

    def line(self) -> str:
        """The summary line."""
        return (
            f"forces:    {self.estimated} leg forces; none for {self.missing} legs (efforts "
            f"missing, NaN or of the wrong length) and {self.singular} near-singular legs"
        )


class ForcePass:
    """Forces and contact probabilities row by row over one pass, the node's messages or a
    recording's rows alike (:class:`~a1_leg_fk.estimation.contact_estimator.ContactEstimator`:
    its state is carried from block to block).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        thresholds: tuple[float | None, float | None] = (None, None),
        force_model: str = DYNAMIC,
        contact_rule: str = FILTER,
        model_corrections: str = DEFAULT_MODEL_CORRECTIONS,
    ) -> None:
        """``thresholds``: touchdown and liftoff normal forces [N] of the ``"threshold"`` contact
        rule, ``None`` for the default (:meth:`ContactThresholds.for_weight` of the URDF's total
        mass); ``force_model``, ``contact_rule`` and ``model_corrections`` as the estimator
        takes them.
        """
        self.estimator = ContactEstimator(
            quadruped, force_model, contact_rule, thresholds, model_corrections
        )
        self.thresholds = self.estimator.rule.thresholds
        self.name_to_slot: Mapping[str, int] = quadruped.name_to_slot
        self.restart()

    def restart(self) -> None:
        """A new pass: the estimator's state and the counts anew."""
        self.estimator.reset()
        self.counts = ForceCounts()
        self._origin_ns: int | None = None

    def summary(self, forces: bool, motion: str | None = None) -> str:
        """The summary's lines (joined by newlines): the force counts (with ``forces``), and
        where the contacts came from: the rule, the force model, the evidence per sample and
        ``motion``, where the base's motion came from (None: none, the base taken as inertial).
        """
        estimator = self.estimator
        motion = motion or "none (the base taken as inertial)"
        forces_used = f" on {estimator.force_model} forces" if self.counts.estimated else ""
        rule = (
            f"contacts:  the {estimator.contact_rule} rule{forces_used}; the base's motion from "
            f"{motion}"
        )
        lines = [self.counts.line()] if forces else []
        if estimator.contact_rule == FILTER:
            lines += [rule, estimator.counts.line()]
            if estimator.corrections is not None:
                lines.append(estimator.corrections.line())
        else:
            lines.append(rule)
        return "\n".join(lines)

    def slot_efforts(self, names: Sequence[str], efforts: np.ndarray) -> np.ndarray:
        """(K, 12) efforts [N m] in slot order from the messages' (K, m) effort arrays; NaN for
        joints not named, and for every joint when ``m`` is not the number of names.
        """
        out = np.full((efforts.shape[0], JOINT_COUNT), math.nan)
        if efforts.shape[1] != len(names):
            return out
        known = [(i, self.name_to_slot.get(name)) for i, name in enumerate(names)]
        pairs = [(i, slot) for i, slot in known if slot is not None]
        if pairs:
            out[:, [slot for _, slot in pairs]] = efforts[:, [i for i, _ in pairs]]
        return out

    def message(
        self,
        stamp_ns: int,
        joints: tuple[Sequence[float], Sequence[float], Sequence[float] | None],
        feet: Sequence[tuple[Sequence[float], Sequence[float]] | None],
        imu: ImuSample,
        phase_prior: Sequence[float] | None = None,
    ) -> ContactStep:
        """:meth:`rows` for one joint state, on floats (the node's per-message path): the
        estimator's :class:`ContactStep` (4 forces [N, base frame], 4 normal forces [N], 4
        contact probabilities, the feet's motions), counted; ``phase_prior``: a gait scheduler's
        probability of stance per foot, as the estimator takes it.
        """
        if self._origin_ns is None:  # seconds since the first stamp: float64 keeps their ns
            self._origin_ns = stamp_ns
        stamp_s = (stamp_ns - self._origin_ns) * 1e-9
        step = self.estimator.step(stamp_s, joints, feet, imu, phase_prior)
        counts = self.counts
        counts.missing += sum(step.missing)
        counts.singular += sum(step.singular)
        counts.estimated += sum(1 for value in step.normals if value == value)  # noqa: PLR0124
        return step

    def message_efforts(self, names: Sequence[str], efforts: Sequence[float]) -> list[float]:
        """One message's efforts [N m] in slot order (as :meth:`slot_efforts`): NaN for joints
        not named, and for every joint when there are not as many efforts as names.
        """
        out = [math.nan] * JOINT_COUNT
        if len(efforts) == len(names):
            slots = self.name_to_slot
            for name, value in zip(names, efforts, strict=True):
                slot = slots.get(name)
                if slot is not None:
                    out[slot] = value
        return out
