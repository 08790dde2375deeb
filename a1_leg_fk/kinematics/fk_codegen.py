"""Generated straight-line Python for a leg's kinematics, and compiling it so it can be debugged.

A leg's stages (:mod:`a1_leg_fk.kinematics.leg_stages`) make its forward kinematics linear in the
cosines and sines of its three angles. :func:`leg_source` writes that arithmetic out once per leg
as Python source, every zero coefficient dropped and every unit coefficient simplified, so that the
per-message path runs no matrix code at all; the same source runs on floats and on numpy arrays.
The expression helpers (:class:`Code`, :func:`linear`, :func:`weighted_sum`) also serve the
inverse kinematics' generated closed form.

:func:`compile_source` registers the text with :mod:`linecache` (as :mod:`dataclasses` and attrs
do for theirs), so a traceback or pdb shows the generated line, not ``???``.
"""

from __future__ import annotations

import itertools
import linecache
import math
import re
import weakref
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

    from a1_leg_fk.kinematics.leg_stages import Stage

Term = float | str
"""A constant, or an expression of the generated code: a variable name, a signed product
(``-0.2*s2``), or a parenthesised sum."""

_sources = itertools.count()
_NAME = re.compile(r"[A-Za-z_]\w*")


def compile_source(source: str, what: str, owner: object) -> dict[str, Any]:
    """Execute generated ``source`` in a namespace of its own and return the namespace.

    ``_cos`` and ``_sin`` are :func:`math.cos` and :func:`math.sin` there. The text is named
    ``<a1_leg_fk generated {what} #n>`` and kept in :mod:`linecache` for as long as ``owner``
    lives, so tracebacks and pdb show the generated lines.
    """
    filename = f"<a1_leg_fk generated {what} #{next(_sources)}>"
    code = compile(source, filename, "exec")
    linecache.cache[filename] = (len(source), None, source.splitlines(keepends=True), filename)
    weakref.finalize(owner, linecache.cache.pop, filename, None)
    namespace: dict[str, Any] = {"_cos": math.cos, "_sin": math.sin}
    exec(code, namespace)  # our own generated source
    return namespace


class Code:
    """Generated statements, with fresh variable names and zero-free linear expressions."""

    def __init__(self, prefix: str) -> None:
        """Variables will be named ``prefix`` followed by a number."""
        self.lines: list[str] = []
        self._prefix = prefix
        self._count = 0

    def assign(self, expressions: Sequence[Term]) -> tuple[Term, ...]:
        """Bind each expression to a fresh variable and return the names.

        Constants stay constants and a bare variable stays itself (no alias lines).
        """
        names: list[Term] = []
        for expression in expressions:
            if isinstance(expression, float) or expression.isidentifier():
                names.append(expression)
            else:
                self._count += 1
                name = f"{self._prefix}{self._count}"
                names.append(name)
                self.lines.append(f"{name} = {expression}")
        return tuple(names)


def linear(row: Sequence[float], vector: Sequence[Term]) -> Term:
    """``row . vector`` as a constant or an expression, zero terms dropped."""
    constant = 0.0
    terms = []
    for coefficient, value in zip(row, vector, strict=True):
        if coefficient == 0.0:
            continue
        if isinstance(value, float):
            constant += float(coefficient) * value
        else:
            terms.append(_scaled(float(coefficient), value))
    return _joined(constant, terms)


def weighted_sum(parts: Sequence[tuple[str, Term]]) -> Term:
    """Sum of ``factor * term`` pairs (factor ``''`` for none, or a signed name), zero terms
    dropped.
    """
    constant = 0.0
    terms = []
    for factor, term in parts:
        if isinstance(term, float) and not factor:
            constant += term
        elif isinstance(term, float):
            if term != 0.0:
                terms.append(_scaled(term, factor))
        else:
            terms.append(_product(factor, term) if factor else term)
    return _joined(constant, terms)


def scaled(coefficient: float, term: Term) -> Term:
    """``coefficient * term``: a constant for a constant term, else an expression, signs
    combined.
    """
    return coefficient * term if isinstance(term, float) else _scaled(coefficient, term)


def product(first: Term, second: Term) -> Term:
    """``first * second``: a constant when either is zero or both are constants, else an
    expression (each a name, a product or a parenthesised sum), signs combined.
    """
    if isinstance(first, float):
        if isinstance(second, float):
            return first * second
        return 0.0 if first == 0.0 else _scaled(first, second)
    if isinstance(second, float):
        return 0.0 if second == 0.0 else _scaled(second, first)
    return _product(first, second)


def term_tuple(terms: Sequence[Term]) -> str:
    """``a, b, c``: the terms as the items of a tuple display."""
    return ", ".join(repr(t) if isinstance(t, float) else t for t in terms)


def _signed(text: str) -> tuple[bool, str]:
    """(negative, the expression without its leading minus)."""
    return (True, text[1:]) if text.startswith("-") else (False, text)


def _scaled(coefficient: float, text: str) -> str:
    """``coefficient * text`` with the signs combined: ``0.2*s2``, not ``-0.2*-s2``."""
    negative, body = _signed(text)
    value = -coefficient if negative else coefficient
    sign = "-" if value < 0.0 else ""
    return f"{sign}{body}" if abs(value) == 1.0 else f"{sign}{abs(value)!r}*{body}"


def _product(factor: str, term: str) -> str:
    """``factor * term`` with the signs combined: ``-s1*p1``, not ``s1*-p1``."""
    factor_negative, factor_body = _signed(factor)
    term_negative, term_body = _signed(term)
    sign = "-" if factor_negative != term_negative else ""
    return f"{sign}{factor_body}*{term_body}"


def _joined(constant: float, terms: list[str]) -> Term:
    """``constant + terms[0] - ...`` as a constant, a single term, or a parenthesised sum."""
    if not terms:
        return constant
    parts = [repr(constant)] if constant != 0.0 else []
    for term in terms:
        negative, body = _signed(term)
        parts.append((f"- {body}" if negative else f"+ {term}") if parts else term)
    return parts[0] if len(parts) == 1 else "(" + " ".join(parts) + ")"


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


def leg_source(stages: Sequence[Stage], foot: np.ndarray) -> str:
    """Python source of a leg's four functions.

    ``position(q0, q1, q2) -> (x, y, z)``, ``position_velocity(q0, q1, q2, dq0, dq1, dq2) -> (x,
    y, z, vx, vy, vz)``, ``position_from_trig(c0, s0, c1, s1, c2, s2)`` and
    ``jacobian_from_trig(c0, s0, c1, s1, c2, s2)`` (the 3x3 Jacobian column by column): angles
    [rad], rates [rad/s], positions [m] and velocities [m/s] in the base frame. ``foot`` is the
    foot's offset [m] in the last stage's child frame.
    """
    position_code, velocity_code, jacobian_code = Code("p"), Code("v"), Code("j")
    point: tuple[Term, ...] = tuple(float(v) for v in foot)
    velocity: tuple[Term, ...] = (0.0, 0.0, 0.0)
    tangents: list[tuple[Term, ...]] = []
    jacobian_point = point
    for slot in reversed(range(len(stages))):
        terms = stages[slot].rodrigues_terms
        offset = stages[slot].offset
        cos, sin, rate = f"c{slot}", f"s{slot}", f"dq{slot}"
        # Velocity first: it needs the point before this stage moves it.
        velocity = velocity_code.assign(
            [
                weighted_sum(
                    [
                        ("", rotated_row(terms, axis, velocity, cos, sin)),
                        (rate, _derivative_row(terms, axis, point, cos, sin)),
                    ]
                )
                for axis in range(3)
            ]
        )
        tangents = [
            jacobian_code.assign([rotated_row(terms, axis, t, cos, sin) for axis in range(3)])
            for t in tangents
        ]
        tangents.insert(
            0,
            jacobian_code.assign(
                [_derivative_row(terms, axis, jacobian_point, cos, sin) for axis in range(3)]
            ),
        )
        first_new_line = len(position_code.lines)
        point = position_code.assign(
            [moved_row(terms, offset, axis, point, cos, sin) for axis in range(3)]
        )
        velocity_code.lines.extend(position_code.lines[first_new_line:])
        if slot > 0:  # the root-side stage's point is not needed by any column
            jacobian_point = jacobian_code.assign(
                [moved_row(terms, offset, axis, jacobian_point, cos, sin) for axis in range(3)]
            )
    trig = "c0, s0, c1, s1, c2, s2"
    from_angles = [f"c{i} = _cos(q{i})\n    s{i} = _sin(q{i})" for i in range(len(stages))]
    body = "\n    ".join(position_code.lines)
    return "\n".join(
        [
            f"def position_from_trig({trig}):\n    {body}\n    return ({term_tuple(point)})\n",
            "def position(q0, q1, q2):\n    "
            + "\n    ".join(from_angles)
            + f"\n    {body}\n    return ({term_tuple(point)})\n",
            "def position_velocity(q0, q1, q2, dq0, dq1, dq2):\n    "
            + "\n    ".join(from_angles + velocity_code.lines)
            + f"\n    return ({term_tuple(point)}, {term_tuple(velocity)})\n",
            f"def jacobian_from_trig({trig}):\n    "
            + "\n    ".join(jacobian_code.lines or ["pass"])
            + f"\n    return ({', '.join(term_tuple(t) for t in tangents)})\n",
        ]
    )


def moved_row(
    terms: tuple[np.ndarray, ...],
    offset: np.ndarray,
    axis: int,
    vector: Sequence[Term],
    cos: str,
    sin: str,
) -> Term:
    """Row ``axis`` of ``o + (C0 + cos C1 + sin C2) vector``: a point moved through a stage
    (``terms`` its Rodrigues terms, ``o`` its offset [m], ``cos``/``sin`` the names of its
    angle's cosine and sine).
    """
    return weighted_sum(
        [("", float(offset[axis])), ("", rotated_row(terms, axis, vector, cos, sin))]
    )


def rotated_row(
    terms: tuple[np.ndarray, ...], axis: int, vector: Sequence[Term], cos: str, sin: str
) -> Term:
    """Row ``axis`` of ``(C0 + cos C1 + sin C2) vector``: a vector turned by a stage (pass the
    transposed terms to turn it back).
    """
    c0, c1, c2 = terms
    return weighted_sum(
        [
            ("", linear(c0[axis], vector)),
            (cos, linear(c1[axis], vector)),
            (sin, linear(c2[axis], vector)),
        ]
    )


def _derivative_row(
    terms: tuple[np.ndarray, ...], axis: int, vector: Sequence[Term], cos: str, sin: str
) -> Term:
    """Row ``axis`` of ``d/dq (C0 + cos C1 + sin C2) vector = (cos C2 - sin C1) vector``."""
    _, c1, c2 = terms
    return weighted_sum([(f"-{sin}", linear(c1[axis], vector)), (cos, linear(c2[axis], vector))])
