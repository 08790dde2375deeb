"""Writers for :mod:`a1_leg_fk.recording.trajectories`: CSV, a new ROS 2 bag, a PNG; each written
under a temporary name and renamed when complete, so an interrupted run leaves nothing under the
final name. CSV and bag stream block by block (memory independent of the bag's length); the plot
collects the feet (it draws them all anyway). No ROS; ``rosbags`` and matplotlib imported lazily.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Unpack

import numpy as np

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.bag_writer import BagWriter
from a1_leg_fk.recording.csv_text import format_rows
from a1_leg_fk.recording.trajectories import (
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
from a1_leg_fk.recording.typestores import require_types

AXES = ("x", "y", "z")
POSITION_COLUMNS = [f"{leg}_{axis}" for leg in LEG_NAMES for axis in AXES]
VELOCITY_COLUMNS = [f"{leg}_v{axis}" for leg in LEG_NAMES for axis in AXES]
WORLD_COLUMNS = [f"{leg}_w{axis}" for leg in LEG_NAMES for axis in AXES]
CONTACT_COLUMNS = [f"{leg}_contact" for leg in LEG_NAMES]
FORCE_COLUMNS = [f"{leg}_f{axis}" for leg in LEG_NAMES for axis in AXES] + CONTACT_COLUMNS
SENSOR_COLUMNS = [f"{leg}_sensor" for leg in LEG_NAMES]


@dataclass
class OutputTarget:
    """One output: its final path, and the temporary one it is written under: the same name in a
    hidden folder beside it (so a bag's storage file and metadata carry the final name).
    """

    final: Path

    @property
    def folder(self) -> Path:
        """The hidden folder beside the final path, named after it and this process."""
        return self.final.with_name(f".{self.final.name}.partial-{os.getpid()}")

    @property
    def temporary(self) -> Path:
        """Where the output is written until :meth:`commit`."""
        return self.folder / self.final.name

    def prepare(self) -> None:
        """A fresh, empty hidden folder."""
        self.discard()
        self.folder.mkdir()

    def discard(self) -> None:
        """Remove the hidden folder and what was written in it."""
        _remove(self.folder)

    def commit(self) -> None:
        """Replace the final path (whatever is there) by the temporary output."""
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

    csv: OutputTarget | None
    bag: OutputTarget | None
    plot: OutputTarget | None
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
        """The outputs as :func:`checked_targets` checks them (the bag is a folder)."""
        targets = checked_targets(
            source,
            {"--csv": csv, "--output-bag": bag, "--plot": plot},
            force,
            folders={"--output-bag"},
        )
        return cls(
            targets.get("--csv"),
            targets.get("--output-bag"),
            targets.get("--plot"),
            storage=storage,
            copy_input=copy_input,
        )

    def all(self) -> list[OutputTarget]:
        """The requested outputs."""
        return [target for target in (self.csv, self.bag, self.plot) if target is not None]

    def written(self) -> list[Path]:
        """The final paths of the outputs that exist."""
        return [target.final for target in self.all() if target.final.exists()]


def checked_targets(
    source: Path,
    paths: Mapping[str, str | None],
    force: bool,
    folders: Collection[str] = (),
) -> dict[str, OutputTarget]:
    """The requested outputs (``paths``: option -> path, ``None`` for not requested), each checked
    by :func:`check_output_path` (the options in ``folders`` write a folder, the others a file)
    before anything is read; :class:`LegFkError` also when two of them name the same path.
    """
    targets = {}
    for option, value in paths.items():
        if value is not None:
            path = Path(value)
            check_output_path(source, path, option, force, folder=option in folders)
            targets[option] = OutputTarget(path)
    finals = [target.final.resolve() for target in targets.values()]
    if len(set(finals)) != len(finals):
        raise LegFkError("two outputs name the same path")
    return targets


def check_output_path(
    source: Path, path: Path, option: str, force: bool, folder: bool = False
) -> None:
    """:class:`LegFkError` naming ``option`` if output ``path`` lies inside the input ``source``,
    sits in a folder that does not exist, or exists (unless ``force``); for a file output
    (``folder`` false), also if it is a folder, which ``--force`` would remove with all in it.
    """
    if not folder and path.is_dir():
        raise LegFkError(f"{option} {path}: is a folder; give a file name")
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
        if outputs.copy_input:
            wanted = {c.msgtype: f"--copy-input: {c.topic}" for c in recording.reader.connections}
            require_types(recording.reader, source, wanted, recording.types)
        for target in outputs.all():
            target.prepare()
        if outputs.csv is not None:
            writers.append(CsvWriter(outputs.csv.temporary, recording))
        if outputs.bag is not None:
            bag_writer = BagWriter(outputs.bag.temporary, recording, outputs.storage)
            writers.append(bag_writer)
        blocks: list[FootBlock] = []
        stats = BlockStats()
        copier = bag_writer if outputs.copy_input else None
        for block in iter_foot_blocks(
            recording, progress=progress, on_message=copier.copy if copier else None
        ):
            stats.add(block, recording)
            for writer in writers:
                writer.write(block)
            if outputs.plot is not None:
                blocks.append(block)
        for writer in writers:
            writer.close()
        summary = stats.summary(recording)
        if outputs.plot is not None:
            from a1_leg_fk.plots import plot_trajectories  # matplotlib only for a plot

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


# --- CSV -----------------------------------------------------------------------------------------


class CsvWriter:
    """Rows ``stamp_ns, bag_time_ns, FR_x .. RL_z[, FR_vx .. RL_vz][, FR_wx .. RL_wz][, FR_fx ..
    RL_fz][, FR_contact .. RL_contact][, FR_sensor .. RL_sensor]`` (forces [N] in the base frame,
    with ``--forces``; contact probabilities, with ``--forces`` or ``--contacts``; a LowState's
    foot sensors, raw counts);
    values written so that ``float(text)`` gives the same float back
    (:mod:`a1_leg_fk.recording.csv_text`); empty cells for NaN. The velocity columns are there when
    the recording has foot velocities: decided by the first block of rows; should velocities first
    turn up later, the rows written so far get empty velocity cells (one pass over the file so
    far).
    """

    def __init__(self, path: Path, recording: Recording) -> None:
        self.path = path
        self.recording = recording
        self.world = recording.base_pose is not None
        self.contacts = recording.forces is not None
        self.forces = recording.force_output
        self.sensors = recording.lowstate is not None
        self.velocity_columns: bool | None = None  # not decided before the first rows
        self.file = open(path, "wb")  # noqa: SIM115 (open until close() or abort())

    def _header(self) -> bytes:
        columns = [
            "stamp_ns",
            "bag_time_ns",
            *POSITION_COLUMNS,
            *(VELOCITY_COLUMNS if self.velocity_columns else []),
            *(WORLD_COLUMNS if self.world else []),
            *(FORCE_COLUMNS if self.forces else CONTACT_COLUMNS if self.contacts else []),
            *(SENSOR_COLUMNS if self.sensors else []),
        ]
        return (",".join(columns) + "\n").encode()

    def write(self, block: FootBlock) -> None:
        """Append the rows of ``block``."""
        rows = len(block.stamps_ns)
        velocities = self.recording.has_velocities  # already set by this block if it has any
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
        if self.forces and block.forces is not None:
            parts.append(block.forces.reshape(rows, -1))
        if self.contacts and block.contacts is not None:
            parts.append(block.contacts)
        if self.sensors and block.sensor is not None:
            parts.append(block.sensor)
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
