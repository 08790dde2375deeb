"""How far a leg-odometry track is from the truth (a recorded base pose): no ROS, numpy only.

The track starts at the odom origin; the truth anywhere. Both are compared as displacements from
the first row that has a truth pose, the track turned about z by the heading difference at that
row (an IMU's yaw reference need not be the truth's). Planar tracks are compared in x, y only.
The truth's velocity is its positions' derivative on its own samples (central differences),
interpolated to the track's stamps and expressed in the truth's base frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.recording.base_pose import BasePoses


@dataclass(frozen=True)
class TruthComparison:
    """Over the ``rows`` compared: ``distance_m`` travelled by the truth [m]; the final position
    error [m] and as % of that distance; the final heading error [rad]; the RMSE of the base
    velocity (all three axes, base frame) [m/s].
    """

    rows: int
    distance_m: float
    final_error_m: float
    final_error_percent: float
    heading_error_rad: float
    velocity_rmse_mps: float

    def line(self) -> str:
        """One summary line."""
        return (
            f"final position error {self.final_error_m:.3f} m "
            f"({self.final_error_percent:.2f} % of {self.distance_m:.3f} m), heading error "
            f"{math.degrees(self.heading_error_rad):.2f} deg, velocity RMSE "
            f"{self.velocity_rmse_mps:.4f} m/s ({self.rows} rows)"
        )


def yaw_of_quaternions(q: np.ndarray) -> np.ndarray:
    """(N,) yaw [rad] of (N, 4) quaternions x, y, z, w."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    yaw: np.ndarray = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return yaw


def truth_body_velocities(truth: BasePoses, stamps_ns: np.ndarray) -> np.ndarray:
    """(N, 3) the truth's base velocity [m/s] in its base frame at ``stamps_ns`` (NaN where it
    has no pose).
    """
    seconds = (truth.stamps_ns - truth.stamps_ns[0]) / 1e9
    if len(seconds) < 2:
        return np.full((len(stamps_ns), 3), math.nan)
    world = np.gradient(truth.positions, seconds, axis=0)
    at = (stamps_ns - truth.stamps_ns[0]) / 1e9
    interpolated = np.stack([np.interp(at, seconds, world[:, axis]) for axis in range(3)], axis=1)
    _, rotation = truth.at(stamps_ns)
    body: np.ndarray = np.einsum("nji,nj->ni", rotation, interpolated)
    return body


def compare_with_truth(
    stamps_ns: np.ndarray,
    positions: np.ndarray,
    orientations: np.ndarray,
    linear: np.ndarray,
    planar: bool,
    truth: BasePoses,
) -> TruthComparison | None:
    """The comparison of a track (stamps [ns], positions [m], orientations x, y, z, w, linear
    velocities [m/s]) with ``truth``; None when fewer than two rows have a truth pose.
    """
    true_positions, rotations = truth.at(stamps_ns)
    rows = np.flatnonzero(np.isfinite(true_positions).all(axis=1))
    if len(rows) < 2:
        return None
    first, last = rows[0], rows[-1]
    true_yaw = np.arctan2(rotations[rows, 1, 0], rotations[rows, 0, 0])
    yaw = yaw_of_quaternions(orientations[rows])
    turn = true_yaw[0] - yaw[0]
    c, s = math.cos(turn), math.sin(turn)
    moved = positions[last] - positions[first]
    moved = np.array([c * moved[0] - s * moved[1], s * moved[0] + c * moved[1], moved[2]])
    true_moved = true_positions[last] - true_positions[first]
    axes = slice(0, 2) if planar else slice(0, 3)
    error = float(np.linalg.norm(moved[axes] - true_moved[axes]))
    steps = np.diff(true_positions[rows][:, axes], axis=0)
    distance = float(np.linalg.norm(steps, axis=1).sum())
    heading = math.remainder(
        float(np.unwrap(yaw)[-1] - yaw[0]) - float(np.unwrap(true_yaw)[-1] - true_yaw[0]), math.tau
    )
    velocity_error = linear[rows] - truth_body_velocities(truth, stamps_ns[rows])
    rmse = float(np.sqrt(np.mean(np.sum(velocity_error**2, axis=1))))
    percent = 100.0 * error / distance if distance > 0 else math.inf
    return TruthComparison(len(rows), distance, error, percent, heading, rmse)
