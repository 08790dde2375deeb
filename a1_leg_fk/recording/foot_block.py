"""The rows that a pass over a recording yields (:func:`~a1_leg_fk.recording.blocks.
iter_foot_blocks`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from a1_leg_fk.estimation.contact_smoother import EvidenceRows


@dataclass(frozen=True)
class FootBlock:
    """Rows of consecutive accepted messages: like
    :class:`~a1_leg_fk.recording.trajectories.FootTrajectories` (stamps [ns], feet [m] and foot
    velocities [m/s] in the base frame, world feet [m]), velocities always an array (NaN where the
    message gives none); with ``recording.forces``, ``forces`` (N, 4, 3) [N, base frame],
    ``normal_forces`` (N, 4) [N] along minus gravity and ``contacts`` (N, 4) probabilities (NaN
    where none); with ``recording.efforts``, ``efforts`` (N, 12) [N m], the merged joint efforts
    after each message in slot order (NaN where unknown); from a LowState, ``sensor``: its foot
    sensors' raw counts (FR, FL, RR, RL); ``evidence``: the contact filter's evidence per row
    while its contacts are to be smoothed (:mod:`a1_leg_fk.estimation.contact_smoother`).
    """

    stamps_ns: np.ndarray
    bag_times_ns: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    world_positions: np.ndarray | None
    angles: np.ndarray  # (N, 12) [rad]: the merged state after each message, NaN where unknown
    rates: np.ndarray  # (N, 12) [rad/s]: the message's rates where a foot velocity came of them
    forces: np.ndarray | None = None
    normal_forces: np.ndarray | None = None
    contacts: np.ndarray | None = None
    efforts: np.ndarray | None = None
    sensor: np.ndarray | None = None  # (N, 4) a LowState's foot sensors [raw counts]
    evidence: EvidenceRows | None = None  # the contact filter's, when contacts are smoothed

    def rows(self, chosen: slice, contacts: np.ndarray | None = None) -> FootBlock:
        """The rows ``chosen`` of every array (``contacts`` instead of theirs and no evidence, if
        given).
        """
        kept = {name: getattr(self, name) for name in self.__dataclass_fields__}
        cut: dict[str, Any] = {
            name: None if value is None else value[chosen] for name, value in kept.items()
        }
        if contacts is not None:
            cut["contacts"], cut["evidence"] = contacts, None
        return FootBlock(**cut)
