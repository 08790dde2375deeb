"""Recorded runs: a ROS bag in, the four feet over time out (base frame, and world frame with a
recorded base pose). No ROS install: bags are read with ``rosbags`` (imported lazily).

The JointState rules are :class:`~a1_leg_fk.joint_state.FootTracker`'s, as in the node; the model
comes from :func:`~a1_leg_fk.robot_config.load_robot`, as in the node. JointState messages are
read from their serialized bytes (:mod:`a1_leg_fk.joint_state_wire`), not deserialized into
Python objects, and processed in blocks of :data:`BLOCK_MESSAGES` with numpy. Results stream out
block by block (:func:`iter_foot_blocks`), so writers need memory independent of the bag's length;
:func:`read_foot_trajectories` collects them into arrays for notebooks.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, TypedDict, cast

import numpy as np

from a1_leg_fk.joint_state import REJECTIONS, FootTracker
from a1_leg_fk.joint_state_wire import JointStateDecoder, WireError, cdr_layout
from a1_leg_fk.kinematics import Quadruped
from a1_leg_fk.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.mcap_salvage import salvage
from a1_leg_fk.robot_config import load_robot
from a1_leg_fk.urdf import LegFkError

if TYPE_CHECKING:  # rosbags and tqdm are imported when a bag is read
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection
    from tqdm import tqdm

ROSBAGS_HINT = "reading ROS bags needs rosbags: pip install rosbags"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
DESCRIPTION_TYPE = "std_msgs/msg/String"
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
POSE_COVARIANCE_TYPE = "geometry_msgs/msg/PoseWithCovarianceStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
BASE_POSE_TYPES = (ODOMETRY_TYPE, POSE_TYPE, POSE_COVARIANCE_TYPE, TF_TYPE)
BLOCK_MESSAGES = 4096
DEFAULT_MAX_POSE_GAP_S = 0.1
LEGS = len(LEG_NAMES)


class RecordingChoices(TypedDict, total=False):
    """The choices of :func:`open_recording` (its keyword arguments)."""

    topic: str | None
    urdf: str | Path | None
    foot_links: Sequence[str]
    joint_aliases: Sequence[str]
    base_pose: str | None
    max_pose_gap_s: float


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
            f"topic:     {self.topic} (sensor_msgs/msg/JointState)",
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
                4, f"non-finite joint values: {self.non_finite_joints} (their legs held back)"
            )
        if self.unknown_names:
            lines.insert(4, f"ignored names: {list(self.unknown_names[:20])}")
        if self.base_pose_topic:
            lines.append(
                f"base pose: {self.base_pose_topic}; {self.rows_without_pose} rows without a pose (outside its time range or in a gap)"
            )
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


@dataclass(frozen=True)
class FootBlock:
    """Rows of consecutive accepted messages: like :class:`FootTrajectories`, velocities always
    an array (NaN where the message gives none).
    """

    stamps_ns: np.ndarray
    bag_times_ns: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    world_positions: np.ndarray | None


@dataclass
class Recording:
    """An open bag with the choices made for it; iterate with :func:`iter_foot_blocks`."""

    reader: AnyReader  # open
    path: Path
    joint_states: Connection
    quadruped: Quadruped
    model_source: str
    base_pose: BasePoses | None
    base_pose_topic: str | None
    ros1: bool
    has_velocities: bool = False  # set while reading: some row had a finite foot velocity
    stopped: str = ""
    salvage_note: str = ""  # what was read of a truncated MCAP file
    tracker: FootTracker | None = None  # the rules' state and counts of the current pass


# --- opening --------------------------------------------------------------------------------------


def _rosbags() -> ModuleType:
    """``rosbags.highlevel``, or a :class:`LegFkError` that says how to install rosbags."""
    try:
        from rosbags import highlevel
    except ImportError as error:
        raise LegFkError(ROSBAGS_HINT) from error
    return highlevel


def open_recording(
    path: str | Path,
    *,
    topic: str | None = None,
    urdf: str | Path | None = None,
    foot_links: Sequence[str] = (),
    joint_aliases: Sequence[str] = (),
    base_pose: str | None = None,
    max_pose_gap_s: float = DEFAULT_MAX_POSE_GAP_S,
) -> Recording:
    """Open a bag and make the choices (topic, model, base pose); :class:`LegFkError` naming the
    problem for bad input. Close with :func:`close_recording`.
    """
    path = Path(path)
    reader, salvage_note = _open_reader(path)
    try:
        joint_states = _pick_topic(
            reader, path, topic, (JOINT_STATE_TYPE,), "--topic", "JointState"
        )
        try:
            description, description_topic = (
                (None, "") if urdf else _recorded_description(reader, joint_states)
            )
        except Exception as error:  # noqa: BLE001 (rosbags: a corrupt message or storage)
            raise LegFkError(
                f"{path}: cannot read its robot_description topic: {_one_line(error)}"
            ) from None
        if urdf:
            robot = load_robot(
                urdf_file=str(urdf), foot_links=foot_links, joint_aliases=joint_aliases
            )
            source = f"--urdf {urdf}"
        elif description is not None:
            name = f"robot_description topic {description_topic} in {path}"
            robot = load_robot(
                description,
                foot_links=foot_links,
                joint_aliases=joint_aliases,
                description_name=name,
            )
            source = name
        else:
            robot = load_robot(foot_links=foot_links, joint_aliases=joint_aliases)
            source = f"embedded A1 ({robot.source})"
        poses = None
        if base_pose:
            pose_connection = _pick_topic(
                reader, path, base_pose, BASE_POSE_TYPES, "--base-pose", "base pose"
            )
            try:
                poses = BasePoses.read(
                    reader, pose_connection, robot.quadruped.base_frame, max_pose_gap_s
                )
            except LegFkError:
                raise
            except Exception as error:  # noqa: BLE001 (rosbags: a corrupt pose message or storage)
                raise LegFkError(
                    f"--base-pose {base_pose}: cannot read it: {_one_line(error)}"
                ) from None
        return Recording(
            reader,
            path,
            joint_states,
            robot.quadruped,
            source,
            poses,
            base_pose,
            not reader.is2,
            salvage_note=salvage_note,
        )
    except BaseException:
        _close_reader(reader)
        raise


def close_recording(recording: Recording) -> None:
    """Close the bag (and remove the copy of a salvaged one)."""
    _close_reader(recording.reader)


def _close_reader(reader: AnyReader) -> None:
    reader.close()
    folder = getattr(reader, "salvage_folder", None)
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)


def _open_reader(path: Path) -> tuple[AnyReader, str]:
    """An open reader of the bag at ``path``, and ``""`` or a note on what was salvaged of a
    truncated MCAP file (read from a copy of its complete records).
    """
    highlevel = _rosbags()
    if not path.exists():
        raise LegFkError(f"{path}: no such file or directory")
    opened = _storage_file(path) if path.is_dir() else path
    try:
        reader = highlevel.AnyReader([opened])
        reader.open()
        return reader, ""
    except Exception as error:  # noqa: BLE001 (rosbags raises several kinds for unreadable files)
        problem = f"{path}: cannot open as a ROS bag: {_one_line(error)}"
    mcaps = (
        sorted(opened.glob("*.mcap"))
        if opened.is_dir()
        else [opened]
        if opened.suffix == ".mcap"
        else []
    )
    salvaged = _salvaged_reader(highlevel, mcaps[0]) if len(mcaps) == 1 else None
    if salvaged is None:
        raise LegFkError(problem)
    return salvaged


def _salvaged_reader(highlevel: ModuleType, mcap: Path) -> tuple[AnyReader, str] | None:
    """A reader of the complete records of a truncated MCAP file (copied to a temporary folder,
    removed when the reader closes), or None.
    """
    folder = Path(tempfile.mkdtemp(prefix="a1_leg_fk_salvage_"))
    try:
        kept = salvage(mcap, folder / mcap.name)
        reader = highlevel.AnyReader([kept.path]) if kept is not None else None
        if reader is not None:
            reader.open()
    except Exception:  # noqa: BLE001 (not even the salvaged part can be read)
        reader = None
    if reader is None or kept is None:
        shutil.rmtree(folder, ignore_errors=True)
        return None
    reader.salvage_folder = folder  # removed by _close_reader
    note = (
        f"{mcap} is truncated or has no readable summary: read its first {kept.kept:,} of "
        f"{kept.size:,} bytes (the complete records)"
    )
    return reader, note


def _storage_file(directory: Path) -> Path:
    """What to open for a bag directory: itself when it has ``metadata.yaml``, else its one
    storage file (``.mcap`` or ``.db3``).
    """
    if (directory / "metadata.yaml").exists():
        return directory
    storage = sorted(child for child in directory.iterdir() if child.suffix in (".db3", ".mcap"))
    if not storage:
        raise LegFkError(
            f"{directory}: a directory without a ROS 2 bag (no metadata.yaml, no .db3 or .mcap file)"
        )
    if len(storage) > 1:
        raise LegFkError(
            f"{directory}: no metadata.yaml and {len(storage)} storage files; give one of them: {', '.join(p.name for p in storage)}"
        )
    return storage[0]


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return text[:300]


def _pick_topic(
    reader: AnyReader, path: Path, wanted: str | None, types: Sequence[str], option: str, what: str
) -> Connection:
    """The connection of ``wanted`` (or the only one of ``types``); errors list the candidates."""
    topics = {connection.topic: connection.msgtype for connection in reader.connections}
    listing = ", ".join(f"{name} ({kind})" for name, kind in sorted(topics.items())) or "none"
    if wanted is not None:
        if wanted not in topics:
            raise LegFkError(f"{option} {wanted}: no such topic in {path}; topics: {listing}")
        if topics[wanted] not in types:
            raise LegFkError(
                f"{option} {wanted} is {topics[wanted]}, expected {' or '.join(types)}"
            )
        chosen = wanted
    else:
        candidates = sorted(name for name, kind in topics.items() if kind in types)
        if not candidates:
            raise LegFkError(f"{path}: no {' or '.join(types)} topic; topics: {listing}")
        if len(candidates) > 1:
            raise LegFkError(
                f"{path}: several {what} topics, choose one with {option}: {', '.join(candidates)}"
            )
        chosen = candidates[0]
    return next(connection for connection in reader.connections if connection.topic == chosen)


def _recorded_description(reader: AnyReader, joint_states: Connection) -> tuple[str | None, str]:
    """The latest ``robot_description`` message before the first JointState, and its topic."""
    connections = [
        c
        for c in reader.connections
        if c.msgtype == DESCRIPTION_TYPE and c.topic.split("/")[-1] == "robot_description"
    ]
    if not connections:
        return None, ""
    latest, topic = None, ""
    for connection, _, raw in reader.messages(connections=[*connections, joint_states]):
        if connection is joint_states:
            break
        message: Any = reader.deserialize(raw, connection.msgtype)  # a std_msgs/msg/String
        latest, topic = message.data, connection.topic
    return latest, topic


# --- base pose ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BasePoses:
    """The base's pose over time: stamps [ns] sorted, positions (M, 3) [m], unit quaternions
    (M, 4) x, y, z, w, in ``world_frame``; interpolated at query stamps (linear / slerp).
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    world_frame: str
    max_gap_ns: int

    @classmethod
    def read(
        cls, reader: AnyReader, connection: Connection, base_frame: str, max_gap_s: float
    ) -> BasePoses:
        """All poses of one topic (deserialized: a pose stream is small next to the joints')."""
        stamps, values, frames = [], [], []
        for _, _, raw in reader.messages(connections=[connection]):
            message = reader.deserialize(raw, connection.msgtype)
            for stamp, frame, pose in _poses_of(
                message, connection.msgtype, base_frame.lstrip("/")
            ):
                stamps.append(stamp)
                frames.append(frame)
                values.append(pose)
        if not stamps:
            raise LegFkError(
                f"--base-pose {connection.topic}: no pose of the base frame '{base_frame}' in it"
            )
        order = np.argsort(np.array(stamps, dtype=np.int64), kind="stable")
        data = np.array(values)[order]
        quaternions = data[:, 3:] / np.linalg.norm(data[:, 3:], axis=1, keepdims=True)
        return cls(
            np.array(stamps, dtype=np.int64)[order],
            data[:, :3],
            quaternions,
            frames[0],
            round(max_gap_s * 1e9),
        )

    def at(self, stamps_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(positions (N, 3) [m], rotation matrices (N, 3, 3)) at ``stamps_ns``; NaN where a stamp
        lies outside the poses' time range or between two poses further apart than the gap.
        """
        stamps = self.stamps_ns
        lower = np.clip(np.searchsorted(stamps, stamps_ns, side="right") - 1, 0, len(stamps) - 1)
        upper = np.minimum(lower + 1, len(stamps) - 1)
        t0, t1 = stamps[lower], stamps[upper]
        exact = t0 == stamps_ns
        span = t1 - t0
        inside = (
            (stamps_ns >= stamps[0])
            & (stamps_ns <= stamps[-1])
            & (exact | (span <= self.max_gap_ns))
        )
        alpha = np.where(exact | (span == 0), 0.0, (stamps_ns - t0) / np.where(span > 0, span, 1))
        position = self.positions[lower] + alpha[:, None] * (
            self.positions[upper] - self.positions[lower]
        )
        quaternion = _slerp(self.quaternions[lower], self.quaternions[upper], alpha)
        rotation = _rotation_matrices(quaternion)
        position[~inside] = math.nan
        rotation[~inside] = math.nan
        return position, rotation


def _poses_of(
    message: Any, msgtype: str, base_frame: str
) -> Iterator[tuple[int, str, list[float]]]:
    """(stamp [ns], parent frame, [x, y, z, qx, qy, qz, qw]) of each base pose in a message."""
    if msgtype == TF_TYPE:
        for transform in message.transforms:
            if transform.child_frame_id.lstrip("/") == base_frame:
                t, r = transform.transform.translation, transform.transform.rotation
                yield (
                    _stamp(transform.header),
                    transform.header.frame_id.lstrip("/"),
                    [t.x, t.y, t.z, r.x, r.y, r.z, r.w],
                )
        return
    pose = message.pose if msgtype == POSE_TYPE else message.pose.pose
    p, r = pose.position, pose.orientation
    yield _stamp(message.header), message.header.frame_id, [p.x, p.y, p.z, r.x, r.y, r.z, r.w]


def _stamp(header: Any) -> int:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _slerp(q0: np.ndarray, q1: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Spherical interpolation between unit quaternions (N, 4), the shorter way round."""
    dot = np.sum(q0 * q1, axis=1)
    q1 = np.where(dot[:, None] < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    close = sin_theta < 1e-9
    safe = np.where(close, 1.0, sin_theta)
    w0 = np.where(close, 1.0 - alpha, np.sin((1.0 - alpha) * theta) / safe)
    w1 = np.where(close, alpha, np.sin(alpha * theta) / safe)
    q = w0[:, None] * q0 + w1[:, None] * q1
    unit: np.ndarray = q / np.linalg.norm(q, axis=1, keepdims=True)
    return unit


def _rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of unit quaternions (N, 4) x, y, z, w."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=1),
        ],
        axis=1,
    )


# --- the pass over the joint states ---------------------------------------------------------------


def iter_foot_blocks(
    recording: Recording,
    *,
    progress: bool = False,
    on_message: Callable[[Connection, int, bytes], None] | None = None,
) -> Iterator[FootBlock]:
    """The feet, block by block, in bag order. ``on_message(connection, bag_time_ns, raw)`` is
    called for every message of every topic (with it, the whole bag is read, e.g. to copy it).

    A truncated or corrupt bag ends the pass early: what was read is yielded, and
    ``recording.stopped`` says where and why.
    """
    reader, joint_states = recording.reader, recording.joint_states
    tracker = recording.tracker = FootTracker(recording.quadruped)
    connections = [] if on_message else [joint_states]
    total = sum(c.msgcount for c in reader.connections) if on_message else joint_states.msgcount
    bar = _progress_bar(total, progress)
    batch = _Batch(recording, tracker, JointStateDecoder(ros1=recording.ros1))
    read = shown = 0
    try:
        for connection, bag_time, raw in _guarded(recording, _raw_messages(reader, connections)):
            read += 1
            if on_message is not None:
                on_message(connection, bag_time, raw)
                if connection is not joint_states:
                    continue
            if batch.raws and (len(raw) != batch.length or len(batch.raws) >= BLOCK_MESSAGES):
                if bar is not None:
                    bar.update(read - shown)
                    shown = read
                yield from batch.blocks()
            batch.add(raw, bag_time)
        yield from batch.blocks()
    except _Corrupt as error:
        recording.stopped = str(error)
    finally:
        if bar is not None:
            bar.update(read - shown)
            bar.close()


def _raw_messages(
    reader: AnyReader, connections: list[Connection]
) -> Iterator[tuple[Connection, int, bytes]]:
    """(connection, bag time [ns], raw bytes) in bag order; a single bag's reader directly (no
    merge of several).
    """
    if len(reader.readers) == 1:
        return reader.readers[0].messages(connections=connections)
    return reader.messages(connections=connections)


def _guarded(
    recording: Recording, messages: Iterator[tuple[Connection, int, bytes]]
) -> Iterator[tuple[Connection, int, bytes]]:
    """``messages`` until the storage cannot be read further (truncated, corrupt): then
    ``recording.stopped`` says where and why, and the iteration ends.
    """
    bag_time = None
    try:
        for item in messages:
            bag_time = item[1]
            yield item
    except Exception as error:  # noqa: BLE001 (rosbags raises several kinds for broken storage)
        recording.stopped = f"cannot read past bag time {bag_time} ns: {_one_line(error)}"


class _Corrupt(Exception):
    """A JointState message that cannot be decoded; the pass stops there."""


class _Batch:
    """Consecutive JointState messages of one length, as raw bytes. A steady stream (same name
    list, lengths and layout, little-endian CDR) is decoded with numpy for the whole batch;
    anything else message by message.
    """

    def __init__(
        self, recording: Recording, tracker: FootTracker, decoder: JointStateDecoder
    ) -> None:
        self.recording, self.tracker, self.decoder = recording, tracker, decoder
        self.raws: list[bytes] = []
        self.bag_times: list[int] = []
        self.length = -1

    def add(self, raw: bytes, bag_time: int) -> None:
        if not self.raws:
            self.length = len(raw)
        self.raws.append(raw)
        self.bag_times.append(bag_time)

    def blocks(self) -> Iterator[FootBlock]:
        """The rows of the batch's messages; empties the batch. :class:`_Corrupt` after the rows
        before a message that cannot be decoded.
        """
        raws, bag_times = self.raws, self.bag_times
        self.raws, self.bag_times = [], []
        if not raws:
            return
        arrays = None if self.recording.ros1 else self._vectorised(raws, bag_times)
        if arrays is not None:
            yield from _finish(self.recording, self.tracker, self.decoder.names, *arrays)
            return
        yield from self._one_by_one(raws, bag_times)

    def _vectorised(
        self, raws: list[bytes], bag_times: list[int]
    ) -> tuple[np.ndarray, ...] | None:
        layout = cdr_layout(bytes(raws[0]))
        if layout is None:
            return None
        matrix = np.frombuffer(b"".join(raws), dtype=np.uint8).reshape(len(raws), self.length)
        template = matrix[0, layout.fixed]
        if not (matrix[:, layout.fixed] == template).all():
            return None
        self.decoder.fields(raws[0])  # the names, for the rules (and the next message's check)
        stamps = (
            np.ascontiguousarray(matrix[:, 4:8]).view("<i4")[:, 0].astype(np.int64) * 1_000_000_000
            + np.ascontiguousarray(matrix[:, 8:12]).view("<u4")[:, 0]
        )
        bag_times_ns = np.array(bag_times, dtype=np.int64)
        stamps = np.where(stamps == 0, bag_times_ns, stamps)
        positions = np.ascontiguousarray(matrix[:, layout.positions]).view("<f8")
        velocities = np.ascontiguousarray(matrix[:, layout.velocities]).view("<f8")
        return stamps, bag_times_ns, positions, velocities

    def _one_by_one(self, raws: list[bytes], bag_times: list[int]) -> Iterator[FootBlock]:
        fields = self.decoder.fields
        pending = _Pending()
        for raw, bag_time in zip(raws, bag_times):
            try:
                stamp, changed, order, positions, velocities = fields(raw)
            except WireError as error:
                yield from pending.finish(self)
                raise _Corrupt(f"JointState at bag time {bag_time} ns: {error}") from None
            if pending.count and (
                changed
                or order != pending.order
                or len(positions) != pending.position_bytes
                or len(velocities) != pending.velocity_bytes
            ):
                yield from pending.finish(self)
                pending = _Pending()
            if not pending.count:
                pending.start(self.decoder.names, order, len(positions), len(velocities))
            pending.count += 1
            pending.stamps.append(stamp or bag_time)
            pending.bag_times.append(bag_time)
            pending.positions.append(positions)
            pending.velocities.append(velocities)
        yield from pending.finish(self)


class _Pending:
    """Consecutive messages with one name list and the same array lengths, kept as bytes."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.order = "<"
        self.position_bytes = self.velocity_bytes = 0
        self.count = 0
        self.stamps: list[int] = []
        self.bag_times: list[int] = []
        self.positions: list[bytes] = []
        self.velocities: list[bytes] = []

    def start(
        self, names: list[str], order: str, position_bytes: int, velocity_bytes: int
    ) -> None:
        self.names, self.order = names, order
        self.position_bytes, self.velocity_bytes = position_bytes, velocity_bytes

    def finish(self, batch: _Batch) -> Iterator[FootBlock]:
        """The rows of these messages (none if there are none)."""
        if not self.count:
            return
        dtype = np.dtype(f"{self.order}f8")
        positions = np.frombuffer(b"".join(self.positions), dtype).reshape(
            self.count, self.position_bytes // 8
        )
        velocities = np.frombuffer(b"".join(self.velocities), dtype).reshape(
            self.count, self.velocity_bytes // 8
        )
        yield from _finish(
            batch.recording,
            batch.tracker,
            self.names,
            np.array(self.stamps, dtype=np.int64),
            np.array(self.bag_times, dtype=np.int64),
            positions.astype(np.float64),
            velocities.astype(np.float64),
        )


def _finish(
    recording: Recording,
    tracker: FootTracker,
    names: list[str],
    stamps: np.ndarray,
    bag_times: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
) -> Iterator[FootBlock]:
    """Run the rules over consecutive messages with one name list and yield their rows (if any).
    ``positions`` [rad] (K, n), ``velocities`` [rad/s] (K, n or 0 or another length).
    """
    result = tracker.update_block(names, positions, velocities)
    angles = result.angles[result.accepted]
    feet = feet_of(recording.quadruped, angles)
    rows = ~np.isnan(feet).all(axis=(1, 2))
    if not rows.any():
        return
    feet = feet[rows]
    rates = result.rates[result.accepted][rows]
    foot_velocities = velocities_of(recording.quadruped, angles[rows], rates)
    recording.has_velocities = recording.has_velocities or bool(np.isfinite(foot_velocities).any())
    stamps = stamps[result.accepted][rows]
    bag_times = bag_times[result.accepted][rows]
    world = None
    if recording.base_pose is not None:
        origin, rotation = recording.base_pose.at(stamps)
        world = origin[:, None, :] + np.einsum("nij,nlj->nli", rotation, feet)
    yield FootBlock(stamps, bag_times, feet, foot_velocities, world)


def feet_of(quadruped: Quadruped, angles: np.ndarray) -> np.ndarray:
    """(N, 4, 3) feet [m], base frame, for (N, 12) angles [rad]; NaN for legs with a NaN angle."""
    out = np.empty((angles.shape[0], LEGS, 3))
    cos, sin = np.cos(angles), np.sin(angles)
    for leg_slot, leg in enumerate(quadruped.legs):
        columns = slice(leg_slot * JOINTS_PER_LEG, (leg_slot + 1) * JOINTS_PER_LEG)
        trig = [value for pair in zip(cos[:, columns].T, sin[:, columns].T) for value in pair]
        x, y, z = leg.position_from_trig(*trig)
        out[:, leg_slot, 0], out[:, leg_slot, 1], out[:, leg_slot, 2] = x, y, z
    return out


def velocities_of(quadruped: Quadruped, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """(N, 4, 3) J(q)·q̇ [m/s], base frame; NaN for legs whose angles or rates are not all finite."""
    out = np.full((angles.shape[0], LEGS, 3), math.nan)
    usable = np.isfinite(rates).reshape(-1, LEGS, JOINTS_PER_LEG).all(axis=2) & np.isfinite(
        angles
    ).reshape(-1, LEGS, JOINTS_PER_LEG).all(axis=2)
    rows = usable.any(axis=1)
    if rows.any():
        jacobians = quadruped.jacobians_batch(np.nan_to_num(angles[rows]))
        velocity = np.einsum(
            "nlij,nlj->nli",
            jacobians,
            np.nan_to_num(rates[rows]).reshape(-1, LEGS, JOINTS_PER_LEG),
        )
        with np.errstate(invalid="ignore"):
            velocity[~usable[rows] | ~np.isfinite(velocity).all(axis=2)] = math.nan
        out[rows] = velocity
    return out


def _progress_bar(total: int, enabled: bool) -> tqdm[None] | None:
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, unit="msg", unit_scale=True, mininterval=0.5, smoothing=0.1)


def summary_of(
    recording: Recording,
    rows: int,
    rows_without_pose: int,
    first: int | None,
    last: int | None,
    wall_time_s: float,
) -> RecordingSummary:
    """The summary of a finished pass."""
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
        rows,
        rows_without_pose,
        first,
        last,
        wall_time_s,
        "; ".join(part for part in (recording.salvage_note, recording.stopped) if part),
    )


class BlockStats:
    """Counts rows, rows without a pose and the stamp range over a pass (for the summary)."""

    def __init__(self) -> None:
        self.rows = 0
        self.rows_without_pose = 0
        self.first: int | None = None
        self.last: int | None = None
        self.started = time.perf_counter()

    def add(self, block: FootBlock) -> None:
        if not len(block.stamps_ns):
            return
        self.rows += len(block.stamps_ns)
        if block.world_positions is not None:
            self.rows_without_pose += int(np.isnan(block.world_positions).all(axis=(1, 2)).sum())
        low, high = int(block.stamps_ns.min()), int(block.stamps_ns.max())
        self.first = low if self.first is None else min(self.first, low)
        self.last = high if self.last is None else max(self.last, high)

    def summary(self, recording: Recording) -> RecordingSummary:
        return summary_of(
            recording,
            self.rows,
            self.rows_without_pose,
            self.first,
            self.last,
            time.perf_counter() - self.started,
        )


# --- the notebook API -----------------------------------------------------------------------------


def read_foot_trajectories(
    path: str | Path,
    *,
    topic: str | None = None,
    urdf: str | Path | None = None,
    foot_links: Sequence[str] = (),
    joint_aliases: Sequence[str] = (),
    base_pose: str | None = None,
    max_pose_gap_s: float = DEFAULT_MAX_POSE_GAP_S,
    progress: bool = False,
) -> FootTrajectories:
    """The four feet over a recorded run, as arrays (one row per accepted JointState message
    that leaves at least one leg known, in bag order).

    ``path``: a ROS 2 bag directory, a ``.mcap`` file or a ROS 1 ``.bag``. ``topic``: the
    JointState topic (needed when there are several). Model: ``urdf`` (a path), else the bag's
    ``robot_description`` topic (the latest message before the first JointState), else the
    embedded A1; ``foot_links``/``joint_aliases`` as the node's parameters (``"KEY=value"``).
    ``base_pose``: an Odometry / PoseStamped / PoseWithCovarianceStamped / TFMessage topic that
    gives the base's pose in a world frame, interpolated at each JointState stamp (NaN where the
    stamp is outside the poses' range or in a gap longer than ``max_pose_gap_s`` [s]).
    Raises :class:`LegFkError` for bad input; a bag that cannot be read to its end gives what was
    read, with ``summary.stopped`` saying why.
    """
    recording = open_recording(
        path,
        topic=topic,
        urdf=urdf,
        foot_links=foot_links,
        joint_aliases=joint_aliases,
        base_pose=base_pose,
        max_pose_gap_s=max_pose_gap_s,
    )
    try:
        stats = BlockStats()
        blocks = []
        for block in iter_foot_blocks(recording, progress=progress):
            stats.add(block)
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
    )


__all__ = [
    "BasePoses",
    "FootBlock",
    "FootTrajectories",
    "RecordingSummary",
    "close_recording",
    "collected",
    "iter_foot_blocks",
    "open_recording",
    "read_foot_trajectories",
]
