"""Writers for :mod:`a1_leg_fk.recording`: CSV, a new ROS 2 bag, a PNG; each written under a
temporary name and renamed when complete, so an interrupted run leaves nothing under the final
name. CSV and bag stream block by block (memory independent of the bag's length); the plot
collects the feet (it draws them all anyway). No ROS; ``rosbags`` and matplotlib imported lazily.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal, Unpack

import numpy as np

from a1_leg_fk.csv_text import format_rows
from a1_leg_fk.legs import LEG_NAMES
from a1_leg_fk.recording import (
    BlockStats,
    FootBlock,
    Recording,
    RecordingChoices,
    RecordingSummary,
    close_recording,
    collected,
    iter_foot_blocks,
    open_recording,
)
from a1_leg_fk.urdf import LegFkError

if TYPE_CHECKING:  # rosbags is imported when a bag is written
    from rosbags.interfaces import Connection, Qos
    from rosbags.typesys.store import Typestore

    from a1_leg_fk.recording import FootTrajectories

AXES = ("x", "y", "z")
POSITION_COLUMNS = [f"{leg}_{axis}" for leg in LEG_NAMES for axis in AXES]
VELOCITY_COLUMNS = [f"{leg}_v{axis}" for leg in LEG_NAMES for axis in AXES]
WORLD_COLUMNS = [f"{leg}_w{axis}" for leg in LEG_NAMES for axis in AXES]
BAG_VERSION: Literal[9] = 9  # rosbag2 metadata version as Jazzy writes it
INFINITE_DURATION = (9223372036, 854775807)  # rosbag2 Jazzy's spelling of an infinite QoS duration


@dataclass
class _Target:
    """One output: its final path, and the temporary one it is written under: the same name in a
    hidden folder beside it (so a bag's storage file and metadata carry the final name).
    """

    final: Path

    @property
    def folder(self) -> Path:
        return self.final.with_name(f".{self.final.name}.partial-{os.getpid()}")

    @property
    def temporary(self) -> Path:
        return self.folder / self.final.name

    def prepare(self) -> None:
        self.discard()
        self.folder.mkdir()

    def discard(self) -> None:
        _remove(self.folder)

    def commit(self) -> None:
        _remove(self.final)
        os.replace(self.temporary, self.final)
        self.folder.rmdir()


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    elif path.exists() or path.is_symlink():
        path.unlink()


@dataclass
class Outputs:
    """The requested outputs, checked before anything is read."""

    csv: _Target | None
    bag: _Target | None
    plot: _Target | None
    storage: str
    copy_input: bool

    @classmethod
    def checked(
        cls,
        source: Path,
        *,
        csv: str | None,
        bag: str | None,
        plot: str | None,
        storage: str = "mcap",
        copy_input: bool = False,
        force: bool = False,
    ) -> Outputs:
        """:class:`LegFkError` for an output that exists (without ``force``), lies inside the input
        bag, or sits in a folder that does not exist.
        """
        targets: list[_Target | None] = []
        for option, value in (("--csv", csv), ("--output-bag", bag), ("--plot", plot)):
            if value is None:
                targets.append(None)
                continue
            path = Path(value)
            _check_target(source, path, option, force)
            targets.append(_Target(path))
        finals = [target.final.resolve() for target in targets if target is not None]
        if len(set(finals)) != len(finals):
            raise LegFkError("two outputs name the same path")
        csv_target, bag_target, plot_target = targets
        return cls(csv_target, bag_target, plot_target, storage=storage, copy_input=copy_input)

    def all(self) -> list[_Target]:
        """The requested outputs."""
        return [target for target in (self.csv, self.bag, self.plot) if target is not None]

    def written(self) -> list[Path]:
        """The final paths of the outputs that exist."""
        return [target.final for target in self.all() if target.final.exists()]


def _check_target(source: Path, path: Path, option: str, force: bool) -> None:
    resolved, input_path = path.resolve(), source.resolve()
    if resolved == input_path or input_path in resolved.parents:
        raise LegFkError(f"{option} {path}: inside the input bag {source}; write it elsewhere")
    if not resolved.parent.is_dir():
        raise LegFkError(f"{option} {path}: folder {path.parent} does not exist")
    if (path.exists() or path.is_symlink()) and not force:
        raise LegFkError(f"{option} {path}: exists already (use --force to replace it)")


def convert(
    source: Path, outputs: Outputs, *, progress: bool = False, **choices: Unpack[RecordingChoices]
) -> RecordingSummary:
    """One pass over ``source`` writing every requested output; returns the summary. On any
    exception (including KeyboardInterrupt) the temporary outputs are removed.
    """
    recording = open_recording(source, **choices)
    writers: list[CsvWriter | BagWriter] = []
    bag_writer = None
    try:
        for target in outputs.all():
            target.prepare()
        if outputs.csv is not None:
            writers.append(CsvWriter(outputs.csv.temporary, recording))
        if outputs.bag is not None:
            bag_writer = BagWriter(
                outputs.bag.temporary, recording, outputs.storage, outputs.copy_input
            )
            writers.append(bag_writer)
        blocks: list[FootBlock] = []
        stats = BlockStats()
        copier = bag_writer if outputs.copy_input else None
        for block in iter_foot_blocks(
            recording, progress=progress, on_message=copier.copy if copier else None
        ):
            stats.add(block)
            for writer in writers:
                writer.write(block)
            if outputs.plot is not None:
                blocks.append(block)
        for writer in writers:
            writer.close()
        summary = stats.summary(recording)
        if outputs.plot is not None:
            plot_trajectories(collected(blocks, recording, summary), outputs.plot.temporary)
        for target in outputs.all():
            target.commit()
        return summary
    except BaseException:
        for writer in writers:
            writer.abort()
        for target in outputs.all():
            target.discard()
        raise
    finally:
        close_recording(recording)


# --- CSV --------------------------------------------------------------------------------------------


class CsvWriter:
    """Rows ``stamp_ns, bag_time_ns, FR_x .. RL_z[, FR_vx .. RL_vz][, FR_wx .. RL_wz]``; values
    written so that ``float(text)`` gives the same float back (:mod:`a1_leg_fk.csv_text`); empty
    cells for NaN. The velocity columns are there when the recording has foot velocities: decided
    by the first block of rows; should velocities first turn up later, the rows written so far
    get empty velocity cells (one pass over the file so far).
    """

    def __init__(self, path: Path, recording: Recording) -> None:
        self.path = path
        self.world = recording.base_pose is not None
        self.velocity_columns: bool | None = None  # not decided before the first rows
        self.file = open(path, "wb")  # noqa: SIM115 (open until close() or abort())

    def _header(self) -> bytes:
        columns = [
            "stamp_ns",
            "bag_time_ns",
            *POSITION_COLUMNS,
            *(VELOCITY_COLUMNS if self.velocity_columns else []),
            *(WORLD_COLUMNS if self.world else []),
        ]
        return (",".join(columns) + "\n").encode()

    def write(self, block: FootBlock) -> None:
        """Append the rows of ``block``."""
        rows = len(block.stamps_ns)
        velocities = bool(np.isfinite(block.velocities).any())
        if self.velocity_columns is None:
            self.velocity_columns = velocities
            self.file.write(self._header())
        elif velocities and not self.velocity_columns:
            self._add_velocity_columns()
        parts = [block.positions.reshape(rows, -1)]
        if self.velocity_columns:
            parts.append(block.velocities.reshape(rows, -1))
        if block.world_positions is not None:
            parts.append(block.world_positions.reshape(rows, -1))
        self.file.write(
            format_rows(
                np.stack([block.stamps_ns, block.bag_times_ns], axis=1),
                np.concatenate(parts, axis=1),
            )
        )

    def close(self) -> None:
        """Finish the file (the header alone when no rows came)."""
        if self.velocity_columns is None:  # no rows: the header alone
            self.velocity_columns = False
            self.file.write(self._header())
        self.file.close()

    def abort(self) -> None:
        """Close the file, unfinished (it is being discarded)."""
        self.file.close()

    def _add_velocity_columns(self) -> None:
        """Rewrite the rows so far with empty velocity cells after the position cells."""
        self.file.close()
        self.velocity_columns = True
        first, empty = 2 + len(POSITION_COLUMNS), [b""] * len(VELOCITY_COLUMNS)
        wide = self.path.with_name(self.path.name + ".wide")
        with open(self.path, "rb") as narrow, open(wide, "wb") as out:
            narrow.readline()
            out.write(self._header())
            for line in narrow:
                cells = line.rstrip(b"\n").split(b",")
                out.write(b",".join(cells[:first] + empty + cells[first:]) + b"\n")
        os.replace(wide, self.path)
        self.file = open(self.path, "ab")  # noqa: SIM115 (open until close() or abort())


# --- the output bag ---------------------------------------------------------------------------------


class BagWriter:
    """A ROS 2 bag with ``/foot_positions/<leg>``, ``/foot_velocities/<leg>`` (when velocities
    exist) and ``/foot_positions_world/<leg>`` (with a base pose), messages serialized here (CDR)
    with the JointState's header stamp and bag time; optionally every input message too.
    """

    def __init__(self, path: Path, recording: Recording, storage: str, copy_input: bool) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore

        self.recording = recording
        self.typestore = get_typestore(Stores.ROS2_JAZZY)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        self.writer = Writer(path, version=BAG_VERSION, storage_plugin=plugin)
        self.writer.open()
        self.base_frame = recording.quadruped.base_frame
        self.world_frame = (
            recording.base_pose.world_frame if recording.base_pose is not None else ""
        )
        self.topics: dict[str, Connection] = {}
        self.copied: dict[int, Connection] = {}
        self.copy_input = copy_input
        self.ros1 = recording.ros1

    def _connection(
        self, topic: str, msgtype: str, typestore: Typestore | None = None
    ) -> Connection:
        connection = self.topics.get(topic)
        if connection is None:
            connection = self.topics[topic] = self.writer.add_connection(
                topic,
                msgtype,
                typestore=typestore or self.typestore,
                offered_qos_profiles=[default_qos()],
            )
        return connection

    def write(self, block: FootBlock) -> None:
        """Write the feet of ``block`` as PointStamped (and velocity) messages."""
        groups = [
            ("/foot_positions", "geometry_msgs/msg/PointStamped", self.base_frame, block.positions)
        ]
        if self.recording.has_velocities:  # already set by this block if it has any
            groups.append(
                (
                    "/foot_velocities",
                    "geometry_msgs/msg/Vector3Stamped",
                    self.base_frame,
                    block.velocities,
                )
            )
        if block.world_positions is not None:
            groups.append(
                (
                    "/foot_positions_world",
                    "geometry_msgs/msg/PointStamped",
                    self.world_frame,
                    block.world_positions,
                )
            )
        stamps, bag_times = block.stamps_ns.tolist(), block.bag_times_ns.tolist()
        for prefix, msgtype, frame, values in groups:
            for leg_slot, leg in enumerate(LEG_NAMES):
                leg_values = values[:, leg_slot]
                rows = np.flatnonzero(np.isfinite(leg_values).all(axis=1))
                if not len(rows):
                    continue
                connection = self._connection(f"{prefix}/{leg}", msgtype)
                head = _frame_bytes(frame)
                for row, (x, y, z) in zip(rows.tolist(), leg_values[rows].tolist()):
                    sec, nanosec = divmod(stamps[row], 1_000_000_000)
                    self.writer.write(
                        connection,
                        bag_times[row],
                        _CDR_LE + _STAMP.pack(sec, nanosec) + head + _XYZ.pack(x, y, z),
                    )

    def copy(self, connection: Connection, bag_time: int, raw: bytes) -> None:
        """Copy one input message (ROS 1 messages converted to CDR)."""
        target = self.copied.get(connection.id)
        # ROS 1 messages are converted with the ROS 2 definitions of their types (std_msgs/Header
        # loses its seq); other bags keep their own definitions.
        typestore = (
            self.typestore
            if self.ros1 and connection.msgtype in self.typestore.fielddefs
            else self.recording.reader.typestore
        )
        if target is None:
            target = self.copied[connection.id] = self.writer.add_connection(
                connection.topic,
                connection.msgtype,
                typestore=typestore,
                offered_qos_profiles=_input_qos(connection),
            )
        data: bytes | memoryview = raw
        if self.ros1:
            try:
                data = typestore.ros1_to_cdr(raw, connection.msgtype)
            except Exception as error:  # noqa: BLE001 (rosbags: a type it cannot convert)
                raise LegFkError(
                    f"--copy-input: cannot convert {connection.topic} ({connection.msgtype}) to ROS 2: {error}"
                ) from None
        self.writer.write(target, bag_time, data)

    def close(self) -> None:
        """Finish the bag."""
        self.writer.close()

    def abort(self) -> None:
        """Close the bag, ignoring errors (it is being discarded anyway)."""
        with contextlib.suppress(Exception):
            self.writer.close()


_CDR_LE = b"\x00\x01\x00\x00"  # encapsulation header: CDR, little endian
_STAMP = struct.Struct("<iI")
_XYZ = struct.Struct("<3d")


def _frame_bytes(frame: str) -> bytes:
    """The CDR ``frame_id`` string after the stamp, padded so the float64s that follow are
    8-aligned (offsets relative to the 4-byte encapsulation header, which the stamp follows).
    """
    encoded = frame.encode() + b"\0"
    text = struct.pack("<I", len(encoded)) + encoded
    padding = -(8 + len(text)) % 8
    return text + b"\0" * padding


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


# --- the plot ---------------------------------------------------------------------------------------


def plot_trajectories(trajectories: FootTrajectories, path: Path) -> Path:
    """x, y, z of each foot over time [s from the first stamp]; world frame when available."""
    from a1_leg_fk.plots import LEG_COLOURS, _save, pyplot

    plt = pyplot()
    world_positions = trajectories.world_positions
    world = world_positions is not None and bool(np.isfinite(world_positions).any())
    values = world_positions if world_positions is not None and world else trajectories.positions
    frame = trajectories.world_frame if world else trajectories.base_frame
    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(11, 8))
    stamps = trajectories.stamps_ns
    seconds = (stamps - stamps[0]) / 1e9 if len(stamps) else stamps
    for axis_slot, (axis, name) in enumerate(zip(axes, AXES)):
        for leg_slot, leg in enumerate(LEG_NAMES):
            axis.plot(
                seconds,
                values[:, leg_slot, axis_slot],
                color=LEG_COLOURS[leg],
                linewidth=0.8,
                label=leg,
            )
        axis.set_ylabel(f"{name} [m]")
        axis.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", ncol=4, fontsize="small")
    axes[-1].set_xlabel("time since the first JointState stamp [s]")
    summary = trajectories.summary
    figure.suptitle(
        f"Feet in frame '{frame}': {Path(summary.path).name}, {summary.topic}, {summary.rows} rows"
    )
    return _save(figure, plt, path)
