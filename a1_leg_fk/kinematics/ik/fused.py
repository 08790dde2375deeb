"""The four legs' generated IK in one function (:func:`fused_solver`): every leg's closed-form
body of :mod:`a1_leg_fk.kinematics.ik.codegen` with its FK residual inlined, the fast path of
:meth:`Quadruped.ik <a1_leg_fk.kinematics.quadruped.Quadruped.ik>`. No ROS.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

from a1_leg_fk.kinematics.fk_codegen import compile_source
from a1_leg_fk.kinematics.ik.code_parts import SCALAR_NAMES
from a1_leg_fk.kinematics.ik.codegen import scalar_body
from a1_leg_fk.kinematics.ik.leg_solver import LegSolver


@functools.lru_cache(maxsize=16)
def fused_solver(
    solvers: tuple[LegSolver, ...],
) -> tuple[Callable[..., tuple[float, ...] | None], tuple[float, ...]] | None:
    """The generated bodies of every leg's :func:`scalar_body` in one function, and the default
    seed (the middles, 12 angles [rad]); ``None`` when a leg has no generated solver.

    ``solve(x0, y0, z0, ..., z3, r0, ..., r11)`` takes the targets [m, base frame] and the seed
    [rad] in slot order; it returns the 12 angles [rad] and the 4 residuals [m] (the distance from
    :meth:`CompiledLeg.position` at those angles to the target) as one flat tuple, or ``None``
    when some leg has no in-limit solution there or needs the general path (:meth:`LegSolver.solve`
    then decides every leg, as it would have).
    """
    targets = [f"_{axis}{slot}" for slot in range(len(solvers)) for axis in "xyz"]
    seeds = [f"_r{joint}" for joint in range(3 * len(solvers))]
    lines = [f"def solve({', '.join(targets)}, {', '.join(seeds)}):"]
    for slot, solver in enumerate(solvers):
        geometry, first_sign = solver.geometry, solver._first_roll_sign
        if geometry is None or first_sign is None:
            return None
        tx, ty, tz = targets[3 * slot : 3 * slot + 3]
        body = scalar_body(
            geometry,
            solver._limits,
            first_sign,
            (tx, ty, tz),
            seeds[3 * slot : 3 * slot + 3],
            fused=True,
        )
        q0, q1, q2 = (f"_q{joint}" for joint in range(3 * slot, 3 * slot + 3))
        trig = ", ".join(f"_cos({q}), _sin({q})" for q in (q0, q1, q2))
        trig = f"c0, s0, c1, s1, c2, s2 = {trig}"
        if "branch_trig" in body:
            trig = f"""if branch_trig:
        length = _hypot(along, across)
        c1, s1 = along / length, across / length
    else:
        {trig}"""
        lines += [
            body.replace("UNREACHED", "return None").replace("ROLL_OUTSIDE", "continue"),
            f"    if best is None:\n        return None\n    {q0}, {q1}, {q2} = best\n    {trig}",
            function_body(solver.leg.source, "position_from_trig", "fx, fy, fz"),
            f"    _e{slot} = _hypot(fx - {tx}, fy - {ty}, fz - {tz})  # hypot: no overflow",
        ]
    outputs = [f"_q{joint}" for joint in range(3 * len(solvers))] + [
        f"_e{slot}" for slot in range(len(solvers))
    ]
    lines.append(f"    return ({', '.join(outputs)})\n")
    namespace = compile_source("\n".join(lines), "IK of the legs", solvers[0])
    namespace.update(SCALAR_NAMES)
    return namespace["solve"], sum((solver._middle for solver in solvers), ())


def function_body(source: str, function: str, names: str) -> str:
    """The body of the generated ``function`` (``position`` or ``position_from_trig``) in a leg's
    FK ``source`` (see :class:`CompiledLeg`), assigning the foot [m, base frame] to ``names``
    instead of returning it.
    """
    start = source.index("\n", source.index(f"def {function}(")) + 1
    # The functions are blank-line separated.
    body, _ = source[start:].split("\n\n", 1)
    return body.replace("\n    return ", f"\n    {names} = ")
