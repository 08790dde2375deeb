"""Bags for the tests, written with rosbags: ROS 2 (sqlite3 or MCAP) and ROS 1, with JointState
messages given as plain tuples, and any other typed messages."""

from __future__ import annotations

from collections.abc import Sequence
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


@dataclass
class BagSpec:
    """Messages to write: (topic, msgtype, bag time [ns], message object) in any order."""

    entries: list[tuple[str, str, int, object]] = field(default_factory=list)

    def add(self, topic: str, msgtype: str, bag_time_ns: int, message: object) -> None:
        self.entries.append((topic, msgtype, bag_time_ns, message))

    def add_joint_state(self, topic: str, bag_time_ns: int, message: JointStateMsg) -> None:
        self.add(topic, "sensor_msgs/msg/JointState", bag_time_ns, joint_state(message))


def write_bag(path: Path, spec: BagSpec, kind: str = "mcap") -> Path:
    """Write ``spec`` as ``kind``: "mcap" or "sqlite3" (a ROS 2 bag directory) or "ros1" (.bag)."""
    entries = sorted(spec.entries, key=lambda entry: entry[2])
    if kind == "ros1":
        with Writer1(path) as writer:
            connections = {}
            for topic, msgtype, stamp, message in entries:
                if topic not in connections:
                    connections[topic] = writer.add_connection(
                        topic, msgtype, typestore=ROS1_TYPESTORE
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
            writer.write(connections[topic], stamp, TYPESTORE.serialize_cdr(message, msgtype))
    return path
