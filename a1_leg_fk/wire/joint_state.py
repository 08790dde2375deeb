"""Read the fields of a ``sensor_msgs/msg/JointState`` straight from its serialized bytes.

Two layouts: ROS 2 CDR (a 4-byte encapsulation header, then fields aligned to their size relative
to the end of that header; either byte order) and ROS 1 (little endian, packed, header
``seq``/``stamp``/``frame_id``). The header stamp, the name list and the position, velocity and
effort arrays are read (not ``frame_id``). A steady stream repeats the same name list: its bytes
are compared with the previous message's, and the names are decoded only when they change.

The one decoder of both ``foot_fk_node`` (a raw subscription) and the bag tools. No ROS and no
``rosbags`` here; the tests check this decoder against ``rosbags``' deserializer.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from a1_leg_fk.wire.imu import ImuFields

_UINT32 = {"<": struct.Struct("<I"), ">": struct.Struct(">I")}
Uint32Reader = Callable[[bytes, int], tuple[int, ...]]
"""``struct.Struct.unpack_from`` of a uint32 in the message's byte order: ``(raw, offset)``."""
_STAMP_CDR = {"<": struct.Struct("<iI"), ">": struct.Struct(">iI")}
_STAMP_ROS1 = struct.Struct("<II")


class WireError(ValueError):
    """The bytes are not a JointState of the expected layout (truncated or corrupt)."""


class WireFields(NamedTuple):
    """One message's fields as :meth:`JointStateDecoder.fields` reads them; the arrays are raw
    float64 bytes in ``order``, for callers that batch them (:func:`doubles` makes floats).
    """

    stamp_ns: int  # header stamp [ns]; 0 when unset
    names_changed: bool  # the name list differs from the previous message's
    order: str  # byte order of the arrays: "<" or ">"
    positions: bytes  # [rad]
    velocities: bytes  # [rad/s]
    efforts: bytes  # [N m]


_NATIVE_ORDER = "<" if struct.pack("=H", 1) == struct.pack("<H", 1) else ">"


def doubles(data: bytes, order: str) -> Sequence[float]:
    """The float64 values of ``data`` (bytes in ``order``): a zero-copy view where ``order`` is
    the machine's own, else unpacked.
    """
    if order == _NATIVE_ORDER:
        return memoryview(data).cast("d")
    return struct.unpack(f"{order}{len(data) // 8}d", data)


class JointStateDecoder:
    """Decodes consecutive JointState messages of one connection; ``ros1`` selects the layout."""

    imu: ImuFields | None = None
    """The IMU of the latest message: a JointState has none (a LowState's decoder has one)."""

    def __init__(self, ros1: bool = False) -> None:
        self.ros1 = ros1
        self._names_bytes = b""
        self._names: list[str] = []

    @property
    def names(self) -> list[str]:
        """The name list of the latest decoded message."""
        return self._names

    def fields(self, raw: bytes | memoryview) -> WireFields:
        """The :class:`WireFields` of one serialized message; the names are :attr:`names`.
        :class:`WireError` if the message is cut short or corrupt.
        """
        raw = bytes(raw)
        try:
            return self._fields_ros1(raw) if self.ros1 else self._fields_cdr(raw)
        except (struct.error, UnicodeDecodeError) as error:
            raise WireError(f"malformed JointState ({len(raw)} bytes): {error}") from None

    def _fields_cdr(self, raw: bytes) -> WireFields:
        # offsets are relative to the end of the 4-byte encapsulation header (CDR alignment)
        if len(raw) < 16 or raw[1] > 1:
            raise WireError(f"not a CDR message (encapsulation {raw[:4].hex()})")
        order = "<" if raw[1] == 1 else ">"
        u32 = _UINT32[order].unpack_from
        sec, nanosec = _STAMP_CDR[order].unpack_from(raw, 4)
        names_start = (12 + u32(raw, 12)[0] + 3) & -4
        known = self._names_bytes
        changed = not (known and raw.startswith(known, 4 + names_start))
        if changed:
            self._names, offset = _cdr_names(raw, names_start, u32)
            self._names_bytes = raw[4 + names_start : 4 + offset]
        else:
            offset = names_start + len(known)
        positions, offset = _cdr_doubles(raw, offset, u32)
        velocities, offset = _cdr_doubles(raw, offset, u32)
        efforts, _ = _cdr_doubles(raw, offset, u32)
        return WireFields(
            sec * 1_000_000_000 + nanosec, changed, order, positions, velocities, efforts
        )

    def _fields_ros1(self, raw: bytes) -> WireFields:
        u32 = _UINT32["<"].unpack_from
        sec, nanosec = _STAMP_ROS1.unpack_from(raw, 4)
        names_start = 16 + u32(raw, 12)[0]
        known = self._names_bytes
        changed = not (known and raw.startswith(known, names_start))
        if changed:
            count = u32(raw, names_start)[0]
            _check_count(count, len(raw), "names")
            offset, names = names_start + 4, []
            for _ in range(count):
                length = u32(raw, offset)[0]
                if offset + 4 + length > len(raw):
                    raise WireError(f"name string of {length} bytes runs past the message")
                names.append(raw[offset + 4 : offset + 4 + length].decode())
                offset += 4 + length
            self._names, self._names_bytes = names, raw[names_start:offset]
        else:
            offset = names_start + len(known)
        positions, offset = _packed_doubles(raw, offset)
        velocities, offset = _packed_doubles(raw, offset)
        efforts, _ = _packed_doubles(raw, offset)
        return WireFields(
            sec * 1_000_000_000 + nanosec, changed, "<", positions, velocities, efforts
        )


@dataclass(frozen=True)
class CdrLayout:
    """Where a CDR (little endian) JointState keeps its fields, for messages of the same length
    and layout: byte offsets in the serialized message; ``fixed`` lists the bytes that define the
    layout (header, lengths, the name list), which all such messages must share.
    """

    positions: slice
    velocities: slice
    efforts: slice
    fixed: np.ndarray  # byte indices


def cdr_layout(raw: bytes) -> CdrLayout | None:
    """The layout of a little-endian CDR JointState, or None (other byte order, malformed)."""
    if len(raw) < 16 or raw[1] != 1:
        return None
    u32 = _UINT32["<"].unpack_from
    try:
        names_start = (12 + u32(raw, 12)[0] + 3) & -4
        _, names_end = _cdr_names(raw, names_start, u32)
        spans, fixed = [], [range(4), range(12, 16), range(4 + names_start, 4 + names_end)]
        offset = names_end
        for _ in range(3):  # position, velocity, effort
            offset = (offset + 3) & -4
            fixed.append(range(4 + offset, 8 + offset))
            data, end = _cdr_doubles(raw, offset, u32)
            spans.append(slice(4 + end - len(data), 4 + end))
            offset = end
    except (struct.error, UnicodeDecodeError, WireError):
        return None
    if 4 + offset != len(raw):
        return None
    indices = np.fromiter((i for block in fixed for i in block), dtype=np.intp)
    return CdrLayout(spans[0], spans[1], spans[2], indices)


def _cdr_names(raw: bytes, offset: int, u32: Uint32Reader) -> tuple[list[str], int]:
    """The ``sequence<string>`` at ``offset`` (relative to the body): (names, offset after it)."""
    count = u32(raw, 4 + offset)[0]
    offset += 4
    _check_count(count, len(raw), "names")
    names = []
    for _ in range(count):
        offset = (offset + 3) & -4
        length = u32(raw, 4 + offset)[0]
        start = 4 + offset + 4
        if length < 1 or start + length > len(raw):
            raise WireError(f"name string of {length} bytes runs past the message")
        names.append(raw[start : start + length - 1].decode())  # CDR strings end in NUL
        offset += 4 + length
    return names, offset


def _check_count(count: int, available: int, what: str) -> None:
    if count > available:
        raise WireError(f"{what}: {count} elements cannot fit in {available} bytes")


def _cdr_doubles(raw: bytes, offset: int, u32: Uint32Reader) -> tuple[bytes, int]:
    """The ``sequence<float64>`` at ``offset`` (relative to the body): (its bytes, offset
    after).
    """
    offset = (offset + 3) & -4
    count = u32(raw, 4 + offset)[0]
    offset += 4
    if count:
        offset = (offset + 7) & -8
    end = offset + 8 * count
    if 4 + end > len(raw):
        raise WireError(
            f"float64 sequence of {count} elements runs past the message ({len(raw)} bytes)"
        )
    return raw[4 + offset : 4 + end], end


def _packed_doubles(raw: bytes, offset: int) -> tuple[bytes, int]:
    count = _UINT32["<"].unpack_from(raw, offset)[0]
    end = offset + 4 + 8 * count
    if end > len(raw):
        raise WireError(
            f"float64 array of {count} elements runs past the message ({len(raw)} bytes)"
        )
    return raw[offset + 4 : end], end
