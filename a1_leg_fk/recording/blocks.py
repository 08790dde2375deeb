"""The pass over a recording's JointState messages: their serialized bytes (no deserialization)
in blocks of :data:`BLOCK_MESSAGES`, through :class:`~a1_leg_fk.tracking.FootTracker`'s rules,
to :class:`FootBlock` rows of feet [m] and foot velocities [m/s] in the base frame (and in the
world frame with a base pose; with ``recording.forces``, foot forces [N] and contacts from the
efforts, :mod:`a1_leg_fk.recording.forces`). No ROS install: ``rosbags`` and ``tqdm`` come
with the open bag.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, cast

import numpy as np

from a1_leg_fk.kinematics.batch_velocities import velocities_of
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.contact_smoothing import smoothed_blocks
from a1_leg_fk.recording.foot_block import FootBlock
from a1_leg_fk.recording.lowstate import no_finite_motors
from a1_leg_fk.recording.reader import JOINT_STATE_TYPE, Recording
from a1_leg_fk.tracking import FootTracker
from a1_leg_fk.wire.joint_state import (
    JointStateDecoder,
    WireError,
    cdr_layout,
)

if TYPE_CHECKING:  # rosbags and tqdm are imported when a bag is read
    from rosbags.interfaces import Connection
    from tqdm import tqdm

    from a1_leg_fk.recording.lowstate import LowStateInput
    from a1_leg_fk.wire.lowstate import LowStateRows

BLOCK_MESSAGES = 4096
LEGS = len(LEG_NAMES)


def iter_foot_blocks(
    recording: Recording,
    *,
    progress: bool = False,
    on_message: Callable[[Connection, int, bytes], None] | None = None,
    others: Sequence[Connection] | None = None,
) -> Iterator[FootBlock]:
    """The feet, block by block, in bag order. ``on_message(connection, bag_time_ns, raw)`` is
    called for every message read: of every topic (the whole bag is read, e.g. to copy it), or
    with ``others``, of the joint states and those topics alone (e.g. an IMU's, read in step).
    Contacts smoothed over the recording when ``recording.forces.smoothed``
    (:func:`~a1_leg_fk.recording.contact_smoothing.smoothed_blocks`: the blocks then come a
    lag later, cut where the smoothed rows end).

    A truncated or corrupt bag ends the pass early (:class:`~a1_leg_fk.recording.reads.
    RecordingReads`): what was read is yielded, and ``recording.stopped`` says where and why.
    :class:`LegFkError` at the end of a whole pass in which no message named a joint of the
    model's legs (a bag of another robot): then every row (there are none) and output would be
    empty.
    """
    blocks = _foot_blocks(recording, progress, on_message, others)
    forces = recording.forces
    return smoothed_blocks(blocks, forces) if forces is not None and forces.smoothed else blocks


def _foot_blocks(
    recording: Recording,
    progress: bool,
    on_message: Callable[[Connection, int, bytes], None] | None,
    others: Sequence[Connection] | None,
) -> Iterator[FootBlock]:
    """The pass of :func:`iter_foot_blocks`, with the filter's own (causal) contacts."""
    reader, joint_states = recording.reader, recording.joint_states
    tracker = recording.tracker = FootTracker(recording.quadruped)
    if recording.forces is not None:
        recording.forces.restart()
    recording.has_velocities = False  # this pass's
    every = on_message is not None and others is None  # every topic: the whole bag
    connections = [] if every else [joint_states, *(c for c in others or () if c != joint_states)]
    total = sum(c.msgcount for c in (reader.connections if every else connections))
    bar = _progress_bar(total, progress)
    kind = _Batch if recording.lowstate is None else _LowStateBatch
    batch = kind(recording, tracker, JointStateDecoder(ros1=recording.ros1))
    read = shown = 0
    messages = recording.reads.messages(connections, "the bag" if every else "")
    try:
        for connection, bag_time, raw in messages:
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
    except _Corrupt:
        pass  # recording.reads says where
    finally:
        messages.close()
        if bar is not None:
            bar.update(read - shown)
            bar.close()
    if tracker.counts.messages and not batch.leg_joint_named and not recording.stopped:
        raise LegFkError(no_leg_joints_problem(recording, batch.first_names))
    if isinstance(batch, _LowStateBatch) and batch.added and not batch.rows_out:
        raise no_finite_motors(recording.reads, joint_states.topic, tracker.counts)


def no_leg_joints_problem(recording: Recording, names: list[str]) -> str:
    """What is wrong with a JointState topic none of whose messages names a leg joint of the
    model (``names``: the first message's names), and the ways out; one line.
    """
    topic = recording.joint_states.topic
    others = sorted(
        c.topic
        for c in recording.reader.connections
        if c.msgtype == JOINT_STATE_TYPE and c.topic != topic
    )
    shown = ", ".join(names[:8]) + (", ..." if len(names) > 8 else "")
    return (
        f"{recording.path}: no JointState message on {topic} names a leg joint of the model "
        f"({recording.model_source}): it expects {', '.join(recording.quadruped.joint_names)}; "
        f"its messages name {shown or 'no joint'} ({len(names)} names). If the robot is a "
        "quadruped, map its names with --joint-aliases NAME=joint or give its model with "
        "--urdf FILE; or choose another JointState topic with --topic"
        + (f" (the bag also has {', '.join(others)})" if others else "")
    )


class _Corrupt(Exception):
    """A JointState message that cannot be decoded (noted in ``recording.reads``); the pass
    stops there.
    """


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
        self.added = 0  # JointState messages added so far
        self.length = -1
        self.leg_joint_named = False  # some message so far named a joint of the model's legs
        self.first_names: list[str] = []  # the first non-empty name list, for the error

    def seen(self, names: list[str]) -> None:
        """Note the name list of messages about to go through the rules."""
        if self.leg_joint_named:
            return
        slots = self.recording.quadruped.name_to_slot
        self.leg_joint_named = any(name in slots for name in names)
        self.first_names = self.first_names or list(names)

    def add(self, raw: bytes, bag_time: int) -> None:
        if not self.raws:
            self.length = len(raw)
        self.added += 1
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
            self.seen(self.decoder.names)
            yield from _finish(self.recording, self.tracker, self.decoder.names, *arrays)
            return
        yield from self._one_by_one(raws, bag_times)

    def _vectorised(
        self, raws: list[bytes], bag_times: list[int]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None] | None:
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
        efforts = np.ascontiguousarray(matrix[:, layout.efforts]).view("<f8")
        return stamps, bag_times_ns, positions, velocities, efforts

    def _one_by_one(self, raws: list[bytes], bag_times: list[int]) -> Iterator[FootBlock]:
        fields = self.decoder.fields
        pending = _Pending()
        first = self.added - len(raws) + 1  # the number of the batch's first JointState
        for index, (raw, bag_time) in enumerate(zip(raws, bag_times), first):
            try:
                stamp, changed, order, positions, velocities, efforts = fields(raw)
            except WireError as error:
                yield from pending.finish(self)
                topic = self.recording.joint_states.topic
                self.recording.reads.undecodable(bag_time, index, topic, str(error))
                raise _Corrupt from None
            if pending.stamps and (
                changed
                or order != pending.order
                or len(positions) != pending.position_bytes
                or len(velocities) != pending.velocity_bytes
                or len(efforts) != pending.effort_bytes
            ):
                yield from pending.finish(self)
                pending = _Pending()
            if not pending.stamps:
                pending.start(
                    self.decoder.names, order, len(positions), len(velocities), len(efforts)
                )
            pending.stamps.append(stamp or bag_time)
            pending.bag_times.append(bag_time)
            pending.positions.append(positions)
            pending.velocities.append(velocities)
            pending.efforts.append(efforts)
        yield from pending.finish(self)


class _LowStateBatch(_Batch):
    """Consecutive LowState messages (:mod:`a1_leg_fk.recording.lowstate`): the motors as
    joint states named by leg and role, stamped with their bag times.
    """

    rows_out = 0  # rows yielded so far

    def blocks(self) -> Iterator[FootBlock]:
        """The rows of the batch's messages; :class:`_Corrupt` after the rows before one that
        cannot be decoded.
        """
        raws, bag_times = self.raws, self.bag_times
        self.raws, self.bag_times = [], []
        lowstate = cast("LowStateInput", self.recording.lowstate)
        before = self.added - len(raws)
        rows, bad = lowstate.decode(self.recording.reads, raws, bag_times, before)
        if len(rows.tick):
            self.seen(lowstate.names)
            times = np.array(bag_times[: len(rows.tick)], dtype=np.int64)
            wanted = self.recording.forces is not None or self.recording.efforts
            arrays = (
                times,
                times,
                rows.positions,
                rows.velocities,
                rows.efforts if wanted else None,
            )
            for block in _finish(self.recording, self.tracker, lowstate.names, *arrays, rows):
                self.rows_out += len(block.stamps_ns)
                yield block
        if bad:
            raise _Corrupt


class _Pending:
    """Consecutive messages with one name list and the same array lengths, kept as bytes."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.order = "<"
        self.position_bytes = self.velocity_bytes = self.effort_bytes = 0
        self.stamps: list[int] = []
        self.bag_times: list[int] = []
        self.positions: list[bytes] = []
        self.velocities: list[bytes] = []
        self.efforts: list[bytes] = []

    def start(
        self,
        names: list[str],
        order: str,
        position_bytes: int,
        velocity_bytes: int,
        effort_bytes: int,
    ) -> None:
        self.names, self.order = names, order
        self.position_bytes, self.velocity_bytes = position_bytes, velocity_bytes
        self.effort_bytes = effort_bytes

    def finish(self, batch: _Batch) -> Iterator[FootBlock]:
        """The rows of these messages (none if there are none)."""
        count = len(self.stamps)
        if not count:
            return
        dtype = np.dtype(f"{self.order}f8")
        positions = np.frombuffer(b"".join(self.positions), dtype).reshape(
            count, self.position_bytes // 8
        )
        velocities = np.frombuffer(b"".join(self.velocities), dtype).reshape(
            count, self.velocity_bytes // 8
        )
        batch.seen(self.names)
        efforts = np.frombuffer(b"".join(self.efforts), dtype).reshape(
            count, self.effort_bytes // 8
        )
        yield from _finish(
            batch.recording,
            batch.tracker,
            self.names,
            np.array(self.stamps, dtype=np.int64),
            np.array(self.bag_times, dtype=np.int64),
            positions.astype(np.float64),
            velocities.astype(np.float64),
            efforts.astype(np.float64)
            if batch.recording.forces is not None or batch.recording.efforts
            else None,
        )


def _finish(
    recording: Recording,
    tracker: FootTracker,
    names: list[str],
    stamps: np.ndarray,
    bag_times: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    efforts: np.ndarray | None = None,
    lowstate: LowStateRows | None = None,
) -> Iterator[FootBlock]:
    """Run the rules over consecutive messages with one name list and yield their rows (if any).
    ``positions`` [rad] (K, n), ``velocities`` [rad/s] and ``efforts`` [N m] (K, n or 0 or
    another length; efforts only with ``recording.forces`` or ``recording.efforts``); the
    ``lowstate`` rows they came from, for the foot sensors.
    """
    result = tracker.update_block(names, positions, velocities, efforts)
    angles = result.angles[result.accepted]
    known = np.isfinite(angles).reshape(-1, LEGS, JOINTS_PER_LEG).all(axis=2)  # (N, 4)
    rows = known.any(axis=1)  # a leg known, as the node needs to publish its foot
    if not rows.any():
        return
    feet = recording.quadruped.fk_batch(np.nan_to_num(angles[rows]))
    feet[~known[rows]] = math.nan
    rates = result.rates[result.accepted][rows]
    foot_velocities = velocities_of(recording.quadruped, angles[rows], known[rows], rates)
    recording.has_velocities = recording.has_velocities or bool(np.isfinite(foot_velocities).any())
    stamps = stamps[result.accepted][rows]
    bag_times = bag_times[result.accepted][rows]
    world = None
    if recording.base_pose is not None:
        origin, rotation = recording.base_pose.at(stamps)
        world = origin[:, None, :] + np.einsum("nij,nlj->nli", rotation, feet)
    rates[~np.repeat(np.isfinite(foot_velocities).all(axis=2), JOINTS_PER_LEG, axis=1)] = math.nan
    forces, normals, contacts, evidence = None, None, None, None
    if recording.forces is not None:
        slot_efforts = (
            recording.forces.slot_efforts(names, efforts)[result.accepted][rows]
            if efforts is not None and efforts.shape[1]
            else None
        )
        forces, normals, contacts, evidence = recording.forces.rows(
            stamps, (angles[rows], rates, slot_efforts), (feet, foot_velocities)
        )
    yield FootBlock(
        stamps,
        bag_times,
        feet,
        foot_velocities,
        world,
        angles[rows],
        rates,
        forces,
        normals,
        contacts,
        result.efforts[result.accepted][rows] if recording.efforts else None,
        None if lowstate is None else lowstate.foot_force[result.accepted][rows],
        evidence,
    )


def _progress_bar(total: int, enabled: bool) -> tqdm[None] | None:
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, unit="msg", unit_scale=True, mininterval=0.5, smoothing=0.1)
