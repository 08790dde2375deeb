"""Every subscription of every node goes through one guarded read (issue 38): a message that
cannot be read is counted per topic and reason, warned about (at most once a second per topic and
reason, with the reason) and dropped; the node keeps its last good state and goes on.

A subscription is raw (the serialized bytes) and names two functions: ``read`` (bytes -> what the
node takes: a wire decoder, :func:`read_imu`, :func:`message_reader`) and ``use`` (the node's
handling of it). Whatever ``read`` raises means the bytes cannot be read ("malformed": truncated,
bit flips, a length field of gigabytes, another message type's bytes); ``use`` is the node's own
code and is not guarded, so a bug in it still surfaces. The good path costs one function call
more than a plain subscription (no work per field).

``use`` may call :meth:`GuardedInputs.reject` for a message that was read but cannot be used
(e.g. ``non_finite``). The counts are ``/diagnostics`` values ``rejected_<topic>_<reason>``
(:meth:`GuardedInputs.values`; the topic as subscribed, ``/`` as ``_``):
``rejected_imu_malformed``, ``rejected_foot_targets_FR_malformed``, ..., beside
``received_<topic>``: every message the subscription was given, read or not (one increment on the
good path), so that a count of rejected messages can be checked against what arrived, whatever
a best-effort transport dropped on the way.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from typing import Any, TypeVar

from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu

from a1_leg_fk.ros.glue import WarnThrottle
from a1_leg_fk.ros.odometry_wire import imu_message_fields
from a1_leg_fk.wire.imu import ImuFields, imu_fields

MALFORMED = "malformed"
"""The reason of a message whose bytes cannot be read."""
T = TypeVar("T")


class GuardedInputs:
    """A node's guarded subscriptions and their counts of rejected messages."""

    def __init__(self, node: Node) -> None:
        self._node = node
        self._warnings = WarnThrottle(node)
        self.rejected: Counter[str] = Counter()
        """Messages rejected so far, by ``<topic>_<reason>``."""
        self._reported = 0  # the total at the previous :meth:`rejected_since`
        self._received: dict[str, list[int]] = {}  # per topic key: [messages received]
        self.callbacks: dict[str, Callable[[bytes], None]] = {}
        """Each topic's subscription callback (bytes in), as rclpy calls it."""

    def subscribe(
        self,
        message: type,
        topic: str,
        read: Callable[[bytes], T],
        use: Callable[[T], None],
        qos: QoSProfile,
        **options: Any,
    ) -> None:
        """Subscribe ``topic`` (``message``'s type, raw): each message's bytes through ``read``,
        what it gives to ``use``; a message ``read`` raises on is counted, warned about and
        dropped. ``options``: :meth:`rclpy.node.Node.create_subscription`'s.
        """
        key = topic.strip("/").replace("/", "_")
        self.rejected[f"{key}_{MALFORMED}"] += 0  # listed from the start
        received = self._received.setdefault(key, [0])
        reject = self.reject

        def on_message(raw: bytes) -> None:
            received[0] += 1
            try:
                value = read(raw)
            except Exception as error:  # noqa: BLE001 (bytes that cannot be read, whatever the reader says)
                reject(topic, MALFORMED, f"{type(error).__name__}: {error}", len(raw))
                return
            use(value)

        self.callbacks[topic] = on_message
        self._node.create_subscription(message, topic, on_message, qos, raw=True, **options)

    def reject(self, topic: str, reason: str, detail: str, size: int | None = None) -> None:
        """Count a message of ``topic`` rejected for ``reason`` and warn (throttled) with the
        ``detail``; ``size``: its length [bytes], where known.
        """
        key = f"{topic.strip('/').replace('/', '_')}_{reason}"
        self.rejected[key] += 1
        what = f" ({size} bytes)" if size is not None else ""
        self._warnings.warn(
            key,
            f"ignoring a message on {self._node.resolve_topic_name(topic)}{what}: {reason}: "
            f"{' '.join(detail.split())[:200]} ({self.rejected[key]} {reason} so far)",
        )

    def values(self) -> dict[str, int]:
        """The ``/diagnostics`` values: ``received_<topic>`` and ``rejected_<topic>_<reason>``
        -> messages.
        """
        received = {f"received_{key}": count[0] for key, count in sorted(self._received.items())}
        return received | {f"rejected_{key}": n for key, n in sorted(self.rejected.items())}

    def rejected_since(self) -> int:
        """Messages rejected since the previous call (all of them at the first)."""
        total = self.rejected.total()
        since, self._reported = total - self._reported, total
        return since


def read_imu(raw: bytes) -> ImuFields:
    """A serialized sensor_msgs/msg/Imu's fields: from its bytes (:func:`imu_fields`), else
    deserialized (another byte order, padding); raises if it cannot be read.
    """
    return imu_fields(raw) or imu_message_fields(deserialize_message(raw, Imu))


def message_reader(message: type[T]) -> Callable[[bytes], T]:
    """A ``read`` deserializing bytes into a ``message`` object (rclpy's; raises on bytes that
    are not one).
    """

    def read(raw: bytes) -> T:
        return deserialize_message(raw, message)  # type: ignore[no-any-return]

    return read
