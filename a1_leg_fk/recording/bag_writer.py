"""The ``--output-bag`` writer of :mod:`a1_leg_fk.recording.outputs`: a ROS 2 bag of the feet.

``/foot_positions/<leg>`` (``geometry_msgs/msg/PointStamped``, base frame),
``/foot_velocities/<leg>`` (``Vector3Stamped``, when velocities exist) and
``/foot_positions_world/<leg>`` (``PointStamped``, world frame, with a base pose), with forces
``/foot_forces/<leg>`` (``WrenchStamped``, base frame, the ground's force on the foot [N]), with
forces or contacts ``/foot_contacts`` (``JointState``: name FR, FL, RR, RL, position the contact
probability, effort the normal force [N] along minus gravity, velocity empty), in MCAP or
sqlite3, metadata version and QoS profiles as rosbag2 Jazzy writes them. The messages are
serialized here (little-endian CDR: a header, then three float64 [m or m/s]) with the JointState's
header stamp and bag time; optionally every input message is copied too. ``rosbags`` is
imported when a bag is written.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.trajectories import FootBlock, Recording
from a1_leg_fk.wire.output import (
    contacts_bytes,
    contacts_layout,
    frame_bytes,
    stamped_vector_bytes,
    wrench_bytes,
)

if TYPE_CHECKING:  # rosbags is imported when a bag is written
    from rosbags.interfaces import Connection, Qos
    from rosbags.typesys.store import Typestore

BAG_VERSION: Literal[9] = 9  # rosbag2 metadata version as Jazzy writes it
INFINITE_DURATION = (9223372036, 854775807)  # rosbag2 Jazzy's spelling of an infinite QoS duration


class BagWriter:
    """A ROS 2 bag with ``/foot_positions/<leg>``, ``/foot_velocities/<leg>`` (when velocities
    exist) and ``/foot_positions_world/<leg>`` (with a base pose), messages serialized here (CDR)
    with the JointState's header stamp and bag time; optionally every input message too.
    """

    def __init__(self, path: Path, recording: Recording, storage: str) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        self.recording = recording
        self.typestore = get_typestore(Stores.ROS2_JAZZY)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self.writer = Writer(path, version=BAG_VERSION, storage_plugin=plugin)
        self.writer.open()
        # the CDR frame_id after the stamp of every base-frame and world-frame message
        self.base_head = frame_bytes(recording.quadruped.base_frame)
        self.world_head = frame_bytes(
            recording.base_pose.world_frame if recording.base_pose is not None else ""
        )
        self.topics: dict[str, Connection] = {}
        self.copied: dict[int, tuple[Connection, Typestore]] = {}  # input id -> target, types
        self.ros1 = recording.ros1

    def _connection(self, topic: str, msgtype: str) -> Connection:
        connection = self.topics.get(topic)
        if connection is None:
            connection = self.topics[topic] = self.writer.add_connection(
                topic, msgtype, typestore=self.typestore, offered_qos_profiles=[default_qos()]
            )
        return connection

    def write(self, block: FootBlock) -> None:
        """Write the feet of ``block`` as PointStamped (and velocity) messages."""
        groups = [
            ("/foot_positions", "geometry_msgs/msg/PointStamped", self.base_head, block.positions)
        ]
        if self.recording.has_velocities:  # already set by this block if it has any
            groups.append(
                (
                    "/foot_velocities",
                    "geometry_msgs/msg/Vector3Stamped",
                    self.base_head,
                    block.velocities,
                )
            )
        if block.world_positions is not None:
            groups.append(
                (
                    "/foot_positions_world",
                    "geometry_msgs/msg/PointStamped",
                    self.world_head,
                    block.world_positions,
                )
            )
        stamps, bag_times = block.stamps_ns.tolist(), block.bag_times_ns.tolist()
        if block.forces is not None and self.recording.force_output:
            groups.append(
                ("/foot_forces", "geometry_msgs/msg/WrenchStamped", self.base_head, block.forces)
            )
        self._write_contacts(block, stamps, bag_times)
        for prefix, msgtype, head, values in groups:
            for leg_slot, leg in enumerate(LEG_NAMES):
                leg_values = values[:, leg_slot]
                rows = np.flatnonzero(np.isfinite(leg_values).all(axis=1))
                if not len(rows):
                    continue
                connection = self._connection(f"{prefix}/{leg}", msgtype)
                serialize = wrench_bytes if prefix == "/foot_forces" else stamped_vector_bytes
                for row, vector in zip(rows.tolist(), leg_values[rows].tolist()):
                    sec, nanosec = divmod(stamps[row], 1_000_000_000)
                    self.writer.write(
                        connection, bag_times[row], serialize(head, sec, nanosec, vector)
                    )

    def _write_contacts(self, block: FootBlock, stamps: list[int], bag_times: list[int]) -> None:
        """``/foot_contacts`` JointStates of the rows with a contact estimate for some leg."""
        if block.contacts is None or block.normal_forces is None:
            return
        rows = np.flatnonzero(np.isfinite(block.contacts).any(axis=1))
        if not len(rows):
            return
        connection = self._connection("/foot_contacts", "sensor_msgs/msg/JointState")
        layout = contacts_layout(self.recording.quadruped.base_frame)
        for row, probabilities, normal in zip(
            rows.tolist(), block.contacts[rows].tolist(), block.normal_forces[rows].tolist()
        ):
            sec, nanosec = divmod(stamps[row], 1_000_000_000)
            self.writer.write(
                connection,
                bag_times[row],
                contacts_bytes(layout, sec, nanosec, probabilities, normal),
            )

    def copy(self, connection: Connection, bag_time: int, raw: bytes) -> None:
        """Copy one input message (ROS 1 messages converted to CDR)."""
        copied = self.copied.get(connection.id)
        if copied is None:
            copied = self.copied[connection.id] = self._copy_target(connection)
        target, typestore = copied
        data: bytes | memoryview = raw
        if self.ros1:
            try:
                data = typestore.ros1_to_cdr(raw, connection.msgtype)
            except Exception as error:  # noqa: BLE001 (rosbags: a type it cannot convert)
                raise LegFkError(
                    f"--copy-input: cannot convert {connection.topic} ({connection.msgtype}) to "
                    f"ROS 2: {error}"
                ) from None
        self.writer.write(target, bag_time, data)

    def _copy_target(self, connection: Connection) -> tuple[Connection, Typestore]:
        """The output connection of an input connection, and the types it is written with."""
        # ROS 1 messages are converted with the ROS 2 definitions of their types (std_msgs/Header
        # loses its seq); other bags keep their own definitions.
        typestore = (
            self.typestore
            if self.ros1 and connection.msgtype in self.typestore.fielddefs
            else self.recording.reader.typestore
        )
        target = self.writer.add_connection(
            connection.topic,
            connection.msgtype,
            typestore=typestore,
            offered_qos_profiles=_input_qos(connection),
        )
        return target, typestore

    def close(self) -> None:
        """Finish the bag."""
        self.writer.close()

    def abort(self) -> None:
        """Close the bag, ignoring errors (it is being discarded anyway)."""
        with contextlib.suppress(Exception):
            self.writer.close()


def default_qos() -> Qos:
    """The QoS rosbag2 Jazzy records for a default publisher: reliable, volatile, keep last 10."""
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )

    infinite = QosTime(*INFINITE_DURATION)
    return Qos(
        QosHistory.KEEP_LAST,
        10,
        QosReliability.RELIABLE,
        QosDurability.VOLATILE,
        infinite,
        infinite,
        QosLiveliness.AUTOMATIC,
        infinite,
        False,
    )


def _input_qos(connection: Connection) -> list[Qos]:
    profiles = getattr(connection.ext, "offered_qos_profiles", None)
    return list(profiles) if profiles else [default_qos()]
