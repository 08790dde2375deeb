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
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.fk_codegen import Code, Term, compile_source, linear, scaled, weighted_sum
from a1_leg_fk.ik_closed_form import ARGUMENT_TOLERANCE, Geometry, branches
from a1_leg_fk.ik_seed import LIMIT_TOLERANCE_RAD, SCALAR, TWO_PI, representative_angle

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
    "_sqrt": np.sqrt,
    "_clip": np.clip,
    "_atan2": np.arctan2,
    "_inf": math.inf,
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


def _bound(code: Code, expressions: Sequence[Term]) -> tuple[Term, ...]:
    """Constants, names and negated names as they are, other expressions bound to fresh
    variables.
    """
    return tuple(
        e if isinstance(e, float) or e.lstrip("-").isidentifier() else code.assign([e])[0]
        for e in expressions
    )


@dataclass(frozen=True)
class _RollStage:
    """The generated code of the closed form's first step (see :mod:`a1_leg_fk.inverse`)."""

    head: tuple[str, ...]
    """Lines computing the target in the roll joint's frame from the target's names."""
    a: Term
    """``b . t0``, with :attr:`b_cross` the roll branches' ``A`` and ``B``."""
    b_cross: Term
    knee: tuple[str, ...]
    """Lines computing, for one roll branch (``c0``, ``s0``), the target's coordinates ``gx``,
    ``gy`` [m] in the plane normal to the pitch axis, relative to the pitch joint."""
    gx: Term
    gy: Term


def _roll_stage(g: Geometry, targets: Sequence[str]) -> _RollStage:
    """The code of the roll step for a target named ``targets`` (x, y, z [m], base frame)."""
    code = Code("t")
    relative = _bound(
        code,
        [
            weighted_sum([("", name), ("", -origin)])
            for name, origin in zip(targets, g.roll_origin, strict=True)
        ],
    )
    t0 = _bound(code, [linear(row, relative) for row in g.roll_rotation_t])
    along, a, b = _bound(
        code, [linear(g.roll_axis, t0), linear(g.pitch_axis, t0), linear(g.pitch_cross, t0)]
    )
    along_factor = str(along)  # a0 . t0 depends on the target: an expression, never a constant
    ax, ay, az = g.roll_axis
    # T0 - a0 (a0 . t0); exactly 0 along a roll axis that is a coordinate axis.
    coordinate_axis = sorted(abs(axis) for axis in g.roll_axis) == [0.0, 0.0, 1.0]
    across = _bound(
        code,
        [
            0.0
            if coordinate_axis and axis != 0.0
            else weighted_sum([("", t), (along_factor, -axis)])
            for t, axis in zip(t0, g.roll_axis)
        ],
    )
    # A0 x t0.
    crossed = _bound(
        code, [linear(row, t0) for row in ((0.0, -az, ay), (az, 0.0, -ax), (-ay, ax, 0.0))]
    )
    # Rot(a0, -q0) t0 - o1 = a0 (a0 . t0) - o1 + c0 across - s0 crossed, by parts, so that each
    # plane coordinate is one sum: no variable for a coordinate it does not need, no negations.
    moved = [
        [(along_factor, axis), ("", -origin), ("c0", p), ("-s0", c)]
        for axis, origin, p, c in zip(g.roll_axis, g.pitch_origin, across, crossed)
    ]
    knee = Code("k")
    gx, gy = knee.assign(
        [
            weighted_sum(
                sorted(
                    (
                        (factor, scaled(k, term))
                        for k, parts in zip(row, moved)
                        if k != 0.0
                        for factor, term in parts
                    ),
                    key=_negative,  # a positive term first: no unary minus
                )
            )
            for row in g.plane
        ]
    )
    return _RollStage(tuple(code.lines), a, b, tuple(knee.lines), gx, gy)


def _negative(part: tuple[str, Term]) -> bool:
    """Whether a ``(factor, term)`` part of :func:`weighted_sum` is subtracted."""
    factor, term = part
    negative_term = term < 0.0 if isinstance(term, float) else term.startswith("-")
    return factor.startswith("-") != negative_term


def _first_roll_sign(
    g: Geometry, limits: Sequence[tuple[float, float]], typical: Sequence[float]
) -> float:
    """The roll branch (+1 or -1) holding the in-limit solution at a typical target [m, base
    frame] (the foot at the middle of the ranges), tried first: where only one roll branch can be
    inside the limits the other is then seldom computed.
    """
    lower, upper = limits[0]
    x, y, z = typical
    for (angles, exact), sign in zip(branches(g, x, y, z, SCALAR)[::2], (1.0, -1.0)):
        if exact and representative_angle(angles[0], 0.0, lower, upper, SCALAR)[1]:
            return sign
    return 1.0


def _single_roll_bound(limits: Sequence[tuple[float, float]]) -> float:
    """``C`` such that where ``|cos_roll| < C`` at most one roll branch lies inside the roll's
    limits: the branches are ``2 acos(cos_roll)`` apart (modulo 2 pi), more than the range is
    wide (with the tolerances, and 1e-9 rad for rounding); 0 (never) for a wide or no range.
    """
    lower, upper = limits[0]
    half_width = (upper - lower) / 2.0 + LIMIT_TOLERANCE_RAD + 1e-9
    return math.cos(half_width) if half_width < math.pi / 2.0 else 0.0


def _representative(
    name: str,
    limits: Sequence[tuple[float, float]],
    slot: int,
    seed: str,
    outside: str,
    mark: str = "",
) -> str:
    """:func:`representative_angle` on ``name`` in place, as statements: nothing to do for an angle
    already inside the limits; else (after the statement ``mark``, if any) its value modulo 2 pi
    just above the lower limit, clamped onto the range within :data:`LIMIT_TOLERANCE_RAD` and
    ``outside`` beyond; for a continuous joint the value within pi of ``seed``.
    """
    lower, upper = limits[slot]
    if lower == -math.inf:
        return f"{name} = {seed} + ({name} - {seed} + {math.pi!r}) % {TWO_PI!r} - {math.pi!r}"
    low = lower - LIMIT_TOLERANCE_RAD
    return f"""if not {lower!r} <= {name} <= {upper!r}:{f"{chr(10)}    {mark}" if mark else ""}
    {name} = {low!r} + ({name} - {low!r}) % {TWO_PI!r}
    if {name} > {upper!r}:
        if {name} > {upper + LIMIT_TOLERANCE_RAD!r}:
            {outside}
        {name} = {upper!r}
    elif {name} < {lower!r}:
        {name} = {lower!r}"""


def _representatives(name: str, limits: Sequence[tuple[float, float]], slot: int) -> str:
    """:func:`representative_angle` on the array ``name`` in place, as statements:
    clamped into the range and ``name_inside`` (by floor: numpy's ``%`` on floats is several times
    slower; exact for an angle already inside); for a continuous joint the value within pi of the
    seed ``r<slot>``.
    """
    lower, upper = limits[slot]
    if lower == -math.inf:
        return (
            f"{name} = {name} - r{slot} + {math.pi!r}\n"
            f"{name} = {name} - {TWO_PI!r} * _floor({name} * {1.0 / TWO_PI!r})"
            f" - {math.pi!r} + r{slot}\n"
            f"{name}_inside = True"
        )
    low = lower - LIMIT_TOLERANCE_RAD
    return (
        f"{name} = {name} - {TWO_PI!r} * _floor(({name} - {low!r}) * {1.0 / TWO_PI!r})\n"
        f"{name}_inside = {name} <= {upper + LIMIT_TOLERANCE_RAD!r}\n"
        f"{name} = _clip({name}, {lower!r}, {upper!r})"
    )


@dataclass(frozen=True)
class _Knee:
    """The knee step's text pieces shared by the float and the array code: the knee branches that
    can be inside the knee's limits, and per branch the cosine, sine and angle of the knee and the
    foot in the knee plane at that angle.
    """

    signs: tuple[float, ...]
    cos_knee: Term
    sin_knee: Term
    angle: Term
    fx: Term
    fy: Term


def _knee(g: Geometry, limits: Sequence[tuple[float, float]]) -> _Knee:
    """The knee step: ``q2 = peak +- acos(knee argument)``, the sign folded in where only one
    branch can be inside the knee's limits (else a ``knee_sign`` loop variable).
    """
    peak = math.atan2(g.sin_peak, g.cos_peak)
    signs = tuple(
        sign for sign in (1.0, -1.0) if _knee_branch_can_be_inside(peak, sign, *limits[2])
    ) or (1.0, -1.0)
    if len(signs) == 2:
        signed_sin, signed_angle = "knee_sign * sin_knee", "knee_sign * knee_angle"
    else:
        sign = "-" if signs[0] < 0.0 else ""
        signed_sin, signed_angle = f"{sign}sin_knee", f"{sign}knee_angle"
    return _Knee(
        signs,
        weighted_sum([("cos_knee", g.cos_peak), (signed_sin, -g.sin_peak)]),
        weighted_sum([("cos_knee", g.sin_peak), (signed_sin, g.cos_peak)]),
        weighted_sum([("", peak), (signed_angle, 1.0)]),
        weighted_sum([("", g.foot_u[0]), ("c2", g.foot_v[0]), ("s2", g.foot_w[0])]),
        weighted_sum([("", g.foot_u[1]), ("c2", g.foot_v[1]), ("s2", g.foot_w[1])]),
    )


def _indented(text: str, spaces: int) -> str:
    """``text`` with every line after the first indented by ``spaces`` more."""
    return text.replace("\n", "\n" + " " * spaces)


def _clamped_argument(name: str, outside: str) -> str:
    """Statements that leave an ``acos`` argument ``name`` inside [-1, 1] alone, clamp it onto +-1
    within :data:`ARGUMENT_TOLERANCE` and execute ``outside`` beyond.
    """
    return f"""if not -1.0 <= {name} <= 1.0:
    if abs({name}) > {1.0 + ARGUMENT_TOLERANCE!r}:
        {outside}
    {name} = 1.0 if {name} > 0.0 else -1.0"""


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
    stage, knee = _roll_stage(g, targets), _knee(g, limits)
    r0, r1, r2 = seeds
    single = _single_roll_bound(limits)
    trig = fused and len(knee.signs) == 1
    mark = "branch_trig = False" if trig else ""
    nearer = (
        f"best is None or (q0 - {r0}) ** 2 + (q1 - {r1}) ** 2 + (q2 - {r2}) ** 2"
        f" < (best[0] - {r0}) ** 2 + (best[1] - {r1}) ** 2 + (best[2] - {r2}) ** 2"
    )
    early = f"{-single!r} < cos_roll < {single!r}"  # then the other roll branch is outside
    branch = f"""c2, s2 = {knee.cos_knee}, {knee.sin_knee}
q2 = {knee.angle}
{_representative("q2", limits, 2, r2, "continue", mark)}
fx, fy = {knee.fx}, {knee.fy}
along, across = fx * {stage.gx} + fy * {stage.gy}, fx * {stage.gy} - fy * {stage.gx}
q1 = _atan2(across, along)
{_representative("q1", limits, 1, r1, "continue", mark)}
if {nearer}:
    best = (q0, q1, q2)"""
    if len(knee.signs) == 2:
        branch = f"for knee_sign in {knee.signs!r}:\n    " + _indented(branch, 4)
        if single > 0.0:
            branch += f"\nif best is not None and {early}:\n    break"
    elif single > 0.0:
        branch += f"\n    if {early}:\n        break"
    roll_branch = f"""c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
q0 = _atan2(s0, c0)
{_representative("q0", limits, 0, r0, "ROLL_OUTSIDE", mark)}
{chr(10).join(stage.knee)}
cos_knee = ({stage.gx} * {stage.gx} + {stage.gy} * {stage.gy} - {g.alpha!r}) / {g.kappa!r}
{_clamped_argument("cos_knee", "continue")}{"" if fused else f"{chr(10)}reachable = True"}
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
{_clamped_argument("cos_roll", "UNREACHED")}
sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
cos_base, sin_base = {stage.a} / radius, {stage.b_cross} / radius
{start if fused else "best, reachable, roll_outside = None, False, False"}
for roll_sign in {(first_sign, -first_sign)!r}:
    {_indented(roll_branch, 4)}{no_break}"""
    return "    " + _indented(body, 4) + "\n"


def fast_solver(
    g: Geometry,
    limits: Sequence[tuple[float, float]],
    leg: str,
    owner: object,
    typical: Sequence[float],
) -> tuple[Callable[..., Any], Callable[..., Any], float] | None:
    """The closed form of :func:`branches` and the choice of :meth:`LegSolver.solve` as one
    generated function on floats with the leg's constants folded in, as the FK is (see
    :func:`a1_leg_fk.fk_codegen.leg_source`), or ``None`` when a joint has finite limits 2 pi or
    more apart (then the general path decides). ``solve(tx, ty, tz, r0, r1, r2)`` takes a target
    [m, base frame] and the seed [rad]; it returns ``(angles, reachable)`` with ``angles`` the
    in-limit exact solution nearest the seed (``None`` if there is none), or ``None`` for the
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
    first_sign = _first_roll_sign(g, limits, typical)
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
    namespace.update(_SCALAR_NAMES)
    arrays = compile_source(
        _batch_source(g, limits, first_sign), f"IK of leg {leg}, arrays", owner
    )
    arrays.update(_ARRAY_NAMES)
    return namespace["solve"], arrays["solve_batch"], first_sign


def _batch_source(g: Geometry, limits: Sequence[tuple[float, float]], first_sign: float) -> str:
    """The source of the generated ``knee_batch`` and ``solve_batch`` (see :func:`fast_solver`)."""
    stage, knee = _roll_stage(g, ("tx", "ty", "tz")), _knee(g, limits)
    tolerance = 1.0 + ARGUMENT_TOLERANCE
    branch = f"""c2, s2 = {knee.cos_knee}, {knee.sin_knee}
q2 = {knee.angle}
{_representatives("q2", limits, 2)}
fx, fy = {knee.fx}, {knee.fy}
along, across = fx * gx + fy * gy, fx * gy - fy * gx
q1 = _atan2(across, along)
{_representatives("q1", limits, 1)}
found = usable & q1_inside & q2_inside"""
    if len(knee.signs) == 1:
        knee_code = branch + "\nreturn [found, q0, q1, q2, c0, s0, along, across, c2, s2]"
    else:  # both knee branches: the nearer the seed where both are inside
        knee_code = f"""d0 = (q0 - r0) ** 2
best_distance = _full(q0.shape, _inf)
best = [best_distance] * 9
for knee_sign in {knee.signs!r}:
    {_indented(branch, 4)}
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
    {_indented(_representatives(f"{name}_q0", limits, 0), 4)}
    {name}_q0_inside &= roll_exact"""

    return f"""def knee_batch(c0, s0, q0, gx, gy, usable, r0, r1, r2):
    knee_argument = (gx * gx + gy * gy - {g.alpha!r}) / {g.kappa!r}
    usable = usable & (abs(knee_argument) <= {tolerance!r})
    cos_knee = _clip(knee_argument, -1.0, 1.0)
    sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
    knee_angle = _atan2(sin_knee, cos_knee)
    {_indented(knee_code, 4)}

def _distance(best, r0, r1, r2):
    return (best[1] - r0) ** 2 + (best[2] - r1) ** 2 + (best[3] - r2) ** 2

def roll_batch(c0, s0, tx, ty, tz):
    {_indented(chr(10).join(stage.head), 4)}
    {_indented(chr(10).join(stage.knee), 4)}
    return {stage.gx}, {stage.gy}

def solve_batch(tx, ty, tz, r0, r1, r2):
    {_indented(chr(10).join(stage.head), 4)}
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
    {_indented(chr(10).join(stage.knee), 4)}
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
    namespace.update(_SCALAR_NAMES)
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
