"""What ``a1-leg-fk odom`` keeps of the odometry rows it streams (:class:`KeptRows`), for its
summary and plot, instead of the rows themselves: their count, the last position and the path
length; with a truth to compare with, the columns the comparison reads (stamps, positions,
orientations, linear velocities: 88 bytes a row, 5.3 MB a recorded minute at 1 kHz); for the
plot, every ``stride``-th row, at most :data:`PLOT_ROWS` (the stride doubles as rows come).
No ROS, numpy only.
"""

from __future__ import annotations

import numpy as np

from a1_leg_fk.recording.base_pose import BasePoses
from a1_leg_fk.recording.odometry_rows import TrackRows
from a1_leg_fk.recording.odometry_truth import TruthComparison, compare_with_truth

PLOT_ROWS = 20_000
"""The plot draws at most this many rows (twice the pixels across its panels)."""
TRUTH_COLUMNS = ("stamps_ns", "positions", "orientations", "linear")
"""The columns :func:`~a1_leg_fk.recording.odometry_truth.compare_with_truth` reads."""


class KeptRows:
    """The summary's and the plot's share of the rows :meth:`add`-ed: ``rows``, ``last``
    position [m] (None before any), ``distance_m`` the path length [m]; ``truth``: keep the
    comparison's columns; ``plot``: keep the plot's rows.
    """

    def __init__(self, truth: bool, plot: bool) -> None:
        self.rows = 0
        self.last: np.ndarray | None = None
        self.distance_m = 0.0
        self._truth: dict[str, list[np.ndarray]] | None = (
            {name: [] for name in TRUTH_COLUMNS} if truth else None
        )
        self._plot: list[TrackRows] | None = [] if plot else None
        self._plot_index: list[np.ndarray] = []
        self._plot_rows = 0
        self.stride = 1

    def add(self, rows: TrackRows) -> None:
        """The next block of rows."""
        if not len(rows):
            return
        positions = rows.positions
        path = positions if self.last is None else np.vstack([self.last, positions])
        self.distance_m += float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        index = np.arange(self.rows, self.rows + len(rows))
        self.rows += len(rows)
        self.last = positions[-1].copy()
        if self._truth is not None:
            for name, kept in self._truth.items():
                kept.append(getattr(rows, name))
        if self._plot is not None:
            self._keep_for_plot(rows, index)

    def comparison(self, planar: bool, truth: BasePoses) -> TruthComparison | None:
        """The rows against ``truth`` (:func:`~a1_leg_fk.recording.odometry_truth.
        compare_with_truth`; ``planar``: in x, y only); None when fewer than two rows have a
        pose.
        """
        assert self._truth is not None, "KeptRows(truth=True) keeps what the comparison needs"
        columns = {name: np.concatenate(kept) for name, kept in self._truth.items() if kept}
        if not columns:
            return None
        return compare_with_truth(
            columns["stamps_ns"],
            columns["positions"],
            columns["orientations"],
            columns["linear"],
            planar,
            truth,
        )

    def plotted(self) -> TrackRows:
        """The plot's rows: every ``stride``-th."""
        assert self._plot is not None, "KeptRows(plot=True) keeps the plot's rows"
        return TrackRows.joined(self._plot)

    def _keep_for_plot(self, rows: TrackRows, index: np.ndarray) -> None:
        """Keep the rows at multiples of the stride; double it while more than
        :data:`PLOT_ROWS` are kept.
        """
        assert self._plot is not None
        chosen = index % self.stride == 0
        self._plot.append(rows.take(chosen))
        self._plot_index.append(index[chosen])
        self._plot_rows += int(chosen.sum())
        while self._plot_rows > PLOT_ROWS:
            self.stride *= 2
            kept, kept_index = TrackRows.joined(self._plot), np.concatenate(self._plot_index)
            chosen = kept_index % self.stride == 0
            self._plot, self._plot_index = [kept.take(chosen)], [kept_index[chosen]]
            self._plot_rows = int(chosen.sum())
