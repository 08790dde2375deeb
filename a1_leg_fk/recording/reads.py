"""The one place where the messages of a recording are read: every pass over a bag (the
robot_description, the base pose, the IMU, the ``--forces`` pre-check, the JointState pass of
``bag``, ``gait`` and ``odom``) iterates :meth:`RecordingReads.messages` or
:meth:`RecordingReads.decoded`; a new reader of some topic must do the same.

A damaged recording (bit flips, zeroed runs, a copy cut short, duplicated blocks) makes the
underlying reader (``rosbags``: its MCAP, sqlite3 and ROS 1 readers, their decompressors, the
deserializer) fail in many ways: its own ``ReaderError``, ``AssertionError``, ``struct.error``,
sqlite's corruption errors, a data cell that is an integer, ``MemoryError``, ... Whatever it
raises *while it reads* ends the read: the recording is damaged from there on. The first damage
found is kept as one line (:attr:`RecordingReads.damage`: which message of which topic, its bag
time, and the reader's own words, which name the file offset where it knows it), and no later
read goes past it: every pass yields the messages before it, so every output holds what could be
read, and the commands exit 1. Only calls into the reader are guarded: an error raised by this
package's own code while it handles a message is not the recording's and propagates.

Reads are bounded: :class:`BoundedPath` opens the bag's files so that no read asks for more bytes
than the file has left, so a length field that claims terabytes is a short read (the reader's
"truncated record at offset ..."), not an allocation.
"""

from __future__ import annotations

import io
import os
from collections.abc import Generator, Iterator, Sequence
from pathlib import Path, PosixPath
from typing import TYPE_CHECKING, Any

from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:  # rosbags is imported when a bag is opened
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

DAMAGED = "the recording is damaged: "
NOTHING_AFTER = -(2**63)
"""The end of a recording damaged before its first readable message: nothing is read."""


class DamagedRecording(LegFkError):
    """The recording is damaged where something had to be read (exit 1, not bad input)."""


def one_line(error: BaseException) -> str:
    """An error's message on one line (whitespace runs as one space), at most 300 characters."""
    text = " ".join(str(error).split()) or type(error).__name__
    return text[:300]


def reason(error: BaseException) -> str:
    """What a reader raised, on one line, with the kind of error (``AssertionError`` and
    ``MemoryError`` say nothing else).
    """
    text = " ".join(str(error).split())
    return f"{type(error).__name__}: {text}"[:300] if text else type(error).__name__


class RecordingReads:
    """Every read of the messages of one open recording, and where it is damaged (see the
    module docstring).
    """

    def __init__(self, reader: AnyReader, path: Path) -> None:
        self.reader = reader
        self.path = path
        self.damage = ""  # the one line on the damage found first; "" while none was found
        self.end_ns: int | None = None  # no message at or after this bag time [ns] is read

    def messages(
        self, connections: Sequence[Connection], what: str = ""
    ) -> Generator[tuple[Connection, int, bytes], None, None]:
        """(connection, bag time [ns], serialized bytes) of ``connections`` in bag order, up to
        the end of the recording or the first damage (``what`` names the read in the damage
        line; default: the topics).
        """
        what = what or ", ".join(sorted({c.topic for c in connections}))
        count, last = 0, None
        try:
            source = iter(self._raw_messages(connections))
        except Exception as error:  # noqa: BLE001 (any failure of the reader: the recording's)
            self.stop(NOTHING_AFTER, f"cannot read {what}: {reason(error)}")
            return
        while True:
            try:
                connection, bag_time, raw = next(source)
            except StopIteration:
                return
            except Exception as error:  # noqa: BLE001 (any failure of the reader: the recording's)
                self.stop(_after(last), _unreadable(what, count, last, error))
                return
            problem = _cell_problem(bag_time, raw)
            if problem:
                at = bag_time if isinstance(bag_time, int) else _after(last)
                self.stop(at, f"message {count + 1:,} of {what}: {problem}")
                return
            if self.end_ns is not None and bag_time >= self.end_ns:
                return
            count, last = count + 1, bag_time
            yield connection, bag_time, raw

    def decoded(self, connection: Connection) -> Generator[tuple[int, Any], None, None]:
        """(bag time [ns], deserialized message) of one connection, as :meth:`messages`; a
        message the deserializer cannot decode is damage too.
        """
        messages = self.messages([connection])
        try:
            for index, (_, bag_time, raw) in enumerate(messages, 1):
                message = self.deserialize(connection, bag_time, index, raw)
                if message is None:
                    return
                yield bag_time, message
        finally:
            messages.close()

    def deserialize(self, connection: Connection, bag_time: int, index: int, raw: bytes) -> Any:
        """Message ``index`` (from 1) of ``connection``, deserialized; None if it cannot be
        decoded: damage, the reads end before it.
        """
        try:
            return self.reader.deserialize(raw, connection.msgtype)
        except Exception as error:  # noqa: BLE001 (the deserializer on damaged bytes)
            self.undecodable(bag_time, index, connection.topic, reason(error))
            return None

    def undecodable(self, bag_time: int, index: int, topic: str, problem: str) -> None:
        """Note that message ``index`` (from 1) of ``topic``, at ``bag_time`` [ns], cannot be
        decoded (``problem``): the recording ends before it.
        """
        self.stop(
            bag_time,
            f"message {index:,} of {topic} (bag time {bag_time} ns) cannot be decoded: {problem}",
        )

    def stop(self, end_ns: int, detail: str) -> None:
        """Damage found: no message at or after ``end_ns`` is read any more. The earliest
        damage is the one reported.
        """
        if self.end_ns is None or end_ns < self.end_ns:
            self.end_ns = end_ns
            self.damage = DAMAGED + detail

    def check(self) -> None:
        """:class:`DamagedRecording` if damage was found (for a read that found nothing it
        needs, because of it).
        """
        if self.damage:
            raise DamagedRecording(f"{self.path}: {self.damage}")

    def _raw_messages(
        self, connections: Sequence[Connection]
    ) -> Iterator[tuple[Connection, int, bytes]]:
        """The reader's messages before :attr:`end_ns`; a single bag's reader directly (no
        merge of several).
        """
        reader = self.reader
        if len(reader.readers) == 1:
            return reader.readers[0].messages(connections=connections, stop=self.end_ns)
        return reader.messages(connections=connections, stop=self.end_ns)


def _after(bag_time: int | None) -> int:
    """The end of what can be read when reading failed after a message at ``bag_time`` [ns]
    (None: before any message).
    """
    return NOTHING_AFTER if bag_time is None else bag_time + 1


def _unreadable(what: str, count: int, last: int | None, error: Exception) -> str:
    """The damage line of a reader that failed after ``count`` messages of ``what``, the last
    at bag time ``last`` [ns].
    """
    if last is None:
        return f"cannot read the first message of {what}: {reason(error)}"
    return f"cannot read past message {count:,} of {what} (bag time {last} ns): {reason(error)}"


def _cell_problem(bag_time: object, raw: object) -> str:
    """What is wrong with the types of a message the reader gave ("" if nothing): sqlite3 stores
    any type in any cell, so a damaged file can give an integer as the data.
    """
    if not isinstance(raw, bytes | bytearray | memoryview):
        return f"its data is {type(raw).__name__} {str(raw)[:40]!r}, not bytes"
    if not isinstance(bag_time, int) or isinstance(bag_time, bool):
        return f"its bag time is {type(bag_time).__name__} {str(bag_time)[:40]!r}, not an integer"
    return ""


class BoundedPath(PosixPath):
    """A path whose binary files (``open("rb")``) never read past their end: see
    :class:`_BoundedFile`. Paths made from it (``path / "x.mcap"``) are bounded too, so a bag
    directory's files are.
    """

    def open(  # the same call as Path.open; binary reads bounded
        self,
        mode: str = "r",
        buffering: int = -1,
        encoding: str | None = None,
        errors: str | None = None,
        newline: str | None = None,
    ) -> Any:
        """As :meth:`Path.open`; ``"rb"`` gives a :class:`_BoundedFile`."""
        if mode == "rb":
            return _BoundedFile(io.FileIO(self, "rb"))
        return super().open(mode, buffering, encoding, errors, newline)


class _BoundedFile(io.BufferedReader):
    """A buffered binary file whose ``read(n)`` asks for at most the bytes left in the file: a
    damaged length field (terabytes) gives a short read instead of an allocation of that size.
    """

    def __init__(self, raw: io.FileIO) -> None:
        super().__init__(raw)
        self._size = os.fstat(raw.fileno()).st_size

    def read(self, size: int | None = -1) -> bytes:
        """Up to ``size`` bytes (all that is left for ``-1`` or ``None``)."""
        if size is not None and size > 0:
            left = self._size - self.tell()
            if size > left:  # the file may have grown (a bag being recorded): look again
                self._size = os.fstat(self.fileno()).st_size
                size = min(size, max(self._size - self.tell(), 0))
        return super().read(size)
