"""What ``a1-leg-fk view`` draws besides the robot, as Rerun columns over the ``stamp`` timeline:
the feet (markers coloured by P(stance), force arrows, trails in odom), the base's path and the
truth's, and the time series (joint angles, foot heights, normal forces, P(stance), velocity
with its +-3 sigma band and the truth's, the gait diagram, the filter's NIS and gate counts).

Inputs are rows (:class:`FeetRows`, :class:`BaseRows`): a whole recording's, from the ``bag``
pipeline (:class:`~a1_leg_fk.recording.trajectories.FootTrajectories`) and the ``odom`` pipeline
(:class:`~a1_leg_fk.recording.odometry.OdometryTrack`), or a live stream's, a few at a time
(:mod:`.live`): the values logged are theirs, unchanged (units: m, rad, N, m/s).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import rerun as rr

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.recording.base_pose import rotation_matrices
from a1_leg_fk.recording.odometry import OdometryTrack
from a1_leg_fk.recording.trajectories import FootTrajectories
from a1_leg_fk.view.robot import ODOM, send_known

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
    send_known(
        recording, entity, stamps_ns, known, lambda: rr.Scalars.columns(scalars=values[known])
    )


def stance_colors(probabilities: np.ndarray | None, rows: int) -> np.ndarray:
    """(rows, 4) RGBA of P(stance) (N, 4): swing blue to stance red, grey where unknown."""
    if probabilities is None:
        return np.broadcast_to(UNKNOWN_COLOR, (rows, 4)).copy()
    p = np.nan_to_num(probabilities, nan=0.0).clip(0.0, 1.0)[:, None]
    colors: np.ndarray = (SWING_COLOR * (1.0 - p) + STANCE_COLOR * p).round().astype(np.uint8)
    colors[~np.isfinite(probabilities)] = UNKNOWN_COLOR
    return colors


@dataclass(frozen=True)
class FeetRows:
    """The feet over rows, as ``bag`` computes them: ``stamps_ns`` (N,) [ns]; ``positions``
    (N, 4, 3) [m] in the base frame; ``contacts`` (N, 4) P(stance), ``forces`` (N, 4, 3) [N] in
    the base frame, ``normal_forces`` (N, 4) [N] along minus gravity and ``angles`` (N, joints)
    [rad], each None where not computed; NaN where unknown.
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    contacts: np.ndarray | None = None
    forces: np.ndarray | None = None
    normal_forces: np.ndarray | None = None
    angles: np.ndarray | None = None

    @classmethod
    def of(cls, feet: FootTrajectories) -> FeetRows:
        """The rows of a recording's pass."""
        return cls(
            feet.stamps_ns,
            feet.positions,
            feet.contacts,
            feet.forces,
            feet.normal_forces,
            feet.angles,
        )


@dataclass(frozen=True)
class BaseRows:
    """The odometry over rows: ``stamps_ns`` (N,) [ns]; the pose in odom, ``positions`` (N, 3)
    [m] and ``orientations`` (N, 4) x, y, z, w; the velocity in the base frame ``linear`` (N, 3)
    [m/s] and its variances ``linear_variances`` (N, 3) [m^2/s^2].
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    linear: np.ndarray
    linear_variances: np.ndarray

    @classmethod
    def of(cls, track: OdometryTrack) -> BaseRows:
        """The rows of a recording's odometry."""
        return cls(
            track.stamps_ns,
            track.positions,
            track.orientations,
            track.linear,
            track.twist_variances[:, :3],
        )


def log_styles(recording: rr.RecordingStream, base_frame: str) -> None:
    """What does not change over time (static): the feet's frame, the gait bars' width."""
    for leg in LEG_NAMES:
        recording.log(f"{FEET}/{leg}", rr.CoordinateFrame(base_frame), static=True)
        recording.log(f"{FEET}/{leg}/force", rr.CoordinateFrame(base_frame), static=True)
        recording.log(f"{PLOTS}/gait/{leg}", rr.SeriesLines(widths=6.0, names=leg), static=True)


def send_feet(recording: rr.RecordingStream, rows: FeetRows) -> None:
    """Per leg, in the base frame: the foot (coloured by P(stance)) and its force arrow."""
    for slot, leg in enumerate(LEG_NAMES):
        position = rows.positions[:, slot]
        known = np.isfinite(position).all(axis=1)
        contacts = rows.contacts[:, slot] if rows.contacts is not None else None
        send_known(
            recording,
            f"{FEET}/{leg}",
            rows.stamps_ns,
            known,
            lambda: rr.Points3D.columns(
                positions=position[known],  # noqa: B023 (called at once)
                colors=stance_colors(contacts, len(position))[known],  # noqa: B023
                radii=np.full(int(known.sum()), FOOT_RADIUS_M, np.float32),  # noqa: B023
            ),
        )
        if rows.forces is not None:
            _send_arrows(recording, leg, rows.stamps_ns, position, rows.forces[:, slot])


def _send_arrows(
    recording: rr.RecordingStream,
    leg: str,
    stamps_ns: np.ndarray,
    position: np.ndarray,
    force: np.ndarray,
) -> None:
    """``leg``'s force arrows: ``force`` (N, 3) [N] from ``position`` (N, 3) [m], base frame."""
    known = np.isfinite(position).all(axis=1) & np.isfinite(force).all(axis=1)
    send_known(
        recording,
        f"{FEET}/{leg}/force",
        stamps_ns,
        known,
        lambda: rr.Arrows3D.columns(
            origins=position[known], vectors=force[known] * FORCE_ARROW_M_PER_N
        ),
    )


def send_feet_plots(recording: rr.RecordingStream, rows: FeetRows, joints: Sequence[str]) -> None:
    """Joint angles [rad] (``joints``: the names of ``rows.angles``' columns), foot heights (z
    in the base frame) [m], normal forces [N] and P(stance), one series per joint or leg.
    """
    stamps = rows.stamps_ns
    if rows.angles is not None:
        for slot, joint in enumerate(joints):
            send_scalars(recording, f"{PLOTS}/joint_angle/{joint}", stamps, rows.angles[:, slot])
    for slot, leg in enumerate(LEG_NAMES):
        send_scalars(recording, f"{PLOTS}/foot_height/{leg}", stamps, rows.positions[:, slot, 2])
        if rows.normal_forces is not None:
            send_scalars(
                recording, f"{PLOTS}/normal_force/{leg}", stamps, rows.normal_forces[:, slot]
            )
        if rows.contacts is not None:
            send_scalars(recording, f"{PLOTS}/p_stance/{leg}", stamps, rows.contacts[:, slot])


def send_paths(
    recording: rr.RecordingStream,
    feet: FeetRows,
    base: BaseRows,
    truth: np.ndarray | None = None,
) -> None:
    """In odom (static lines): the base's path, the truth's (``truth`` (N, 3) [m] at the base's
    rows), and each foot's trail (the feet at the rows the odometry has a pose for).
    """
    recording.log(f"{ODOM}/path", _strip(base.positions, (40, 40, 40, 255)), static=True)
    if truth is not None:
        recording.log(f"{ODOM}/truth", _strip(truth, (40, 180, 60, 255)), static=True)
    row = np.searchsorted(base.stamps_ns, feet.stamps_ns).clip(0, max(len(base.stamps_ns) - 1, 0))
    matched = base.stamps_ns[row] == feet.stamps_ns if len(base.stamps_ns) else np.zeros(0, bool)
    if not matched.any():
        return
    rotations = rotation_matrices(base.orientations[row[matched]])
    world = np.einsum("nij,nlj->nli", rotations, feet.positions[matched])
    world += base.positions[row[matched]][:, None, :]
    for slot, leg in enumerate(LEG_NAMES):
        recording.log(
            f"{ODOM}/trails/{leg}", _strip(world[:, slot], (200, 120, 0, 255)), static=True
        )


def _strip(points: np.ndarray, color: tuple[int, int, int, int]) -> rr.LineStrips3D:
    """One line through the finite ``points`` (N, 3) [m]."""
    return rr.LineStrips3D([points[np.isfinite(points).all(axis=1)]], colors=[color], radii=0.004)


def send_velocity(
    recording: rr.RecordingStream, base: BaseRows, truth: np.ndarray | None = None
) -> None:
    """The velocity in the base frame [m/s] with its +-3 sigma band, and the truth's (``truth``
    (N, 3) [m/s] at the base's rows).
    """
    stamps, linear = base.stamps_ns, base.linear
    sigma = np.sqrt(base.linear_variances)
    for axis, name in enumerate(AXES):
        entity = f"{PLOTS}/velocity/{name}"
        send_scalars(recording, f"{entity}/estimate", stamps, linear[:, axis])
        send_scalars(
            recording, f"{entity}/plus_3sigma", stamps, linear[:, axis] + 3 * sigma[:, axis]
        )
        send_scalars(
            recording, f"{entity}/minus_3sigma", stamps, linear[:, axis] - 3 * sigma[:, axis]
        )
        if truth is not None:
            send_scalars(recording, f"{entity}/truth", stamps, truth[:, axis])


def send_gait(recording: rr.RecordingStream, stamps_ns: np.ndarray, stance: np.ndarray) -> None:
    """The gait diagram: leg k's stance (``stance`` (N, 4) bool) drawn at height 4 - k."""
    for slot, leg in enumerate(LEG_NAMES):
        level = np.where(stance[:, slot], float(len(LEG_NAMES) - slot), np.nan)
        send_scalars(recording, f"{PLOTS}/gait/{leg}", stamps_ns, level)


def send_filter(recording: rr.RecordingStream, stamps_ns: np.ndarray, history: np.ndarray) -> None:
    """The state filter's NIS per row and its running gate counts (``history``: the
    :class:`~a1_leg_fk.recording.odometry.OdometryTrack`'s ``filter_history``).
    """
    if not len(history):
        return
    stamps = stamps_ns
    nis_sum, nis_count = np.diff(history[:, 0], prepend=0.0), np.diff(history[:, 1], prepend=0.0)
    nis = np.where(nis_count > 0, nis_sum / np.where(nis_count > 0, nis_count, 1.0), np.nan)
    send_scalars(recording, f"{PLOTS}/filter/nis", stamps, nis)
    for group, name in enumerate(GATE_COUNTS):
        for slot, leg in enumerate(LEG_NAMES):
            column = history[:, 2 + 4 * group + slot]
            send_scalars(recording, f"{PLOTS}/filter/{name}/{leg}", stamps, column)
    send_scalars(recording, f"{PLOTS}/filter/gate_resets", stamps, history[:, 10])
