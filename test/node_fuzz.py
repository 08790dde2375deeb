"""Damaged messages on every input topic of a running node (issue 38): the harness of the CI fuzz
(test/ros/test_input_fuzz.py) and of ``make fuzz`` (bench/fuzz_nodes.py); the nodes:
test/fuzzed_nodes.py, the run and its checks: test/node_fuzz_run.py.

Each input topic gets serialized messages published raw (a publisher of the topic's type given
bytes), interleaved with good input the node must answer. Damage whose outcome is known by
construction (:data:`KNOWN`): bytes cut short and a length field of gigabytes cannot be read;
bytes appended (CDR readers ignore what follows the last field) and well-formed absurd values
(NaN, infinities, 1e300, a zero quaternion, 1e6 m/s^2, another robot's text) can (checked
offline against the nodes' own readers: test/ros/test_fuzz_generator.py). Damage whose outcome is
not known beforehand (:data:`UNKNOWN`: bit flips anywhere, another message type's bytes on the
topic). The counts are checked exactly, whatever a best-effort transport drops: in a phase of
unreadable messages only, the node's ``rejected_<topic>_malformed`` grows by what its
``received_<topic>`` grows (:meth:`NodeFuzz.settled`); in a phase of readable ones only, by 0.
"""

from __future__ import annotations

import math
import random
import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from diagnostic_msgs.msg import DiagnosticArray
from fuzz_messages import imu_bytes, joint_state_bytes, point_bytes, string_bytes
from geometry_msgs.msg import PointStamped, Vector3Stamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

TRUNCATED, ABSURD_LENGTH, EXTENDED, ABSURD_VALUES = (
    "truncated",
    "absurd length",
    "extended",
    "absurd values",
)
"""Truncated messages keep at least 8 bytes (the rmw may not deliver a payload of its 4-byte
encapsulation alone) and lose at least 4 of their fields' bytes: Fast DDS pads a payload with
zeros to a multiple of 4 bytes, which completes a message cut 1 to 3 bytes short (found by the
exact count: 3 of 40 such PointStamped were read)."""
BIT_FLIPS, OTHER_TYPE = "bit flips", "another type"
KNOWN = (TRUNCATED, ABSURD_LENGTH, EXTENDED, ABSURD_VALUES)
UNKNOWN = (BIT_FLIPS, OTHER_TYPE)
UNREADABLE = (TRUNCATED, ABSURD_LENGTH)
ABSURD_LENGTHS = (0xFFFFFFFF, 0x80000000, 0x7FFFFFF0, 1 << 24)
FRAME_ID_LENGTH = 12
"""Where a message that starts with a std_msgs/Header keeps its frame_id's length (after the
4-byte encapsulation and the stamp)."""
READABLE = (EXTENDED, ABSURD_VALUES)
BATCH = 25
"""Damaged messages between two good inputs (well under the nodes' queue of 100)."""
QUIET_S = 0.2
"""How long no answer must come before drives whose answers are counted are sent [s]."""


@dataclass
class InputTopic:
    """One input topic of a node: its type, a good message and a well-formed absurd one, the
    offsets of its length fields, and the QoS to publish it with.
    """

    topic: str
    message: type
    good: Callable[[int], bytes]  # stamp [ns] -> bytes
    absurd: Callable[[int, random.Random], bytes]
    read: Callable[[bytes], object]  # the node's reader of the topic's bytes
    length_offsets: tuple[int, ...] = (FRAME_ID_LENGTH,)
    qos: QoSProfile = field(default_factory=lambda: QoSProfile(depth=1000))
    pause_s: float = 0.0  # between messages (a keep-last-1 reader keeps only the latest)
    good_each_batch: bool = True  # False: the good message only once, when connecting
    other: Callable[[int, random.Random], bytes] | None = None  # a like type's bytes (a layout)

    @property
    def kinds(self) -> tuple[str, ...]:
        """The damage it can be sent: a fixed-size type (no length field, ``length_offsets``
        empty) has no length to make absurd, and Fast DDS refuses to publish more bytes than
        its size ("cannot publish data"), so none appended."""
        fixed = () if self.length_offsets else (ABSURD_LENGTH, EXTENDED)
        return tuple(kind for kind in KNOWN + UNKNOWN if kind not in fixed)

    @property
    def unreadable(self) -> tuple[str, ...]:
        """Its damage unreadable by construction."""
        return tuple(kind for kind in UNREADABLE if kind in self.kinds)

    @property
    def readable(self) -> tuple[str, ...]:
        """Its damage readable by construction."""
        return tuple(kind for kind in READABLE if kind in self.kinds)


def data_length(raw: bytes, read: Callable[[bytes], object]) -> int:
    """The bytes of ``raw`` its fields take, for the node's reader ``read``: rclpy's serializer
    may leave a few bytes after them, which a reader never looks at.
    """
    low, high = 4, len(raw)  # read(raw[:high]) works, read(raw[:low]) does not
    while high - low > 1:
        middle = (low + high) // 2
        try:
            read(raw[:middle])
        except Exception:  # noqa: BLE001 (whatever the reader raises: too short)
            low = middle
        else:
            high = middle
    return high


def damaged(kind: str, topic: InputTopic, stamp_ns: int, rng: random.Random) -> bytes:
    """One message of ``topic`` damaged as ``kind`` says."""
    good = topic.good(stamp_ns)
    if kind == TRUNCATED:
        return good[: rng.randrange(8, data_length(good, topic.read) - 3)]  # see TRUNCATED
    if kind == ABSURD_LENGTH:
        data = bytearray(good)
        struct.pack_into("<I", data, rng.choice(topic.length_offsets), rng.choice(ABSURD_LENGTHS))
        return bytes(data)
    if kind == EXTENDED:
        return good + rng.randbytes(rng.randrange(1, 200))
    if kind == ABSURD_VALUES:
        return topic.absurd(stamp_ns, rng)
    if kind == BIT_FLIPS:
        data = bytearray(good)
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        return bytes(data)
    others = [
        joint_state_bytes(stamp_ns),
        imu_bytes(stamp_ns),
        point_bytes(stamp_ns, (0.1, 0.2, -0.3)),
        string_bytes("<robot/>"),
        rng.randbytes(rng.randrange(0, 400)),
        *([topic.other(stamp_ns, rng)] if topic.other else []),
    ]
    return rng.choice([raw for raw in others if topic.length_offsets or len(raw) <= len(good)])


@dataclass
class Tally:
    """What was sent to one topic."""

    unreadable_kinds: tuple[str, ...] = UNREADABLE
    sent: dict[str, int] = field(default_factory=lambda: dict.fromkeys(KNOWN + UNKNOWN, 0))
    asked: int = 0  # good inputs sent after a batch of this topic's damage
    answered: int = 0  # and answered

    @property
    def unreadable(self) -> int:
        return sum(self.sent[kind] for kind in self.unreadable_kinds)

    @property
    def unknown(self) -> int:
        return sum(self.sent[kind] for kind in UNKNOWN)


def header_stamp(msg: object) -> object:
    """An output's header stamp [ns]: what answers a drive stamped so."""
    stamp = msg.header.stamp  # type: ignore[attr-defined]
    return stamp.sec * 1_000_000_000 + stamp.nanosec


@dataclass
class FuzzedNode:
    """A node under fuzz: its command, its input topics, how to drive it (publish one good input
    with a stamp [ns]) and the output topic whose stamps answer the drive, and the outputs
    checked for finite values.
    """

    name: str
    command: list[str]
    inputs: list[InputTopic]
    status: str  # the end of its /diagnostics status name
    drive_topic: str
    drive: Callable[[int], bytes]
    answer: tuple[str, type]
    outputs: dict[str, type]
    env: dict[str, str] = field(default_factory=dict)  # for the node's process
    answer_key: Callable[[object], object] = header_stamp  # of an answer
    expected: Callable[[int], object] = int  # the key answering the drive of a stamp [ns]
    counted: int = 0
    """Above 0: its answers cannot be matched to drives (stamped with the receive time), so they
    are counted: each check sends this many drives and wants at least as many more answers."""


def all_values(msg: object) -> list[float]:
    """The floats of an output message the checks look at."""
    if isinstance(msg, PointStamped):
        return [msg.point.x, msg.point.y, msg.point.z]
    if isinstance(msg, Vector3Stamped):
        return [msg.vector.x, msg.vector.y, msg.vector.z]
    if isinstance(msg, WrenchStamped):
        f = msg.wrench.force
        return [f.x, f.y, f.z]
    if isinstance(msg, Odometry):
        p, q, v, w = (
            msg.pose.pose.position,
            msg.pose.pose.orientation,
            *((msg.twist.twist.linear, msg.twist.twist.angular)),
        )
        return [p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z,
                *msg.pose.covariance, *msg.twist.covariance]  # fmt: skip
    if isinstance(msg, JointState):
        return list(msg.position)
    raise TypeError(type(msg))


class NodeFuzz:
    """Publishers of every input and subscribers of every output of one running node."""

    def __init__(self, probe, node: FuzzedNode, seed: int) -> None:
        self.probe = probe
        self.node = node
        self.rng = random.Random(seed)
        self.publishers = {
            topic.topic: probe.node.create_publisher(topic.message, topic.topic, topic.qos)
            for topic in node.inputs
        }
        if node.drive_topic not in self.publishers:
            self.publishers[node.drive_topic] = probe.node.create_publisher(
                JointState, node.drive_topic, QoSProfile(depth=1000)
            )
        self.tallies = {topic.topic: Tally(topic.unreadable) for topic in node.inputs}
        self.answered: set[object] = set()
        self.answers = 0  # messages on the answer topic
        self.non_finite: list[str] = []
        self.outputs = 0
        answer_topic = node.answer[0]
        for topic, kind in node.outputs.items():
            probe.node.create_subscription(
                kind, topic, self._output(topic, topic == answer_topic), QoSProfile(depth=1000)
            )
        self.diagnostics: dict[str, str] = {}
        self.diagnostics_received = 0
        probe.node.create_subscription(
            DiagnosticArray, "/diagnostics", self._on_diagnostics, QoSProfile(depth=10)
        )

    def _output(self, topic: str, answers: bool) -> Callable[[object], None]:
        def on_output(msg: object) -> None:
            self.outputs += 1
            values = all_values(msg)
            if not all(math.isfinite(v) for v in values):
                self.non_finite.append(f"{topic}: {values}")
            if answers:
                self.answers += 1
                self.answered.add(self.node.answer_key(msg))

        return on_output

    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.name.endswith(self.node.status):
                self.diagnostics = {kv.key: kv.value for kv in status.values}
                self.diagnostics_received += 1

    def now_ns(self) -> int:
        return int(self.probe.node.get_clock().now().nanoseconds)

    def good_input_answered(self, timeout_s: float = 15.0, every: bool = False) -> bool:
        """Publish a good message on every input (``every``: also those sent only once), then
        the drive; True once it is answered.
        """
        for topic in self.node.inputs:
            if topic.topic != self.node.drive_topic and (every or topic.good_each_batch):
                self.publishers[topic.topic].publish(topic.good(self.now_ns()))
        self.probe.spin_for(0.01)
        if self.node.counted:
            return self.drives_counted(timeout_s)
        stamp = self.now_ns()
        self.publishers[self.node.drive_topic].publish(self.node.drive(stamp))
        wanted = self.node.expected(stamp)
        return self.probe.spin_until(lambda: wanted in self.answered, timeout_s)

    def drives_counted(self, timeout_s: float) -> bool:
        """Once no answer came for :data:`QUIET_S` (those of damaged messages still on their way
        would count as the drives'), publish ``counted`` drives; True once at least as many
        more answers arrived within ``timeout_s``.
        """
        wanted, seen = self.node.counted, -1
        deadline = time.monotonic() + timeout_s
        while self.answers != seen and time.monotonic() < deadline:
            seen = self.answers
            self.probe.spin_for(QUIET_S)
        before = self.answers
        for _ in range(wanted):
            self.publishers[self.node.drive_topic].publish(self.node.drive(self.now_ns()))
            self.probe.spin_for(0.002)
        return self.probe.spin_until(lambda: self.answers >= before + wanted, timeout_s)

    def wait_connected(self, timeout_s: float = 30.0) -> bool:
        """Drive the node until it answers (discovery done both ways) with the robot of the
        good robot_description (its /diagnostics ``model``), if it is one of its inputs.
        """
        fuzzed = {topic.topic for topic in self.node.inputs}
        model = "robot_description" if "robot_description" in fuzzed else ""
        return self.probe.spin_until(
            lambda: (
                self.good_input_answered(0.5, every=True)
                and model in self.diagnostics.get("model", "")
            ),
            timeout_s,
        )

    def send(self, topic: InputTopic, kinds: Sequence[str], count: int) -> list[str]:
        """``count`` damaged messages of ``kinds`` on ``topic`` in batches, the good input after
        each; the batches whose good input was not answered.
        """
        tally, missed = self.tallies[topic.topic], []
        for start in range(0, count, BATCH):
            self.send_only(topic, kinds, min(BATCH, count - start))
            tally.asked += 1
            if self.good_input_answered():
                tally.answered += 1
            else:
                missed.append(f"{topic.topic}: no answer after message {start + BATCH}")
        return missed

    def send_only(self, topic: InputTopic, kinds: Sequence[str], count: int) -> None:
        """``count`` damaged messages of ``kinds`` on ``topic``, nothing else."""
        publisher, tally = self.publishers[topic.topic], self.tallies[topic.topic]
        kinds = [kind for kind in kinds if kind in topic.kinds]
        for _ in range(count):
            kind = self.rng.choice(kinds)
            publisher.publish(damaged(kind, topic, self.now_ns(), self.rng))
            tally.sent[kind] += 1
            if topic.pause_s:
                self.probe.spin_for(topic.pause_s)
            else:
                self.probe.executor.spin_once(timeout_sec=0.0005)

    def rejected(self, topic: str) -> int:
        """The latest report's ``rejected_<topic>_malformed`` (-1: none yet)."""
        return int(self.diagnostics.get(f"rejected_{key_of(topic)}_malformed", "-1"))

    def rejected_values(self) -> dict[str, str]:
        """The latest report's ``received_*`` and ``rejected_*`` values."""
        wanted = ("received_", "rejected_")
        return {k: v for k, v in self.diagnostics.items() if k.startswith(wanted)}

    def counts(self) -> dict[str, tuple[int, int]]:
        """Per input topic: (``received_<topic>``, ``rejected_<topic>_malformed``) of the latest
        report (-1: absent).
        """
        values = self.diagnostics
        return {
            topic: (int(values.get(f"received_{key_of(topic)}", "-1")), self.rejected(topic))
            for topic in self.tallies
        }

    def settled(self, timeout_s: float = 30.0) -> dict[str, tuple[int, int]] | None:
        """:meth:`counts` once two successive reports agree on them (the node has read all that
        reached it: its report timer runs between its subscription callbacks); None if they do
        not within ``timeout_s``.
        """
        deadline, previous = time.monotonic() + timeout_s, None
        while time.monotonic() < deadline:
            if not self.fresh_report():
                return None
            now = self.counts()
            if now == previous:
                return now
            previous = now
        return None

    def fresh_report(self, timeout_s: float = 5.0) -> bool:
        """Spin until the node's next /diagnostics report (False: none within ``timeout_s``)."""
        seen = self.diagnostics_received
        return self.probe.spin_until(lambda: self.diagnostics_received > seen, timeout_s)


def key_of(topic: str) -> str:
    """A topic as its /diagnostics keys name it."""
    return topic.strip("/").replace("/", "_")
