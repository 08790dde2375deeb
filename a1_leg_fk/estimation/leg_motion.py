"""What each foot says about the base's velocity, rolling feet included (plain floats: this runs
for every joint state, in the node at 1 kHz).

A stance foot does not slip: the point of its sole that touches the ground is still. For a
spherical foot of radius ``r`` (Unitree's feet; the A1's toe collision sphere has r = 0.02 m) that
point is ``c = r d`` from the sphere's centre (the foot frame), ``d`` the unit vector of gravity
("down") in the base frame, and it belongs to the calf. Its velocity in the world, in base
coordinates, is zero::

    0 = v + w x (p + c) + J(q) q_dot + w_leg x c

``v`` [m/s] and ``w`` [rad/s] the base's linear and angular velocity, ``p`` [m] the foot frame,
``J q_dot`` its velocity relative to the base, ``w_leg`` [rad/s] the calf's angular velocity
relative to the base (the sum of joint axis x joint rate). So each stance foot gives
``v = e - w x r`` with ``e = -(J q_dot + w_leg x c)`` and ``r = p + c``: :class:`LegMotion`
returns ``e``, ``r`` and how deep the contact point lies along gravity, ``depth = d . r`` [m],
which the kinematic stance test compares. Ignoring the rolling (r = 0) takes the sphere's centre
for still: it moves at ``|w_calf| r`` (~25 mm/s on a trotting A1).

Frames: the base frame (the URDF root link), as in :mod:`a1_leg_fk.kinematics.quadruped`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import NamedTuple

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES, foot_sphere
from a1_leg_fk.model.urdf import Joint

LEGS = len(LEG_NAMES)
CENTRED_SPHERE_M = 1e-9
"""A collision sphere whose centre is this close [m] to its link's origin is the foot sphere."""

Vector = tuple[float, float, float]


class FootMotion(NamedTuple):
    """One foot at one sample, base frame: ``e`` [m/s], the base velocity it gives when the base
    does not turn; ``r`` [m], its contact point; ``depth`` [m], ``d . r``, how far below the base
    the contact point lies along gravity.
    """

    e: Vector
    r: Vector
    depth: float


def foot_radii(quadruped: Quadruped) -> tuple[float, ...]:
    """Each foot's rolling radius [m]: the radius of the foot link's largest ``<collision>``
    sphere (:func:`~a1_leg_fk.model.legs.foot_sphere`, the one the foot forces use), else 0 (a
    point foot). A sphere off the link's origin (the Go2's sits 2 mm behind it) is followed by
    :class:`LegMotion` exactly.
    """
    radii = []
    for leg in quadruped.legs:
        sphere = foot_sphere(quadruped.model, leg.chain.foot_link)
        radii.append(sphere.radius if sphere is not None else 0.0)
    return tuple(radii)


def sphere_centre_legs(quadruped: Quadruped) -> tuple[CompiledLeg | None, ...]:
    """Per leg, the FK of its foot sphere's centre when that lies off the foot link's origin
    (more than :data:`CENTRED_SPHERE_M`): the leg's chain with one more fixed joint, to the
    centre; None where the sphere is centred or there is none.
    """
    legs: list[CompiledLeg | None] = []
    for leg in quadruped.legs:
        chain = leg.chain
        sphere = foot_sphere(quadruped.model, chain.foot_link)
        if sphere is None or max(map(abs, sphere.center)) <= CENTRED_SPHERE_M:
            legs.append(None)
            continue
        centre = Joint(f"{chain.foot_link}_sphere", "fixed", chain.foot_link,
                       f"{chain.foot_link}_sphere", sphere.center, (0.0, 0.0, 0.0),
                       (1.0, 0.0, 0.0), None, None)  # fmt: skip
        legs.append(CompiledLeg(replace(chain, joints=(*chain.joints, centre))))
    return tuple(legs)


class _CalfRate:
    """A leg's calf angular velocity relative to the base [rad/s, base frame].

    With the stages of :mod:`a1_leg_fk.kinematics.leg_stages` (``p -> o + M Rot(a, q) p``), joint
    i's axis in the base frame is ``R_i M_i a_i``, with ``R_0 = I``, ``R_1 = M_0 Rot(a_0, q_0)``
    and ``R_2 = R_1 M_1 Rot(a_1, q_1)``; Rodrigues' ``M Rot(a, q) = C0 + cos q C1 + sin q C2``
    leaves products with constants: ``w = A0 dq0 + R_1 (B1 dq1 + (K0 + cos q1 K1 + sin q1 K2)
    dq2)``.
    """

    def __init__(self, leg: CompiledLeg) -> None:
        hip, pitch, knee = leg.stages
        self.a0: Vector = _vector(hip.rotation @ hip.axis)
        self.hip = tuple(tuple(float(x) for x in term.ravel()) for term in hip.rodrigues_terms)
        self.b1: Vector = _vector(pitch.rotation @ pitch.axis)
        knee_axis = knee.rotation @ knee.axis
        self.k = tuple(_vector(term @ knee_axis) for term in pitch.rodrigues_terms)


def _vector(values: Sequence[float]) -> Vector:
    return (float(values[0]), float(values[1]), float(values[2]))


class LegMotion:
    """Per-foot motion for one robot (see the module docstring). ``radii`` [m] overrides the
    URDF's foot radii: one per leg, or one for all.
    """

    def __init__(self, quadruped: Quadruped, radii: Sequence[float] | float | None = None) -> None:
        self._calves = tuple(_CalfRate(leg) for leg in quadruped.legs)
        self._centres = sphere_centre_legs(quadruped)
        if radii is None:
            radii = foot_radii(quadruped)
        elif isinstance(radii, (int, float)):
            radii = (float(radii),) * LEGS
        self.radii = tuple(float(radius) for radius in radii)

    def foot(
        self,
        leg: int,
        angles: Sequence[float],
        rates: Sequence[float],
        position: Sequence[float],
        velocity: Sequence[float],
        down: Vector,
    ) -> FootMotion:
        """Leg ``leg``'s foot: its three ``angles`` [rad] and ``rates`` [rad/s], its ``position``
        [m] and ``velocity`` [m/s] (``J q_dot``) in the base frame, gravity's unit direction
        ``down`` in the base frame. A foot sphere off the foot's origin: its centre's own.
        """
        centre = self._centres[leg]
        if centre is not None:
            q0, q1, q2 = angles[0], angles[1], angles[2]
            moving = centre.position_velocity(q0, q1, q2, rates[0], rates[1], rates[2])
            position, velocity = moving[:3], moving[3:]
        r, depth = self.contact(leg, position, down)
        return FootMotion(self.still_base_velocity(leg, angles, rates, velocity, down), r, depth)

    def contact(self, leg: int, position: Sequence[float], down: Vector) -> tuple[Vector, float]:
        """(``r``, ``depth``) of leg ``leg``'s contact point (see :class:`FootMotion`): cheap,
        for every foot; :meth:`still_base_velocity` only for the feet that stand.
        """
        radius = self.radii[leg]
        dx, dy, dz = down
        rx, ry, rz = (
            position[0] + radius * dx,
            position[1] + radius * dy,
            position[2] + radius * dz,
        )
        return (rx, ry, rz), rx * dx + ry * dy + rz * dz

    def still_base_velocity(
        self,
        leg: int,
        angles: Sequence[float],
        rates: Sequence[float],
        velocity: Sequence[float],
        down: Vector,
    ) -> Vector:
        """``e`` of :class:`FootMotion`: ``-(J q_dot + w_calf x c)`` [m/s], base frame."""
        ox, oy, oz = self.calf_rate(leg, angles, rates)
        radius = self.radii[leg]
        cx, cy, cz = radius * down[0], radius * down[1], radius * down[2]
        return (
            -(velocity[0] + oy * cz - oz * cy),
            -(velocity[1] + oz * cx - ox * cz),
            -(velocity[2] + ox * cy - oy * cx),
        )

    def calf_rate(self, leg: int, angles: Sequence[float], rates: Sequence[float]) -> Vector:
        """The calf's angular velocity relative to the base [rad/s, base frame] for the leg's
        three ``angles`` [rad] and ``rates`` [rad/s] (see :class:`_CalfRate`).
        """
        calf = self._calves[leg]
        q0, q1 = angles[0], angles[1]
        dq0, dq1, dq2 = rates[0], rates[1], rates[2]
        c0, s0, c1, s1 = math.cos(q0), math.sin(q0), math.cos(q1), math.sin(q1)
        k0, k1, k2 = calf.k
        wx = k0[0] + c1 * k1[0] + s1 * k2[0]
        wy = k0[1] + c1 * k1[1] + s1 * k2[1]
        wz = k0[2] + c1 * k1[2] + s1 * k2[2]
        b1 = calf.b1
        ux, uy, uz = b1[0] * dq1 + wx * dq2, b1[1] * dq1 + wy * dq2, b1[2] * dq1 + wz * dq2
        h0, h1, h2 = calf.hip
        a0 = calf.a0
        return (
            a0[0] * dq0
            + (h0[0] + c0 * h1[0] + s0 * h2[0]) * ux
            + (h0[1] + c0 * h1[1] + s0 * h2[1]) * uy
            + (h0[2] + c0 * h1[2] + s0 * h2[2]) * uz,
            a0[1] * dq0
            + (h0[3] + c0 * h1[3] + s0 * h2[3]) * ux
            + (h0[4] + c0 * h1[4] + s0 * h2[4]) * uy
            + (h0[5] + c0 * h1[5] + s0 * h2[5]) * uz,
            a0[2] * dq0
            + (h0[6] + c0 * h1[6] + s0 * h2[6]) * ux
            + (h0[7] + c0 * h1[7] + s0 * h2[7]) * uy
            + (h0[8] + c0 * h1[8] + s0 * h2[8]) * uz,
        )
