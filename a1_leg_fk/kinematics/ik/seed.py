"""The seed rule of the inverse kinematics (see :mod:`a1_leg_fk.kinematics.ik.four_legs`): which
value modulo 2 pi of a joint angle [rad] is used, inside the URDF limits where one is, and the
default seed.

One formula serves floats and numpy arrays: the math namespaces :data:`SCALAR` and :data:`ARRAY`.
No ROS.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from types import SimpleNamespace
from typing import Any

import numpy as np

from a1_leg_fk.model.urdf import Joint

LIMIT_TOLERANCE_RAD = 1e-10
"""An angle this close outside a limit [rad] counts as inside, and is clamped to the limit."""
TWO_PI = 2.0 * math.pi
FloatsOrArrays = Any
"""A float, or a numpy array of them with ``xp=ARRAY``: one formula serves both (a union type
would need a cast at every operator)."""

SCALAR = SimpleNamespace(
    sqrt=math.sqrt,
    hypot=math.hypot,
    atan2=math.atan2,
    ceil=math.ceil,
    round=round,
    minimum=min,
    maximum=max,
    where=lambda condition, yes, no: yes if condition else no,
    not_=operator.not_,
)
ARRAY = SimpleNamespace(
    sqrt=np.sqrt,
    hypot=np.hypot,
    atan2=np.arctan2,
    ceil=np.ceil,
    round=np.round,
    minimum=np.minimum,
    maximum=np.maximum,
    where=np.where,
    not_=np.logical_not,
)


def range_middle(joint: Joint) -> float:
    """The middle of a joint's range [rad], 0 for a continuous joint: the seed when none is
    given.
    """
    return 0.0 if joint.lower is None or joint.upper is None else (joint.lower + joint.upper) / 2.0


def wrapped_distance(a: Sequence[float], b: Sequence[float]) -> float:
    """The largest difference [rad] between two angle triples, each taken modulo 2 pi."""
    return max(abs((x - y + math.pi) % TWO_PI - math.pi) for x, y in zip(a, b))


def representative_angle(
    angle: FloatsOrArrays,
    reference: FloatsOrArrays,
    lower: float,
    upper: float,
    xp: SimpleNamespace,
) -> tuple[FloatsOrArrays, FloatsOrArrays]:
    """``angle + 2 pi k`` inside ``[lower, upper]`` nearest ``reference`` where there is one (then
    clamped into the range, and ``True``); else ``False`` with, for a range narrower than 2 pi,
    the value just above the lower limit, and otherwise the value nearest ``reference``.
    """
    if upper - lower < TWO_PI:  # at most one value in range: no need for the reference
        low = lower - LIMIT_TOLERANCE_RAD
        value = low + (angle - low) % TWO_PI
        inside = value <= upper + LIMIT_TOLERANCE_RAD
        return xp.where(inside, xp.minimum(xp.maximum(value, lower), upper), value), inside
    if lower == -math.inf:  # continuous: the value within pi of the reference
        return reference + (angle - reference + math.pi) % TWO_PI - math.pi, True
    nearest = angle + TWO_PI * xp.round((reference - angle) / TWO_PI)
    low, high = lower - LIMIT_TOLERANCE_RAD, upper + LIMIT_TOLERANCE_RAD
    inside = (nearest >= low) & (nearest <= high)
    raised = nearest + TWO_PI * xp.ceil((low - nearest) / TWO_PI)  # the smallest value >= low
    lowered = nearest - TWO_PI * xp.ceil((nearest - high) / TWO_PI)  # the largest value <= high
    outside = xp.not_(inside)
    raised_inside = outside & (raised <= high)
    lowered_inside = outside & (lowered >= low)
    # Of two in-range values (a range wider than 2 pi), the nearer the reference.
    prefer_raised = raised_inside & (
        xp.not_(lowered_inside) | (abs(raised - reference) <= abs(lowered - reference))
    )
    value = xp.where(prefer_raised, raised, xp.where(lowered_inside, lowered, nearest))
    inside = inside | raised_inside | lowered_inside
    value = xp.where(inside, xp.minimum(xp.maximum(value, lower), upper), value)
    return value, inside
