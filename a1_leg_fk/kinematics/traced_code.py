"""Straight-line code with forward-mode derivatives, written by running an algorithm on traced
values.

A :class:`Traced` value is a term of generated code (a constant or a variable name, see
:mod:`a1_leg_fk.kinematics.fk_codegen`) together with its derivatives along a fixed number of
*seed* directions. Running an algorithm (say a leg's kinetic energy) on traced values with the
operations below writes its arithmetic into a :class:`~a1_leg_fk.kinematics.fk_codegen.Code`, one
line per operation, with the derivatives' lines beside the value's (forward-mode automatic
differentiation, done once when the model is built); zero terms are dropped as they arise, so the
result is the algorithm specialised to one leg's constants. :func:`function_source` then keeps
only the lines that a function's results need.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from a1_leg_fk.kinematics.fk_codegen import Code, Term, linear, product, weighted_sum

_NAME = re.compile(r"[A-Za-z_]\w*")


@dataclass(frozen=True)
class Traced:
    """A value of generated code (``value``) and its derivatives along each seed direction
    (``tangents``), all terms of the same :class:`~a1_leg_fk.kinematics.fk_codegen.Code`.
    """

    value: Term
    tangents: tuple[Term, ...]


def constant(value: float, directions: int) -> Traced:
    """A constant: its derivatives are zero."""
    return Traced(float(value), (0.0,) * directions)


def combine(code: Code, coefficients: Sequence[float], items: Sequence[Traced]) -> Traced:
    """``sum(c * item)`` for constant coefficients ``c``, zero terms dropped."""
    directions = len(items[0].tangents)
    value = linear(coefficients, [item.value for item in items])
    tangents = [
        linear(coefficients, [item.tangents[d] for item in items]) for d in range(directions)
    ]
    first, *rest = code.assign([value, *tangents])
    return Traced(first, tuple(rest))


def add(code: Code, items: Sequence[Traced]) -> Traced:
    """The sum of ``items``."""
    return combine(code, [1.0] * len(items), items)


def multiply(code: Code, first: Traced, second: Traced) -> Traced:
    """``first * second``, with the product rule for the derivatives."""
    value = product(first.value, second.value)
    tangents = [
        weighted_sum([("", product(first.value, d_second)), ("", product(d_first, second.value))])
        for d_first, d_second in zip(first.tangents, second.tangents, strict=True)
    ]
    result, *rest = code.assign([value, *tangents])
    return Traced(result, tuple(rest))


def dot(code: Code, first: Sequence[Traced], second: Sequence[Traced]) -> Traced:
    """The dot product of two traced vectors."""
    return add(code, [multiply(code, u, v) for u, v in zip(first, second, strict=True)])


def function_source(signature: str, lines: Sequence[str], returned: str) -> str:
    """``def signature`` of the assignments (``name = expression``, in order) that ``returned``
    needs, returning it: every line whose value nothing returned depends on is dropped.
    """
    needed = set(_NAME.findall(returned))
    kept = []
    for line in reversed(lines):
        name, _, expression = line.partition(" = ")
        if name in needed:
            kept.append(line)
            needed |= set(_NAME.findall(expression))
    body = "\n    ".join(reversed(kept)) if kept else "pass"
    return f"def {signature}:\n    {body}\n    return ({returned})\n"
