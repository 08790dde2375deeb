"""Gait contacts from foot forces: the kinematic analysis's ground, heights and speeds (for the
stride metrics), with each foot's stance taken from its force-based contact probability
(:mod:`a1_leg_fk.estimation.contacts`, >= 0.5) instead of its height and speed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from a1_leg_fk.gait.contacts import Contacts, prepare
from a1_leg_fk.gait.phases import apply_min_phase, segment_slices, stances_of


def with_force_stance(
    contacts: Contacts,
    stamps_s: np.ndarray,
    probabilities: np.ndarray,
    unsorted: str = "sort",
    note: str = "stance from the contact estimate (probability >= 0.5)",
) -> Contacts:
    """``contacts`` (from :func:`~a1_leg_fk.gait.contacts.detect_contacts` on the same stamps
    [s]) with the stance of (N, 4) contact probabilities (NaN: no estimate, counted as swing),
    rows sorted and de-duplicated as ``contacts``' were; phases shorter than the thresholds'
    ``min_phase_s`` removed as for the kinematic stance (:mod:`a1_leg_fk.gait.phases`: blips
    dropped or bridged, counted per leg); ``note`` says where the stance came from.
    """
    known = np.nan_to_num(probabilities, nan=-1.0)  # finite, so that prepare keeps every row
    _, packed, _ = prepare(stamps_s, np.repeat(known[..., None], 3, axis=2), unsorted)
    raw = (packed[..., 0] >= 0.5) & contacts.valid
    times = contacts.times_s
    segments = [segment_slices(contacts.valid[:, slot]) for slot in range(raw.shape[1])]
    stance, blips = apply_min_phase(times, raw, segments, contacts.thresholds.min_phase_s)
    stances = tuple(
        stances_of(times, stance[:, slot], segments[slot]) for slot in range(stance.shape[1])
    )
    return replace(
        contacts,
        stance=stance,
        stances=stances,
        notes=(*contacts.notes, note),
        blips=blips,
        blip_samples=stance != raw,
    )
