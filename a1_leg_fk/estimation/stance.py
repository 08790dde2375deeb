"""Which feet stand, and which of those to believe: kinematic stance and slip rejection.

Stance comes from elsewhere when it can (a contact mask or probabilities, e.g. the force estimate
from joint efforts): :func:`stance_from_contacts`. Otherwise :func:`kinematic_stance`: the feet
whose contact points are the lowest along gravity, within a band [m] of the lowest one. Either
way, :func:`consistent_feet` then drops a foot whose base-velocity estimate [m/s] is far from the
others' (a slipping foot, a foot taken for standing that is not).
"""

from __future__ import annotations

import numpy as np

CONTACT_PROBABILITY = 0.5
"""A foot with a contact probability at or above this stands."""


def stance_from_contacts(contacts: np.ndarray, usable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(stance (4,) bool, weights (4,)) from contact probabilities (4,) in [0, 1] (a bool mask
    works too); only ``usable`` feet (finite estimates) stand. A foot's weight is its probability.
    """
    probability = np.clip(np.nan_to_num(np.asarray(contacts, dtype=float)), 0.0, 1.0)
    stance = usable & (probability >= CONTACT_PROBABILITY)
    return stance, np.where(stance, probability, 0.0)


def kinematic_stance(depth: np.ndarray, usable: np.ndarray, band_m: float) -> np.ndarray:
    """(4,) bool: the usable feet whose contact point is within ``band_m`` [m] of the deepest
    one's along gravity (``depth`` (4,) [m], larger = lower).
    """
    if not usable.any():
        return usable.copy()
    deepest = depth[usable].max()
    with np.errstate(invalid="ignore"):
        return usable & (depth >= deepest - band_m)


def consistent_feet(
    estimates: np.ndarray,
    stance: np.ndarray,
    previous: np.ndarray | None,
    previous_sigma: float,
    threshold: float,
) -> np.ndarray:
    """(4,) bool: the stance feet whose estimate (``estimates`` (4, 3) [m/s]) lies within the gate
    of the reference. With three or more stance feet the reference is their per-axis median and
    the gate ``threshold`` [m/s]; two feet within ``threshold`` of each other vouch for each other.
    Otherwise the reference is ``previous`` (the last estimate) and the gate ``threshold + 3
    previous_sigma`` (its standard deviation [m/s], which grows while no foot stands, so that feet
    are believed again); with no previous estimate, every stance foot is kept.
    """
    feet = np.flatnonzero(stance)
    if feet.size >= 3:
        reference, gate = np.median(estimates[feet], axis=0), threshold
    elif feet.size == 2 and np.linalg.norm(estimates[feet[0]] - estimates[feet[1]]) <= threshold:
        return stance.copy()
    elif previous is not None and feet.size:
        reference, gate = previous, threshold + 3.0 * previous_sigma
    else:
        return stance.copy()
    kept = np.zeros_like(stance)
    kept[feet[np.linalg.norm(estimates[feet] - reference, axis=1) <= gate]] = True
    return kept
