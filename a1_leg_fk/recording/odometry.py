"""Leg odometry of a recorded run: the bag's JointState (and Imu) messages through the node's
pipeline (:class:`~a1_leg_fk.estimation.odometry_feed.OdometryFeed`), in bag order, as a live node
would have received them. No ROS install: the bag is read with ``rosbags``
(:mod:`a1_leg_fk.recording.reader`), JointState messages by the same rules and blocks as
``a1-leg-fk bag`` (:mod:`a1_leg_fk.recording.blocks`); the stance from the merged joint efforts'
contacts from the merged joint efforts' foot forces and the feet's kinematics, or the kinematics
alone, as the node decides it (:data:`~a1_leg_fk.estimation.odometry_feed.CONTACT_SOURCES`).

It streams (:func:`odometry_stream`): the IMU is read in the same pass as the joint states, and
the rows come in blocks as they become final (at once, or a smoother's window later), so a pass
keeps no more of the recording than a block and the smoother's window, whatever its length.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from itertools import repeat
from pathlib import Path
from typing import TYPE_CHECKING, Unpack

import numpy as np

from a1_leg_fk.estimation.contact_estimator import EvidenceCounts
from a1_leg_fk.estimation.filter_model import DEFAULT_GROUND, FilterCounts, FilterSettings
from a1_leg_fk.estimation.ground_outputs import ground_values
from a1_leg_fk.estimation.imu_pairing import DEFAULT_IMU_WAIT_S, ImuPairing
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.estimation.odometry import OdometryCounts, OdometrySample, OdometrySettings
from a1_leg_fk.estimation.odometry_feed import AUTO, FORCE, KINEMATIC, OdometryFeed
from a1_leg_fk.estimation.odometry_smoother import OdometrySmoother
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.foot_block import FootBlock
from a1_leg_fk.recording.forces import check_has_efforts
from a1_leg_fk.recording.imu_stream import ImuStream
from a1_leg_fk.recording.odometry_rows import LiveRow, TrackRows, running_counts
from a1_leg_fk.recording.reader import Recording, pick_topic
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

IMU_TYPE = "sensor_msgs/msg/Imu"
END_OF_BAG = 2**63 - 1
"""[ns] A bag time after every message's."""
BLOCK_ROWS = 4096
"""Rows the stream gives at a time (:func:`odometry_stream`)."""


@dataclass(frozen=True)
class OdometryOptions:
    """How the odometry runs. ``imu_topic``: its sensor_msgs/msg/Imu topic (default: the only
    one, if any; ``use_imu`` false: none); ``radius_m`` overrides the feet's URDF radius;
    ``contacts``: the contacts' source (``auto``, ``force``: a bag without efforts is bad input,
    ``kinematic``); ``filter_settings`` and ``ground`` the state filter's; ``smoothed``: the
    filter's states smoothed over the recording (:class:`~a1_leg_fk.estimation.
    odometry_smoother.OdometrySmoother`), else the filter's own, as the node has them;
    ``progress``: a progress bar; ``imu_wait_s``: how long [s, stamp time] a joint state waits
    for its IMU sample (:class:`~a1_leg_fk.estimation.imu_pairing.ImuPairing`).
    """

    imu_topic: str | None = None
    use_imu: bool = True
    radius_m: float | None = None
    settings: OdometrySettings | None = None
    contacts: str = AUTO
    filter_settings: FilterSettings | None = None
    ground: str = DEFAULT_GROUND
    smoothed: bool = False
    progress: bool = False
    imu_wait_s: float = DEFAULT_IMU_WAIT_S


@dataclass(frozen=True)
class TrackInfo:
    """What the odometry over a recording found besides its rows. ``planar``: the last row's
    pose is planar (legs alone); ``smoothed``: the filter's rows smoothed over the recording
    (else the filter's own, causal). ``truth``: the base's recorded pose (``--truth``), else
    None. ``contacts``: the contacts' source asked for (auto, force, kinematic),
    ``contact_counts`` the samples with each evidence, ``contacts_note`` why there are no foot
    forces for this robot ("" when there are). ``filtered``: the rows the state filter gave (the
    others: the legs alone, without an accelerometer), ``filter_counts``, its final biases (gyro
    [rad/s], accelerometer [m/s^2]) and the feet's noise scale.
    """

    planar: bool
    smoothed: bool
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


@dataclass(frozen=True)
class OdometryTrack(TrackRows, TrackInfo):
    """The odometry over a recording, whole: its rows, one per accepted JointState with joint
    velocities (:class:`~a1_leg_fk.recording.odometry_rows.TrackRows`), and :class:`TrackInfo`.
    """

    @classmethod
    def of_rows(cls, rows: TrackRows, info: TrackInfo) -> OdometryTrack:
        """The track of ``rows`` and ``info``."""
        return cls(**vars(rows), **vars(info))


class OdometryStream:
    """The odometry's rows as they become final, in blocks (:class:`TrackRows`): iterate once;
    ``info`` is set when the last block has been given.
    """

    def __init__(self, blocks: Generator[TrackRows, None, TrackInfo]) -> None:
        self._blocks = blocks
        self.info: TrackInfo | None = None

    def __iter__(self) -> Iterator[TrackRows]:
        self.info = yield from self._blocks


def odometry_track(
    path: str | Path,
    options: OdometryOptions | None = None,
    **choices: Unpack[RecordingChoices],
) -> OdometryTrack:
    """The leg odometry of a bag, whole (:func:`odometry_stream`'s rows joined)."""
    stream = odometry_stream(path, options, **choices)
    rows = TrackRows.joined(list(stream))
    assert stream.info is not None
    return OdometryTrack.of_rows(rows, stream.info)


def odometry_stream(
    path: str | Path,
    options: OdometryOptions | None = None,
    block_rows: int = BLOCK_ROWS,
    **choices: Unpack[RecordingChoices],
) -> OdometryStream:
    """The leg odometry of a bag as it streams: blocks of ``block_rows`` final rows (the last
    block shorter), the IMU read in the same pass as the joint states
    (:class:`~a1_leg_fk.recording.imu_stream.ImuStream`). ``choices`` as
    :func:`~a1_leg_fk.recording.trajectories.open_recording`'s, whose ``base_pose`` is the truth
    to compare with and ``model_corrections`` the contacts'. :class:`LegFkError` for bad input,
    when iterated.
    """
    return OdometryStream(_blocks(Path(path), options or OdometryOptions(), block_rows, choices))


def _blocks(
    path: Path, options: OdometryOptions, block_rows: int, choices: RecordingChoices
) -> Generator[TrackRows, None, TrackInfo]:
    """The pass of :func:`odometry_stream`."""
    recording = open_recording(path, **choices)
    try:
        corrections = choices.get("model_corrections", DEFAULT_MODEL_CORRECTIONS)
        feed, imu = _inputs(recording, path, options, corrections)
        stats, samples, planar = BlockStats(), [], True
        pending: deque[LiveRow] = deque()  # the live values of the rows not final yet
        live: list[LiveRow] = []
        smoother = OdometrySmoother(feed.filter) if options.smoothed else None
        blocks = iter_foot_blocks(
            recording,
            progress=options.progress,
            on_message=imu.add if imu else None,
            others=[imu.connection] if imu else None,
        )
        wait_s = options.imu_wait_s if imu is not None and imu.lowstate is None else 0.0
        for sample in _samples(blocks, stats, ImuPairing(feed, wait_s), imu):
            pending.append(
                (ground_values(feed.ground_plane(sample)), running_counts(feed.filter.counts))
            )
            final = [sample] if smoother is None else smoother.add(sample, feed.samples_filtered)
            samples += final
            live += [pending.popleft() for _ in final]
            if len(samples) >= block_rows:
                planar = samples[-1].planar
                yield TrackRows.of(samples, live)
                samples, live = [], []
        if smoother is not None:
            samples += smoother.finish()
            live += pending
        if samples:
            planar = samples[-1].planar
            yield TrackRows.of(samples, live)
        summary = stats.summary(recording)
        imu_samples = imu.finish() if imu else 0
    finally:
        close_recording(recording)
    return TrackInfo(
        planar=bool(planar),
        smoothed=options.smoothed,
        base_frame=recording.quadruped.base_frame,
        imu_topic=imu.connection.topic if imu else None,
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
        truth=recording.base_pose,
        truth_topic=recording.base_pose_topic,
        summary=summary,
    )


def _inputs(
    recording: Recording, path: Path, options: OdometryOptions, corrections: str
) -> tuple[OdometryFeed, ImuStream | None]:
    """The odometry's pipeline for ``recording`` (the contacts' ``corrections``: online, off or
    a calibration file) and its IMU's stream (None: no IMU); :class:`LegFkError` for bad input.
    """
    contacts, use_imu = options.contacts, options.use_imu
    recording.efforts = contacts != KINEMATIC
    lowstate = recording.lowstate  # a LowState carries its motors' torques and its IMU
    if contacts == FORCE and lowstate is None:
        check_has_efforts(
            recording.reads, recording.joint_states, recording.ros1, "--contacts force"
        )
    if lowstate is not None and options.imu_topic:
        raise LegFkError(f"--imu: {lowstate.connection.topic} is a LowState, with its IMU")
    if lowstate is not None:
        imu = ImuStream(recording.reads, lowstate.connection, lowstate) if use_imu else None
    else:
        connection = _imu_connection(recording.reader, path, options.imu_topic, use_imu)
        imu = ImuStream(recording.reads, connection) if connection else None
    feed = OdometryFeed(
        recording.quadruped,
        options.settings,
        options.radius_m,
        use_imu=use_imu,
        contacts=contacts,
        filter_settings=options.filter_settings,
        ground=options.ground,
        model_corrections=corrections,
    )
    if contacts == FORCE and feed.note:
        raise LegFkError(f"--contacts force: {feed.note}")
    return feed, imu


def _samples(
    blocks: Iterator[FootBlock], stats: BlockStats, pairing: ImuPairing, imu: ImuStream | None
) -> Iterator[OdometrySample]:
    """The feed's causal samples of every block's rows (``stats`` counts the blocks), the IMU's
    and the joint states' messages paired in bag order (:class:`~a1_leg_fk.estimation.
    imu_pairing.ImuPairing`); at the end, the joint states still held after the IMU's last
    samples.
    """
    for block in blocks:
        stats.add(block)
        yield from _block_samples(block, pairing, imu)
    if pairing.holding and imu is not None:
        for _, imu_stamp, reading in imu.until(END_OF_BAG):
            yield from pairing.imu(imu_stamp, reading)
    yield from pairing.flush()


def _block_samples(
    block: FootBlock, pairing: ImuPairing, imu: ImuStream | None
) -> Iterator[OdometrySample]:
    """The feed's causal samples released by ``block``'s rows, each row after the IMU's samples
    up to its bag time.
    """
    usable = np.isfinite(block.positions).all(axis=2) & np.isfinite(block.velocities).all(axis=2)
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
        if imu is not None:
            for _, imu_stamp, reading in imu.until(bag_time):
                yield from pairing.imu(imu_stamp, reading)
        feet = [
            (position, velocity) if ok else None
            for position, velocity, ok in zip(positions, velocities, known)
        ]
        yield from pairing.joint(stamp, feet, angles, rates, effort, bag_time)


def _imu_connection(
    reader: AnyReader, path: Path, wanted: str | None, use_imu: bool
) -> Connection | None:
    """The Imu topic: ``wanted``, else the only one; None without one or when not ``use_imu``."""
    if not use_imu:
        return None
    if wanted is None and not any(c.msgtype == IMU_TYPE for c in reader.connections):
        return None
    return pick_topic(reader, path, wanted, (IMU_TYPE,), "--imu", "Imu")
