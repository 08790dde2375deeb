"""A truncated MCAP file (a recorder killed, a copy cut short) has no footer and no summary, so
``rosbags`` refuses it. :func:`salvage` copies its complete records into a new file that ends with
an MCAP footer without summary; ``rosbags`` reads such a file by scanning it. The input is not
modified. Only the records are checked (opcode + length), not their content.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

MAGIC = b"\x89MCAP0\r\n"
_RECORD = struct.Struct("<BQ")  # opcode, content length
_FOOTER = _RECORD.pack(0x02, 20) + struct.pack("<QQI", 0, 0, 0) + MAGIC  # no summary
_FOOTER_OPCODE, _CHUNK_OPCODE, _DATA_END_OPCODE = 0x02, 0x06, 0x0F
_CHUNK_HEAD = struct.Struct("<QQQI")  # start time, end time, uncompressed size, CRC


@dataclass(frozen=True)
class Salvaged:
    """The copy and what it holds: ``kept`` bytes of the original's ``size``."""

    path: Path
    kept: int
    size: int


def salvage(source: Path, target: Path) -> Salvaged | None:
    """Copy the complete records of ``source`` (an MCAP file) to ``target`` with a footer; None
    when ``source`` does not start like an MCAP file or has no complete record after its header.
    The complete records inside a cut, uncompressed chunk are kept too (as top-level records).
    """
    size = source.stat().st_size
    with source.open("rb") as data:
        if data.read(len(MAGIC)) != MAGIC:
            return None
        end = _complete_records(data, len(MAGIC), size, top_level=True)
        inner_start, inner_end = _cut_chunk_records(data, end, size)
    if end <= len(MAGIC):
        return None
    with source.open("rb") as data, target.open("wb") as out:
        _copy(data, out, end)
        data.seek(inner_start)
        _copy(data, out, inner_end - inner_start)
        out.write(_FOOTER)
    return Salvaged(target, inner_end if inner_end > inner_start else end, size)


def _cut_chunk_records(data: BinaryIO, offset: int, size: int) -> tuple[int, int]:
    """(start, end) of the complete records inside the uncompressed chunk cut at the file's end
    that starts at ``offset``; (0, 0) if there is none.
    """
    if offset + _RECORD.size + _CHUNK_HEAD.size + 4 > size:
        return 0, 0
    data.seek(offset)
    opcode, _ = _RECORD.unpack(data.read(_RECORD.size))
    if opcode != _CHUNK_OPCODE:
        return 0, 0
    data.read(_CHUNK_HEAD.size)
    if struct.unpack("<I", data.read(4))[0]:  # a compression's name: compressed, not salvaged
        return 0, 0
    start = data.tell() + 8  # after the records' byte length
    end = _complete_records(data, start, size)
    return (start, end) if end > start else (0, 0)


def _complete_records(data: BinaryIO, start: int, size: int, top_level: bool = False) -> int:
    """The offset after the last record from ``start`` on that lies wholly before ``size``; at the
    top level, stop at the data end record or a footer (the summary after them is not needed).
    """
    end = offset = start
    while offset + _RECORD.size <= size:
        data.seek(offset)
        opcode, length = _RECORD.unpack(data.read(_RECORD.size))
        if (top_level and opcode == _FOOTER_OPCODE) or offset + _RECORD.size + length > size:
            break
        offset += _RECORD.size + length
        end = offset
        if top_level and opcode == _DATA_END_OPCODE:
            break
    return end


def _copy(source: BinaryIO, target: BinaryIO, length: int) -> None:
    remaining = length
    while remaining:
        block = source.read(min(remaining, 1 << 20))
        if not block:
            break
        target.write(block)
        remaining -= len(block)
