"""The closed form of :mod:`a1_leg_fk.kinematics.ik.closed_form` and the seed rule as generated
straight-line Python with a leg's constants folded in (the common case, fast), as the FK is
(:mod:`a1_leg_fk.kinematics.fk_codegen`): one leg on floats and on numpy columns, and the four legs
fused in one function. Compiled by :func:`a1_leg_fk.kinematics.fk_codegen.compile_source`
(tracebacks and pdb show the generated lines). No ROS.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from a1_leg_fk.kinematics.fk_codegen import (
    compile_source,
)
from a1_leg_fk.kinematics.ik.closed_form import ARGUMENT_TOLERANCE, Geometry
from a1_leg_fk.kinematics.ik.code_parts import (
    ARRAY_NAMES,
    SCALAR_NAMES,
    clamped_argument,
    first_roll_sign,
    indented,
    knee_stage,
    representative,
    representatives,
    roll_stage,
    single_roll_bound,
)
from a1_leg_fk.kinematics.ik.seed import TWO_PI


def scalar_body(
    g: Geometry,
    limits: Sequence[tuple[float, float]],
    first_sign: float,
    targets: Sequence[str] = ("tx", "ty", "tz"),
    seeds: Sequence[str] = ("r0", "r1", "r2"),
    fused: bool = False,
) -> str:
    """The body (indented 4) of the generated ``solve`` on floats: it leaves in ``best`` the
    in-limit solution nearest the seed (``None`` if there is none) and in ``reachable`` whether
    any branch reaches the target, or executes ``UNREACHED`` (a roll argument beyond 1) or
    ``ROLL_OUTSIDE`` (a roll angle outside the limits; then ``continue``), placeholders the
    caller replaces. The target and seed are the variables ``targets`` and ``seeds``.

    ``fused`` (for :func:`fused_solver`): no ``reachable``, and where the leg has one knee branch
    ``branch_trig`` tells whether ``c0, s0, c2, s2`` and ``along, across`` (the cosine and sine of
    ``q1`` times a length) are those of the angles in ``best``: the roll loop was left by its
    ``break`` right after choosing them, and no angle went through the modulo or a clamp.
    """
    stage, knee = roll_stage(g, targets), knee_stage(g, limits)
    r0, r1, r2 = seeds
    single = single_roll_bound(limits)
    trig = fused and len(knee.signs) == 1
    mark = "branch_trig = False" if trig else ""
    nearer = (
        f"best is None or (q0 - {r0}) ** 2 + (q1 - {r1}) ** 2 + (q2 - {r2}) ** 2"
        f" < (best[0] - {r0}) ** 2 + (best[1] - {r1}) ** 2 + (best[2] - {r2}) ** 2"
    )
    early = f"{-single!r} < cos_roll < {single!r}"  # then the other roll branch is outside
    branch = f"""c2, s2 = {knee.cos_knee}, {knee.sin_knee}
q2 = {knee.angle}
{representative("q2", limits, 2, r2, "continue", mark)}
fx, fy = {knee.fx}, {knee.fy}
along, across = fx * {stage.gx} + fy * {stage.gy}, fx * {stage.gy} - fy * {stage.gx}
q1 = _atan2(across, along)
{representative("q1", limits, 1, r1, "continue", mark)}
if {nearer}:
    best = (q0, q1, q2)"""
    if len(knee.signs) == 2:
        branch = f"for knee_sign in {knee.signs!r}:\n    " + indented(branch, 4)
        if single > 0.0:
            branch += f"\nif best is not None and {early}:\n    break"
    elif single > 0.0:
        branch += f"\n    if {early}:\n        break"
    roll_branch = f"""c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
q0 = _atan2(s0, c0)
{representative("q0", limits, 0, r0, "ROLL_OUTSIDE", mark)}
{chr(10).join(stage.knee)}
cos_knee = ({stage.gx} * {stage.gx} + {stage.gy} * {stage.gy} - {g.alpha!r}) / {g.kappa!r}
{clamped_argument("cos_knee", "continue")}{"" if fused else f"{chr(10)}reachable = True"}
sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
knee_angle = _atan2(sin_knee, cos_knee)
{branch}"""
    start = "best, branch_trig = None, True" if trig else "best = None"
    no_break = "\nelse:\n    branch_trig = False" if trig else ""  # the loop ran out
    body = f"""{chr(10).join(stage.head)}
radius = _sqrt({stage.a} * {stage.a} + {stage.b_cross} * {stage.b_cross})
if not 0.0 < radius < _inf:  # on the roll axis, or too far for the squares
    return None
cos_roll = {g.lateral_m!r} / radius
{clamped_argument("cos_roll", "UNREACHED")}
sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
cos_base, sin_base = {stage.a} / radius, {stage.b_cross} / radius
{start if fused else "best, reachable, roll_outside = None, False, False"}
for roll_sign in {(first_sign, -first_sign)!r}:
    {indented(roll_branch, 4)}{no_break}"""
    return "    " + indented(body, 4) + "\n"


def fast_solver(
    g: Geometry,
    limits: Sequence[tuple[float, float]],
    leg: str,
    owner: object,
    typical: Sequence[float],
) -> tuple[Callable[..., Any], Callable[..., Any], float] | None:
    """The closed form of :func:`branches` and the choice of :meth:`LegSolver.solve` as one
    generated function on floats with the leg's constants folded in, as the FK is (see
    :func:`a1_leg_fk.kinematics.fk_codegen.leg_source`), or ``None`` when a joint has finite limits
    2 pi or more apart (then the general path decides). ``solve(tx, ty, tz, r0, r1, r2)`` takes a
    target [m, base frame] and the seed [rad]; it returns ``(angles, reachable)`` with ``angles``
    the in-limit exact solution nearest the seed (``None`` if there is none), or ``None`` for the
    general path to decide (a target on the roll axis or too far for its squares; no solution in
    the limits and a roll angle outside them, whose branch was not followed). Returned with it:
    ``solve_batch``, the same code on (N,) numpy columns, returning the three angle columns,
    whether the row has an in-limit solution (the other columns are meaningless where not) and
    the chosen branch's cosines and sines ``(c0, s0, c1, s1, c2, s2)`` (of the angles before
    any clamping onto a limit); and the roll branch tried first (for :func:`scalar_body`), the
    one holding the in-limit solution at ``typical``, a target [m] (the foot at the middle of
    the ranges).
    """
    if any(lower != -math.inf and not upper - lower < TWO_PI for lower, upper in limits):
        return None
    first_sign = first_roll_sign(g, limits, typical)
    body = scalar_body(g, limits, first_sign)
    source = (
        "def solve(tx, ty, tz, r0, r1, r2):\n"
        + body.replace("UNREACHED", "return None, False").replace(
            "ROLL_OUTSIDE", "roll_outside = True; continue"
        )
        + """    if best is None and roll_outside:  # a roll branch outside the limits may reach it
        return None
    return best, reachable
"""
    )
    namespace = compile_source(source, f"IK of leg {leg}", owner)
    namespace.update(SCALAR_NAMES)
    arrays = compile_source(
        _batch_source(g, limits, first_sign), f"IK of leg {leg}, arrays", owner
    )
    arrays.update(ARRAY_NAMES)
    return namespace["solve"], arrays["solve_batch"], first_sign


def _batch_source(g: Geometry, limits: Sequence[tuple[float, float]], first_sign: float) -> str:
    """The source of the generated ``knee_batch`` and ``solve_batch`` (see :func:`fast_solver`)."""
    stage, knee = roll_stage(g, ("tx", "ty", "tz")), knee_stage(g, limits)
    tolerance = 1.0 + ARGUMENT_TOLERANCE
    branch = f"""c2, s2 = {knee.cos_knee}, {knee.sin_knee}
q2 = {knee.angle}
{representatives("q2", limits, 2)}
fx, fy = {knee.fx}, {knee.fy}
along, across = fx * gx + fy * gy, fx * gy - fy * gx
q1 = _atan2(across, along)
{representatives("q1", limits, 1)}
found = usable & q1_inside & q2_inside"""
    if len(knee.signs) == 1:
        knee_code = branch + "\nreturn [found, q0, q1, q2, c0, s0, along, across, c2, s2]"
    else:  # both knee branches: the nearer the seed where both are inside
        knee_code = f"""d0 = (q0 - r0) ** 2
best_distance = _full(q0.shape, _inf)
best = [best_distance] * 9
for knee_sign in {knee.signs!r}:
    {indented(branch, 4)}
    distance = _where(found, d0 + (q1 - r1) ** 2 + (q2 - r2) ** 2, _inf)
    better = distance < best_distance
    best_distance = _where(better, distance, best_distance)
    new = (q0, q1, q2, c0, s0, along, across, c2, s2)
    best = [_where(better, value, old) for value, old in zip(new, best)]
return [best_distance < _inf, *best]"""

    def roll_branch(name: str, sign: float) -> str:
        """The columns of one roll branch: cosine, sine, angle and whether it is inside (the
        products as the float code's ``roll_sign * ...``: a factor of +-1 is exact).
        """
        minus, plus = ("-", "+") if sign > 0.0 else ("+", "-")
        return f"""{name}_c0 = cos_cos {minus} sin_sin
    {name}_s0 = sin_cos {plus} cos_sin
    {name}_q0 = _atan2({name}_s0, {name}_c0)
    {indented(representatives(f"{name}_q0", limits, 0), 4)}
    {name}_q0_inside &= roll_exact"""

    return f"""def knee_batch(c0, s0, q0, gx, gy, usable, r0, r1, r2):
    knee_argument = (gx * gx + gy * gy - {g.alpha!r}) / {g.kappa!r}
    usable = usable & (abs(knee_argument) <= {tolerance!r})
    cos_knee = _clip(knee_argument, -1.0, 1.0)
    sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
    knee_angle = _atan2(sin_knee, cos_knee)
    {indented(knee_code, 4)}

def _distance(best, r0, r1, r2):
    return (best[1] - r0) ** 2 + (best[2] - r1) ** 2 + (best[3] - r2) ** 2

def roll_batch(c0, s0, tx, ty, tz):
    {indented(chr(10).join(stage.head), 4)}
    {indented(chr(10).join(stage.knee), 4)}
    return {stage.gx}, {stage.gy}

def solve_batch(tx, ty, tz, r0, r1, r2):
    {indented(chr(10).join(stage.head), 4)}
    radius = _sqrt({stage.a} * {stage.a} + {stage.b_cross} * {stage.b_cross})
    roll_argument = {g.lateral_m!r} / radius
    roll_exact = (abs(roll_argument) <= {tolerance!r}) & (radius < _inf)
    cos_roll = _clip(roll_argument, -1.0, 1.0)
    sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
    cos_base, sin_base = {stage.a} / radius, {stage.b_cross} / radius
    cos_cos, sin_sin = cos_base * cos_roll, sin_base * sin_roll
    sin_cos, cos_sin = sin_base * cos_roll, cos_base * sin_roll
    {roll_branch("first", first_sign)}
    {roll_branch("second", -first_sign)}
    # Each row's first roll branch inside the limits; the other as well where both are inside.
    c0 = _where(first_q0_inside, first_c0, second_c0)
    s0 = _where(first_q0_inside, first_s0, second_s0)
    q0 = _where(first_q0_inside, first_q0, second_q0)
    {indented(chr(10).join(stage.knee), 4)}
    inside = first_q0_inside | second_q0_inside
    best = knee_batch(c0, s0, q0, {stage.gx}, {stage.gy}, inside, r0, r1, r2)
    both = _flatnonzero(first_q0_inside & second_q0_inside)
    if both.size:
        c0, s0, q0 = second_c0[both], second_s0[both], second_q0[both]
        gx, gy = roll_batch(c0, s0, tx[both], ty[both], tz[both])
        seed = r0[both], r1[both], r2[both]
        other = knee_batch(c0, s0, q0, gx, gy, True, *seed)
        mine = [column[both] for column in best[:4]]
        # The nearer the seed; on a tie the first branch, as the scalar code.
        closer = other[0] & (~mine[0] | (_distance(other, *seed) < _distance(mine, *seed)))
        rows = both[closer]
        for column, new in zip(best, other):
            column[rows] = new[closer]
    found, best0, best1, best2, cos0, sin0, x1, y1, cos2, sin2 = best
    # A distance in the knee's plane, < 1 m where a branch was found: no overflow.
    norm1 = _sqrt(x1 * x1 + y1 * y1)
    return best0, best1, best2, found, (cos0, sin0, x1 / norm1, y1 / norm1, cos2, sin2)
"""
