"""Rows of a leg-odometry track as numpy arrays (:class:`TrackRows`): a block of the samples the
odometry gave (:class:`~a1_leg_fk.estimation.odometry.OdometrySample`, Python objects of ~1 kB
each) packed into columns of 216 bytes a row, so a pass over a recording keeps no sample
object longer than one block.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from a1_leg_fk.estimation.filter_model import FilterCounts
from a1_leg_fk.estimation.ground_outputs import GROUND_COLUMNS
from a1_leg_fk.estimation.odometry import OdometrySample

LiveRow = tuple[tuple[float, ...], tuple[float, ...]]
"""A row's local ground (:func:`~a1_leg_fk.estimation.ground_outputs.ground_values`) and the
filter's running counts (:func:`running_counts`), as the feed had them after the row."""
HISTORY_WIDTH = 11


@dataclass(frozen=True)
class TrackRows:
    """N rows of odometry: ``stamps_ns`` (N,); pose in odom: ``positions`` (N, 3) [m],
    ``orientations`` (N, 4) x, y, z, w; twist in the base frame: ``linear`` (N, 3) [m/s],
    ``angular`` (N, 3) [rad/s]; covariance diagonals ``pose_variances`` (x, y, z, roll, pitch,
    yaw) and ``twist_variances`` (vx .. wz) (N, 6); ``stance`` and ``used`` (N, 4) bool: the
    legs taken for standing and those the estimate used. Live, as the node has them after each
    row (also under smoothed rows): ``grounds`` (N, 7) the local ground
    (:data:`~a1_leg_fk.estimation.ground_outputs.GROUND_COLUMNS`) and ``filter_history`` (N, 11)
    the filter's running counts: NIS sum, NIS count, feet used (4), feet rejected by the gate (4),
    gate resets.
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    linear: np.ndarray
    angular: np.ndarray
    pose_variances: np.ndarray
    twist_variances: np.ndarray
    stance: np.ndarray
    used: np.ndarray
    grounds: np.ndarray
    filter_history: np.ndarray

    @classmethod
    def of(cls, samples: Sequence[OdometrySample], live: Sequence[LiveRow]) -> TrackRows:
        """The rows of ``samples`` and, for each, what the feed had live (:data:`LiveRow`)."""
        if len(live) != len(samples):
            raise ValueError(f"{len(samples)} samples but {len(live)} live rows")

        def column(name: str, width: int) -> np.ndarray:
            return np.array([getattr(s, name) for s in samples], dtype=float).reshape(-1, width)

        return cls(
            stamps_ns=np.array([s.stamp_ns for s in samples], dtype=np.int64),
            positions=column("position", 3),
            orientations=column("orientation", 4),
            linear=column("linear", 3),
            angular=column("angular", 3),
            pose_variances=column("pose_variance", 6),
            twist_variances=column("twist_variance", 6),
            stance=_mask([s.stance for s in samples]),
            used=_mask([s.used for s in samples]),
            grounds=np.array([g for g, _ in live], dtype=float).reshape(-1, len(GROUND_COLUMNS)),
            filter_history=np.array([h for _, h in live], dtype=float).reshape(-1, HISTORY_WIDTH),
        )

    @classmethod
    def joined(cls, blocks: Sequence[TrackRows]) -> TrackRows:
        """The rows of ``blocks`` one after the other (none: no rows)."""
        if not blocks:
            return cls.of([], [])
        return cls(
            **{f.name: np.concatenate([getattr(b, f.name) for b in blocks]) for f in fields(cls)}
        )

    def take(self, rows: np.ndarray) -> TrackRows:
        """The rows at the indices (or mask) ``rows``."""
        return TrackRows(**{f.name: getattr(self, f.name)[rows] for f in fields(self)})

    def __len__(self) -> int:
        return len(self.stamps_ns)


def _mask(legs: Sequence[Sequence[int]]) -> np.ndarray:
    """(N, 4) bool: row n has True at the legs ``legs[n]``."""
    mask = np.zeros((len(legs), 4), dtype=bool)
    for row, chosen in enumerate(legs):
        mask[row, list(chosen)] = True
    return mask


def running_counts(counts: FilterCounts) -> tuple[float, ...]:
    """The filter's running counts as :attr:`TrackRows.filter_history` keeps a row."""
    return (counts.nis_sum, counts.nis_count, *counts.used, *counts.rejected, counts.gate_resets)
