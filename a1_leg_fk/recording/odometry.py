"""Leg odometry of a recorded run: the bag's JointState (and Imu) messages through the node's
pipeline (:class:`~a1_leg_fk.estimation.odometry_feed.OdometryFeed`), in bag order, as a live node
would have received them. No ROS install: the bag is read with ``rosbags``
(:mod:`a1_leg_fk.recording.reader`), JointState messages by the same rules and blocks as
``a1-leg-fk bag`` (:mod:`a1_leg_fk.recording.blocks`); the stance from the merged joint efforts'
contacts from the merged joint efforts' foot forces and the feet's kinematics, or the kinematics
alone, as the node decides it (:data:`~a1_leg_fk.estimation.odometry_feed.CONTACT_SOURCES`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import repeat
from pathlib import Path
from typing import TYPE_CHECKING, Any, Unpack

import numpy as np

from a1_leg_fk.estimation.contact_estimator import EvidenceCounts
from a1_leg_fk.estimation.filter_model import FLAT, FilterCounts, FilterSettings
from a1_leg_fk.estimation.imu import imu_reading
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.estimation.odometry import OdometryCounts, OdometrySample, OdometrySettings
from a1_leg_fk.estimation.odometry_feed import AUTO, FORCE, KINEMATIC, OdometryFeed
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.forces import check_has_efforts
from a1_leg_fk.recording.reader import pick_topic
from a1_leg_fk.recording.trajectories import (
    BasePoses,
    BlockStats,
    RecordingChoices,
    RecordingSummary,
    close_recording,
    iter_foot_blocks,
    open_recording,
)

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

    from a1_leg_fk.estimation.odometry import ImuReading
    from a1_leg_fk.recording.reads import RecordingReads

IMU_TYPE = "sensor_msgs/msg/Imu"


@dataclass(frozen=True)
class OdometryTrack:
    """The odometry over a recording, one row per accepted JointState with joint velocities (N):
    ``stamps_ns`` (N,);
    pose in odom: ``positions`` (N, 3) [m], ``orientations`` (N, 4) x, y, z, w; twist in the base
    frame: ``linear`` (N, 3) [m/s], ``angular`` (N, 3) [rad/s]; covariance diagonals
    ``pose_variances`` and ``twist_variances`` (N, 6); ``stance`` and ``used`` (N, 4) bool.
    ``truth``: the base's recorded pose (``--truth``), else None. ``contacts``: the contacts'
    source asked for (auto, force, kinematic), ``contact_counts`` the samples with each
    evidence, ``contacts_note`` why there are no foot forces for this robot ("" when there are).
    ``filtered``: the rows the state filter gave (the others: the legs alone, without an
    accelerometer), ``filter_counts``, its final biases (gyro [rad/s], accelerometer [m/s^2])
    and the feet's noise scale.
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
    planar: bool
    base_frame: str
    imu_topic: str | None
    imu_samples: int
    rows_with_imu: int
    radii: tuple[float, ...]
    counts: OdometryCounts
    contacts: str
    contact_counts: EvidenceCounts
    contacts_note: str
    filtered: int
    filter_counts: FilterCounts
    biases: tuple[tuple[float, ...], tuple[float, ...]]
    noise_scales: tuple[float, float]
    truth: BasePoses | None
    truth_topic: str | None
    summary: RecordingSummary


def odometry_track(
    path: str | Path,
    *,
    imu_topic: str | None = None,
    use_imu: bool = True,
    radius_m: float | None = None,
    settings: OdometrySettings | None = None,
    contacts: str = AUTO,
    filter_settings: FilterSettings | None = None,
    ground: str = FLAT,
    progress: bool = False,
    **choices: Unpack[RecordingChoices],
) -> OdometryTrack:
    """The leg odometry of a bag. ``imu_topic``: its sensor_msgs/msg/Imu topic (default: the only
    one, if any; ``use_imu`` false: none); ``radius_m`` overrides the feet's URDF radius;
    ``contacts``: the contacts' source (``auto``, ``force``: a bag without efforts is bad input,
    ``kinematic``); ``filter_settings`` and ``ground`` the state filter's; ``choices`` as
    :func:`~a1_leg_fk.recording.trajectories.open_recording`'s, whose ``base_pose`` is the truth
    to compare with and ``model_corrections`` the contacts'. :class:`LegFkError` for bad input.
    """
    recording = open_recording(path, **choices)
    try:
        recording.efforts = contacts != KINEMATIC
        lowstate = recording.lowstate  # a LowState carries its motors' torques and its IMU
        if contacts == FORCE and lowstate is None:
            check_has_efforts(
                recording.reads, recording.joint_states, recording.ros1, "--contacts force"
            )
        if lowstate is not None and imu_topic:
            raise LegFkError(f"--imu: {lowstate.connection.topic} is a LowState, with its IMU")
        if lowstate is not None:
            imu_connection = lowstate.connection if use_imu else None
            imu = lowstate.imu_samples(recording.reads) if use_imu else []
        else:
            imu_connection = _imu_connection(recording.reader, Path(path), imu_topic, use_imu)
            imu = _imu_samples(recording.reads, imu_connection) if imu_connection else []
        feed = OdometryFeed(
            recording.quadruped,
            settings,
            radius_m,
            use_imu=use_imu,
            contacts=contacts,
            filter_settings=filter_settings,
            ground=ground,
            model_corrections=choices.get("model_corrections", DEFAULT_MODEL_CORRECTIONS),
        )
        if contacts == FORCE and feed.note:
            raise LegFkError(f"--contacts force: {feed.note}")
        stats, samples, next_imu = BlockStats(), [], 0
        for block in iter_foot_blocks(recording, progress=progress):
            stats.add(block)
            usable = np.isfinite(block.positions).all(axis=2) & np.isfinite(block.velocities).all(
                axis=2
            )
            efforts = block.efforts.tolist() if block.efforts is not None else repeat(None)
            rows = zip(
                block.stamps_ns.tolist(),
                block.bag_times_ns.tolist(),
                block.positions.tolist(),
                block.velocities.tolist(),
                usable.tolist(),
                block.angles.tolist(),
                block.rates.tolist(),
                efforts,
            )
            for stamp, bag_time, positions, velocities, known, angles, rates, effort in rows:
                while next_imu < len(imu) and imu[next_imu][0] <= bag_time:
                    feed.add_imu(imu[next_imu][1], imu[next_imu][2])
                    next_imu += 1
                feet = [
                    (position, velocity) if ok else None
                    for position, velocity, ok in zip(positions, velocities, known)
                ]
                sample = feed.step(stamp, feet, angles, rates, efforts=effort)
                if sample is not None:
                    samples.append(sample)
        summary = stats.summary(recording)
    finally:
        close_recording(recording)
    return _track(
        samples,
        recording.quadruped.base_frame,
        imu_connection,
        len(imu),
        feed,
        recording.base_pose_topic,
        recording.base_pose,
        summary,
    )


def _track(
    samples: Sequence[OdometrySample],
    base_frame: str,
    imu_connection: Connection | None,
    imu_samples: int,
    feed: OdometryFeed,
    truth_topic: str | None,
    truth: BasePoses | None,
    summary: RecordingSummary,
) -> OdometryTrack:
    def column(name: str, width: int, dtype: type = float) -> np.ndarray:
        return np.array([getattr(s, name) for s in samples], dtype=dtype).reshape(-1, width)

    return OdometryTrack(
        stamps_ns=np.array([s.stamp_ns for s in samples], dtype=np.int64),
        positions=column("position", 3),
        orientations=column("orientation", 4),
        linear=column("linear", 3),
        angular=column("angular", 3),
        pose_variances=column("pose_variance", 6),
        twist_variances=column("twist_variance", 6),
        stance=_mask([s.stance for s in samples]),
        used=_mask([s.used for s in samples]),
        planar=bool(samples[-1].planar) if samples else True,
        base_frame=base_frame,
        imu_topic=imu_connection.topic if imu_connection else None,
        imu_samples=imu_samples,
        rows_with_imu=feed.samples_with_imu,
        radii=feed.motion.radii,
        counts=feed.odometry.counts,
        contacts=feed.source,
        contact_counts=feed.counts,
        contacts_note=feed.note,
        filtered=feed.samples_filtered,
        filter_counts=feed.filter.counts,
        biases=(tuple(feed.filter.gyro_bias.tolist()), tuple(feed.filter.accel_bias.tolist())),
        noise_scales=feed.filter.gate.scales,
        truth=truth,
        truth_topic=truth_topic,
        summary=summary,
    )


def _mask(legs: Sequence[Sequence[int]]) -> np.ndarray:
    """(N, 4) bool: row n has True at the legs ``legs[n]``."""
    mask = np.zeros((len(legs), 4), dtype=bool)
    for row, chosen in enumerate(legs):
        mask[row, list(chosen)] = True
    return mask


def _imu_connection(
    reader: AnyReader, path: Path, wanted: str | None, use_imu: bool
) -> Connection | None:
    """The Imu topic: ``wanted``, else the only one; None without one or when not ``use_imu``."""
    if not use_imu:
        return None
    if wanted is None and not any(c.msgtype == IMU_TYPE for c in reader.connections):
        return None
    return pick_topic(reader, path, wanted, (IMU_TYPE,), "--imu", "Imu")


def _imu_samples(
    reads: RecordingReads, connection: Connection
) -> list[tuple[int, int, ImuReading | None]]:
    """(bag time [ns], stamp [ns], reading) of every Imu message up to damage, in bag order (the
    stamp is the bag time where the header's is zero, as for joint states).
    """
    samples = []
    message: Any
    for bag_time, message in reads.decoded(connection):
        stamp = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
        q, w, a = message.orientation, message.angular_velocity, message.linear_acceleration
        reading = imu_reading(
            (q.x, q.y, q.z, q.w),
            message.orientation_covariance,
            (w.x, w.y, w.z),
            message.angular_velocity_covariance,
            (a.x, a.y, a.z),
            message.linear_acceleration_covariance,
        )
        samples.append((bag_time, stamp or bag_time, reading))
    return samples
