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

The code comes from running the kinetic energy, joint by joint in the joints' own frames (the
velocities of the recursive Newton-Euler method: ``w_k = R_k^T w_(k-1) + a_k dq_k``, ``v_k = R_k^T
(v_(k-1) + w_(k-1) x o_k)``, ``T_k = m v.v / 2 + v.(w x mu) + w.I w / 2``), on traced values
(:mod:`a1_leg_fk.kinematics.traced_code`) whose six seed directions are the three angles and the
three rates: the derivatives are exact, and every term that is zero for this leg's geometry is
dropped when the code is written.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.fk_codegen import Code, compile_source, term_tuple
from a1_leg_fk.kinematics.leg_segments import Segment, leg_segments
from a1_leg_fk.kinematics.leg_stages import Stage
from a1_leg_fk.kinematics.traced_code import (
    Traced,
    add,
    combine,
    constant,
    dot,
    function_source,
    multiply,
)
from a1_leg_fk.model.legs import JOINTS_PER_LEG
from a1_leg_fk.model.urdf import RobotModel

Vector = tuple[Traced, Traced, Traced]
DIRECTIONS = 2 * JOINTS_PER_LEG
"""Seed directions: the three angles, then the three rates."""
ARGUMENTS = "c0, s0, c1, s1, c2, s2, dq0, dq1, dq2, wx, wy, wz"


class LegDynamics:
    """One leg's generated dynamics (see the module text).

    ``kinetic_terms(c0, s0, c1, s1, c2, s2, dq0, dq1, dq2, wx, wy, wz) -> (dT/dq0, dT/dq1,
    dT/dq2, p0, p1, p2)``: for the cosines and sines of the angles, the rates [rad/s] and the
    base's angular velocity [rad/s, base frame]; [N m] and [N m s]. Floats or (K,) arrays.
    """

    def __init__(self, model: RobotModel, leg: CompiledLeg) -> None:
        """The dynamics of ``leg`` with the masses and inertias of ``model``."""
        self.segments = leg_segments(model, leg)
        self.source = kinetic_source(leg.stages, self.segments)
        namespace = compile_source(self.source, f"dynamics of {leg.chain.leg}", self)
        self.kinetic_terms: Callable[..., tuple[Any, ...]] = namespace["kinetic_terms"]


def kinetic_source(stages: Sequence[Stage], segments: Sequence[Segment]) -> str:
    """Python source of ``kinetic_terms`` (see :class:`LegDynamics`) for a leg's stages and
    segments.
    """
    code = Code("k")
    angular: Vector = _inputs(("wx", "wy", "wz"), {})
    linear: Vector = (constant(0.0, DIRECTIONS),) * 3
    energies = []
    for k, (stage, part) in enumerate(zip(stages, segments, strict=True)):
        cos, sin = _inputs((f"c{k}", f"s{k}"), {0: (k, f"-s{k}"), 1: (k, f"c{k}")})
        rate = _inputs((f"dq{k}",), {0: (JOINTS_PER_LEG + k, 1.0)})[0]
        moved = _cross_constant(code, angular, stage.offset)
        linear = _turned_back(code, stage, _sum(code, linear, moved), cos, sin)
        turned = _turned_back(code, stage, angular, cos, sin)
        angular = _sum(code, turned, tuple(combine(code, [float(a)], [rate]) for a in stage.axis))
        energies.append(_segment_energy(code, part, linear, angular))
    energy = add(code, energies)
    return function_source(f"kinetic_terms({ARGUMENTS})", code.lines, term_tuple(energy.tangents))


def _segment_energy(code: Code, part: Segment, linear: Vector, angular: Vector) -> Traced:
    """``m v.v / 2 + v.(w x mu) + w.I w / 2`` [J] of one segment moving at ``linear`` [m/s] and
    ``angular`` [rad/s] (its frame's origin, in its frame).
    """
    inertia_times = tuple(combine(code, list(row), angular) for row in part.inertia)
    swirl = _cross_constant(code, angular, part.moment)
    return combine(
        code,
        [0.5 * part.mass, 1.0, 0.5],
        [dot(code, linear, linear), dot(code, linear, swirl), dot(code, angular, inertia_times)],
    )


def _inputs(names: Sequence[str], seeds: dict[int, tuple[int, float | str]]) -> Any:
    """Traced inputs named ``names``; ``seeds[i] = (direction, derivative)`` gives input ``i``
    its one non-zero derivative.
    """
    traced = []
    for index, name in enumerate(names):
        tangents: list[float | str] = [0.0] * DIRECTIONS
        if index in seeds:
            direction, derivative = seeds[index]
            tangents[direction] = derivative
        traced.append(Traced(name, tuple(tangents)))
    return tuple(traced)


def _sum(code: Code, first: Sequence[Traced], second: Sequence[Traced]) -> Vector:
    """``first + second``, component by component."""
    x, y, z = (add(code, [u, v]) for u, v in zip(first, second, strict=True))
    return x, y, z


def _cross_constant(code: Code, vector: Vector, fixed: np.ndarray) -> Vector:
    """``vector x fixed`` for a constant 3-vector ``fixed``."""
    fx, fy, fz = (float(v) for v in fixed)
    vx, vy, vz = vector
    return (
        combine(code, [fz, -fy], [vy, vz]),
        combine(code, [fx, -fz], [vz, vx]),
        combine(code, [fy, -fx], [vx, vy]),
    )


def _turned_back(code: Code, stage: Stage, vector: Vector, cos: Traced, sin: Traced) -> Vector:
    """``(C0 + cos C1 + sin C2)^T vector``: a vector of the joint's parent side in its child
    frame.
    """
    c0, c1, c2 = (term.T for term in stage.rodrigues_terms)
    rows = []
    for axis in range(3):
        fixed = combine(code, list(c0[axis]), vector)
        along_cos = multiply(code, cos, combine(code, list(c1[axis]), vector))
        along_sin = multiply(code, sin, combine(code, list(c2[axis]), vector))
        rows.append(add(code, [fixed, along_cos, along_sin]))
    x, y, z = rows
    return x, y, z
