"""Read the fields of a ``sensor_msgs/msg/JointState`` straight from its serialized bytes.

Two layouts: ROS 2 CDR (a 4-byte encapsulation header, then fields aligned to their size relative
to the end of that header; either byte order) and ROS 1 (little endian, packed, header
``seq``/``stamp``/``frame_id``). Only the fields the FK needs are read: the header stamp, the name
list and the position/velocity arrays. A steady stream repeats the same name list: its bytes are
compared with the previous message's, and the names are decoded only when they change.

No ROS and no ``rosbags`` here; the tests check this decoder against ``rosbags``' deserializer.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

_UINT32 = {"<": struct.Struct("<I"), ">": struct.Struct(">I")}
_STAMP_CDR = {"<": struct.Struct("<iI"), ">": struct.Struct(">iI")}
_STAMP_ROS1 = struct.Struct("<II")
_DOUBLES = {"<": np.dtype("<f8"), ">": np.dtype(">f8")}


class WireError(ValueError):
    """The bytes are not a JointState of the expected layout (truncated or corrupt)."""


@dataclass(frozen=True)
class WireJointState:
    """One message's fields: stamp [ns] (header, 0 when unset), names (``None`` when the name
    bytes equal the previous message's), positions [rad] and velocities [rad/s] as float64 arrays
    (views of the message bytes in their byte order)."""

    stamp_ns: int
    names: list[str] | None
    positions: np.ndarray
    velocities: np.ndarray


class JointStateDecoder:
    """Decodes consecutive JointState messages of one connection; ``ros1`` selects the layout."""

    def __init__(self, ros1: bool = False) -> None:
        self.ros1 = ros1
        self._names_bytes = b""
        self._names: list[str] = []

    @property
    def names(self) -> list[str]:
        """The name list of the latest decoded message."""
        return self._names

    def decode(self, raw: bytes | memoryview) -> WireJointState:
        """The fields of one serialized message; :class:`WireError` if it is cut short or corrupt."""
        try:
            return self._decode_ros1(bytes(raw)) if self.ros1 else self._decode_cdr(bytes(raw))
        except (struct.error, ValueError, UnicodeDecodeError, IndexError) as error:
            if isinstance(error, WireError):
                raise
            raise WireError(f"malformed JointState ({len(raw)} bytes): {error}") from None

    def _decode_cdr(self, raw: bytes) -> WireJointState:
        if len(raw) < 4 or raw[1] not in (0, 1):
            raise WireError(f"not a CDR message (encapsulation {raw[:4].hex()})")
        order = "<" if raw[1] == 1 else ">"
        u32 = _UINT32[order].unpack_from
        body = 4  # offsets below are relative to the end of the encapsulation header
        sec, nanosec = _STAMP_CDR[order].unpack_from(raw, body)
        frame_length = u32(raw, body + 8)[0]
        offset = _aligned(12 + frame_length, 4)
        names_start = offset
        if self._names_bytes and raw.startswith(self._names_bytes, body + names_start):
            names = None
            offset += len(self._names_bytes)
        else:
            names, offset = self._cdr_names(raw, offset, u32)
            self._names_bytes = raw[body + names_start : body + offset]
            self._names = names
        positions, offset = _cdr_doubles(raw, offset, u32, order)
        velocities, _ = _cdr_doubles(raw, offset, u32, order)
        return WireJointState(sec * 1_000_000_000 + nanosec, names, positions, velocities)

    @staticmethod
    def _cdr_names(raw: bytes, offset: int, u32) -> tuple[list[str], int]:  # noqa: ANN001
        count = u32(raw, 4 + offset)[0]
        offset += 4
        _check_count(count, len(raw), "names")
        names = []
        for _ in range(count):
            offset = _aligned(offset, 4)
            length = u32(raw, 4 + offset)[0]
            start = 4 + offset + 4
            if length < 1 or start + length > len(raw):
                raise WireError(f"name string of {length} bytes runs past the message")
            names.append(raw[start : start + length - 1].decode())  # CDR strings end in NUL
            offset += 4 + length
        return names, offset

    def _decode_ros1(self, raw: bytes) -> WireJointState:
        u32 = _UINT32["<"].unpack_from
        sec, nanosec = _STAMP_ROS1.unpack_from(raw, 4)
        offset = 12 + 4 + u32(raw, 12)[0]
        names_start = offset
        if self._names_bytes and raw.startswith(self._names_bytes, names_start):
            names = None
            offset += len(self._names_bytes)
        else:
            count = u32(raw, offset)[0]
            _check_count(count, len(raw), "names")
            offset += 4
            names = []
            for _ in range(count):
                length = u32(raw, offset)[0]
                if offset + 4 + length > len(raw):
                    raise WireError(f"name string of {length} bytes runs past the message")
                names.append(raw[offset + 4 : offset + 4 + length].decode())
                offset += 4 + length
            self._names_bytes = raw[names_start:offset]
            self._names = names
        positions, offset = _packed_doubles(raw, offset)
        velocities, _ = _packed_doubles(raw, offset)
        return WireJointState(sec * 1_000_000_000 + nanosec, names, positions, velocities)


def _aligned(offset: int, size: int) -> int:
    return (offset + size - 1) & -size


def _check_count(count: int, available: int, what: str) -> None:
    if count > available:
        raise WireError(f"{what}: {count} elements cannot fit in {available} bytes")


def _cdr_doubles(raw: bytes, offset: int, u32, order: str) -> tuple[np.ndarray, int]:  # noqa: ANN001
    """A ``sequence<float64>`` at ``offset`` (relative to the body): (values, offset after it)."""
    offset = _aligned(offset, 4)
    count = u32(raw, 4 + offset)[0]
    offset += 4
    if count:
        offset = _aligned(offset, 8)
    _check_count(count * 8, len(raw) - 4 - offset, "float64 sequence")
    values = np.frombuffer(raw, _DOUBLES[order], count, 4 + offset)
    return values, offset + 8 * count


def _packed_doubles(raw: bytes, offset: int) -> tuple[np.ndarray, int]:
    count = _UINT32["<"].unpack_from(raw, offset)[0]
    offset += 4
    _check_count(count * 8, len(raw) - offset, "float64 array")
    return np.frombuffer(raw, _DOUBLES["<"], count, offset), offset + 8 * count
