"""The good and the well-formed absurd messages of the node fuzz's topics (issue 38; the
harness: test/node_fuzz.py, the nodes: test/fuzzed_nodes.py), serialized as the nodes receive
them.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence

from geometry_msgs.msg import PointStamped
from hostile_values import SPECIAL_VALUES
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Imu, JointState
from shared import PYBULLET_NAMES, STANDING
from std_msgs.msg import String


def frame_stamp(msg: object, stamp_ns: int) -> None:
    """Set ``msg.header.stamp`` to ``stamp_ns`` [ns]."""
    stamp = msg.header.stamp  # type: ignore[attr-defined]
    stamp.sec, stamp.nanosec = divmod(stamp_ns, 1_000_000_000)


def joint_state_bytes(stamp_ns: int, values: Sequence[float] = STANDING) -> bytes:
    """A JointState of the A1 (PyBullet's names), velocities and efforts included."""
    msg = JointState(name=list(PYBULLET_NAMES), position=[float(v) for v in values])
    msg.velocity = [0.1] * 12
    msg.effort = [2.0] * 12
    frame_stamp(msg, stamp_ns)
    return serialize_message(msg)


def imu_bytes(stamp_ns: int, rng: random.Random | None = None) -> bytes:
    """An Imu level and at rest, or (``rng``) one of well-formed absurd values."""
    msg = Imu()
    msg.orientation.w = 1.0
    msg.linear_acceleration.z = 9.81
    if rng is not None:
        pick = rng.choice
        q = msg.orientation
        q.x, q.y, q.z, q.w = (pick([*SPECIAL_VALUES, 0.0]) for _ in range(4))
        w, a = msg.angular_velocity, msg.linear_acceleration
        w.x, w.y, w.z = (pick(SPECIAL_VALUES) for _ in range(3))
        a.x, a.y, a.z = (pick([*SPECIAL_VALUES, 1e6, -1e6]) for _ in range(3))
        msg.orientation_covariance[0] = pick([-1.0, 0.0, math.nan, 1e300])
        msg.angular_velocity_covariance[0] = pick([-1.0, 0.0, math.inf])
    frame_stamp(msg, stamp_ns)
    return serialize_message(msg)


def absurd_joint_state(stamp_ns: int, rng: random.Random) -> bytes:
    """A JointState of the A1's names with absurd values and array lengths."""
    values = [rng.choice(SPECIAL_VALUES) for _ in range(12)]
    msg = JointState(name=list(PYBULLET_NAMES), position=values)
    msg.velocity = [rng.choice(SPECIAL_VALUES) for _ in range(rng.choice([0, 11, 12, 13]))]
    msg.effort = [rng.choice([1e300, -1e6, math.nan]) for _ in range(rng.choice([0, 12, 40]))]
    frame_stamp(msg, stamp_ns)
    return serialize_message(msg)


def point_bytes(stamp_ns: int, xyz: Sequence[float]) -> bytes:
    msg = PointStamped()
    msg.point.x, msg.point.y, msg.point.z = (float(v) for v in xyz)
    frame_stamp(msg, stamp_ns)
    return serialize_message(msg)


def string_bytes(text: str) -> bytes:
    return serialize_message(String(data=text))


ABSURD_DESCRIPTIONS = (
    "",
    "hello robot",
    "<robot name='x'/>",
    "<robot name='x'><link name='a'>",
    "\u0000" * 3 + "\U0001f9bf" * 50,
)
