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

The math is generated from each compiled leg's stages (:mod:`a1_leg_fk.kinematics.compiled_leg`),
one straight-line function per leg that computes g(q) and solves for F in the joints' own frames
(:mod:`a1_leg_fk.kinematics.leg_statics`). It is the statics of the
kinematic chain, so it sits in the kinematics beside the Jacobians, below
:class:`~a1_leg_fk.kinematics.quadruped.Quadruped`, whose ``foot_forces`` is a thin method over
it; the contact rule built on these forces is :mod:`a1_leg_fk.estimation`'s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from a1_leg_fk.kinematics.compiled_leg import BATCH_CHUNK_ROWS, CompiledLeg
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.leg_statics import LegStatics
from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES
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
            LegStatics(quadruped.model, leg, foot_radius_m) for leg in quadruped.legs
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
        gravity = gravity_rows(gravity_base, 1)[0].tolist()
        out, missing, singular = self.estimate_floats(q, tau, gravity)
        return ForceEstimate(np.array(out), np.array(missing), np.array(singular))

    def estimate_floats(
        self,
        q: Sequence[float],
        tau: Sequence[float],
        gravity: Sequence[float],
        legs: Sequence[bool] | None = None,
    ) -> tuple[list[list[float]], list[bool], list[bool]]:
        """:meth:`estimate` on Python floats, without numpy (the node's per-message path): 12
        angles [rad], 12 efforts [N m] and gravity (3,) [m/s^2]; per leg its force [N] (NaN when
        none), whether it is missing and whether it is near-singular; ``legs``: which legs to
        solve (None: all; the others missing).
        """
        out = [[math.nan] * 3 for _ in range(LEGS)]
        missing, singular = [True] * LEGS, [False] * LEGS
        isfinite, cos, sin = math.isfinite, math.cos, math.sin
        gx, gy, gz = gravity
        if not (isfinite(gx) and isfinite(gy) and isfinite(gz)):
            return out, missing, singular
        for slot, statics in enumerate(self._legs):
            if legs is not None and not legs[slot]:
                continue
            first = slot * JOINTS_PER_LEG
            q0, q1, q2 = q[first : first + JOINTS_PER_LEG]
            t0, t1, t2 = tau[first : first + JOINTS_PER_LEG]
            missing[slot] = not (
                isfinite(q0) and isfinite(q1) and isfinite(q2)
                and isfinite(t0) and isfinite(t1) and isfinite(t2)
            )  # fmt: skip
            if missing[slot]:
                continue
            x, y, z, det, size = statics.solve(
                cos(q0), sin(q0), cos(q1), sin(q1), cos(q2), sin(q2), t0, t1, t2, gx, gy, gz
            )
            singular[slot] = not abs(det) >= self.min_condition * size
            if not singular[slot]:
                out[slot] = [x / det, y / det, z / det]
        return out, missing, singular

    def estimate_batch(
        self, angles: ArrayLike, efforts: ArrayLike, gravity_base: ArrayLike | None = None
    ) -> ForceEstimate:
        """Foot forces for (N, 12) angles [rad] and efforts [N m]; ``gravity_base`` (3,) or
        (N, 3) [m/s^2] in the base frame (default :data:`LEVEL_GRAVITY`). Non-finite values
        make their leg :attr:`ForceEstimate.missing`, never an error; finite values so large
        that the force overflows give it as infinite, silently (as :meth:`estimate_floats`).
        """
        q = batch_array(angles, "angles")
        tau = batch_array(efforts, "efforts")
        if tau.shape != q.shape:
            raise LegFkError(f"efforts have shape {tau.shape}, angles {q.shape}")
        gravity = gravity_rows(gravity_base, q.shape[0])
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
                with np.errstate(over="ignore", invalid="ignore"):
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
        q = batch_array(angles, "angles")
        if not np.isfinite(q).all():
            raise LegFkError("angles: NaN or infinite values")
        gravity = gravity_rows(gravity_base, q.shape[0])
        cos, sin = np.cos(q), np.sin(q)
        out = np.empty_like(q)
        for slot, statics in enumerate(self._legs):
            joints = slice(slot * JOINTS_PER_LEG, (slot + 1) * JOINTS_PER_LEG)
            torques = statics.gravity_torques(*_trig(cos[:, joints], sin[:, joints]), *gravity.T)
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
        """(K, 3) forces [N] and (K,) singular flags of one leg (:class:`LegStatics`)."""
        *scaled, det, size = self._legs[slot].solve(*_trig(cos, sin), *efforts.T, *gravity.T)
        singular = ~(np.abs(det) >= self.min_condition * size)
        inverse = 1.0 / np.where(singular, 1.0, det)
        forces = np.empty((cos.shape[0], 3))
        for i in range(3):
            forces[:, i] = scaled[i] * inverse
        return forces, singular


def _trig(cos: np.ndarray, sin: np.ndarray) -> tuple[np.ndarray, ...]:
    """(c0, s0, c1, s1, c2, s2) of a leg's (K, 3) cosines and sines."""
    return cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2]


def _row(values: ArrayLike, what: str) -> np.ndarray:
    try:
        row = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"{what} must be {JOINT_COUNT} numbers: {error}") from error
    if row.shape != (JOINT_COUNT,):
        raise LegFkError(f"{what} must be {JOINT_COUNT} numbers (3 per leg), got {row.shape}")
    return row[np.newaxis]


def batch_array(values: ArrayLike, what: str) -> np.ndarray:
    """(N, 12) float64 of ``values``; :class:`LegFkError` naming ``what`` otherwise."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"{what} must be an (N, {JOINT_COUNT}) array: {error}") from error
    if array.ndim != 2 or array.shape[1] != JOINT_COUNT:
        raise LegFkError(f"{what} must have shape (N, {JOINT_COUNT}), got {array.shape}")
    return array


def gravity_rows(gravity_base: ArrayLike | None, rows: int) -> np.ndarray:
    """(rows, 3) gravity [m/s^2] from None (level), a (3,) vector or a (rows, 3) array."""
    gravity = np.asarray(LEVEL_GRAVITY if gravity_base is None else gravity_base, dtype=float)
    if gravity.shape == (3,):
        return np.broadcast_to(gravity, (rows, 3))
    if gravity.shape != (rows, 3):
        raise LegFkError(f"gravity_base must have shape (3,) or ({rows}, 3), got {gravity.shape}")
    return gravity
