"""Which feet stand, and which of those to believe: kinematic stance and slip rejection (plain
floats, per sample).

Stance comes from elsewhere when it can (contact probabilities, e.g. the force estimate from joint
efforts): :func:`stance_from_contacts`. Otherwise :func:`kinematic_stance`: the feet whose contact
points are the lowest along gravity, within a band [m] of the lowest one. Either way,
:func:`consistent_feet` then drops a foot whose base-velocity estimate [m/s] is far from the
others' (a slipping foot, or a foot taken for standing that is not).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

CONTACT_PROBABILITY = 0.5
"""A foot with a contact probability at or above this stands."""

Vector = tuple[float, float, float]


def stance_from_contacts(contacts: Sequence[float], usable: Sequence[bool]) -> dict[int, float]:
    """Leg -> weight of the standing feet: the ``usable`` ones whose contact probability (in
    [0, 1]; a bool works too) is at least :data:`CONTACT_PROBABILITY`; the weight is the
    probability.
    """
    weights = {}
    for leg, (probability, ok) in enumerate(zip(contacts, usable)):
        p = min(float(probability), 1.0)
        if ok and p >= CONTACT_PROBABILITY:  # NaN is not
            weights[leg] = p
    return weights


def kinematic_stance(depths: Sequence[float | None], band_m: float) -> dict[int, float]:
    """Leg -> weight 1 of the feet whose contact point lies within ``band_m`` [m] of the deepest
    one's along gravity (``depths`` [m], larger = lower; None for a foot without one).
    """
    known = [depth for depth in depths if depth is not None]
    if not known:
        return {}
    floor = max(known) - band_m
    return {leg: 1.0 for leg, depth in enumerate(depths) if depth is not None and depth >= floor}


def _distance(a: Vector, b: Vector) -> float:
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)


def _mean(vectors: list[Vector]) -> Vector:
    count = len(vectors)
    return (
        sum(v[0] for v in vectors) / count,
        sum(v[1] for v in vectors) / count,
        sum(v[2] for v in vectors) / count,
    )


def consistent_feet(
    estimates: Mapping[int, Vector],
    previous: Vector | None,
    previous_sigma: float,
    threshold: float,
) -> list[int]:
    """The stance feet (``estimates``: leg -> its base-velocity estimate [m/s]) to believe: the
    largest group that agree, by consensus. Each foot gathers the feet within ``threshold`` [m/s]
    of its own estimate (itself included); the foot with the most wins, ties going to the group
    whose mean is closest to ``previous`` (the last estimate), and its group is kept. When no two
    feet agree, the foot closest to ``previous`` is kept if it lies within ``threshold + 3
    previous_sigma`` (the last estimate's standard deviation [m/s], which grows while no foot
    stands, so that feet are believed again); with no previous estimate, all of them are.
    """
    legs = list(estimates)
    limit = threshold * threshold
    groups = []
    for leg in legs:
        x, y, z = estimates[leg]
        groups.append(
            [
                other
                for other in legs
                if (x - estimates[other][0]) ** 2
                + (y - estimates[other][1]) ** 2
                + (z - estimates[other][2]) ** 2
                <= limit
            ]
        )
    largest = max((len(group) for group in groups), default=0)
    if largest >= 2:
        best = sorted({tuple(group) for group in groups if len(group) == largest})
        if previous is not None and len(best) > 1:
            best.sort(key=lambda group: _distance(_mean([estimates[g] for g in group]), previous))
        return list(best[0])
    if previous is None or not legs:
        return legs
    closest = min(legs, key=lambda leg: _distance(estimates[leg], previous))
    gate = threshold + 3.0 * previous_sigma
    return [closest] if _distance(estimates[closest], previous) <= gate else []
