"""What ``a1-leg-fk view`` draws besides the robot, as Rerun columns over the ``stamp`` timeline:
the feet (markers coloured by P(stance), force arrows, trails in odom), the base's path and the
truth's, and the time series (joint angles, foot heights, normal forces, P(stance), velocity
with its +-3 sigma band and the truth's, the gait diagram, the filter's NIS and gate counts).

Inputs are the arrays of the ``bag`` pipeline (:class:`~a1_leg_fk.recording.trajectories.
FootTrajectories`) and the ``odom`` pipeline (:class:`~a1_leg_fk.recording.odometry.
OdometryTrack`): the values logged are theirs, unchanged (units: m, rad, N, m/s).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.recording.base_pose import rotation_matrices
from a1_leg_fk.recording.odometry import OdometryTrack
from a1_leg_fk.recording.odometry_truth import truth_body_velocities
from a1_leg_fk.recording.trajectories import FootTrajectories
from a1_leg_fk.view.robot import ODOM, time_column

FEET = "feet"
"""Per leg, in the base frame: ``feet/<leg>`` the foot, ``feet/<leg>/force`` its force arrow."""
PLOTS = "plots"
FORCE_ARROW_M_PER_N = 0.002
"""Force arrows' length per newton [m/N]: the A1 standing on four feet, about 0.07 m."""
FOOT_RADIUS_M = 0.02
STANCE_COLOR = np.array([230, 60, 40, 255], np.uint8)
SWING_COLOR = np.array([40, 120, 230, 255], np.uint8)
UNKNOWN_COLOR = np.array([150, 150, 150, 255], np.uint8)
AXES = ("x", "y", "z")
GATE_COUNTS = ("used", "rejected")


def send_scalars(
    recording: rr.RecordingStream, entity: str, stamps_ns: np.ndarray, values: np.ndarray
) -> None:
    """``values`` (N,) at ``stamps_ns`` (N,) [ns], the rows where they are finite."""
    known = np.isfinite(values)
    if known.any():
        recording.send_columns(
            entity,
            indexes=[time_column(stamps_ns[known])],
            columns=rr.Scalars.columns(scalars=values[known]),
        )


def stance_colors(probabilities: np.ndarray | None, rows: int) -> np.ndarray:
    """(rows, 4) RGBA of P(stance) (N, 4): swing blue to stance red, grey where unknown."""
    if probabilities is None:
        return np.broadcast_to(UNKNOWN_COLOR, (rows, 4)).copy()
    p = np.nan_to_num(probabilities, nan=0.0).clip(0.0, 1.0)[:, None]
    colors: np.ndarray = (SWING_COLOR * (1.0 - p) + STANCE_COLOR * p).round().astype(np.uint8)
    colors[~np.isfinite(probabilities)] = UNKNOWN_COLOR
    return colors


def send_feet(recording: rr.RecordingStream, feet: FootTrajectories) -> None:
    """Per leg, in the base frame: the foot (coloured by P(stance)) and its force arrow."""
    for slot, leg in enumerate(LEG_NAMES):
        recording.log(f"{FEET}/{leg}", rr.CoordinateFrame(feet.base_frame), static=True)
        position = feet.positions[:, slot]
        known = np.isfinite(position).all(axis=1)
        if not known.any():
            continue
        contacts = feet.contacts[:, slot] if feet.contacts is not None else None
        recording.send_columns(
            f"{FEET}/{leg}",
            indexes=[time_column(feet.stamps_ns[known])],
            columns=rr.Points3D.columns(
                positions=position[known],
                colors=stance_colors(contacts, len(position))[known],
                radii=np.full(int(known.sum()), FOOT_RADIUS_M, np.float32),
            ),
        )
        if feet.forces is not None:
            _send_arrows(recording, leg, feet.base_frame, feet.stamps_ns, position, feet.forces)


def _send_arrows(
    recording: rr.RecordingStream,
    leg: str,
    frame: str,
    stamps_ns: np.ndarray,
    position: np.ndarray,
    forces: np.ndarray,
) -> None:
    slot = LEG_NAMES.index(leg)
    force = forces[:, slot]
    known = np.isfinite(position).all(axis=1) & np.isfinite(force).all(axis=1)
    recording.log(f"{FEET}/{leg}/force", rr.CoordinateFrame(frame), static=True)
    if known.any():
        recording.send_columns(
            f"{FEET}/{leg}/force",
            indexes=[time_column(stamps_ns[known])],
            columns=rr.Arrows3D.columns(
                origins=position[known], vectors=force[known] * FORCE_ARROW_M_PER_N
            ),
        )


def send_feet_plots(
    recording: rr.RecordingStream, feet: FootTrajectories, joints: Sequence[str]
) -> None:
    """Joint angles [rad], foot heights (z in the base frame) [m], normal forces [N] and
    P(stance), one series per joint or leg.
    """
    stamps = feet.stamps_ns
    if feet.angles is not None:
        for slot, joint in enumerate(joints):
            send_scalars(recording, f"{PLOTS}/joint_angle/{joint}", stamps, feet.angles[:, slot])
    for slot, leg in enumerate(LEG_NAMES):
        send_scalars(recording, f"{PLOTS}/foot_height/{leg}", stamps, feet.positions[:, slot, 2])
        if feet.normal_forces is not None:
            send_scalars(
                recording, f"{PLOTS}/normal_force/{leg}", stamps, feet.normal_forces[:, slot]
            )
        if feet.contacts is not None:
            send_scalars(recording, f"{PLOTS}/p_stance/{leg}", stamps, feet.contacts[:, slot])


def send_paths(
    recording: rr.RecordingStream, feet: FootTrajectories, track: OdometryTrack
) -> None:
    """In odom: the base's path, the truth's, and each foot's trail (the feet at the rows the
    odometry has a pose for).
    """
    recording.log(f"{ODOM}/path", _strip(track.positions, (40, 40, 40, 255)), static=True)
    if track.truth is not None:
        truth, _ = track.truth.at(track.stamps_ns)
        recording.log(f"{ODOM}/truth", _strip(truth, (40, 180, 60, 255)), static=True)
    row = np.searchsorted(track.stamps_ns, feet.stamps_ns).clip(
        0, max(len(track.stamps_ns) - 1, 0)
    )
    matched = track.stamps_ns[row] == feet.stamps_ns if len(track.stamps_ns) else np.zeros(0, bool)
    if not matched.any():
        return
    rotations = rotation_matrices(track.orientations[row[matched]])
    world = np.einsum("nij,nlj->nli", rotations, feet.positions[matched])
    world += track.positions[row[matched]][:, None, :]
    for slot, leg in enumerate(LEG_NAMES):
        recording.log(
            f"{ODOM}/trails/{leg}", _strip(world[:, slot], (200, 120, 0, 255)), static=True
        )


def _strip(points: np.ndarray, color: tuple[int, int, int, int]) -> rr.LineStrips3D:
    """One line through the finite ``points`` (N, 3) [m]."""
    return rr.LineStrips3D([points[np.isfinite(points).all(axis=1)]], colors=[color], radii=0.004)


def send_odometry_plots(recording: rr.RecordingStream, track: OdometryTrack) -> None:
    """The velocity in the base frame [m/s] with its +-3 sigma band (and the truth's), the gait
    diagram (leg k's stance drawn at height 4 - k), the filter's NIS per row and its running gate
    counts.
    """
    stamps = track.stamps_ns
    sigma = np.sqrt(track.twist_variances[:, :3])
    truth = truth_body_velocities(track.truth, stamps) if track.truth is not None else None
    for axis, name in enumerate(AXES):
        entity = f"{PLOTS}/velocity/{name}"
        send_scalars(recording, f"{entity}/estimate", stamps, track.linear[:, axis])
        send_scalars(
            recording, f"{entity}/plus_3sigma", stamps, track.linear[:, axis] + 3 * sigma[:, axis]
        )
        send_scalars(
            recording, f"{entity}/minus_3sigma", stamps, track.linear[:, axis] - 3 * sigma[:, axis]
        )
        if truth is not None:
            send_scalars(recording, f"{entity}/truth", stamps, truth[:, axis])
    for slot, leg in enumerate(LEG_NAMES):
        level = np.where(track.stance[:, slot], float(len(LEG_NAMES) - slot), np.nan)
        recording.log(f"{PLOTS}/gait/{leg}", rr.SeriesLines(widths=6.0, names=leg), static=True)
        send_scalars(recording, f"{PLOTS}/gait/{leg}", stamps, level)
    history = track.filter_history
    if not len(history):
        return
    nis_sum, nis_count = np.diff(history[:, 0], prepend=0.0), np.diff(history[:, 1], prepend=0.0)
    nis = np.where(nis_count > 0, nis_sum / np.where(nis_count > 0, nis_count, 1.0), np.nan)
    send_scalars(recording, f"{PLOTS}/filter/nis", stamps, nis)
    for group, name in enumerate(GATE_COUNTS):
        for slot, leg in enumerate(LEG_NAMES):
            column = history[:, 2 + 4 * group + slot]
            send_scalars(recording, f"{PLOTS}/filter/{name}/{leg}", stamps, column)
    send_scalars(recording, f"{PLOTS}/filter/gate_resets", stamps, history[:, 10])
