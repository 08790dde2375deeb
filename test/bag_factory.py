"""Bags for the tests, written with rosbags: ROS 2 (sqlite3 or MCAP) and ROS 1, with JointState
messages given as plain tuples, and any other typed messages. Also bags as older recorders wrote
them: rosbag2 of Humble and Foxy (sqlite3, metadata version 5 / 4, no message definitions; written
here with sqlite3, as rosbags' writer writes versions 8 and 9 only) and ROS 1 bags whose
definitions use ``roslib/Header``."""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Sequence
from contextlib import closing
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
ROS1_TYPESTORE = get_typestore(Stores.ROS1_NOETIC)
T = TYPESTORE.types
T0 = 1_700_000_000_000_000_000
"""The tests' first stamp [ns] (November 2023)."""


@dataclass
class JointStateMsg:
    """One JointState: stamp [ns] (0 = unset), names, positions, velocities and efforts (may be
    empty)."""

    stamp_ns: int
    names: Sequence[str]
    positions: Sequence[float]
    velocities: Sequence[float] = ()
    frame_id: str = ""
    efforts: Sequence[float] = ()


def joint_state(message: JointStateMsg):
    return T["sensor_msgs/msg/JointState"](
        header(message.stamp_ns, message.frame_id),
        list(message.names),
        np.array(message.positions, dtype=float),
        np.array(message.velocities, dtype=float),
        np.array(message.efforts, dtype=float),
    )


def header(stamp_ns: int, frame: str):
    return T["std_msgs/msg/Header"](
        T["builtin_interfaces/msg/Time"](*divmod(stamp_ns, 1_000_000_000)), frame
    )


def pose(position: Sequence[float], xyzw: Sequence[float]):
    """A ``geometry_msgs/msg/Pose``: position [m] and orientation quaternion (x, y, z, w)."""
    return T["geometry_msgs/msg/Pose"](
        T["geometry_msgs/msg/Point"](*position), T["geometry_msgs/msg/Quaternion"](*xyzw)
    )


def rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def pose_message(kind: str, stamp: int, position: list[float], yaw: float):
    """A base pose of ``kind`` in frame ``odom`` (a rotation about z by ``yaw``)."""
    base = pose(position, (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)))
    covariance = np.zeros(36)
    if kind == "nav_msgs/msg/Odometry":
        twist = T["geometry_msgs/msg/TwistWithCovariance"](
            T["geometry_msgs/msg/Twist"](
                T["geometry_msgs/msg/Vector3"](0, 0, 0), T["geometry_msgs/msg/Vector3"](0, 0, 0)
            ),
            covariance,
        )
        return T[kind](
            header(stamp, "odom"),
            "trunk",
            T["geometry_msgs/msg/PoseWithCovariance"](base, covariance),
            twist,
        )
    if kind == "geometry_msgs/msg/PoseStamped":
        return T[kind](header(stamp, "odom"), base)
    if kind == "geometry_msgs/msg/PoseWithCovarianceStamped":
        return T[kind](
            header(stamp, "odom"), T["geometry_msgs/msg/PoseWithCovariance"](base, covariance)
        )
    transform = T["geometry_msgs/msg/Transform"](
        T["geometry_msgs/msg/Vector3"](*position), base.orientation
    )
    other = T["geometry_msgs/msg/TransformStamped"](header(stamp, "trunk"), "FR_hip", transform)
    mine = T["geometry_msgs/msg/TransformStamped"](header(stamp, "/odom"), "/trunk", transform)
    return T[kind]([other, mine])


@dataclass
class BagSpec:
    """Messages to write: (topic, msgtype, bag time [ns], message object) in any order."""

    entries: list[tuple[str, str, int, object]] = field(default_factory=list)

    def add(self, topic: str, msgtype: str, bag_time_ns: int, message: object) -> None:
        self.entries.append((topic, msgtype, bag_time_ns, message))

    def add_joint_state(self, topic: str, bag_time_ns: int, message: JointStateMsg) -> None:
        self.add(topic, "sensor_msgs/msg/JointState", bag_time_ns, joint_state(message))


def write_bag(path: Path, spec: BagSpec, kind: str = "mcap") -> Path:
    """Write ``spec`` as ``kind``: "mcap" or "sqlite3" (a ROS 2 bag directory; a message given
    as ``bytes`` is written as it is), "humble" or "foxy"
    (a ROS 2 bag directory as those distros' rosbag2 wrote it), "ros1" or "ros1-roslib" (.bag,
    the latter with ``roslib/Header`` in its definitions), "mcap-zstd" (a directory with one
    ``.mcap`` file of zstd chunks, see :func:`write_chunked_mcap`).
    """
    entries = sorted(spec.entries, key=lambda entry: entry[2])
    if kind == "mcap-zstd":
        return write_chunked_mcap(path, entries)
    if kind in PRE_IRON:
        return write_pre_iron_bag(path, entries, kind)
    if kind in ("ros1", "ros1-roslib"):
        with Writer1(path) as writer:
            connections = {}
            for topic, msgtype, stamp, message in entries:
                if topic not in connections:
                    text, md5 = ROS1_TYPESTORE.generate_msgdef(msgtype)
                    connections[topic] = writer.add_connection(
                        topic,
                        msgtype,
                        msgdef=roslib_header(text) if kind == "ros1-roslib" else text,
                        md5sum=md5,
                    )
                ros2 = TYPESTORE.serialize_cdr(message, msgtype)
                writer.write(connections[topic], stamp, TYPESTORE.cdr_to_ros1(ros2, msgtype))
        return path
    plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    with Writer2(path, version=9, storage_plugin=plugin) as writer:
        connections = {}
        for topic, msgtype, stamp, message in entries:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
            data = (  # bytes are written as given (a damaged message's)
                message
                if isinstance(message, bytes)
                else TYPESTORE.serialize_cdr(message, msgtype)
            )
            writer.write(connections[topic], stamp, data)
    return path


def write_chunked_mcap(
    path: Path, entries: list[tuple[str, str, int, object]], chunk_bytes: int = 16384
) -> Path:
    """A directory holding one ``.mcap`` file (no ``metadata.yaml``) written by the format's
    reference library as rosbag2's MCAP plugin records: ``ros2msg`` schemas, CDR messages,
    zstd-compressed chunks (here small, ``chunk_bytes``, so that a short recording has many),
    message indexes and a summary."""
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter

    path.mkdir()
    channels: dict[str, int] = {}
    with (path / f"{path.name}.mcap").open("wb") as stream:
        writer = McapWriter(stream, chunk_size=chunk_bytes, compression=CompressionType.ZSTD)
        writer.start(profile="ros2", library="bag_factory")
        for topic, msgtype, stamp, message in entries:
            if topic not in channels:
                definition, _ = TYPESTORE.generate_msgdef(msgtype, ros_version=2)
                schema = writer.register_schema(msgtype, "ros2msg", definition.encode())
                channels[topic] = writer.register_channel(topic, "cdr", schema)
            data = bytes(TYPESTORE.serialize_cdr(message, msgtype))
            writer.add_message(channels[topic], stamp, data, stamp)
        writer.finish()
    return path


# --- bags as older recorders wrote them ----------------------------------------------------------

OLD_HEADER = """MSG: roslib/Header
# metadata of stamped data, as the first ROS releases defined it
# consecutively increasing id
uint32 seq
# seconds and nanoseconds since the epoch
time stamp
# the data's frame
string frame_id
"""


def roslib_header(definition: str) -> str:
    """A ROS 1 definition as the first ROS releases wrote it: the header field spelled
    ``Header``, the header's own definition as ``roslib/Header`` (the same three fields)."""
    section = "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
    return definition.replace("std_msgs/Header header", "Header header").replace(
        section, OLD_HEADER
    )


def pre_iron_qos(durability: int, lease_sec: int, lease_nsec: int) -> str:
    """One offered QoS profile in rosbag2's pre-Iron YAML text (metadata.yaml and the topics
    table): reliable, keep last; Humble writes infinite durations as (9223372036, 854775807),
    Foxy wrote (0, 0)."""
    time = f"\n    sec: {lease_sec}\n    nsec: {lease_nsec}"
    return (
        f"- history: 3\n  depth: 0\n  reliability: 1\n  durability: {durability}\n"
        f"  deadline:{time}\n  lifespan:{time}\n  liveliness: 1\n"
        f"  liveliness_lease_duration:{time}\n  avoid_ros_namespace_conventions: false"
    )


PRE_IRON = {
    # kind: (metadata version, schema table's ros_distro or None, infinite QoS duration)
    "humble": (5, "humble", (9223372036, 854775807)),
    "foxy": (4, None, (0, 0)),
}


def write_pre_iron_bag(path: Path, entries: list[tuple[str, str, int, object]], kind: str) -> Path:
    """A rosbag2 directory as Humble (0.15.4 on) or Foxy recorded it: one sqlite3 file without
    message definitions (Humble: with its ``schema`` table, schema version 3, and an empty
    ``metadata`` table), and ``metadata.yaml`` of version 5 or 4 without ``ros_distro`` or type
    hashes. Messages may be typed objects or raw CDR bytes (a type nobody can define)."""
    version, distro, infinite = PRE_IRON[kind]
    path.mkdir()
    storage = f"{path.name}_0.db3"
    tables = """
        CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
            serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
        CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
            timestamp INTEGER NOT NULL, data BLOB NOT NULL);
        CREATE INDEX timestamp_idx ON messages (timestamp ASC);
    """
    if distro:
        tables += f"""
            CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
            CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,
                metadata TEXT NOT NULL);
            INSERT INTO schema(schema_version, ros_distro) VALUES (3, '{distro}');
        """
    topics: dict[str, tuple[int, str, str]] = {}  # name -> (id, type, QoS)
    counts: dict[str, int] = {}
    with closing(sqlite3.connect(path / storage)) as db, db:
        db.executescript(tables)
        for topic, msgtype, stamp, message in entries:
            if topic not in topics:
                # latched like a robot_description publisher, else volatile
                durability = 1 if topic.endswith("robot_description") else 2
                topics[topic] = (len(topics) + 1, msgtype, pre_iron_qos(durability, *infinite))
                db.execute(
                    "INSERT INTO topics VALUES (?, ?, ?, 'cdr', ?)",
                    (topics[topic][0], topic, msgtype, topics[topic][2]),
                )
            raw = isinstance(message, bytes)
            data = message if raw else TYPESTORE.serialize_cdr(message, msgtype)
            db.execute(
                "INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)",
                (topics[topic][0], stamp, data),
            )
            counts[topic] = counts.get(topic, 0) + 1
    (path / "metadata.yaml").write_text(
        pre_iron_metadata(version, storage, [e[2] for e in entries], topics, counts)
    )
    return path


def pre_iron_metadata(
    version: int,
    storage: str,
    stamps: list[int],
    topics: dict[str, tuple[int, str, str]],
    counts: dict[str, int],
) -> str:
    """``metadata.yaml`` with the keys, their order and the QoS text of rosbag2's version 5
    (Humble) or 4 (Foxy) writer."""
    start, duration = (min(stamps), max(stamps) - min(stamps)) if stamps else (0, 0)
    listing = "".join(
        f"    - topic_metadata:\n        name: {topic}\n        type: {msgtype}\n"
        f"        serialization_format: cdr\n        offered_qos_profiles: {json.dumps(qos)}\n"
        f"      message_count: {counts.get(topic, 0)}\n"
        for topic, (_, msgtype, qos) in topics.items()
    )
    files = f"  relative_file_paths:\n    - {storage}\n"
    times = (
        f"  duration:\n    nanoseconds: {duration}\n"
        f"  starting_time:\n    nanoseconds_since_epoch: {start}\n"
        f"  message_count: {len(stamps)}\n"
    )
    text = f"rosbag2_bagfile_information:\n  version: {version}\n  storage_identifier: sqlite3\n"
    compression = '  compression_format: ""\n  compression_mode: ""\n'
    if version == 4:
        return text + files + times + "  topics_with_message_count:\n" + listing + compression
    per_file = (
        f"  files:\n    - path: {storage}\n      starting_time:\n"
        f"        nanoseconds_since_epoch: {start}\n      duration:\n"
        f"        nanoseconds: {duration}\n      message_count: {len(stamps)}\n"
    )
    return (
        text + times + "  topics_with_message_count:\n" + listing + compression + files + per_file
    )
