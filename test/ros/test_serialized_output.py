"""The node's pre-serialized foot messages are byte for byte what rclpy would serialize.

rclpy leaves whatever was in memory in the alignment padding between the frame_id string and the
three float64 (seen: b"g::"); the node writes zeros there. CDR layout: a 4-byte encapsulation
header, int32 sec, uint32 nanosec, uint32 string length, the text and its NUL, padding to 8, then
the three float64.
"""

from __future__ import annotations

import math

from geometry_msgs.msg import PointStamped, Vector3Stamped
from hypothesis import given, settings
from hypothesis import strategies as st
from rclpy.serialization import deserialize_message, serialize_message

from a1_leg_fk.ros.serialized_output import SerializedStamped

frame_ids = st.text(alphabet=st.characters(min_codepoint=33, max_codepoint=0x2FF), max_size=24)
finite = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(
    frame_ids,
    st.integers(-(2**31), 2**31 - 1),
    st.integers(0, 2**32 - 1),
    st.tuples(finite, finite, finite),
)
def test_patched_bytes_equal_rclpy_serialization(frame_id, sec, nanosec, values):
    patched = SerializedStamped(frame_id)
    assert patched.usable
    point, vector = PointStamped(), Vector3Stamped()
    for msg, fields in ((point, point.point), (vector, vector.vector)):
        msg.header.frame_id = frame_id
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        fields.x, fields.y, fields.z = values
    data = patched.serialized(sec, nanosec, values)
    assert data == _zero_padding(serialize_message(point), frame_id)
    assert data == _zero_padding(serialize_message(vector), frame_id)
    back = deserialize_message(data, PointStamped)
    assert (
        back.point.x,
        back.point.y,
        back.point.z,
    ) == values and back.header.frame_id == frame_id


def test_one_buffer_serves_successive_feet_without_leftovers():
    patched = SerializedStamped("trunk")
    first = patched.serialized(1, 2, (0.1, -0.2, math.pi))
    patched.serialized(3, 4, (9.0, 9.0, 9.0))
    assert patched.serialized(1, 2, (0.1, -0.2, math.pi)) == first


def _zero_padding(data: bytes, frame_id: str) -> bytes:
    text_end = 4 + 4 + 4 + 4 + len(frame_id.encode()) + 1
    values_start = len(data) - 3 * 8
    assert 0 <= values_start - text_end < 8
    return data[:text_end] + bytes(values_start - text_end) + data[values_start:]
