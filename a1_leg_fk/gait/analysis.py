"""Gait analysis from world-frame feet: contacts (kinematic, with hysteresis), stride metrics, gait
name.

Pure numpy (no ROS, no file I/O): the input is ``stamps_s`` (N,) [s] and ``world_feet`` (N, 4, 3)
[m], the feet in a world frame with z up, legs in :data:`a1_leg_fk.model.legs.LEG_NAMES` order (FR,
FL, RR, RL); NaN rows (a missing base pose) are gaps. Any source works: a bag through
:mod:`a1_leg_fk.recording.trajectories`, a simulation, a motion-capture file.

The work is split by job, and this module re-exports the public API of both:

* :mod:`a1_leg_fk.gait.contacts` -- :func:`detect_contacts`: ground plane, foot speeds [m/s],
  hysteresis, minimum phase, stance edge times [s] (:class:`Contacts`, :class:`ContactThresholds`).
* :mod:`a1_leg_fk.gait.metrics` -- :func:`gait_metrics`: duty factor, stride period [s], step
  length [m], swing clearance [m], touchdown phases vs FR and the gait's name
  (:class:`GaitReport`).

:func:`analyze_gait` runs both. Times are in seconds from the first stamp.
"""

from __future__ import annotations

import numpy as np

from a1_leg_fk.gait.contacts import Contacts, GroundPlane, detect_contacts
from a1_leg_fk.gait.metrics import GaitReport, LegMetrics, gait_metrics
from a1_leg_fk.gait.phases import Blips, Stance
from a1_leg_fk.gait.thresholds import ContactThresholds

__all__ = [
    "Blips",
    "ContactThresholds",
    "Contacts",
    "GaitReport",
    "GroundPlane",
    "LegMetrics",
    "Stance",
    "analyze_gait",
    "detect_contacts",
    "gait_metrics",
]


def analyze_gait(
    stamps_s: np.ndarray,
    world_feet: np.ndarray,
    thresholds: ContactThresholds = ContactThresholds(),
    unsorted: str = "sort",
) -> tuple[Contacts, GaitReport]:
    """:func:`detect_contacts` then :func:`gait_metrics`: contacts and the gait report in one
    call.
    """
    contacts = detect_contacts(stamps_s, world_feet, thresholds, unsorted)
    return contacts, gait_metrics(contacts)
