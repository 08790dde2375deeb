"""Foot forces and contact probabilities per joint state, the one pipeline of the node
(``foot_fk_node``'s ``foot_forces/<leg>`` and ``foot_contacts``) and the bag tools (``a1-leg-fk
bag --forces/--contacts``, ``gait``), without ROS.

Per joint state: the foot forces [N, base frame] from the efforts, by the legs' dynamics
(:mod:`a1_leg_fk.estimation.momentum_observer`, ``force_model="dynamic"``, the default) or
quasi-statically (:mod:`a1_leg_fk.kinematics.foot_forces`, ``"static"``); their normal parts
along minus gravity; and each foot's probability of stance from the contact filter
(:mod:`a1_leg_fk.estimation.contact_filter`), which fuses the normal force (where there is one)
with the feet's heights and speeds (:mod:`a1_leg_fk.estimation.leg_motion`). A joint state without
efforts still gets its contacts, from the kinematic evidence alone; :attr:`ContactEstimator.counts`
says how many samples had which evidence.

The IMU, when there is one, gives gravity's direction (its orientation), the base's angular
velocity (its gyro) and its specific force (accelerometer); each may be missing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from a1_leg_fk.estimation.contact_filter import ContactFilter
from a1_leg_fk.estimation.contact_model import ContactModel
from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_force
from a1_leg_fk.estimation.correction_file import read_correction_file
from a1_leg_fk.estimation.effort_timing import EffortTiming
from a1_leg_fk.estimation.force_lag import LagTails
from a1_leg_fk.estimation.leg_motion import FootMotion, LegMotion
from a1_leg_fk.estimation.model_corrections import (
    DEFAULT_MODEL_CORRECTIONS,
    MODEL_CORRECTIONS,
    ONLINE,
    CorrectionSettings,
    ModelCorrections,
)
from a1_leg_fk.estimation.momentum_observer import NO_ROTATION, MomentumObserver
from a1_leg_fk.kinematics.foot_forces import LEVEL_GRAVITY, FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

DYNAMIC, STATIC = "dynamic", "static"
FORCE_MODELS = (DYNAMIC, STATIC)
FILTER, THRESHOLD = "filter", "threshold"
CONTACT_RULES = (FILTER, THRESHOLD)
"""The fused filter (default), or the normal force's hysteresis between two thresholds
(:class:`~a1_leg_fk.estimation.contacts.ContactRule`; no contacts without efforts)."""
LEGS = len(LEG_NAMES)
Vector = tuple[float, float, float]


@dataclass(frozen=True)
class ImuSample:
    """What the IMU (aligned with the base, at its origin) says at a joint state, base frame:
    gravity [m/s^2] (from the orientation; None: the base taken as level), angular velocity
    [rad/s] and specific force [m/s^2] (None: unknown).
    """

    gravity: Sequence[float] | None = None
    angular_velocity: Sequence[float] | None = None
    specific_force: Sequence[float] | None = None


@dataclass
class EvidenceCounts:
    """Joint states whose contacts fused a force with the kinematics, and those with the
    kinematics alone (no efforts).
    """

    force: int = 0
    kinematic: int = 0

    def line(self) -> str:
        """The counts in words (summaries and diagnostics)."""
        return (
            f"evidence:  force + kinematic for {self.force} samples, kinematic evidence alone "
            f"for {self.kinematic}"
        )


class ContactStep(NamedTuple):
    """One joint state's result: 4 forces [N, base frame] (NaN: none), 4 normal forces [N]
    along minus gravity, 4 probabilities of stance, per leg whether its values were missing and
    whether its Jacobian was near singular, and each foot's motion (:class:`FootMotion`, None:
    unknown, or the threshold rule, which needs none).
    """

    forces: list[list[float]]
    normals: list[float]
    probabilities: list[float]
    missing: list[bool]
    singular: list[bool]
    motions: list[FootMotion | None]


class ContactEstimator:
    """Forces and contacts of one robot, stepped with each joint state in time order."""

    def __init__(
        self,
        quadruped: Quadruped,
        force_model: str = DYNAMIC,
        contact_rule: str = FILTER,
        thresholds: tuple[float | None, float | None] = (None, None),
        model_corrections: str = DEFAULT_MODEL_CORRECTIONS,
    ) -> None:
        """``force_model``: ``"dynamic"`` or ``"static"``; ``contact_rule``: ``"filter"`` (its
        scales :meth:`ContactModel.for_robot` of the URDF's weight and leg length) or
        ``"threshold"`` (touchdown and liftoff normal forces ``thresholds`` [N], None for
        :meth:`ContactThresholds.for_weight`'s defaults); ``model_corrections``: ``"online"``
        learns and takes off the joints' friction and bias and the legs' inertia scales
        (:mod:`a1_leg_fk.estimation.model_corrections`; the dynamic force model and the filter
        only), ``"off"``, or the path of a calibration's file
        (:mod:`a1_leg_fk.estimation.correction_file`: its terms and scales taken off as they
        are, its payload added to the URDF's weight, its efforts' scale and latency undone:
        :mod:`a1_leg_fk.estimation.effort_timing`).
        """
        for name, value, choices in (
            ("force model", force_model, FORCE_MODELS),
            ("contact rule", contact_rule, CONTACT_RULES),
        ):
            if value not in choices:
                raise LegFkError(f"{name} must be one of {', '.join(choices)}: {value!r}")
        self.force_model, self.contact_rule = force_model, contact_rule
        self.model_corrections = model_corrections
        self.statics = FootForces(quadruped)
        self.calibration = (
            None
            if model_corrections in MODEL_CORRECTIONS
            else read_correction_file(
                model_corrections, quadruped.joint_names, self.statics.total_mass_kg
            )
        )
        """The calibration's file (None: online or off)."""
        self.correction_settings: CorrectionSettings | None = None
        """The online corrections' settings from the next :meth:`reset` (None: the defaults;
        a calibration learns without forgetting)."""
        calibration = self.calibration
        self.timing = (
            EffortTiming()
            if calibration is None
            else EffortTiming(calibration.effort_scale, calibration.effort_latency_s)
        )
        """The efforts' scale and latency the calibration's file gives (none: 1 and 0)."""
        self.observer = MomentumObserver(quadruped) if force_model == DYNAMIC else None
        self.motion = LegMotion(quadruped)
        payload = self.calibration.payload_kg if self.calibration is not None else 0.0
        weight = (self.statics.total_mass_kg + payload) * STANDARD_GRAVITY
        self.model = ContactModel.for_robot(weight, leg_length_m(quadruped))
        self.tails = LagTails(self.force_lag_s, self.model.force_half_n)
        """The filter's force evidence: the observer's lag undone where a loaded foot lets go."""
        self.rule = ContactRule(ContactThresholds.for_weight(weight, *thresholds))
        self.reset()

    def reset(self) -> None:
        """Forget the past (a new pass over a recording): every foot at even odds (in swing for
        the threshold rule), the observers restarting, the counts zero.
        """
        if self.observer is not None:
            self.observer.reset()
            self.observer.corrections = None
            if self.calibration is not None:
                self.observer.corrections = ModelCorrections(
                    fixed=self.calibration.terms, scales=self.calibration.inertia_scales
                )
            elif self.model_corrections == ONLINE and self.contact_rule == FILTER:
                self.observer.corrections = ModelCorrections(self.correction_settings)
        self.filter = ContactFilter(self.model)
        self.tails.reset()
        self.timing.reset()
        self.rule = ContactRule(self.rule.thresholds)
        self.counts = EvidenceCounts()
        self._stamp_s = math.nan

    def step(
        self,
        stamp_s: float,
        joints: tuple[Sequence[float], Sequence[float], Sequence[float] | None],
        feet: Sequence[tuple[Sequence[float], Sequence[float]] | None],
        imu: ImuSample,
        phase_prior: Sequence[float] | None = None,
    ) -> ContactStep:
        """One joint state at ``stamp_s`` [s]: ``joints`` the 12 angles [rad], rates [rad/s] and
        efforts [N m] (slot order, NaN where unknown; efforts None: none); ``feet`` per leg its
        position [m] and velocity ``J q_dot`` [m/s], base frame (None: unknown; a NaN velocity
        gives that foot no speed evidence); ``phase_prior``: a gait scheduler's probability of
        stance per foot (None: none), evidence for the filter.
        """
        angles, rates, efforts = joints
        if efforts is not None and not self.timing.identity:
            efforts = self.timing.efforts(stamp_s, efforts)
            joints = (angles, rates, efforts)
        gravity = LEVEL_GRAVITY if imu.gravity is None else imu.gravity
        gx, gy, gz = gravity
        norm = math.sqrt(gx * gx + gy * gy + gz * gz)
        down: Vector = (gx / norm, gy / norm, gz / norm)
        forces, missing, singular = self._forces(stamp_s, joints, gravity, imu)
        normals = [math.nan] * LEGS  # none without efforts
        if efforts is not None:
            normals = [normal_force(force, down) for force in forces]
        if self.contact_rule == THRESHOLD:
            probabilities = self.rule.update(normals) if efforts is not None else [math.nan] * LEGS
            return ContactStep(forces, normals, probabilities, missing, singular, [None] * LEGS)
        foot, n = self.motion.foot, JOINTS_PER_LEG
        motions = [
            None if leg_foot is None or not _finite(leg_foot[0])
            else foot(leg, angles[n * leg : n * leg + n], rates[n * leg : n * leg + n],
                      leg_foot[0], leg_foot[1], down)
            for leg, leg_foot in enumerate(feet)
        ]  # fmt: skip
        dt = stamp_s - self._stamp_s
        self._stamp_s = stamp_s if not dt < 0.0 else self._stamp_s
        with_force = efforts is not None and any(n == n for n in normals)  # noqa: PLR0124 (NaN)
        evidence = None  # the filter's forces: none without efforts
        if with_force:
            self.counts.force += 1
            evidence = self.tails.evidence(dt, normals)
        else:
            self.counts.kinematic += 1
            self.tails.reset()
        probabilities = self.filter.update(
            dt if math.isfinite(dt) else 0.0,
            motions,
            (imu.angular_velocity or NO_ROTATION, imu.specific_force),
            evidence,
            phase_prior,
            down=down,
        )
        corrections = self.corrections
        if corrections is not None and with_force:
            corrections.learn(dt, probabilities, motions, self.model.height_half_m)
        return ContactStep(forces, normals, probabilities, missing, singular, motions)

    @property
    def force_lag_s(self) -> float:
        """[s] The time constant of the lag of the normal forces it gives: the momentum
        observer's ``1 / K`` (0 with the statics).
        """
        return 0.0 if self.observer is None else 1.0 / self.observer.gain_per_s

    @property
    def corrections(self) -> ModelCorrections | None:
        """The model's online corrections (None: off)."""
        return None if self.observer is None else self.observer.corrections

    def _forces(
        self,
        stamp_s: float,
        joints: tuple[Sequence[float], Sequence[float], Sequence[float] | None],
        gravity: Sequence[float],
        imu: ImuSample,
    ) -> tuple[list[list[float]], list[bool], list[bool]]:
        """The foot forces of the chosen model (all NaN without efforts)."""
        angles, rates, efforts = joints
        if efforts is None:
            return [[math.nan] * 3 for _ in range(LEGS)], [True] * LEGS, [False] * LEGS
        if self.observer is None:
            return self.statics.estimate_floats(angles, efforts, gravity)
        return self.observer.step_floats(
            stamp_s, (angles, rates, efforts), gravity, imu.specific_force, imu.angular_velocity
        )


def _finite(position: Sequence[float]) -> bool:
    """True when a foot's position [m] is known: all three coordinates finite."""
    isfinite = math.isfinite
    return isfinite(position[0]) and isfinite(position[1]) and isfinite(position[2])


def leg_length_m(quadruped: Quadruped) -> float:
    """The mean over the legs of thigh plus calf length [m]: the knee joint's distance from the
    hip-pitch joint plus the foot's from the knee.
    """
    lengths = [
        float(np.linalg.norm(leg.stages[2].offset) + np.linalg.norm(leg.foot_offset))
        for leg in quadruped.legs
    ]
    return sum(lengths) / len(lengths)
