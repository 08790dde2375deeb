"""The CDR bytes of the messages the package writes for every joint state, built by patching
constant parts (no message objects): ``geometry_msgs/WrenchStamped`` (the foot forces) and the
``foot_contacts`` ``sensor_msgs/JointState``. Shared by the node's output
(:mod:`a1_leg_fk.ros.foot_output`) and the bag writer (:mod:`a1_leg_fk.recording.bag_writer`).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

from a1_leg_fk.model.legs import LEG_NAMES

_CDR_LE = b"\x00\x01\x00\x00"  # encapsulation header: CDR, little endian
_STAMP = struct.Struct("<iI")
_XYZ = struct.Struct("<3d")
_NO_TORQUE = _XYZ.pack(0.0, 0.0, 0.0)  # the torque of a WrenchStamped, after its force
_LEG_VALUES = struct.Struct(f"<{len(LEG_NAMES)}d")


def contacts_layout(frame: str) -> tuple[bytes, bytes]:
    """The constant CDR bytes of a ``/foot_contacts`` JointState: after the stamp, the frame,
    the leg names and the position count (padded to 8); between the positions and the efforts,
    the empty velocity and the effort count. Offsets relative to the encapsulation header.
    """
    body = bytearray(struct.pack("<I", len(frame) + 1) + frame.encode() + b"\0")
    offset = 8  # the stamp
    body += b"\0" * (-(offset + len(body)) % 4)
    body += struct.pack("<I", len(LEG_NAMES))
    for leg in LEG_NAMES:
        body += b"\0" * (-(offset + len(body)) % 4)
        body += struct.pack("<I", len(leg) + 1) + leg.encode() + b"\0"
    body += b"\0" * (-(offset + len(body)) % 4)
    body += struct.pack("<I", len(LEG_NAMES))
    body += b"\0" * (-(offset + len(body)) % 8)
    # the positions end 8-aligned: velocity count 0, effort count, and the efforts stay aligned
    return bytes(body), struct.pack("<II", 0, len(LEG_NAMES))


def frame_bytes(frame: str) -> bytes:
    """The CDR ``frame_id`` string after the stamp, padded so the float64s that follow are
    8-aligned (offsets relative to the 4-byte encapsulation header, which the stamp follows).
    """
    encoded = frame.encode() + b"\0"
    text = struct.pack("<I", len(encoded)) + encoded
    padding = -(8 + len(text)) % 8
    return text + b"\0" * padding


def stamped_vector_bytes(head: bytes, sec: int, nanosec: int, vector: Sequence[float]) -> bytes:
    """A ``geometry_msgs/PointStamped`` or ``Vector3Stamped``'s CDR: the stamp, ``head``
    (:func:`frame_bytes`) and the three float64s.
    """
    return _CDR_LE + _STAMP.pack(sec, nanosec) + head + _XYZ.pack(*vector)


def wrench_bytes(head: bytes, sec: int, nanosec: int, force: Sequence[float]) -> bytes:
    """A ``geometry_msgs/WrenchStamped``'s CDR: the stamp, ``head`` (:func:`frame_bytes`), the
    force [N] and a zero torque.
    """
    return stamped_vector_bytes(head, sec, nanosec, force) + _NO_TORQUE


def contacts_bytes(
    layout: tuple[bytes, bytes],
    sec: int,
    nanosec: int,
    probabilities: Sequence[float],
    normal: Sequence[float],
) -> bytes:
    """A ``foot_contacts`` JointState's CDR: the stamp, the :func:`contacts_layout` parts, the
    four contact probabilities and the four normal forces [N].
    """
    head, middle = layout
    return (
        _CDR_LE
        + _STAMP.pack(sec, nanosec)
        + head
        + _LEG_VALUES.pack(*probabilities)
        + middle
        + _LEG_VALUES.pack(*normal)
    )
