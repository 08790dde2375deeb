"""One leg's dynamics for the momentum observer, as generated straight-line code: the generalised
momentum ``p = dT/d(dq)`` and ``dT/dq``, where ``T`` is the kinetic energy of the leg's three
segments (:mod:`a1_leg_fk.kinematics.leg_segments`: links, rotors, covers, from the URDF's
``<inertial>`` elements) seen from an inertial frame while the base turns at ``omega``.

Frames and units: angles [rad], rates [rad/s], ``omega`` [rad/s] the base's angular velocity in
the base frame (the IMU's gyro), torques and momenta [N m], [N m s]. The base's translation does
not enter ``T``: a base accelerating at ``a`` acts on the legs as gravity ``g - a`` does, which the
statics' ``g(q)`` (:mod:`a1_leg_fk.kinematics.leg_statics`) takes from the accelerometer's
specific force (``g - a = -f``). With ``p`` and ``dT/dq``, Lagrange's equation of the leg reads::

    dp/dt = tau + tau_ext - g(q) + dT/dq        (dT/dq = C(q, dq)^T dq, the observer's form)

The code writes out the recursion of the Newton-Euler method in the joints' own frames. Out
along the leg, each joint's velocities: ``w_k = R_k^T w_(k-1) + a_k dq_k``, ``v_k = R_k^T
(v_(k-1) + w_(k-1) x o_k)`` (``w_(-1) = omega``, ``v_(-1) = 0``). Back in, the momenta of
everything below joint ``k``, about its origin: ``h_k = m_k v_k + w_k x mu_k + R_(k+1) h_(k+1)``
and ``l_k = mu_k x v_k + I_k w_k + R_(k+1) l_(k+1) + o_(k+1) x R_(k+1) h_(k+1)``. Then ``p_k =
a_k . l_k`` and ``dT/dq_k = -a_k . (v_k x h_k + w_k x l_k)``: turning joint ``k`` turns the
velocities the segments below it see by ``-a_k x``, and ``h_k``, ``l_k`` are ``T``'s gradients
in them. Every term that is zero for this leg's geometry is dropped when the code is written (186
lines for an A1 leg, 3.4 us; with the base not turning, 75 lines and half the time).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.fk_codegen import (
    Code,
    Term,
    compile_source,
    function_source,
    linear,
    product,
    rotated_row,
    term_tuple,
    weighted_sum,
)
from a1_leg_fk.kinematics.leg_segments import Segment, leg_segments
from a1_leg_fk.kinematics.leg_stages import Stage
from a1_leg_fk.model.urdf import RobotModel

Vector = tuple[Term, Term, Term]
TRIG_AND_RATES = "c0, s0, c1, s1, c2, s2, dq0, dq1, dq2"


class LegDynamics:
    """One leg's generated dynamics (see the module text).

    ``kinetic_terms(c0, s0, c1, s1, c2, s2, dq0, dq1, dq2, wx, wy, wz) -> (dT/dq0, dT/dq1,
    dT/dq2, p0, p1, p2)``: for the cosines and sines of the angles, the rates [rad/s] and the
    base's angular velocity [rad/s, base frame]; [N m] and [N m s]. Floats or (K,) arrays.
    ``inertial_terms(c0, s0, c1, s1, c2, s2, dq0, dq1, dq2)``: the same for a base that does not
    turn, generated with ``omega = 0`` (every term of it dropped: less than half the work).
    """

    def __init__(self, model: RobotModel, leg: CompiledLeg) -> None:
        """The dynamics of ``leg`` with the masses and inertias of ``model``."""
        self.segments = leg_segments(model, leg)
        self.source = kinetic_source(leg.stages, self.segments)
        self.inertial_source = kinetic_source(leg.stages, self.segments, inertial=True)
        namespace = compile_source(self.source, f"dynamics of {leg.chain.leg}", self)
        self.kinetic_terms: Callable[..., tuple[Any, ...]] = namespace["kinetic_terms"]
        namespace = compile_source(
            self.inertial_source, f"dynamics of {leg.chain.leg}, inertial base", self
        )
        self.inertial_terms: Callable[..., tuple[Any, ...]] = namespace["inertial_terms"]


def kinetic_source(
    stages: Sequence[Stage], segments: Sequence[Segment], inertial: bool = False
) -> str:
    """Python source of ``kinetic_terms`` (see :class:`LegDynamics`) for a leg's stages and
    segments: the recursion of the module text, written out; ``inertial``: of
    ``inertial_terms``, the base's angular velocity zero.
    """
    code = Code("k")
    trig = [(f"c{k}", f"s{k}") for k in range(len(stages))]
    angular: Vector = (0.0, 0.0, 0.0) if inertial else ("wx", "wy", "wz")
    velocity: Vector = (0.0, 0.0, 0.0)
    velocities = []  # (V_k, W_k), joint k's frame
    for k, stage in enumerate(stages):
        cos, sin = trig[k]
        moved = _cross_constant(code, angular, stage.offset)
        velocity = _turned(code, stage, _sum(code, velocity, moved), cos, sin, back=True)
        turned = _turned(code, stage, angular, cos, sin, back=True)
        spin = (_combine(code, [float(a)], [f"dq{k}"]) for a in stage.axis)
        angular = _sum(code, turned, _vector(spin))
        velocities.append((velocity, angular))
    terms: list[Term] = [0.0] * (2 * len(stages))
    momentum: Vector | None = None  # of the segments below joint k + 1, in joint k + 1's frame
    moment: Vector | None = None  # their angular momentum about joint k + 1
    for k in reversed(range(len(stages))):
        part, (velocity, angular) = segments[k], velocities[k]
        own = _sum(
            code, _scaled(code, part.mass, velocity), _cross_constant(code, angular, part.moment)
        )
        own_moment = _sum(
            code,
            _cross_constant(code, velocity, -part.moment),
            _vector(_combine(code, list(row), angular) for row in part.inertia),
        )
        if momentum is not None and moment is not None:
            child = stages[k + 1]
            carried = _turned(code, child, momentum, *trig[k + 1], back=False)
            turned = _turned(code, child, moment, *trig[k + 1], back=False)
            own_moment = _sum(
                code, own_moment, _sum(code, turned, _cross_constant(code, carried, -child.offset))
            )
            own = _sum(code, own, carried)
        momentum, moment = own, own_moment
        axis = [float(a) for a in stages[k].axis]
        terms[len(stages) + k] = _combine(code, axis, moment)
        torque = _sum(code, _cross(code, velocity, momentum), _cross(code, angular, moment))
        terms[k] = _combine(code, [-a for a in axis], torque)
    returned = term_tuple(terms)
    if inertial:
        return function_source(f"inertial_terms({TRIG_AND_RATES})", code.lines, returned)
    return function_source(f"kinetic_terms({TRIG_AND_RATES}, wx, wy, wz)", code.lines, returned)


def _combine(code: Code, coefficients: Sequence[float], terms: Sequence[Term]) -> Term:
    """``sum(c * term)`` for constant coefficients, bound to a name (zero terms dropped)."""
    return code.assign([linear(coefficients, terms)])[0]


def _vector(terms: Iterable[Term]) -> Vector:
    """Three terms as a vector."""
    x, y, z = terms
    return x, y, z


def _scaled(code: Code, factor: float, vector: Vector) -> Vector:
    """``factor * vector``."""
    return _vector(_combine(code, [factor], [v]) for v in vector)


def _sum(code: Code, first: Sequence[Term], second: Sequence[Term]) -> Vector:
    """``first + second``, component by component."""
    return _vector(_combine(code, [1.0, 1.0], [u, v]) for u, v in zip(first, second, strict=True))


def _cross(code: Code, first: Vector, second: Vector) -> Vector:
    """``first x second``."""
    (ux, uy, uz), (vx, vy, vz) = first, second
    return _vector(
        code.assign([weighted_sum([("", product(a, b)), ("", product(-1.0, product(c, d)))])])[0]
        for a, b, c, d in ((uy, vz, uz, vy), (uz, vx, ux, vz), (ux, vy, uy, vx))
    )


def _cross_constant(code: Code, vector: Vector, fixed: np.ndarray) -> Vector:
    """``vector x fixed`` for a constant 3-vector ``fixed``."""
    fx, fy, fz = (float(v) for v in fixed)
    vx, vy, vz = vector
    return (
        _combine(code, [fz, -fy], [vy, vz]),
        _combine(code, [fx, -fz], [vz, vx]),
        _combine(code, [fy, -fx], [vx, vy]),
    )


def _turned(code: Code, stage: Stage, vector: Vector, cos: str, sin: str, back: bool) -> Vector:
    """``(C0 + cos C1 + sin C2) vector``: a vector of the joint's child frame in its parent's
    (``back``: the transpose, a parent-side vector in the child frame).
    """
    c0, c1, c2 = (term.T if back else term for term in stage.rodrigues_terms)
    return _vector(
        code.assign([rotated_row((c0, c1, c2), axis, vector, cos, sin)])[0] for axis in range(3)
    )
