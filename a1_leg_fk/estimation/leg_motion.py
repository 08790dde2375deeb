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

from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from typing import NamedTuple

from a1_leg_fk.estimation.ground_plane import Point
from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.fk_codegen import (
    Code,
    compile_source,
    function_source,
    linear,
    product,
    rotated_row,
    term_tuple,
    weighted_sum,
)
from a1_leg_fk.kinematics.frames import Quaternion, rotate
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


def calf_rate_source(leg: CompiledLeg) -> str:
    """Python source of ``calf_rate(q0, q1, dq0, dq1, dq2) -> (wx, wy, wz)``: a leg's calf
    angular velocity relative to the base [rad/s, base frame] for its hip and thigh angles [rad]
    and three rates [rad/s], written out with every zero term dropped.

    With the stages of :mod:`a1_leg_fk.kinematics.leg_stages` (``p -> o + M Rot(a, q) p``), joint
    i's axis in the base frame is ``R_i M_i a_i``, with ``R_0 = I``, ``R_1 = M_0 Rot(a_0, q_0)``
    and ``R_2 = R_1 M_1 Rot(a_1, q_1)``; Rodrigues' ``M Rot(a, q) = C0 + cos q C1 + sin q C2``
    leaves products with constants: ``w = A0 dq0 + R_1 (B1 dq1 + (K0 + cos q1 K1 + sin q1 K2)
    dq2)``.
    """
    hip, pitch, knee = leg.stages
    code = Code("w")
    code.lines += ["c0 = _cos(q0)", "s0 = _sin(q0)", "c1 = _cos(q1)", "s1 = _sin(q1)"]
    knee_axis = knee.rotation @ knee.axis
    k0, k1, k2 = (term @ knee_axis for term in pitch.rodrigues_terms)
    b1 = pitch.rotation @ pitch.axis
    cos_rate, sin_rate = code.assign([product("c1", "dq2"), product("s1", "dq2")])
    rates = ("dq1", "dq2", cos_rate, sin_rate)
    inner = code.assign(
        [linear([b1[axis], k0[axis], k1[axis], k2[axis]], rates) for axis in range(3)]
    )
    a0 = hip.rotation @ hip.axis
    rate = [
        weighted_sum(
            [("", linear([a0[axis]], ["dq0"])),
             ("", rotated_row(hip.rodrigues_terms, axis, inner, "c0", "s0"))]
        )
        for axis in range(3)
    ]  # fmt: skip
    return function_source("calf_rate(q0, q1, dq0, dq1, dq2)", code.lines, term_tuple(rate))


class LegMotion:
    """Per-foot motion for one robot (see the module docstring). ``radii`` [m] overrides the
    URDF's foot radii: one per leg, or one for all.
    """

    def __init__(self, quadruped: Quadruped, radii: Sequence[float] | float | None = None) -> None:
        self.sources = tuple(calf_rate_source(leg) for leg in quadruped.legs)
        """Each leg's generated ``calf_rate`` (:func:`calf_rate_source`)."""
        self._calf_rates: tuple[Callable[..., Vector], ...] = tuple(
            compile_source(source, f"calf rate of {leg.chain.leg}", self)["calf_rate"]
            for source, leg in zip(self.sources, quadruped.legs, strict=True)
        )
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
        ox, oy, oz = self._calf_rates[leg](angles[0], angles[1], rates[0], rates[1], rates[2])
        radius = self.radii[leg]
        cx, cy, cz = radius * down[0], radius * down[1], radius * down[2]
        return (
            -(velocity[0] + oy * cz - oz * cy),
            -(velocity[1] + oz * cx - ox * cz),
            -(velocity[2] + ox * cy - oy * cx),
        )

    def calf_rate(self, leg: int, angles: Sequence[float], rates: Sequence[float]) -> Vector:
        """The calf's angular velocity relative to the base [rad/s, base frame] for the leg's
        three ``angles`` [rad] and ``rates`` [rad/s] (see :func:`calf_rate_source`).
        """
        return self._calf_rates[leg](angles[0], angles[1], rates[0], rates[1], rates[2])


def contact_points(
    position: Point,
    orientation: Quaternion,
    feet: Sequence[Sequence[float] | None],
    radii: Sequence[float],
    legs: Iterable[int],
) -> list[tuple[int, Point]]:
    """The contact points [m, odom] of the feet of ``legs``: the base at ``position`` [m] turned
    by ``orientation`` (x, y, z, w: base to odom), each foot's centre ``feet[leg]`` [m, base
    frame] less its rolling radius ``radii[leg]`` [m] straight down; legs without a foot are
    left out.
    """
    points = []
    for leg in legs:
        foot = feet[leg]
        if foot is None:
            continue
        x, y, z = rotate(orientation, (foot[0], foot[1], foot[2]))
        points.append((leg, (position[0] + x, position[1] + y, position[2] + z - radii[leg])))
    return points
