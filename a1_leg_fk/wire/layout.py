"""Where each field of a fixed-size message lies in its serialized bytes, from the message's
definition text: the ``.msg`` field lists (ROS 2 or ROS 1), with the definitions of the types it
nests either in the same text (``MSG: pkg/Type`` sections, as bags record them) or given apart.

Two wire layouts: ROS 2 CDR (every primitive aligned to its size, up to 8, relative to the end of
the 4-byte encapsulation header; offsets here are relative to the message's first byte, header
included) and ROS 1 (packed, little endian). Only messages of fixed size have a layout (no
strings, no unbounded or bounded sequences): Unitree's LowState and SportModeState are such.
No ROS and no ``rosbags`` here.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

PRIMITIVE_SIZES = {
    "bool": 1,
    "byte": 1,
    "char": 1,
    "int8": 1,
    "uint8": 1,
    "int16": 2,
    "uint16": 2,
    "int32": 4,
    "uint32": 4,
    "float32": 4,
    "int64": 8,
    "uint64": 8,
    "float64": 8,
}
"""Bytes of each fixed-size primitive type of the ``.msg`` language."""
NUMPY_CODES = {
    "bool": "u1",
    "byte": "u1",
    "char": "u1",
    "int8": "i1",
    "uint8": "u1",
    "int16": "i2",
    "uint16": "u2",
    "int32": "i4",
    "uint32": "u4",
    "float32": "f4",
    "int64": "i8",
    "uint64": "u8",
    "float64": "f8",
}
"""numpy's code of each primitive (without the byte order)."""
ROS1_TIME = ("time", "duration")  # ROS 1's built-in (sec, nsec) pairs of 32-bit integers
CDR_HEADER = 4
"""Bytes of the CDR encapsulation header before the message's fields."""
_SECTION = re.compile(r"^=+\s*$", re.MULTILINE)
_FIELD = re.compile(r"^([A-Za-z][\w/]*)(?:\[(\d*)\])?\s+([A-Za-z]\w*)\s*$")


class LayoutError(ValueError):
    """The definition has no fixed layout (a string, a sequence, an unknown type) or is not
    valid ``.msg`` text.
    """


@dataclass(frozen=True)
class Field:
    """One leaf field: its first byte in the serialized message, primitive type, element count
    (1 for a scalar).
    """

    offset: int
    primitive: str
    count: int


@dataclass(frozen=True)
class Layout:
    """A fixed-size message's wire layout: ``size`` (bytes of a message, the CDR header included
    for ROS 2) and its leaf fields by path (``motor_state[3].q``, ``imu_state.quaternion``).
    """

    msgtype: str
    ros1: bool
    size: int
    fields: Mapping[str, Field]

    def field(self, path: str) -> Field:
        """The leaf at ``path``; :class:`LayoutError` naming it if the message has none."""
        try:
            return self.fields[path]
        except KeyError:
            raise LayoutError(f"{self.msgtype} has no field {path}") from None


def normalized(msgtype: str) -> str:
    """``pkg/msg/Type`` for ``pkg/Type`` or ``pkg/msg/Type``."""
    parts = msgtype.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) >= 2 else msgtype


def definitions_in(text: str, msgtype: str) -> dict[str, str]:
    """The field lists of a recorded definition (``msgtype``'s first, then each ``MSG:``
    section), by normalized type name.
    """
    sections = _SECTION.split(text)
    found = {normalized(msgtype): sections[0]}
    for section in sections[1:]:
        lines = section.strip("\n").split("\n", 1)
        head = lines[0].strip()
        if head.startswith("MSG:"):
            found[normalized(head[4:].strip())] = lines[1] if len(lines) > 1 else ""
    return found


def layout_of(msgtype: str, definitions: Mapping[str, str], ros1: bool) -> Layout:
    """The layout of ``msgtype`` given the field lists of it and every type it nests (by
    normalized name, :func:`definitions_in`); :class:`LayoutError` if it has none.
    """
    fields: dict[str, Field] = {}
    end = _place(normalized(msgtype), definitions, ros1, 0, "", fields)
    return Layout(normalized(msgtype), ros1, end + (0 if ros1 else CDR_HEADER), fields)


def _place(
    msgtype: str,
    definitions: Mapping[str, str],
    ros1: bool,
    offset: int,
    prefix: str,
    out: dict[str, Field],
) -> int:
    """Lay out ``msgtype``'s fields from ``offset`` (relative to the CDR body, or the ROS 1
    message) into ``out``; the offset after them.
    """
    if msgtype not in definitions:
        raise LayoutError(f"no definition of {msgtype}")
    package = msgtype.split("/", maxsplit=1)[0]
    for line in definitions[msgtype].splitlines():
        text = line.split("#", 1)[0].strip()
        if not text or "=" in text:  # blank, comment or constant
            continue
        match = _FIELD.match(text)
        if match is None:
            raise LayoutError(f"{msgtype}: cannot read the field '{text[:60]}'")
        kind, count_text, name = match.groups()
        if count_text == "":
            raise LayoutError(f"{msgtype}.{name} is a sequence: no fixed layout")
        count = int(count_text) if count_text else 1
        path = f"{prefix}{name}"
        if kind in ROS1_TIME and ros1:
            kind = "uint32"
            count *= 2
        if kind in PRIMITIVE_SIZES:
            size = PRIMITIVE_SIZES[kind]
            if not ros1:
                offset = (offset + size - 1) // size * size
            start = offset + (0 if ros1 else CDR_HEADER)
            out[path] = Field(start, kind, count)
            offset += size * count
            continue
        if kind in ("string", "wstring") or kind.startswith("string<"):
            raise LayoutError(f"{msgtype}.{name} is a string: no fixed layout")
        nested = normalized(kind if "/" in kind else f"{package}/{kind}")
        for index in range(count):
            inner = f"{path}[{index}]." if count_text else f"{path}."
            offset = _place(nested, definitions, ros1, offset, inner, out)
    return offset
