"""The parts of the generated IK code (:mod:`a1_leg_fk.kinematics.ik.codegen`): the roll stage,
the knee stage and the seed rule's in-limit representatives as source text with a leg's constants
folded in, and the names that text uses on floats and on numpy arrays. No ROS.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from a1_leg_fk.kinematics.fk_codegen import (
    Code,
    Term,
    linear,
    scaled,
    weighted_sum,
)
from a1_leg_fk.kinematics.ik.closed_form import ARGUMENT_TOLERANCE, Geometry, branches
from a1_leg_fk.kinematics.ik.seed import LIMIT_TOLERANCE_RAD, SCALAR, TWO_PI, representative_angle

SCALAR_NAMES: dict[str, Any] = {
    "_hypot": math.hypot,
    "_sqrt": math.sqrt,
    "_atan2": math.atan2,
    "_inf": math.inf,
}
"""The names the generated code uses besides ``_cos`` and ``_sin``, on floats."""
ARRAY_NAMES: dict[str, Any] = {
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


def knee_branch_can_be_inside(peak: float, sign: float, lower: float, upper: float) -> bool:
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


def bound(code: Code, expressions: Sequence[Term]) -> tuple[Term, ...]:
    """Constants, names and negated names as they are, other expressions bound to fresh
    variables.
    """
    return tuple(
        e if isinstance(e, float) or e.lstrip("-").isidentifier() else code.assign([e])[0]
        for e in expressions
    )


@dataclass(frozen=True)
class RollStage:
    """The generated code of the closed form's first step (see
    :mod:`a1_leg_fk.kinematics.ik.four_legs`).
    """

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


def roll_stage(g: Geometry, targets: Sequence[str]) -> RollStage:
    """The code of the roll step for a target named ``targets`` (x, y, z [m], base frame)."""
    code = Code("t")
    relative = bound(
        code,
        [
            weighted_sum([("", name), ("", -origin)])
            for name, origin in zip(targets, g.roll_origin, strict=True)
        ],
    )
    t0 = bound(code, [linear(row, relative) for row in g.roll_rotation_t])
    along, a, b = bound(
        code, [linear(g.roll_axis, t0), linear(g.pitch_axis, t0), linear(g.pitch_cross, t0)]
    )
    along_factor = str(along)  # a0 . t0 depends on the target: an expression, never a constant
    ax, ay, az = g.roll_axis
    # T0 - a0 (a0 . t0); exactly 0 along a roll axis that is a coordinate axis.
    coordinate_axis = sorted(abs(axis) for axis in g.roll_axis) == [0.0, 0.0, 1.0]
    across = bound(
        code,
        [
            0.0
            if coordinate_axis and axis != 0.0
            else weighted_sum([("", t), (along_factor, -axis)])
            for t, axis in zip(t0, g.roll_axis)
        ],
    )
    # A0 x t0.
    crossed = bound(
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
                    key=negative,  # a positive term first: no unary minus
                )
            )
            for row in g.plane
        ]
    )
    return RollStage(tuple(code.lines), a, b, tuple(knee.lines), gx, gy)


def negative(part: tuple[str, Term]) -> bool:
    """Whether a ``(factor, term)`` part of :func:`weighted_sum` is subtracted."""
    factor, term = part
    negative_term = term < 0.0 if isinstance(term, float) else term.startswith("-")
    return factor.startswith("-") != negative_term


def first_roll_sign(
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


def single_roll_bound(limits: Sequence[tuple[float, float]]) -> float:
    """``C`` such that where ``|cos_roll| < C`` at most one roll branch lies inside the roll's
    limits: the branches are ``2 acos(cos_roll)`` apart (modulo 2 pi), more than the range is
    wide (with the tolerances, and 1e-9 rad for rounding); 0 (never) for a wide or no range.
    """
    lower, upper = limits[0]
    half_width = (upper - lower) / 2.0 + LIMIT_TOLERANCE_RAD + 1e-9
    return math.cos(half_width) if half_width < math.pi / 2.0 else 0.0


def representative(
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


def representatives(name: str, limits: Sequence[tuple[float, float]], slot: int) -> str:
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
class KneeStage:
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


def knee_stage(g: Geometry, limits: Sequence[tuple[float, float]]) -> KneeStage:
    """The knee step: ``q2 = peak +- acos(knee argument)``, the sign folded in where only one
    branch can be inside the knee's limits (else a ``knee_sign`` loop variable).
    """
    peak = math.atan2(g.sin_peak, g.cos_peak)
    signs = tuple(
        sign for sign in (1.0, -1.0) if knee_branch_can_be_inside(peak, sign, *limits[2])
    ) or (1.0, -1.0)
    if len(signs) == 2:
        signed_sin, signed_angle = "knee_sign * sin_knee", "knee_sign * knee_angle"
    else:
        sign = "-" if signs[0] < 0.0 else ""
        signed_sin, signed_angle = f"{sign}sin_knee", f"{sign}knee_angle"
    return KneeStage(
        signs,
        weighted_sum([("cos_knee", g.cos_peak), (signed_sin, -g.sin_peak)]),
        weighted_sum([("cos_knee", g.sin_peak), (signed_sin, g.cos_peak)]),
        weighted_sum([("", peak), (signed_angle, 1.0)]),
        weighted_sum([("", g.foot_u[0]), ("c2", g.foot_v[0]), ("s2", g.foot_w[0])]),
        weighted_sum([("", g.foot_u[1]), ("c2", g.foot_v[1]), ("s2", g.foot_w[1])]),
    )


def indented(text: str, spaces: int) -> str:
    """``text`` with every line after the first indented by ``spaces`` more."""
    return text.replace("\n", "\n" + " " * spaces)


def clamped_argument(name: str, outside: str) -> str:
    """Statements that leave an ``acos`` argument ``name`` inside [-1, 1] alone, clamp it onto +-1
    within :data:`ARGUMENT_TOLERANCE` and execute ``outside`` beyond.
    """
    return f"""if not -1.0 <= {name} <= 1.0:
    if abs({name}) > {1.0 + ARGUMENT_TOLERANCE!r}:
        {outside}
    {name} = 1.0 if {name} > 0.0 else -1.0"""
