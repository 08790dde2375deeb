"""Unitree's own feet beside ours: ``unitree_go/msg/SportModeState.foot_position_body`` (its
firmware's estimate, body frame, FR, FL, RR, RL) against the feet this package computes from the
same robot's LowState, nearest in time (both stamped with their bag times: neither message has a
header). Not every model fills the field: all-zero feet are skipped.

The feet match when each leg's median distance is within :data:`MATCH_MM`: Unitree's point may be
the foot's contact point where ours is the foot's origin (the sphere's centre), a foot radius
apart (about 20 mm on a Go2). No ROS install: the bag is read through
:class:`~a1_leg_fk.recording.reads.RecordingReads`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.wire.lowstate import SportModeFeet
from a1_leg_fk.wire.unitree_types import SPORT_MODE_STATE

if TYPE_CHECKING:  # rosbags is imported when a bag is opened
    from rosbags.highlevel import AnyReader

    from a1_leg_fk.recording.reads import RecordingReads

MATCH_MM = 25.0
"""[mm] The median distance per leg within which Unitree's feet and ours are said to match."""


@dataclass
class SportFeet:
    """The recorded SportModeState feet: ``stamps_ns`` (M,) bag times, sorted; ``feet`` (M, 4, 3)
    [m], body frame; and the distances to ours collected by :meth:`compare`.
    """

    topic: str
    stamps_ns: np.ndarray
    feet: np.ndarray
    distances: list[np.ndarray] = field(default_factory=list)  # (K, 4) [m] per block

    @classmethod
    def read(cls, reads: RecordingReads) -> SportFeet | None:
        """The bag's one SportModeState topic's filled feet, or None (no such topic, or none
        filled).
        """
        reader: AnyReader = reads.reader
        connections = [c for c in reader.connections if c.msgtype == SPORT_MODE_STATE]
        if len(connections) != 1:
            return None
        connection = connections[0]
        recorded = connection.msgdef.data if connection.msgdef.data.strip() else None
        decoder = SportModeFeet(recorded)
        stamps, feet = [], []
        for _, bag_time, raw in reads.messages([connection]):
            values = decoder.feet(raw)
            if values is not None and np.isfinite(values).all() and values.any():
                stamps.append(bag_time)
                feet.append(values)
        if not stamps:
            return None
        order = np.argsort(np.array(stamps, dtype=np.int64), kind="stable")
        return cls(
            connection.topic, np.array(stamps, dtype=np.int64)[order], np.array(feet)[order]
        )

    def compare(self, stamps_ns: np.ndarray, positions: np.ndarray) -> None:
        """Collect the distances [m] of (N, 4, 3) feet [m], base frame, stamped ``stamps_ns``,
        to the recorded feet nearest in time (NaN where ours are unknown).
        """
        after = np.clip(np.searchsorted(self.stamps_ns, stamps_ns), 0, len(self.stamps_ns) - 1)
        before = np.clip(after - 1, 0, None)
        nearer = np.where(
            np.abs(stamps_ns - self.stamps_ns[before])
            <= np.abs(self.stamps_ns[after] - stamps_ns),
            before,
            after,
        )
        self.distances.append(np.linalg.norm(positions - self.feet[nearer], axis=2))

    def line(self) -> str:
        """The summary's line: each leg's median distance [mm], and whether they match."""
        distances = np.concatenate(self.distances) if self.distances else np.zeros((0, 4))
        if not np.isfinite(distances).any():
            return f"unitree:   {self.topic}: no row of ours to compare with"
        medians = [
            float(np.nanmedian(leg)) * 1e3 if np.isfinite(leg).any() else np.nan
            for leg in distances.T
        ]
        legs = ", ".join(
            f"{leg} {value:.1f}" for leg, value in zip(LEG_NAMES, medians, strict=True)
        )
        worst = np.nanmax(medians)
        verdict = "match" if worst <= MATCH_MM else "do not match"
        return (
            f"unitree:   our feet vs {self.topic} foot_position_body (nearest in time): median "
            f"distance {legs} mm; they {verdict} (within {MATCH_MM:g} mm)"
        )
