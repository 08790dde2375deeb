"""Forward kinematics of the four feet: positions, Jacobians, foot velocities, limits and reach.

Everything expensive happens once, when a :class:`CompiledLeg` is made: the chain is folded into
three stages (:mod:`a1_leg_fk.kinematics.leg_stages`), which turn the whole leg into straight-line
arithmetic in the cosines and sines of its angles, generated once as Python source
(:mod:`a1_leg_fk.kinematics.fk_codegen`). The same source runs on floats (``math``, the per-message
path) and on numpy arrays (the batch path), so both compute exactly the same expression.

Frames and units: joint angles in rad, joint velocities in rad/s, positions in m and foot
velocities in m/s, all in the root link's frame (the base frame), relative to the base.
Configurations are 12 angles in :data:`a1_leg_fk.model.legs.LEG_NAMES` order, three per leg, root
side first (hip roll, hip pitch, knee for the A1).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from a1_leg_fk.kinematics.compiled_leg import BATCH_CHUNK_ROWS, Angles, CompiledLeg
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.ik import four_legs
from a1_leg_fk.kinematics.leg_stages import knee_circle
from a1_leg_fk.model.legs import (
    JOINT_COUNT,
    JOINTS_PER_LEG,
    LEG_NAMES,
    find_legs,
    joint_name_index,
    leg_slot,
)
from a1_leg_fk.model.urdf import Joint, LegFkError, RobotModel, load_urdf


@dataclass(frozen=True)
class Reach:
    """Distance [m] from a leg's hip-pitch axis to its foot over the knee's range [rad]."""

    leg: str
    min_m: float
    knee_at_min: float
    max_m: float
    knee_at_max: float
    max_unlimited_m: float  # over all knee angles, limits ignored (the straight leg)
    knee_at_max_unlimited: float


@dataclass(frozen=True)
class LimitViolation:
    """A joint angle [rad] outside the URDF's ``[lower, upper]``."""

    joint: str
    value: float
    lower: float
    upper: float


class Quadruped:
    """A quadruped's four legs, compiled from a URDF, with joint naming and limits.

    Build it with :meth:`from_urdf`; then :meth:`fk`, :meth:`fk_batch`, :meth:`jacobians`,
    :meth:`foot_velocities` and friends compute in the base frame (:attr:`base_frame`).
    """

    def __init__(
        self,
        model: RobotModel,
        foot_links: Mapping[str, str] | None = None,
        joint_aliases: Mapping[str, str] | None = None,
    ) -> None:
        self.model = model
        self.base_frame = model.root
        self.legs = tuple(CompiledLeg(chain) for chain in find_legs(model, foot_links))
        self._leg_positions = tuple(leg.position for leg in self.legs)
        self.joints: tuple[Joint, ...] = tuple(j for leg in self.legs for j in leg.chain.movable)
        self.joint_names = tuple(joint.name for joint in self.joints)
        self.name_to_slot: Mapping[str, int] = joint_name_index(
            tuple(leg.chain for leg in self.legs), joint_aliases
        )

    @classmethod
    def from_urdf(
        cls,
        source: str | None = None,
        foot_links: Mapping[str, str] | None = None,
        joint_aliases: Mapping[str, str] | None = None,
    ) -> Quadruped:
        """Load a URDF (path, XML string, or ``None`` for the embedded A1) and compile its legs."""
        return cls(load_urdf(source), foot_links, joint_aliases)

    def fk(self, angles: Angles) -> np.ndarray:
        """(4, 3) foot positions [m] in the base frame for 12 joint angles [rad]."""
        q = _quickly_checked_configuration(angles)
        fr, fl, rr, rl = self._leg_positions
        return np.array(
            (
                fr(q[0], q[1], q[2]),
                fl(q[3], q[4], q[5]),
                rr(q[6], q[7], q[8]),
                rl(q[9], q[10], q[11]),
            )
        )

    def fk_batch(self, angles: ArrayLike) -> np.ndarray:
        """(N, 4, 3) foot positions [m] for an (N, 12) array of joint angles [rad]."""
        q = _checked_batch(angles, "angles")
        out = np.empty((q.shape[0], len(LEG_NAMES), 3))
        for rows in _row_blocks(q.shape[0]):
            cos, sin = np.cos(q[rows]), np.sin(q[rows])
            for slot, leg in enumerate(self.legs):
                joints = _leg_columns(slot)
                leg.positions_batch(cos[:, joints], sin[:, joints], out[rows, slot])
        return out

    def foot_velocities(self, angles: Angles, rates: Angles) -> np.ndarray:
        """(4, 3) foot velocities [m/s], base frame, relative to the base: ``J(q) q_dot``."""
        q = _checked_configuration(angles)
        dq = _checked_configuration(rates, "joint velocities")
        out: list[float] = []
        for slot, leg in enumerate(self.legs):
            first = slot * JOINTS_PER_LEG
            out.extend(leg.position_velocity(*q[first : first + 3], *dq[first : first + 3])[3:])
        return np.array(out).reshape(len(LEG_NAMES), 3)

    def foot_velocities_batch(self, angles: ArrayLike, rates: ArrayLike) -> np.ndarray:
        """(N, 4, 3) foot velocities [m/s] for (N, 12) angles [rad] and rates [rad/s]."""
        q = _checked_batch(angles, "angles")
        dq = _checked_batch(rates, "joint velocities")
        if dq.shape != q.shape:
            raise LegFkError(f"joint velocities have shape {dq.shape}, angles {q.shape}")
        jacobians = self.jacobians_batch(q)
        velocities: np.ndarray = np.einsum(
            "nlij,nlj->nli", jacobians, dq.reshape(q.shape[0], len(LEG_NAMES), JOINTS_PER_LEG)
        )
        return velocities

    def jacobians(self, angles: Angles) -> np.ndarray:
        """(4, 3, 3): per leg, d(foot position [m]) / d(its three angles [rad]), base frame."""
        jacobians: np.ndarray = self.jacobians_batch(
            np.asarray(_checked_configuration(angles))[np.newaxis]
        )[0]
        return jacobians

    def jacobians_batch(self, angles: ArrayLike) -> np.ndarray:
        """(N, 4, 3, 3) Jacobians for an (N, 12) array of angles [rad]."""
        q = _checked_batch(angles, "angles")
        out = np.empty((q.shape[0], len(LEG_NAMES), 3, JOINTS_PER_LEG))
        for rows in _row_blocks(q.shape[0]):
            cos, sin = np.cos(q[rows]), np.sin(q[rows])
            for slot, leg in enumerate(self.legs):
                joints = _leg_columns(slot)
                leg.jacobians_batch(cos[:, joints], sin[:, joints], out[rows, slot])
        return out

    def angles_from_names(self, positions: Mapping[str, float]) -> list[float]:
        """The 12 angles [rad] in slot order from a ``{joint name: angle}`` dict naming all of
        them.
        """
        angles: list[float | None] = [None] * JOINT_COUNT
        for name, value in positions.items():
            slot = self.name_to_slot.get(name)
            if slot is None:
                raise LegFkError(
                    f"unknown joint name '{name}': not a leg joint of {self.model.source}"
                )
            angles[slot] = value
        missing = [self.joint_names[slot] for slot, value in enumerate(angles) if value is None]
        if missing:
            raise LegFkError(f"joint angles missing for {missing}")
        return _checked_configuration(cast("list[float]", angles))  # no None left (checked above)

    def joints_outside_limits(self, angles: Angles) -> list[LimitViolation]:
        """The joints whose angle [rad] lies outside their URDF limits (continuous joints have
        none).
        """
        q = _checked_configuration(angles)
        return [
            LimitViolation(joint.name, value, joint.lower, joint.upper)
            for joint, value in zip(self.joints, q)
            if joint.lower is not None
            and joint.upper is not None
            and not joint.lower <= value <= joint.upper
        ]

    @cached_property
    def _forces(self) -> FootForces:
        return FootForces(self)

    def foot_forces(
        self, angles: Angles, efforts: Angles, gravity_base: Sequence[float] | None = None
    ) -> np.ndarray:
        """(4, 3) the force [N] the ground exerts on each foot, base frame, from 12 joint angles
        [rad] and efforts [N m] (the torque each motor applies to its child link, as
        ``JointState.effort``), quasi-static; ``gravity_base`` [m/s^2] is gravity in the base
        frame (default: base level, ``(0, 0, -9.80665)``). A leg whose angles or efforts are
        not finite, or whose knee is near straight, is NaN. See
        :mod:`a1_leg_fk.kinematics.foot_forces`.
        """
        forces: np.ndarray = self._forces.estimate(angles, efforts, gravity_base).forces
        return forces

    def foot_forces_batch(
        self, angles: ArrayLike, efforts: ArrayLike, gravity_base: ArrayLike | None = None
    ) -> np.ndarray:
        """:meth:`foot_forces` for (N, 12) angles [rad] and efforts [N m], gravity (3,) or (N, 3)
        [m/s^2] in the base frame: (N, 4, 3) forces [N], NaN where a leg has none.
        """
        forces: np.ndarray = self._forces.estimate_batch(angles, efforts, gravity_base).forces
        return forces

    @cached_property
    def _ik_solvers(self) -> tuple[four_legs.LegSolver, ...]:
        return tuple(four_legs.LegSolver(leg) for leg in self.legs)

    def ik(self, feet: ArrayLike, seed: Angles | None = None) -> four_legs.IkResult:
        """Joint angles [rad] putting the four feet at ``feet`` ((4, 3) [m], base frame), with a
        status (``ok``, ``outside_limits``, ``unreachable``) and residual [m] per leg; ``seed``
        (12 angles [rad]) picks the solution nearest it (see
        :mod:`a1_leg_fk.kinematics.ik.four_legs`).
        """
        checked_seed = None if seed is None else _quickly_checked_configuration(seed, "seed")
        return four_legs.solve_feet(self._ik_solvers, _checked_feet(feet), checked_seed)

    def ik_batch(
        self, feet: np.ndarray, seed: np.ndarray | None = None
    ) -> four_legs.IkBatchResult:
        """:meth:`ik` for (N, 4, 3) targets [m] and (N, 12) seeds [rad]: (N, 12) angles, (N, 4)
        status codes (:data:`a1_leg_fk.kinematics.ik.four_legs.OK` ...), (N, 4) residuals [m].
        """
        targets = np.asarray(feet, dtype=np.float64)
        if targets.ndim != 3 or targets.shape[1:] != (len(LEG_NAMES), 3):
            raise LegFkError(f"feet must have shape (N, {len(LEG_NAMES)}, 3), got {targets.shape}")
        bad = ~np.isfinite(targets).all(axis=2)
        if bad.any():
            row, slot = (int(i) for i in np.argwhere(bad)[0])
            raise LegFkError(
                f"feet: leg {LEG_NAMES[slot]} of row {row} is not finite"
                f" ({bad.sum()} such targets)"
            )
        seeds = None if seed is None else _checked_batch(seed, "seed")
        if seeds is not None and seeds.shape[0] != targets.shape[0]:
            raise LegFkError(f"seed has {seeds.shape[0]} rows, feet {targets.shape[0]}")
        return four_legs.solve_feet_batch(self._ik_solvers, targets, seeds)

    def ik_leg(
        self, leg: str, point: Sequence[float], seed: Angles | None = None
    ) -> four_legs.LegIk:
        """:meth:`ik` of one leg: ``point`` [m, base frame], ``seed`` its 3 angles [rad] or
        ``None``.
        """
        checked_seed = (
            None
            if seed is None
            else _checked_configuration(seed, f"seed of leg {leg}", JOINTS_PER_LEG)
        )
        return self._ik_solvers[leg_slot(leg)].solve(
            four_legs.checked_point(point, leg), checked_seed
        )

    def ik_solutions(self, leg: str, point: Sequence[float]) -> list[four_legs.Solution]:
        """Every exact IK solution of ``leg`` for ``point`` [m, base frame] (for the A1 topology:
        up to two roll x two knee branches), each with whether it is inside the URDF limits.
        """
        return self._ik_solvers[leg_slot(leg)].solutions(four_legs.checked_point(point, leg))

    def reach(self, leg: str) -> Reach:
        """Distance from the leg's hip-pitch axis to its foot, over the knee's range.

        Defined for legs of the A1 topology, whose knee axis is parallel to the hip-pitch axis.
        """
        compiled = self.legs[leg_slot(leg)]
        pitch, knee = compiled.stages[1], compiled.stages[2]
        circle = knee_circle(pitch, knee, compiled.foot_offset)
        if circle is None:
            raise LegFkError(
                f"leg {leg}: knee axis is not parallel to the hip-pitch axis; reach is not defined"
            )
        alpha, beta, gamma = circle.alpha, circle.beta, circle.gamma

        def distance(angle: float) -> float:
            return math.sqrt(max(alpha + beta * math.cos(angle) + gamma * math.sin(angle), 0.0))

        lower, upper = knee.joint.lower, knee.joint.upper
        if lower is None or upper is None:
            lower, upper = -math.pi, math.pi
        peak = math.atan2(gamma, beta)
        candidates = [lower, upper] + [
            angle
            for base in (peak, peak + math.pi)
            for turn in range(-2, 3)
            if lower <= (angle := base + 2.0 * math.pi * turn) <= upper
        ]
        knee_at_min = min(candidates, key=distance)
        knee_at_max = max(candidates, key=distance)
        return Reach(
            leg,
            distance(knee_at_min),
            knee_at_min,
            distance(knee_at_max),
            knee_at_max,
            distance(peak),
            peak,
        )


def _checked_feet(feet: ArrayLike) -> list[float]:
    """The 12 coordinates [m] of (4, 3) finite targets, leg by leg, or a LegFkError naming the leg.

    Cheap for a (4, 3) float array, the common case: one ``tolist`` and one sum (a NaN or infinity
    makes the sum non-finite; only then is each leg examined).
    """
    try:
        targets = np.asarray(feet, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"feet must be {len(LEG_NAMES)} x 3 numbers: {error}") from error
    if targets.shape != (len(LEG_NAMES), 3):
        raise LegFkError(
            f"feet must have shape ({len(LEG_NAMES)}, 3) (legs {'/'.join(LEG_NAMES)}),"
            f" got {targets.shape}"
        )
    flat: list[float] = targets.ravel().tolist()
    if not math.isfinite(sum(flat)):
        for slot, leg in enumerate(LEG_NAMES):
            four_legs.checked_point(flat[3 * slot : 3 * slot + 3], leg)
    return flat


def _checked_configuration(
    angles: Angles, what: str = "joint angles", count: int = JOINT_COUNT
) -> list[float]:
    """``count`` (12) finite floats, or a LegFkError naming the problem."""
    try:
        q = [float(value) for value in angles]
    except (TypeError, ValueError, OverflowError) as error:
        raise LegFkError(f"{what} must be {count} numbers: {error}") from error
    if len(q) != count:
        per_leg = f" (3 per leg, {'/'.join(LEG_NAMES)})" if count == JOINT_COUNT else ""
        raise LegFkError(f"{what} must be {count} numbers{per_leg}, got {len(q)}")
    for slot, value in enumerate(q):
        if not math.isfinite(value) and count != JOINT_COUNT:
            raise LegFkError(f"{what}: joint {slot} is {value}")
        if not math.isfinite(value):
            leg = LEG_NAMES[slot // JOINTS_PER_LEG]
            raise LegFkError(
                f"{what}: slot {slot} (leg {leg}, joint {slot % JOINTS_PER_LEG}) is {value}"
            )
    return q


def _quickly_checked_configuration(angles: Angles, what: str = "joint angles") -> list[float]:
    """As :func:`_checked_configuration`, but cheap for 12 finite Python floats or ints.

    The common case costs a list copy and a sum: a NaN or infinity makes the sum non-finite, and
    only then is each value examined. (``math.isfinite`` measured as fast as ``x - x == 0.0``
    here, ratio 0.995.)
    """
    try:
        q = angles.tolist() if isinstance(angles, np.ndarray) else list(angles)
        total = sum(q)
        usable = len(q) == JOINT_COUNT and isinstance(total, (float, int)) and math.isfinite(total)
    except (TypeError, OverflowError):  # not numbers; an int too large for a float
        return _checked_configuration(angles, what)
    return q if usable else _checked_configuration(angles, what)


def _checked_batch(angles: ArrayLike, what: str) -> np.ndarray:
    q = np.asarray(angles, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != JOINT_COUNT:
        raise LegFkError(f"{what} must have shape (N, {JOINT_COUNT}), got {q.shape}")
    bad_rows = np.flatnonzero(~np.isfinite(q).all(axis=1))
    if bad_rows.size:
        raise LegFkError(f"{what}: rows {bad_rows[:10].tolist()} hold NaN or infinite values")
    return q


def _row_blocks(rows: int) -> list[slice]:
    return [
        slice(start, min(start + BATCH_CHUNK_ROWS, rows))
        for start in range(0, rows, BATCH_CHUNK_ROWS)
    ]


def _leg_columns(slot: int) -> slice:
    """The columns of leg ``slot``'s three joints in an (N, 12) array of angles."""
    return slice(slot * JOINTS_PER_LEG, (slot + 1) * JOINTS_PER_LEG)
