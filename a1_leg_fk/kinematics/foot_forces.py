"""Foot forces from joint efforts: the legs as a force sensor, quasi-static, without ROS.

A leg at rest (or slow enough that its own inertia does not matter) balances three torques at
each joint: the motor's effort ``tau``, gravity on the leg's own links, and the ground's force
``F`` on the foot acting through the foot Jacobian ``J``::

    g(q) = tau + J(q)^T F      =>      F = J(q)^-T (g(q) - tau)

Conventions (those of ``sensor_msgs/JointState`` and ros2_control, and of PyBullet's applied motor
torque): ``tau`` [N m] is the torque the joint's motor applies to its child link about the joint
axis (positive by the right-hand rule about the URDF ``<axis>``); ``g(q)`` [N m] is the generalised
gravity force, the effort that holds the leg still against gravity with the foot in the air
(minus the torque gravity exerts on the links below the joint); ``F`` [N] is the force the ground
exerts on the foot, in the base frame (the URDF root link); gravity is an acceleration vector
[m/s^2] in the base frame (default: ``-z`` at standard gravity, the base level).

The ground pushes where it touches the foot: a foot with a collision sphere (radius ``r``, its
centre in the foot link's frame) in the URDF touches flat ground ``r`` along gravity from the
sphere's centre, and the Jacobian is that of this point (on the A1, ignoring the 2 cm radius
costs up to ~2.6 N per foot in static poses tilted by 0.15 rad).

``g(q)`` comes from the URDF's ``<inertial>`` masses and centres of mass: every link below a leg's
first movable joint belongs to the *segment* of the nearest movable joint above it (links under a
movable joint outside the leg's chain are taken at that joint's zero angle).

Near a singular Jacobian (the knee straight) the solve amplifies any effort error without bound:
there, and where the efforts or angles of a leg are missing or not finite, a leg gets no force
(NaN), and the result says which and why.

The math is built from the compiled legs (:mod:`a1_leg_fk.kinematics.compiled_leg`, the same
generated straight-line code: the Jacobians of each segment's centre of mass and of the contact
point). It is the statics of the kinematic chain, so it sits in the kinematics beside the
Jacobians, below :class:`~a1_leg_fk.kinematics.quadruped.Quadruped`, whose ``foot_forces`` is a
thin method over it; the contact rule built on these forces is :mod:`a1_leg_fk.estimation`'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from a1_leg_fk.kinematics.compiled_leg import BATCH_CHUNK_ROWS, CompiledLeg
from a1_leg_fk.kinematics.fk_codegen import compile_source, leg_source
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.leg_stages import rpy_matrix
from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES, foot_sphere
from a1_leg_fk.model.urdf import LegFkError, RobotModel

"""[m/s^2]"""
LEVEL_GRAVITY = (0.0, 0.0, -STANDARD_GRAVITY)
"""Gravity in the base frame [m/s^2] when nothing tells its direction: the base level."""
MIN_JACOBIAN_CONDITION = 0.05
"""A leg whose Jacobian columns ``j0, j1, j2`` give ``|det J| / (|j0| |j1| |j2|)`` below this gets
no force. On the A1 the measure is 0.65 standing (knee -1.5 rad), 0.43 at the knee's straightest
limit (-0.916 rad), 0.048 at -0.1 rad and 0 straight; at 0.05 the smallest singular value of J is
~9 mm, so an effort error of 1 N m already moves the force by ~110 N."""
LEGS = len(LEG_NAMES)


@dataclass(frozen=True)
class ForceEstimate:
    """Foot forces for N configurations (one: without the leading N).

    ``forces`` (N, 4, 3) [N]: the force the ground exerts on each foot, base frame, NaN where
    the leg has none; ``missing`` (N, 4): the leg's angles or efforts are missing or not finite;
    ``singular`` (N, 4): its Jacobian is too near singular (:data:`MIN_JACOBIAN_CONDITION`).
    """

    forces: np.ndarray
    missing: np.ndarray
    singular: np.ndarray


Values = Sequence[Any] | np.ndarray
"""Per joint or per axis: floats, or (K,) arrays (the rows of an array)."""


class _LegStatics:
    """One leg's generated functions (see :mod:`a1_leg_fk.kinematics.fk_codegen`): per segment with
    mass, the Jacobian of its centre of mass; per joint, its axis in the base frame; the Jacobian
    of the foot sphere's centre, and the sphere's radius [m].
    """

    def __init__(self, model: RobotModel, leg: CompiledLeg, radius_m: float | None) -> None:
        sphere = foot_sphere(model, leg.chain.foot_link) if radius_m is None else None
        self.radius_m = sphere.radius if sphere is not None else radius_m or 0.0
        center = _foot_point(leg, np.array(sphere.center) if sphere is not None else np.zeros(3))
        self.contact_jacobian: Callable[..., tuple[Any, ...]] = compile_source(
            leg_source(leg.stages, center), f"foot sphere of {leg.chain.leg}", self
        )["jacobian_from_trig"]
        movable = leg.chain.movable
        self.masses: list[float] = []
        self.com_jacobians: list[tuple[float, Callable[..., tuple[Any, ...]]]] = []
        for k, joint in enumerate(movable):
            stop = movable[k + 1].name if k + 1 < len(movable) else None
            mass, moment = _segment(model, joint.child, stop)
            self.masses.append(mass)
            if mass > 0.0:  # the centre of mass, a point in stage k's child frame
                source = leg_source(leg.stages[: k + 1], moment / mass)
                code = compile_source(source, f"CoM of {leg.chain.leg} segment {k}", self)
                self.com_jacobians.append((mass, code["jacobian_from_trig"]))
        # a stage without its offset turns a vector as the leg turns it
        turns = tuple(replace(stage, offset=np.zeros(3)) for stage in leg.stages)
        self.axes: list[Callable[..., tuple[Any, Any, Any]]] = [
            compile_source(
                leg_source(turns[: k + 1], stage.axis), f"axis {stage.joint.name}", self
            )["position_from_trig"]
            for k, stage in enumerate(leg.stages)
        ]

    def gravity_torques(self, trig: Values, gravity: Values) -> list[Any]:
        """g(q) [N m], per joint, for the leg's (c0, s0, c1, s1, c2, s2) and gravity [m/s^2]
        (floats, or (K,) arrays): minus the torque gravity exerts on the links below each joint.
        Straight-line arithmetic: the node's per-message path runs it on floats.
        """
        gx, gy, gz = gravity
        torques: list[Any] = [0.0] * JOINTS_PER_LEG
        for mass, jacobian in self.com_jacobians:
            columns = jacobian(*trig)
            mx, my, mz = mass * gx, mass * gy, mass * gz
            torques[0] = torques[0] - (columns[0] * mx + columns[1] * my + columns[2] * mz)
            if len(columns) > 3:
                torques[1] = torques[1] - (columns[3] * mx + columns[4] * my + columns[5] * mz)
            if len(columns) > 6:
                torques[2] = torques[2] - (columns[6] * mx + columns[7] * my + columns[8] * mz)
        return torques

    def solve(
        self, trig: Values, efforts: Values, gravity: Values
    ) -> tuple[tuple[Any, Any, Any], Any, Any]:
        """``J^T F = g - tau`` by Cramer's rule, J that of the contact point, on floats or (K,)
        arrays alike: ``(det J * F [N] per axis, det J, |j0| |j1| |j2|)``. Written out
        component by component: on floats (the node, once per leg and message) it is the cost.
        """
        gx, gy, gz = gravity
        g0, g1, g2 = self.gravity_torques(trig, gravity)
        r0, r1, r2 = g0 - efforts[0], g1 - efforts[1], g2 - efforts[2]
        ax, ay, az, bx, by, bz, cx, cy, cz = self.contact_jacobian(*trig)[:9]
        if self.radius_m:  # the contact point moves as the foot turns: dc/dq_k = J_k - d x a_k
            scale = self.radius_m / (gx * gx + gy * gy + gz * gz) ** 0.5
            dx, dy, dz = gx * scale, gy * scale, gz * scale
            first, second, third = self.axes
            ex, ey, ez = first(*trig)
            ax, ay, az = (
                ax - (dy * ez - dz * ey),
                ay - (dz * ex - dx * ez),
                az - (dx * ey - dy * ex),
            )
            ex, ey, ez = second(*trig)
            bx, by, bz = (
                bx - (dy * ez - dz * ey),
                by - (dz * ex - dx * ez),
                bz - (dx * ey - dy * ex),
            )
            ex, ey, ez = third(*trig)
            cx, cy, cz = (
                cx - (dy * ez - dz * ey),
                cy - (dz * ex - dx * ez),
                cz - (dx * ey - dy * ex),
            )
        # the columns j0 = a, j1 = b, j2 = c; their cross products b x c, c x a, a x b
        bcx, bcy, bcz = by * cz - bz * cy, bz * cx - bx * cz, bx * cy - by * cx
        cax, cay, caz = cy * az - cz * ay, cz * ax - cx * az, cx * ay - cy * ax
        abx, aby, abz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        det = ax * bcx + ay * bcy + az * bcz
        size = (
            (ax * ax + ay * ay + az * az)
            * (bx * bx + by * by + bz * bz)
            * (cx * cx + cy * cy + cz * cz)
        ) ** 0.5
        scaled = (
            r0 * bcx + r1 * cax + r2 * abx,
            r0 * bcy + r1 * cay + r2 * aby,
            r0 * bcz + r1 * caz + r2 * abz,
        )
        return scaled, det, size


class LeggedRobot(Protocol):
    """What the statics need of a robot (a :class:`~a1_leg_fk.kinematics.quadruped.Quadruped`):
    its URDF model and its four compiled legs.
    """

    @property
    def model(self) -> RobotModel:
        """The robot's URDF model (masses, centres of mass, collision spheres)."""

    @property
    def legs(self) -> tuple[CompiledLeg, ...]:
        """The four compiled legs, FR, FL, RR, RL."""


class FootForces:
    """Quasi-static foot forces of a :class:`~a1_leg_fk.kinematics.quadruped.Quadruped` from its
    joint efforts (see the module text for the conventions).
    """

    def __init__(
        self,
        quadruped: LeggedRobot,
        min_condition: float = MIN_JACOBIAN_CONDITION,
        foot_radius_m: float | None = None,
    ) -> None:
        """Collect each leg's segment masses from the quadruped's URDF; ``min_condition`` gates
        near-singular Jacobians. The contact point: by default on each foot link's collision
        sphere (:func:`~a1_leg_fk.model.legs.foot_sphere`); with ``foot_radius_m`` [m], on a sphere
        of that radius centred on the foot link's origin (0: the origin itself).
        """
        self.min_condition = min_condition
        self._legs = tuple(
            _LegStatics(quadruped.model, leg, foot_radius_m) for leg in quadruped.legs
        )
        self.foot_radii_m = tuple(leg.radius_m for leg in self._legs)
        """Each foot's contact sphere radius [m]."""
        self.total_mass_kg = sum(i.mass for i in quadruped.model.inertials.values())
        """The robot's mass [kg]: every ``<inertial>`` of the URDF."""
        if not self.total_mass_kg > 0.0:
            raise LegFkError(
                f"{quadruped.model.source}: no link has a mass (<inertial><mass>); foot forces "
                "need the masses of the legs"
            )

    def leg_masses_kg(self, leg: int) -> tuple[float, ...]:
        """The masses [kg] of leg slot ``leg``'s three segments, root side first."""
        return tuple(self._legs[leg].masses)

    def estimate(
        self, angles: ArrayLike, efforts: ArrayLike, gravity_base: ArrayLike | None = None
    ) -> ForceEstimate:
        """The foot forces of one configuration, in floats (the per-message path): 12 angles
        [rad] and 12 efforts [N m] (slot order), ``gravity_base`` (3,) [m/s^2] in the base frame;
        a :class:`ForceEstimate` of shapes (4, 3), (4,), (4,).
        """
        q = _row(angles, "joint angles")[0].tolist()
        tau = _row(efforts, "joint efforts")[0].tolist()
        gravity = _gravity(gravity_base, 1)[0].tolist()
        out, missing, singular = self.estimate_floats(q, tau, gravity)
        return ForceEstimate(np.array(out), np.array(missing), np.array(singular))

    def estimate_floats(
        self, q: Sequence[float], tau: Sequence[float], gravity: Sequence[float]
    ) -> tuple[list[list[float]], list[bool], list[bool]]:
        """:meth:`estimate` on Python floats, without numpy (the node's per-message path): 12
        angles [rad], 12 efforts [N m] and gravity (3,) [m/s^2]; per leg its force [N] (NaN when
        none), whether it is missing and whether it is near-singular.
        """
        out = [[math.nan] * 3 for _ in range(LEGS)]
        missing, singular = [True] * LEGS, [False] * LEGS
        isfinite = math.isfinite
        if not (isfinite(gravity[0]) and isfinite(gravity[1]) and isfinite(gravity[2])):
            return out, missing, singular
        for slot, statics in enumerate(self._legs):
            first = slot * JOINTS_PER_LEG
            q0, q1, q2 = q[first : first + JOINTS_PER_LEG]
            t0, t1, t2 = tau[first : first + JOINTS_PER_LEG]
            missing[slot] = not all(isfinite(value) for value in (q0, q1, q2, t0, t1, t2))
            if missing[slot]:
                continue
            trig = (math.cos(q0), math.sin(q0), math.cos(q1), math.sin(q1), math.cos(q2),
                    math.sin(q2))  # fmt: skip
            scaled, det, size = statics.solve(trig, (t0, t1, t2), gravity)
            singular[slot] = not abs(det) >= self.min_condition * size
            if not singular[slot]:
                out[slot] = [scaled[0] / det, scaled[1] / det, scaled[2] / det]
        return out, missing, singular

    def estimate_batch(
        self, angles: ArrayLike, efforts: ArrayLike, gravity_base: ArrayLike | None = None
    ) -> ForceEstimate:
        """Foot forces for (N, 12) angles [rad] and efforts [N m]; ``gravity_base`` (3,) or
        (N, 3) [m/s^2] in the base frame (default :data:`LEVEL_GRAVITY`). Non-finite values
        make their leg :attr:`ForceEstimate.missing`, never an error.
        """
        q = _batch(angles, "angles")
        tau = _batch(efforts, "efforts")
        if tau.shape != q.shape:
            raise LegFkError(f"efforts have shape {tau.shape}, angles {q.shape}")
        gravity = _gravity(gravity_base, q.shape[0])
        rows = q.shape[0]
        forces = np.full((rows, LEGS, 3), math.nan)
        singular = np.zeros((rows, LEGS), dtype=bool)
        finite = np.isfinite(q) & np.isfinite(tau)
        missing = ~finite.reshape(rows, LEGS, JOINTS_PER_LEG).all(axis=2)
        missing |= ~np.isfinite(gravity).all(axis=1)[:, None]
        q, tau = np.where(finite, q, 0.0), np.where(finite, tau, 0.0)
        gravity = np.nan_to_num(gravity)
        for start in range(0, rows, BATCH_CHUNK_ROWS):
            block = slice(start, min(start + BATCH_CHUNK_ROWS, rows))
            cos, sin = np.cos(q[block]), np.sin(q[block])
            for slot in range(LEGS):
                joints = slice(slot * JOINTS_PER_LEG, (slot + 1) * JOINTS_PER_LEG)
                forces[block, slot], singular[block, slot] = self._leg_forces(
                    slot, cos[:, joints], sin[:, joints], tau[block, joints], gravity[block]
                )
        singular &= ~missing
        forces[missing | singular] = math.nan
        return ForceEstimate(forces, missing, singular)

    def gravity_torques_batch(
        self, angles: ArrayLike, gravity_base: ArrayLike | None = None
    ) -> np.ndarray:
        """(N, 12) g(q) [N m]: the efforts that hold the legs still in the air, for (N, 12)
        angles [rad] and gravity (3,) or (N, 3) [m/s^2] in the base frame.
        """
        q = _batch(angles, "angles")
        if not np.isfinite(q).all():
            raise LegFkError("angles: NaN or infinite values")
        gravity = _gravity(gravity_base, q.shape[0])
        cos, sin = np.cos(q), np.sin(q)
        out = np.empty_like(q)
        for slot, statics in enumerate(self._legs):
            joints = slice(slot * JOINTS_PER_LEG, (slot + 1) * JOINTS_PER_LEG)
            g = gravity.T
            torques = statics.gravity_torques(_trig(cos[:, joints], sin[:, joints]), g)
            out[:, joints] = np.stack(np.broadcast_arrays(*torques), axis=1)
        return out

    def _leg_forces(
        self,
        slot: int,
        cos: np.ndarray,
        sin: np.ndarray,
        efforts: np.ndarray,
        gravity: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(K, 3) forces [N] and (K,) singular flags of one leg (:meth:`_LegStatics.solve`)."""
        scaled, det, size = self._legs[slot].solve(_trig(cos, sin), efforts.T, gravity.T)
        singular = ~(np.abs(det) >= self.min_condition * size)
        inverse = 1.0 / np.where(singular, 1.0, det)
        forces = np.empty((cos.shape[0], 3))
        for i in range(3):
            forces[:, i] = scaled[i] * inverse
        return forces, singular


def _trig(cos: np.ndarray, sin: np.ndarray) -> tuple[np.ndarray, ...]:
    """(c0, s0, c1, s1, c2, s2) of a leg's (K, 3) cosines and sines."""
    return cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2]


def _foot_point(leg: CompiledLeg, point: np.ndarray) -> np.ndarray:
    """``point`` [m] of the foot link's frame in the last movable joint's child frame."""
    joints = leg.chain.joints
    last_movable = max(i for i, joint in enumerate(joints) if joint.movable)
    rotation, offset = np.eye(3), np.zeros(3)
    for joint in joints[last_movable + 1 :]:
        offset = offset + rotation @ np.array(joint.origin_xyz)
        rotation = rotation @ rpy_matrix(joint.origin_rpy)
    result: np.ndarray = offset + rotation @ point
    return result


def _segment(model: RobotModel, link: str, stop_joint: str | None) -> tuple[float, np.ndarray]:
    """Mass [kg] and first moment [kg m] (in ``link``'s frame) of ``link`` and everything below
    it, except below the joint named ``stop_joint``; other joints at their zero angle.
    """
    mass, moment = 0.0, np.zeros(3)
    pending = [(link, np.eye(3), np.zeros(3))]
    while pending:
        name, rotation, origin = pending.pop()
        inertial = model.inertials.get(name)
        if inertial is not None:
            mass += inertial.mass
            moment += inertial.mass * (origin + rotation @ np.array(inertial.center))
        pending.extend(
            (
                joint.child,
                rotation @ rpy_matrix(joint.origin_rpy),
                origin + rotation @ np.array(joint.origin_xyz),
            )
            for joint in model.joints.values()
            if joint.parent == name and joint.name != stop_joint
        )
    return mass, moment


def _row(values: ArrayLike, what: str) -> np.ndarray:
    try:
        row = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"{what} must be {JOINT_COUNT} numbers: {error}") from error
    if row.shape != (JOINT_COUNT,):
        raise LegFkError(f"{what} must be {JOINT_COUNT} numbers (3 per leg), got {row.shape}")
    return row[np.newaxis]


def _batch(values: ArrayLike, what: str) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"{what} must be an (N, {JOINT_COUNT}) array: {error}") from error
    if array.ndim != 2 or array.shape[1] != JOINT_COUNT:
        raise LegFkError(f"{what} must have shape (N, {JOINT_COUNT}), got {array.shape}")
    return array


def _gravity(gravity_base: ArrayLike | None, rows: int) -> np.ndarray:
    """(rows, 3) gravity [m/s^2] from None (level), a (3,) vector or a (rows, 3) array."""
    gravity = np.asarray(LEVEL_GRAVITY if gravity_base is None else gravity_base, dtype=float)
    if gravity.shape == (3,):
        return np.broadcast_to(gravity, (rows, 3))
    if gravity.shape != (rows, 3):
        raise LegFkError(f"gravity_base must have shape (3,) or ({rows}, 3), got {gravity.shape}")
    return gravity
