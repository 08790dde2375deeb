"""The closed form of :mod:`a1_leg_fk.ik_closed_form` and the seed rule as generated straight-line
Python with a leg's constants folded in (the common case, fast), as the FK is
(:mod:`a1_leg_fk.fk_codegen`): one leg on floats and on numpy columns, and the four legs fused in
one function. Compiled by :func:`a1_leg_fk.fk_codegen.compile_source` (tracebacks and pdb show the
generated lines). No ROS.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.fk_codegen import Code, Term, compile_source, linear, weighted_sum
from a1_leg_fk.ik_closed_form import ARGUMENT_TOLERANCE, Geometry
from a1_leg_fk.ik_seed import LIMIT_TOLERANCE_RAD, TWO_PI

if TYPE_CHECKING:  # ik_solver imports this module: no cycle at run time
    from a1_leg_fk.ik_solver import LegSolver

_SCALAR_NAMES: dict[str, Any] = {
    "_hypot": math.hypot,
    "_sqrt": math.sqrt,
    "_atan2": math.atan2,
    "_inf": math.inf,
}
"""The names the generated code uses besides ``_cos`` and ``_sin``, on floats."""
_ARRAY_NAMES: dict[str, Any] = {
    "_hypot": np.hypot,
    "_sqrt": np.sqrt,
    "_atan2": np.arctan2,
    "_inf": math.inf,
    "_minimum": np.minimum,
    "_maximum": np.maximum,
    "_where": np.where,
    "_full": np.full,
    "_floor": np.floor,
    "_flatnonzero": np.flatnonzero,
}
"""The same names on numpy arrays, for the generated ``solve_batch``."""


def _knee_branch_can_be_inside(peak: float, sign: float, lower: float, upper: float) -> bool:
    """Whether the knee branch ``peak + sign * acos(...)`` (the acos in [0, pi]) has any value
    modulo 2 pi inside ``[lower, upper]`` [rad] (with a margin of 1e-6 rad: a branch kept in doubt
    only costs time); always for a continuous joint.
    """
    if lower == -math.inf:
        return True
    start, end = sorted((peak, peak + sign * math.pi))
    low, high = lower - 1e-6, upper + 1e-6
    # The first shift of the interval that ends at or above low.
    turns = math.ceil((low - end) / TWO_PI)
    return start + TWO_PI * turns <= high


def fast_solver(
    g: Geometry, limits: Sequence[tuple[float, float]], leg: str, owner: object
) -> tuple[Callable[..., Any], Callable[..., Any], str] | None:
    """The closed form of :func:`branches` and the choice of :meth:`LegSolver.solve` as one
    generated function on floats with the leg's constants folded in, as the FK is (see
    :func:`a1_leg_fk.fk_codegen.leg_source`), or ``None`` when a joint has finite limits 2 pi or more
    apart (then the general path decides). ``solve(tx, ty, tz, r0, r1, r2)`` takes a target
    [m, base frame] and the seed [rad]; it returns ``(angles, reachable)`` with ``angles`` the
    in-limit exact solution nearest the seed (``None`` if there is none), or ``None`` for the
    general path to decide (a target on the roll axis; no solution in the limits and a roll
    angle outside them, whose branch was not followed). Returned with it: ``solve_batch``, the
    same code on (N,) numpy columns (the branch chosen by ``np.where``), returning the three angle
    columns, the seed distance (``inf`` in rows without an in-limit solution, whose other columns
    are then meaningless) and the chosen branch's cosines and sines ``(c0, s0, c1, s1, c2, s2)``
    (of the angles before any clamping onto a limit); and the text of
    ``solve``'s body for :func:`fused_solver` (``return None`` wherever ``solve`` would not return
    an in-limit solution, ``best`` the chosen angles or ``None``).
    """
    if any(lower != -math.inf and not upper - lower < TWO_PI for lower, upper in limits):
        return None
    code = Code("t")

    def bind(code: Code, expressions: Sequence[Term]) -> tuple[Term, ...]:
        """Constants and names as they are, other expressions bound to fresh variables."""
        return tuple(
            e if isinstance(e, float) or e.lstrip("-").isidentifier() else code.assign([e])[0]
            for e in expressions
        )

    target = tuple(
        weighted_sum([("", name), ("", -origin)])
        for name, origin in zip(("tx", "ty", "tz"), g.roll_origin)
    )
    relative = bind(code, target)
    t0 = bind(code, [linear(row, relative) for row in g.roll_rotation_t])
    along, a, b = bind(
        code, [linear(g.roll_axis, t0), linear(g.pitch_axis, t0), linear(g.pitch_cross, t0)]
    )
    ax, ay, az = g.roll_axis
    along_factor = str(along)  # a0 . t0 depends on the target: an expression, never a constant
    # T0 - a0 (a0 . t0)
    across = bind(
        code, [weighted_sum([("", t), (along_factor, -axis)]) for t, axis in zip(t0, g.roll_axis)]
    )
    # A0 x t0.
    crossed = bind(
        code, [linear(row, t0) for row in ((0.0, -az, ay), (az, 0.0, -ax), (-ay, ax, 0.0))]
    )
    head = "\n    ".join(code.lines)
    knee = Code("k")
    moved = bind(
        knee,
        [
            weighted_sum([(along_factor, axis), ("", -origin), ("c0", p), ("-s0", c)])
            for axis, origin, p, c in zip(g.roll_axis, g.pitch_origin, across, crossed)
        ],
    )
    gx, gy = bind(knee, [linear(row, moved) for row in g.plane])
    cos_knee = weighted_sum([("cos_knee", g.cos_peak), ("knee_sign * sin_knee", -g.sin_peak)])
    sin_knee = weighted_sum([("cos_knee", g.sin_peak), ("knee_sign * sin_knee", g.cos_peak)])
    peak = math.atan2(g.sin_peak, g.cos_peak)  # q2 = peak +- acos(knee argument)
    roll_body = "\n        ".join(knee.lines)
    fx = weighted_sum([("", g.foot_u[0]), ("c2", g.foot_v[0]), ("s2", g.foot_w[0])])
    fy = weighted_sum([("", g.foot_u[1]), ("c2", g.foot_v[1]), ("s2", g.foot_w[1])])
    tolerance = 1.0 + ARGUMENT_TOLERANCE

    def representative(
        name: str, angle: str, slot: int, indent: str, outside: str = "continue"
    ) -> str:
        """:func:`representative_angle` for a range narrower than 2 pi (``outside`` when outside) or
        a continuous joint.
        """
        lower, upper = limits[slot]
        if lower == -math.inf:
            return (
                f"{name} = r{slot} + ({angle} - r{slot} + {math.pi!r}) % {TWO_PI!r} - {math.pi!r}"
            )
        low = lower - LIMIT_TOLERANCE_RAD
        return (
            f"{name} = {low!r} + ({angle} - {low!r}) % {TWO_PI!r}\n{indent}if {name} > {upper!r}:\n"
            f"{indent}    if {name} > {upper + LIMIT_TOLERANCE_RAD!r}:\n{indent}        {outside}\n"
            f"{indent}    {name} = {upper!r}\n{indent}elif {name} < {lower!r}:\n{indent}    {name} = {lower!r}"
        )

    knee_signs = tuple(
        sign for sign in (1.0, -1.0) if _knee_branch_can_be_inside(peak, sign, *limits[2])
    ) or (1.0, -1.0)

    def knee_loop(branch: str) -> str:
        """The code of one knee branch (``branch``, its lines indented 12) for each knee sign that
        can give an angle inside the knee's limits: a loop, or the one branch without a loop.
        """
        if len(knee_signs) == 2:
            return f"for knee_sign in {knee_signs!r}:\n            {branch}"
        return f"knee_sign = {knee_signs[0]!r}\n        " + branch.replace("\n    ", "\n")

    scalar_branch = f"""c2, s2 = {cos_knee}, {sin_knee}
            {representative("q2", f"{peak!r} + knee_sign * knee_angle", 2, " " * 12)}
            fx, fy = {fx}, {fy}
            {representative("q1", f"_atan2(fx * {gy} - fy * {gx}, fx * {gx} + fy * {gy})", 1, " " * 12)}
            distance = d0 + (q1 - r1) ** 2 + (q2 - r2) ** 2
            if distance < best_distance:
                best, best_distance = (q0, q1, q2), distance"""
    body = f"""{head}
    radius = _hypot({a}, {b})
    if radius == 0.0:
        return None
    roll_argument = {g.lateral_m!r} / radius
    if abs(roll_argument) > {tolerance!r}:
        return UNREACHED
    cos_roll = 1.0 if roll_argument > 1.0 else -1.0 if roll_argument < -1.0 else roll_argument
    sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
    cos_base, sin_base = {a} / radius, {b} / radius
    best, best_distance, reachable, roll_outside = None, _inf, False, False
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        {representative("q0", "_atan2(s0, c0)", 0, " " * 8, "ROLL_OUTSIDE")}
        {roll_body}
        knee_argument = ({gx} * {gx} + {gy} * {gy} - {g.alpha!r}) / {g.kappa!r}
        if abs(knee_argument) > {tolerance!r}:
            continue
        reachable = True
        d0 = (q0 - r0) ** 2
        cos_knee = 1.0 if knee_argument > 1.0 else -1.0 if knee_argument < -1.0 else knee_argument
        sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
        knee_angle = _atan2(sin_knee, cos_knee)
        {knee_loop(scalar_branch)}
"""
    source = (
        "def solve(tx, ty, tz, r0, r1, r2):\n    "
        + body.replace("UNREACHED", "None, False").replace(
            "ROLL_OUTSIDE", "roll_outside = True; continue"
        )
        + """    if best is None and roll_outside:  # whether a roll branch outside the limits reaches the target
        return None
    return best, reachable
"""
    )

    def representatives(name: str, angle: str, slot: int, indent: str = " " * 12) -> str:
        """:func:`representative_angle` on arrays for a range narrower than 2 pi: ``name`` clamped into
        the range and ``name_inside`` (by floor: numpy's ``%`` on floats is several times slower);
        for a continuous joint the value within pi of the seed.
        """
        lower, upper = limits[slot]
        if lower == -math.inf:
            return (
                f"{name} = {angle} - r{slot} + {math.pi!r}\n{indent}"
                f"{name} = {name} - {TWO_PI!r} * _floor({name} * {1.0 / TWO_PI!r}) - {math.pi!r} + r{slot}\n{indent}"
                f"{name}_inside = True"
            )
        low = lower - LIMIT_TOLERANCE_RAD
        return (
            f"{name} = {angle}\n{indent}{name} = {name} - {TWO_PI!r} * _floor(({name} - {low!r}) * {1.0 / TWO_PI!r})\n{indent}"
            f"{name}_inside = {name} <= {upper + LIMIT_TOLERANCE_RAD!r}\n{indent}"
            f"{name} = _minimum(_maximum({name}, {lower!r}), {upper!r})"
        )

    def select(value: str, previous: str) -> str:
        """The code choosing ``value`` where this knee branch is the better one: with one knee
        branch, ``value`` itself (where it is not usable the distance is inf, so the row is
        decided by the scalar path and its other columns are never read).
        """
        return f"_where(better, {value}, {previous})" if len(knee_signs) == 2 else value

    batch_branch = f"""c2, s2 = {cos_knee}, {sin_knee}
            {representatives("q2", f"{peak!r} + knee_sign * knee_angle", 2)}
            fx, fy = {fx}, {fy}
            along, across = fx * gx + fy * gy, fx * gy - fy * gx
            {representatives("q1", "_atan2(across, along)", 1)}
            distance = d0 + (q1 - r1) ** 2 + (q2 - r2) ** 2
            better = usable & q1_inside & q2_inside & (distance < best_distance)
            best_distance = _where(better, distance, best_distance)
            best0, best1, best2 = {select("q0", "best0")}, {select("q1", "best1")}, {select("q2", "best2")}
            cos0, sin0, cos2, sin2 = {select("c0", "cos0")}, {select("s0", "sin0")}, {select("c2", "cos2")}, {select("s2", "sin2")}
            x1, y1 = {select("along", "x1")}, {select("across", "y1")}"""
    source += f"""
def knee_batch(c0, s0, q0, gx, gy, knee_argument, usable, r0, r1, r2):
    d0 = (q0 - r0) ** 2
    cos_knee = _minimum(_maximum(knee_argument, -1.0), 1.0)
    sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
    knee_angle = _atan2(sin_knee, cos_knee)
    best_distance = _full(q0.shape, _inf)
    best0 = best1 = best2 = cos0 = sin0 = x1 = y1 = cos2 = sin2 = best_distance
    {knee_loop(batch_branch).replace(chr(10) + "    ", chr(10))}
    return [best0, best1, best2, best_distance, cos0, sin0, x1, y1, cos2, sin2]

def solve_batch(tx, ty, tz, r0, r1, r2):
    {head}
    radius = _hypot({a}, {b})
    roll_argument = {g.lateral_m!r} / radius
    roll_exact = abs(roll_argument) <= {tolerance!r}
    cos_roll = _minimum(_maximum(roll_argument, -1.0), 1.0)
    sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
    cos_base, sin_base = {a} / radius, {b} / radius
    roll_branches = []
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        {representatives("q0", "_atan2(s0, c0)", 0, " " * 8)}
        {roll_body}
        gx, gy = {gx}, {gy}
        knee_argument = (gx * gx + gy * gy - {g.alpha!r}) / {g.kappa!r}
        roll_branches.append((c0, s0, q0, gx, gy, knee_argument, roll_exact & q0_inside & (abs(knee_argument) <= {tolerance!r})))
    first, second = roll_branches
    # The knee stage once, on the first usable roll branch; again on the rows where both are usable.
    best = knee_batch(*[_where(first[6], one, other) for one, other in zip(first, second)], r0, r1, r2)
    both = _flatnonzero(first[6] & second[6])
    if both.size:
        other = knee_batch(*[value[both] for value in second], r0[both], r1[both], r2[both])
        closer = other[3] < best[3][both]  # on a tie the first branch, as the scalar code
        for column, value in zip(best, other):
            column[both] = _where(closer, value, column[both])
    best0, best1, best2, best_distance, cos0, sin0, x1, y1, cos2, sin2 = best
    norm1 = _sqrt(x1 * x1 + y1 * y1)  # a distance in the knee's plane, < 1 m where a branch was found
    return best0, best1, best2, best_distance, (cos0, sin0, x1 / norm1, y1 / norm1, cos2, sin2)
"""
    namespace = compile_source(source, f"IK of leg {leg}", owner)
    namespace.update(_SCALAR_NAMES)
    arrays = compile_source(source, f"IK of leg {leg}, arrays", owner)
    arrays.update(_ARRAY_NAMES)
    fused_body = body.replace("UNREACHED", "None").replace("ROLL_OUTSIDE", "continue")
    return namespace["solve"], arrays["solve_batch"], fused_body


@functools.lru_cache(maxsize=16)
def fused_solver(
    solvers: tuple[LegSolver, ...],
) -> tuple[Callable[..., tuple[float, ...] | None], tuple[float, ...]] | None:
    """The generated bodies of every leg's :func:`fast_solver` in one function, and the default
    seed (the middles, 12 angles [rad]); ``None`` when a leg has no generated solver.

    ``solve(x0, y0, z0, ..., z3, r0, ..., r11)`` takes the targets [m, base frame] and the seed
    [rad] in slot order; it returns the 12 angles [rad] and the 4 residuals [m] (the distance from
    :meth:`CompiledLeg.position` at those angles to the target) as one flat tuple, or ``None``
    when some leg has no in-limit solution there or needs the general path (:meth:`LegSolver.solve`
    then decides every leg, as it would have).
    """
    bodies = [body for solver in solvers if (body := solver._fast_body) is not None]
    if len(bodies) < len(solvers):
        return None
    targets = ", ".join(f"_{axis}{slot}" for slot in range(len(solvers)) for axis in "xyz")
    seeds = ", ".join(f"_r{joint}" for joint in range(3 * len(solvers)))
    lines = [f"def solve({targets}, {seeds}):"]
    for slot, (solver, body) in enumerate(zip(solvers, bodies)):
        lines += [
            f"    tx, ty, tz, r0, r1, r2 = _x{slot}, _y{slot}, _z{slot}, _r{3 * slot}, _r{3 * slot + 1}, _r{3 * slot + 2}",
            "    " + body,
            "    if best is None:\n        return None",
            f"    q0, q1, q2 = _q{3 * slot}, _q{3 * slot + 1}, _q{3 * slot + 2} = best",
            position_body(solver.leg.source, "fx, fy, fz"),
            f"    _e{slot} = _hypot(fx - tx, fy - ty, fz - tz)  # hypot: no overflow",
        ]
    outputs = [f"_q{joint}" for joint in range(3 * len(solvers))] + [
        f"_e{slot}" for slot in range(len(solvers))
    ]
    lines.append(f"    return ({', '.join(outputs)})\n")
    namespace = compile_source("\n".join(lines), "IK of the legs", solvers[0])
    namespace.update(_SCALAR_NAMES)
    return namespace["solve"], sum((solver._middle for solver in solvers), ())


def position_body(source: str, names: str) -> str:
    """The body of the generated ``position(q0, q1, q2)`` in a leg's FK ``source`` (see
    :class:`CompiledLeg`), assigning the foot [m, base frame] to ``names`` instead of returning it.
    """
    header = "def position(q0, q1, q2):\n"
    # The functions are blank-line separated.
    body, _ = source[source.index(header) + len(header) :].split("\n\n", 1)
    return body.replace("\n    return ", f"\n    {names} = ")
