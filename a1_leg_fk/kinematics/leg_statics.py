"""One leg's statics as generated straight-line code (:mod:`a1_leg_fk.kinematics.fk_codegen`):
the Jacobians of its segments' centres of mass and of the foot's contact point, its joint axes in
the base frame, and from them the gravity torques g(q) and the Cramer's-rule solve of
``J^T F = g - tau`` that :class:`~a1_leg_fk.kinematics.foot_forces.FootForces` runs per leg (see
that module for the conventions and frames). Every function takes floats or (K,) arrays alike.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.fk_codegen import compile_source, leg_source
from a1_leg_fk.kinematics.leg_stages import rpy_matrix
from a1_leg_fk.model.legs import JOINTS_PER_LEG, foot_sphere
from a1_leg_fk.model.urdf import RobotModel

Values = Sequence[Any] | np.ndarray
"""Per joint or per axis: floats, or (K,) arrays (the rows of an array)."""


class LegStatics:
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
