"""Recorded runs: a ROS bag in, the four feet over time out (base frame, and world frame with a
recorded base pose). No ROS install: bags are read with ``rosbags`` (imported lazily).

The JointState rules are :class:`~a1_leg_fk.tracking.FootTracker`'s, as in the node; the model
comes from :func:`~a1_leg_fk.kinematics.robot_config.load_robot`, as in the node. JointState
messages are read from their serialized bytes (:mod:`a1_leg_fk.wire.joint_state`), not
deserialized into Python objects, and processed in blocks of
:data:`~a1_leg_fk.recording.blocks.BLOCK_MESSAGES` with numpy. Results stream out block by block
(:func:`iter_foot_blocks`), so writers need memory independent of the bag's length;
:func:`read_foot_trajectories` collects them into arrays for notebooks.

This module is the API: the summary of a pass, the arrays of a whole run, and (re-exported) what
the jobs behind them offer: :mod:`a1_leg_fk.recording.reader` opens a bag and makes the choices
(topic, model, base pose), :mod:`a1_leg_fk.recording.base_pose` reads and interpolates the base
pose,
:mod:`a1_leg_fk.recording.blocks` turns the JointState messages into :class:`FootBlock` rows.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Unpack, cast

import numpy as np

from a1_leg_fk.estimation.sensor_contacts import SensorAgreement
from a1_leg_fk.recording.base_pose import DEFAULT_MAX_POSE_GAP_S, BasePoses
from a1_leg_fk.recording.blocks import LEGS, iter_foot_blocks
from a1_leg_fk.recording.foot_block import FootBlock
from a1_leg_fk.recording.lowstate import STAMP_NOTE
from a1_leg_fk.recording.reader import (
    JOINT_STATE_TYPE,
    Recording,
    RecordingChoices,
    close_recording,
    open_recording,
)
from a1_leg_fk.tracking import REJECTIONS

if TYPE_CHECKING:
    from a1_leg_fk.tracking import FootTracker


@dataclass(frozen=True)
class RecordingSummary:
    """What a pass over a bag did. Times in ns (bag clock / header stamps), wall time in s."""

    path: str
    model: str  # where the robot model came from
    topic: str
    base_pose_topic: str | None
    messages: int  # JointState messages read
    outcomes: dict[str, int]  # accepted / no_leg_joints / the rejection reasons -> messages
    non_finite_joints: int
    unknown_names: tuple[str, ...]
    rows: int  # accepted messages that leave at least one leg known
    rows_without_pose: int  # rows outside the base pose's time range or in a gap (with base_pose)
    first_stamp_ns: int | None
    last_stamp_ns: int | None
    wall_time_s: float
    stopped: str = ""  # why reading stopped before the end of the bag ("" = read to the end)
    types: str = ""  # which message types the bag was read with (recording.typestores)
    forces: str = ""  # with forces or contacts: what the estimate gave (RecordingForces.summary)
    input_type: str = JOINT_STATE_TYPE  # the message type of ``topic``
    stamps: str = ""  # where the stamps came from, when not the messages' headers
    sensors: str = ""  # a LowState's foot sensors against the contact estimate (SensorAgreement)
    unitree: str = ""  # our feet against a recorded SportModeState's (SportFeet.line)

    @property
    def rejected(self) -> dict[str, int]:
        """Rejection reason -> messages, for the reasons that occurred."""
        return {
            reason: self.outcomes[reason] for reason in REJECTIONS if self.outcomes.get(reason)
        }

    def lines(self) -> list[str]:
        """The human summary, one fact per line."""
        rate = self.messages / self.wall_time_s if self.wall_time_s > 0 else math.inf
        rejected = (
            ", ".join(f"{reason} {count}" for reason, count in self.rejected.items()) or "none"
        )
        span = (
            f"{(self.last_stamp_ns - self.first_stamp_ns) / 1e9:.3f} s "
            f"({_seconds(self.first_stamp_ns)} .. {_seconds(self.last_stamp_ns)})"
            if self.first_stamp_ns is not None and self.last_stamp_ns is not None
            else "empty"
        )
        lines = [
            f"file:      {self.path}",
            f"model:     {self.model}",
            f"topic:     {self.topic} ({self.input_type})",
            f"types:     {self.types}",
            (
                f"messages:  {self.messages} read, {self.outcomes.get('accepted', 0)} accepted, "
                f"{sum(self.rejected.values())} rejected ({rejected}), "
                f"{self.outcomes.get('no_leg_joints', 0)} without leg joints"
            ),
            f"rows:      {self.rows}",
            f"time span: {span}",
            f"wall time: {self.wall_time_s:.2f} s ({rate:,.0f} messages/s)",
        ]
        if self.non_finite_joints:
            lines.insert(
                5, f"non-finite joint values: {self.non_finite_joints} (their legs held back)"
            )
        if self.unknown_names:
            lines.insert(5, f"ignored names: {list(self.unknown_names[:20])}")
        if self.base_pose_topic:
            lines.append(
                f"base pose: {self.base_pose_topic}; {self.rows_without_pose} rows without a "
                "pose (outside its time range or in a gap)"
            )
        if self.stamps:
            lines.insert(4, f"stamps:    {self.stamps}")
        if self.forces:
            lines.extend(self.forces.split("\n"))
        lines.extend(line for line in (self.sensors, self.unitree) if line)
        if self.stopped:
            lines.append(f"stopped early: {self.stopped}")
        return lines


def _seconds(stamp_ns: int) -> str:
    """A stamp [ns] as exact decimal seconds."""
    sign, magnitude = ("-" if stamp_ns < 0 else ""), abs(stamp_ns)
    return f"{sign}{magnitude // 1_000_000_000}.{magnitude % 1_000_000_000:09d}"


@dataclass(frozen=True)
class FootTrajectories:
    """The feet over a recording (see :func:`read_foot_trajectories`). Legs FR, FL, RR, RL."""

    stamps_ns: (
        np.ndarray
    )  # (N,) int64: JointState header stamps (bag time where the stamp is zero)
    bag_times_ns: np.ndarray  # (N,) int64
    positions: np.ndarray  # (N, 4, 3) [m], base frame, NaN for legs not yet known
    velocities: (
        np.ndarray | None
    )  # (N, 4, 3) [m/s] (NaN where none), None without joint velocities
    world_positions: (
        np.ndarray | None
    )  # (N, 4, 3) [m] in world_frame, NaN where no pose; None without base_pose
    base_frame: str
    world_frame: str | None
    summary: RecordingSummary
    forces: np.ndarray | None = None  # (N, 4, 3) [N], base frame, NaN where none; with forces
    normal_forces: np.ndarray | None = None  # (N, 4) [N] along minus gravity, NaN where none
    contacts: np.ndarray | None = None  # (N, 4) contact probabilities, NaN where none
    sensor: np.ndarray | None = None  # (N, 4) a LowState's foot sensors [raw counts]
    angles: np.ndarray | None = None  # (N, joints) [rad] the merged joint angles, NaN unknown
    urdf_xml: str = ""  # the URDF text the model was read from


class BlockStats:
    """Counts rows, rows without a pose and the stamp range over a pass (for the summary)."""

    def __init__(self) -> None:
        self.rows = 0
        self.rows_without_pose = 0
        self.first: int | None = None
        self.last: int | None = None
        self.started = time.perf_counter()
        self.sensors: SensorAgreement | None = None  # set by the first block with both

    def add(self, block: FootBlock, recording: Recording | None = None) -> None:
        """Count the block's rows; with ``recording``, compare them with its foot sensors (a
        LowState's, when the rows have contact estimates) and its SportModeState feet.
        """
        if not len(block.stamps_ns):
            return
        if recording is not None and recording.sport is not None:
            recording.sport.compare(block.stamps_ns, block.positions)
        if recording is not None and block.sensor is not None and block.contacts is not None:
            self.sensors = self.sensors or SensorAgreement(recording.sensor_threshold)
            self.sensors.add(block.contacts, block.sensor)
        self.rows += len(block.stamps_ns)
        if block.world_positions is not None:
            self.rows_without_pose += int(np.isnan(block.world_positions).all(axis=(1, 2)).sum())
        low, high = int(block.stamps_ns.min()), int(block.stamps_ns.max())
        self.first = low if self.first is None else min(self.first, low)
        self.last = high if self.last is None else max(self.last, high)

    def summary(self, recording: Recording) -> RecordingSummary:
        """The summary of the finished pass over ``recording``."""
        counts = cast("FootTracker", recording.tracker).counts  # set by iter_foot_blocks
        return RecordingSummary(
            str(recording.path),
            recording.model_source,
            recording.joint_states.topic,
            recording.base_pose_topic,
            counts.messages,
            dict(counts.outcomes),
            counts.non_finite_joints,
            tuple(sorted(counts.unknown_names)),
            self.rows,
            self.rows_without_pose,
            self.first,
            self.last,
            time.perf_counter() - self.started,
            "; ".join(part for part in (recording.salvage_note, recording.stopped) if part),
            recording.types,
            recording.forces.summary(recording.force_output) if recording.forces else "",
            recording.joint_states.msgtype,
            STAMP_NOTE if recording.lowstate is not None else "",
            self.sensors.line() if self.sensors is not None and recording.force_output else "",
            recording.sport.line() if recording.sport is not None else "",
        )


# --- the notebook API ----------------------------------------------------------------------------


def read_foot_trajectories(
    path: str | Path, *, progress: bool = False, **choices: Unpack[RecordingChoices]
) -> FootTrajectories:
    """The four feet over a recorded run, as arrays (one row per accepted JointState message
    that leaves at least one leg known, in bag order).

    ``path``: a ROS 2 bag directory, a ``.mcap`` file or a ROS 1 ``.bag``. ``progress``: a
    progress bar on stderr (with tqdm). ``choices``, keyword arguments as
    :func:`open_recording`'s (:class:`RecordingChoices`): ``topic``: the JointState topic
    (needed when there are several), or a Unitree LowState topic (read when the bag has no
    JointState: its motors, IMU and foot sensors, ``sensor``; stamps: bag times). Model:
    ``urdf`` (a path), else the bag's ``robot_description`` topic (the latest message before the
    first JointState), else the embedded A1; ``foot_links``/``joint_aliases`` as the node's
    parameters (``"KEY=value"``).
    ``base_pose``: an Odometry / PoseStamped / PoseWithCovarianceStamped / TFMessage topic that
    gives the base's pose in a world frame, interpolated at each JointState stamp (NaN where the
    stamp is outside the poses' range or in a gap longer than ``max_pose_gap_s`` [s], default
    :data:`DEFAULT_MAX_POSE_GAP_S`). ``forces=True``: foot forces [N] and contact probabilities
    from the joint efforts (``imu``: a sensor_msgs/msg/Imu topic for gravity's direction;
    ``contact_thresholds``: touchdown and liftoff forces [N], ``None`` for the defaults).
    Raises :class:`LegFkError` for bad input; a bag that cannot be read to its end gives what was
    read, with ``summary.stopped`` saying why.
    """
    recording = open_recording(path, **choices)
    try:
        stats = BlockStats()
        blocks = []
        for block in iter_foot_blocks(recording, progress=progress):
            stats.add(block, recording)
            blocks.append(block)
        summary = stats.summary(recording)
    finally:
        close_recording(recording)
    return collected(blocks, recording, summary)


def collected(
    blocks: list[FootBlock], recording: Recording, summary: RecordingSummary
) -> FootTrajectories:
    """The blocks of one pass over ``recording`` as one :class:`FootTrajectories`."""

    def joined(name: str, shape: tuple[int, ...], dtype: type = float) -> np.ndarray:
        parts = [getattr(block, name) for block in blocks]
        return np.concatenate(parts) if parts else np.empty((0, *shape), dtype)

    world = joined("world_positions", (LEGS, 3)) if recording.base_pose is not None else None
    return FootTrajectories(
        stamps_ns=joined("stamps_ns", (), np.int64),
        bag_times_ns=joined("bag_times_ns", (), np.int64),
        positions=joined("positions", (LEGS, 3)),
        velocities=joined("velocities", (LEGS, 3)) if recording.has_velocities else None,
        world_positions=world,
        base_frame=recording.quadruped.base_frame,
        world_frame=recording.base_pose.world_frame if recording.base_pose is not None else None,
        summary=summary,
        forces=joined("forces", (LEGS, 3)) if recording.forces is not None else None,
        normal_forces=joined("normal_forces", (LEGS,)) if recording.forces is not None else None,
        contacts=joined("contacts", (LEGS,)) if recording.forces is not None else None,
        sensor=joined("sensor", (LEGS,)) if recording.lowstate is not None else None,
        angles=joined("angles", (len(recording.quadruped.joint_names),)),
        urdf_xml=recording.urdf_xml,
    )


__all__ = [
    "DEFAULT_MAX_POSE_GAP_S",
    "BasePoses",
    "FootBlock",
    "FootTrajectories",
    "Recording",
    "RecordingChoices",
    "RecordingSummary",
    "close_recording",
    "collected",
    "iter_foot_blocks",
    "open_recording",
    "read_foot_trajectories",
]
