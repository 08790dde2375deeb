"""Opening a recording: the bag (a ROS 2 directory, ``.mcap``, ``.db3`` or ROS 1 ``.bag``, a
truncated MCAP file from a copy of its complete records), the JointState topic, the robot model
(``--urdf``, else the bag's ``robot_description``, else the embedded A1) and the base pose
(:mod:`a1_leg_fk.recording.base_pose`). Every read of its messages goes through its
:class:`~a1_leg_fk.recording.reads.RecordingReads` (damage ends the reads, it never raises out of
the reader). No ROS install: ``rosbags`` is imported when a bag is opened.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, TypedDict

from a1_leg_fk.estimation.contact_estimator import DYNAMIC, FILTER
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.estimation.sensor_contacts import DEFAULT_SENSOR_THRESHOLD_COUNTS
from a1_leg_fk.kinematics.robot_config import load_robot
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.base_pose import BASE_POSE_TYPES, DEFAULT_MAX_POSE_GAP_S, BasePoses
from a1_leg_fk.recording.lowstate import LOWSTATE_TYPES, LowStateInput, refuse_humanoid
from a1_leg_fk.recording.mcap_salvage import salvage
from a1_leg_fk.recording.reads import RecordingReads
from a1_leg_fk.recording.sport_feet import SportFeet
from a1_leg_fk.recording.typestores import CannotOpen, open_reader, require_types

if TYPE_CHECKING:  # rosbags is imported when a bag is opened
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

    from a1_leg_fk.kinematics.quadruped import Quadruped
    from a1_leg_fk.recording.forces import RecordingForces
    from a1_leg_fk.tracking import FootTracker

ROSBAGS_HINT = "reading ROS bags needs rosbags: pip install rosbags"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
DESCRIPTION_TYPE = "std_msgs/msg/String"


class RecordingChoices(TypedDict, total=False):
    """The choices of :func:`open_recording` (its keyword arguments)."""

    topic: str | None
    urdf: str | Path | None
    foot_links: Sequence[str]
    joint_aliases: Sequence[str]
    base_pose: str | None
    max_pose_gap_s: float
    forces: bool
    estimate_contacts: bool
    imu: str | None
    contact_thresholds: tuple[float | None, float | None]
    force_model: str
    contact_rule: str
    model_corrections: str
    sensor_threshold: float
    causal: bool


@dataclass
class Recording:
    """An open bag with the choices made for it; iterate with
    :func:`~a1_leg_fk.recording.blocks.iter_foot_blocks`.
    """

    reader: AnyReader  # open
    path: Path
    joint_states: Connection
    quadruped: Quadruped
    model_source: str
    base_pose: BasePoses | None
    base_pose_topic: str | None
    ros1: bool
    reads: RecordingReads  # every read of the bag's messages, and the damage found
    types: str = ""  # which message types the bag is read with (recording.typestores)
    has_velocities: bool = False  # set while reading: some row had a finite foot velocity
    salvage_note: str = ""  # what was read of a truncated MCAP file
    tracker: FootTracker | None = None  # the rules' state and counts of the current pass
    forces: RecordingForces | None = None  # foot forces and contacts, when asked for
    force_output: bool = False  # the forces are wanted in the outputs (bag --forces)
    efforts: bool = False  # the blocks carry the merged joint efforts (the odometry's contacts)
    lowstate: LowStateInput | None = None  # the joint states are a Unitree LowState's motors
    sensor_threshold: float = DEFAULT_SENSOR_THRESHOLD_COUNTS  # [counts] a LowState foot sensor's
    sport: SportFeet | None = None  # a LowState robot's own feet (SportModeState), if recorded
    urdf_xml: str = ""  # the URDF text the model was read from

    @property
    def stopped(self) -> str:
        """Why reading stopped before the end of the bag (its damage); "" if it did not."""
        return self.reads.damage


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
    forces: bool = False,
    estimate_contacts: bool = False,
    imu: str | None = None,
    contact_thresholds: tuple[float | None, float | None] = (None, None),
    force_model: str = DYNAMIC,
    contact_rule: str = FILTER,
    model_corrections: str = DEFAULT_MODEL_CORRECTIONS,
    sensor_threshold: float = DEFAULT_SENSOR_THRESHOLD_COUNTS,
    causal: bool = False,
) -> Recording:
    """Open a bag and make the choices (topic, model, base pose); :class:`LegFkError` naming the
    problem for bad input. Close with :func:`close_recording`. ``forces``: foot forces and
    contacts from the efforts (:mod:`a1_leg_fk.recording.forces`; the JointStates must carry
    efforts); ``estimate_contacts``: contacts with or without efforts; the IMU from the
    ``sensor_msgs/msg/Imu`` topic ``imu`` if given; ``force_model``, ``contact_rule``,
    ``model_corrections`` and ``contact_thresholds`` (the threshold rule's touchdown and liftoff
    forces [N], ``None``: the defaults for the robot's weight) as
    :class:`~a1_leg_fk.recording.forces.RecordingForces` takes them; ``sensor_threshold``
    [counts]: a LowState's foot sensor above it is in contact; ``causal``: the filter's contacts
    as the node has them, else smoothed over the recording.
    """
    path = Path(path)
    reader, salvage_note, types = _open_reader(path)
    reads = RecordingReads(reader, path)
    try:
        joint_states = pick_input(reader, path, topic)
        lowstate = (
            LowStateInput.open(reads, joint_states)
            if joint_states.msgtype in LOWSTATE_TYPES
            else None
        )
        if lowstate is not None and imu:
            raise LegFkError(f"--imu: {joint_states.topic} is a LowState, which carries its IMU")
        if not urdf:
            require_types(reader, path, _description_types(reader), types)
        description, description_topic = (
            (None, "") if urdf else _recorded_description(reads, joint_states)
        )
        # an empty recorded description counts as none (as in the node): the embedded A1
        name = f"robot_description topic {description_topic} in {path}"
        robot = load_robot(
            description or "",
            str(urdf) if urdf else "",
            foot_links,
            joint_aliases,
            description_name=name,
        )
        if urdf:
            source = f"--urdf {urdf}"
        elif description:
            source = name
        else:
            source = f"embedded A1 ({robot.source})"
        poses = None
        if base_pose:
            pose_connection = pick_topic(
                reader, path, base_pose, BASE_POSE_TYPES, "--base-pose", "base pose"
            )
            require_types(
                reader, path, {pose_connection.msgtype: f"--base-pose {base_pose}"}, types
            )
            poses = BasePoses.read(
                reads, pose_connection, robot.quadruped.base_frame, max_pose_gap_s
            )
        force_pass = (
            _force_pass(
                reads,
                (joint_states, imu, lowstate),
                robot.quadruped,
                forces,
                (contact_thresholds, force_model, contact_rule, model_corrections, causal),
            )
            if forces or estimate_contacts
            else None
        )
        return Recording(
            reader,
            path,
            joint_states,
            robot.quadruped,
            source,
            poses,
            base_pose,
            not reader.is2,
            reads,
            types,
            salvage_note=salvage_note,
            forces=force_pass,
            force_output=forces,
            lowstate=lowstate,
            sensor_threshold=sensor_threshold,
            sport=SportFeet.read(reads) if lowstate is not None else None,
            urdf_xml=robot.urdf_xml,
        )
    except BaseException:
        _close_reader(reader)
        raise


def _force_pass(
    reads: RecordingReads,
    where: tuple[Connection, str | None, LowStateInput | None],
    quadruped: Quadruped,
    needs_efforts: bool,
    settings: tuple[tuple[float | None, float | None], str, str, str, bool],
) -> RecordingForces:
    """The force and contact estimation of a pass over the JointStates of ``where`` (their
    connection, the IMU topic or None, the LowState input or None: its IMU is the IMU);
    :class:`LegFkError` if the JointStates carry no
    efforts while ``needs_efforts``, or the IMU topic gives no orientation. ``settings``: the
    contact thresholds, the force model, the contact rule, the model corrections and whether
    causal (else smoothed).
    """
    from a1_leg_fk.recording.forces import IMU_TYPE, ImuTrack, RecordingForces, check_has_efforts

    joint_states, imu, lowstate = where
    if needs_efforts and lowstate is None:  # a LowState always carries its motors' torques
        needs = "the force estimate (bag --forces, gait --contacts force)"
        check_has_efforts(reads, joint_states, not reads.reader.is2, needs)
    track = lowstate.imu_track(reads) if lowstate is not None else None
    if imu:
        connection = pick_topic(reads.reader, reads.path, imu, (IMU_TYPE,), "--imu", "IMU")
        track = ImuTrack.read(reads, connection)
    thresholds, force_model, contact_rule, corrections, causal = settings
    forces = RecordingForces(quadruped, track, thresholds, force_model, contact_rule, corrections)
    forces.smoothed = not causal and contact_rule == FILTER
    return forces


def close_recording(recording: Recording) -> None:
    """Close the bag (and remove the copy of a salvaged one)."""
    _close_reader(recording.reader)


def _close_reader(reader: AnyReader) -> None:
    reader.close()
    folder = getattr(reader, "salvage_folder", None)
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)


def _open_reader(path: Path) -> tuple[AnyReader, str, str]:
    """An open reader of the bag at ``path``, ``""`` or a note on what was salvaged of a
    truncated MCAP file (read from a copy of its complete records), and which types it is read
    with (:mod:`a1_leg_fk.recording.typestores`).
    """
    _rosbags()
    if not path.exists():
        raise LegFkError(f"{path}: no such file or directory")
    opened = _storage_file(path) if path.is_dir() else path
    try:
        reader, types = open_reader(opened)
        return reader, "", types
    except CannotOpen as error:
        problem = f"{path}: cannot open as a ROS bag: {error}"
    mcaps = (
        sorted(opened.glob("*.mcap"))
        if opened.is_dir()
        else [opened]
        if opened.suffix == ".mcap"
        else []
    )
    salvaged = _salvaged_reader(mcaps[0]) if len(mcaps) == 1 else None
    if salvaged is None:
        raise LegFkError(problem)
    return salvaged


def _salvaged_reader(mcap: Path) -> tuple[AnyReader, str, str] | None:
    """A reader of the complete records of a truncated MCAP file (copied to a temporary folder,
    removed when the reader closes), its note and types (as :func:`_open_reader`), or None.
    """
    folder = Path(tempfile.mkdtemp(prefix="a1_leg_fk_salvage_"))
    try:
        kept = salvage(mcap, folder / mcap.name)
        reader, types = open_reader(kept.path) if kept is not None else (None, "")
    except CannotOpen:  # not even the salvaged part can be read
        reader = None
    if reader is None or kept is None:
        shutil.rmtree(folder, ignore_errors=True)
        return None
    reader.salvage_folder = folder  # type: ignore[attr-defined]  # removed by _close_reader
    note = (
        f"{mcap} is truncated or has no readable summary: read its first {kept.kept:,} of "
        f"{kept.size:,} bytes (the complete records)"
    )
    return reader, note, types


def _storage_file(directory: Path) -> Path:
    """What to open for a bag directory: itself when it has ``metadata.yaml``, else its one
    storage file (``.mcap`` or ``.db3``).
    """
    if (directory / "metadata.yaml").exists():
        return directory
    storage = sorted(child for child in directory.iterdir() if child.suffix in (".db3", ".mcap"))
    if not storage:
        raise LegFkError(
            f"{directory}: a directory without a ROS 2 bag (no metadata.yaml, no .db3 or .mcap "
            "file)"
        )
    if len(storage) > 1:
        raise LegFkError(
            f"{directory}: no metadata.yaml and {len(storage)} storage files; give one of them: "
            f"{', '.join(p.name for p in storage)}"
        )
    return storage[0]


def pick_topic(
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


def pick_input(reader: AnyReader, path: Path, wanted: str | None) -> Connection:
    """The joint states' topic: ``wanted`` (a JointState or a Unitree LowState), else the only
    JointState topic, else (a bag without one) the only LowState topic. A humanoid's LowState is
    refused by name.
    """
    kinds = (JOINT_STATE_TYPE, *LOWSTATE_TYPES)
    refuse_humanoid(reader, wanted, kinds)
    if wanted is None:
        joint_states = any(c.msgtype == JOINT_STATE_TYPE for c in reader.connections)
        if not joint_states and any(c.msgtype in LOWSTATE_TYPES for c in reader.connections):
            return pick_topic(reader, path, None, LOWSTATE_TYPES, "--topic", "LowState")
        kinds = (JOINT_STATE_TYPE,)
    return pick_topic(reader, path, wanted, kinds, "--topic", "JointState")


def _description_connections(reader: AnyReader) -> list[Connection]:
    """The bag's ``robot_description`` topics (``std_msgs/msg/String``, any namespace)."""
    return [
        c
        for c in reader.connections
        if c.msgtype == DESCRIPTION_TYPE and c.topic.split("/")[-1] == "robot_description"
    ]


def _description_types(reader: AnyReader) -> dict[str, str]:
    """The type a recorded robot description needs (none without one), for require_types."""
    topics = [c.topic for c in _description_connections(reader)]
    return {DESCRIPTION_TYPE: f"robot_description topic {topics[0]}"} if topics else {}


def _recorded_description(
    reads: RecordingReads, joint_states: Connection
) -> tuple[str | None, str]:
    """The latest ``robot_description`` message before the first JointState, and its topic."""
    connections = _description_connections(reads.reader)
    if not connections:
        return None, ""
    latest, topic = None, ""
    messages = reads.messages([*connections, joint_states])
    for index, (connection, bag_time, raw) in enumerate(messages, 1):
        if connection is joint_states:
            break
        message = reads.deserialize(connection, bag_time, index, raw)  # a std_msgs/msg/String
        if message is None:
            break
        latest, topic = message.data, connection.topic
    messages.close()
    return latest, topic
