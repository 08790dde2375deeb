"""PNG of a leg-odometry track: the path from above (against the truth's, when there is one) and
the base's velocities over time. matplotlib as in :mod:`a1_leg_fk.plots` (imported when drawn).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from a1_leg_fk.plots import pyplot
from a1_leg_fk.recording.odometry import OdometryTrack
from a1_leg_fk.recording.odometry_truth import truth_body_velocities, yaw_of_quaternions

MIN_SPAN_M = 0.5
"""The path panel shows at least this much [m] along each axis (a straight run stays readable)."""


def plot_odometry(track: OdometryTrack, path: str | Path) -> Path:
    """Write ``path`` (PNG): the path in odom from above, and vx, vy, vz (each with its ±3 sigma
    band) and wz over time.
    """
    plt = pyplot()
    figure, (above, speeds) = plt.subplots(
        1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [1, 1.4]}
    )
    try:
        seconds = (track.stamps_ns - track.stamps_ns[0]) / 1e9 if len(track.stamps_ns) else []
        above.plot(track.positions[:, 0], track.positions[:, 1], label="leg odometry", color="C0")
        truth_path = _aligned_truth(track)
        if truth_path is not None:
            above.plot(truth_path[:, 0], truth_path[:, 1], label="truth", color="k", ls="--")
        above.set(xlabel="x [m]", ylabel="y [m]", title="path in odom, from above", aspect="equal")
        _keep_span(above, track.positions[:, :2], truth_path)
        above.legend(loc="best")
        above.grid(alpha=0.3)
        truth_velocity = (
            truth_body_velocities(track.truth, track.stamps_ns)
            if track.truth is not None
            else None
        )
        for axis, name in enumerate(("vx", "vy", "vz")):
            speeds.plot(seconds, track.linear[:, axis], color=f"C{axis}", lw=0.8, label=name)
            band = 3.0 * np.sqrt(track.twist_variances[:, axis])
            low, high = track.linear[:, axis] - band, track.linear[:, axis] + band
            speeds.fill_between(seconds, low, high, color=f"C{axis}", alpha=0.2, lw=0)
            if truth_velocity is not None:
                speeds.plot(seconds, truth_velocity[:, axis], color=f"C{axis}", ls="--", lw=0.8)
        speeds.plot(seconds, track.angular[:, 2], color="C3", lw=0.8, label="wz [rad/s]")
        speeds.set(
            xlabel="time [s]",
            ylabel="[m/s]",
            title="base velocity, base frame, ±3 sigma shaded"
            + (" (dashed: truth)" if truth_velocity is not None else ""),
        )
        speeds.legend(loc="best")
        speeds.grid(alpha=0.3)
        figure.tight_layout()
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return Path(path)


def _keep_span(axes: object, path: np.ndarray, truth: np.ndarray | None) -> None:
    """Limits of the path panel: the paths' extent, at least :data:`MIN_SPAN_M` on each axis
    about its centre (equal aspect over a few millimetres makes unreadable ticks).
    """
    points = path if truth is None else np.vstack([path, truth])
    points = points[np.isfinite(points).all(axis=1)]
    if not len(points):
        return
    low, high = points.min(axis=0), points.max(axis=0)
    centre, half = (low + high) / 2.0, np.maximum((high - low) / 2.0 * 1.05, MIN_SPAN_M / 2.0)
    axes.set_xlim(centre[0] - half[0], centre[0] + half[0])  # type: ignore[attr-defined]
    axes.set_ylim(centre[1] - half[1], centre[1] + half[1])  # type: ignore[attr-defined]


def _aligned_truth(track: OdometryTrack) -> np.ndarray | None:
    """The truth's positions [m] in odom: from the first row with a pose, turned by the heading
    difference there (as :func:`~a1_leg_fk.recording.odometry_truth.compare_with_truth` compares
    them).
    """
    if track.truth is None:
        return None
    positions, rotations = track.truth.at(track.stamps_ns)
    rows = np.flatnonzero(np.isfinite(positions).all(axis=1))
    if not len(rows):
        return None
    first = rows[0]
    turn = float(
        yaw_of_quaternions(track.orientations[first : first + 1])[0]
        - math.atan2(rotations[first, 1, 0], rotations[first, 0, 0])
    )
    c, s = math.cos(turn), math.sin(turn)
    moved = positions[rows] - positions[first]
    turned = np.stack([c * moved[:, 0] - s * moved[:, 1], s * moved[:, 0] + c * moved[:, 1]], 1)
    aligned: np.ndarray = turned + track.positions[first, :2]
    return aligned
