"""Talking to a running ``foot_fk_node`` from a test: publish joint states, collect feet, call
services.

Importing it claims no ROS domain (conftest's type is for the checker only), so a bench script
(bench/soak.py) can use :func:`joint_state_message` on the domain it chose itself.
"""

from __future__ import annotations

import math
import time
from collections import defaultdict
from pathlib import Path
from typing import TYPE_CHECKING

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu, JointState
from shared import (
    LEGS,
    PYBULLET_NAMES,
    ROOT,
    STANDING,
    UNITREE_NAMES,
    ik_node_command,
    node_command,
)
from std_srvs.srv import Trigger

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from conftest import RosProbe

__all__ = [
    "LEGS",
    "PYBULLET_NAMES",
    "STANDING",
    "UNITREE_NAMES",
    "Diagnostics",
    "NodeClient",
    "SensorStream",
    "distance",
    "ik_node_command",
    "joint_state_message",
    "node_command",
    "package_root",
    "parse_tokens",
    "stamp_ns",
    "to_ros",
]


def joint_state_message(
    names: Iterable[str],
    positions: Iterable[float],
    velocities: Iterable[float] = (),
    *,
    stamp_ns: int,
) -> JointState:
    """A JointState of ``names`` with ``positions`` [rad] and ``velocities`` [rad/s], its header
    stamped ``stamp_ns`` [ns]."""
    msg = JointState(
        name=list(names),
        position=[float(v) for v in positions],
        velocity=[float(v) for v in velocities],
    )
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    return msg


class NodeClient:
    """Publisher of joint_states and collector of the node's feet, under a namespace prefix."""

    def __init__(self, probe: RosProbe, prefix: str = "", joint_states_topic: str = "") -> None:
        self.probe = probe
        node = probe.node
        self.prefix = prefix
        self.positions: dict[str, list[PointStamped]] = defaultdict(list)
        self.velocities: dict[str, list[Vector3Stamped]] = defaultdict(list)
        for leg in LEGS:
            node.create_subscription(
                PointStamped,
                f"{prefix}foot_positions/{leg}",
                self.positions[leg].append,
                QoSProfile(depth=1000),
            )
            node.create_subscription(
                Vector3Stamped,
                f"{prefix}foot_velocities/{leg}",
                self.velocities[leg].append,
                QoSProfile(depth=1000),
            )
        self.publisher = node.create_publisher(
            JointState, joint_states_topic or f"{prefix}joint_states", QoSProfile(depth=1000)
        )
        self.verify_client = node.create_client(Trigger, f"{prefix}verify_fk")
        self.parameters_client = node.create_client(
            SetParameters, f"{prefix}a1_leg_fk/set_parameters"
        )

    def joint_state(
        self, names, positions, velocities=(), stamp_ns: int | None = None
    ) -> JointState:
        """:func:`joint_state_message` stamped ``stamp_ns`` [ns], else now (the probe's clock)."""
        if stamp_ns is None:
            stamp_ns = self.probe.node.get_clock().now().nanoseconds
        return joint_state_message(names, positions, velocities, stamp_ns=stamp_ns)

    def wait_until_connected(self, timeout_s: float = 20.0) -> bool:
        """Publish the standing pose until the node's first FR foot comes back (discovery done)."""

        def answered() -> bool:
            if self.positions["FR"]:
                return True
            self.publisher.publish(self.joint_state(PYBULLET_NAMES, STANDING))
            return False

        ok = self.probe.spin_until(answered, timeout_s)
        self.probe.spin_for(0.3)
        self.clear()
        return ok

    def send(self, msg: JointState) -> None:
        self.publisher.publish(msg)

    def clear(self) -> None:
        for lists in (self.positions, self.velocities):
            for received in lists.values():
                received.clear()

    def wait_for_feet(self, count_per_leg: int = 1, legs=LEGS, timeout_s: float = 10.0) -> bool:
        return self.probe.spin_until(
            lambda: all(len(self.positions[leg]) >= count_per_leg for leg in legs), timeout_s
        )

    def verify(self, timeout_s: float = 10.0) -> Trigger.Response:
        return self.probe.call(self.verify_client, Trigger.Request(), timeout_s)

    def set_string_parameter(self, name: str, value: str, timeout_s: float = 20.0):
        return self.set_parameter(
            name,
            ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value),
            timeout_s,
        )

    def set_parameter(self, name: str, value: ParameterValue, timeout_s: float = 20.0):
        """SetParameters on the node; returns the SetParametersResult."""
        request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
        # A long first attempt: the request may be large (the robustness tests send 50 MB).
        return self.probe.call(self.parameters_client, request, timeout_s, attempt_s=10.0).results[
            0
        ]


class Diagnostics:
    """A node's latest /diagnostics status, as a dict of its key/values plus its message.

    ``name_suffix`` picks the status by the end of its name (the node's name comes first):
    ``"foot kinematics"`` (foot_fk_node) or ``"foot inverse kinematics"`` (foot_ik_node). The
    status's level (``DiagnosticStatus.OK``, ...) is :attr:`level`.
    """

    def __init__(self, probe: RosProbe, name_suffix: str = "foot kinematics") -> None:
        self.probe = probe
        self.name_suffix = name_suffix
        self.received = 0
        self.latest: dict[str, str] = {}
        self.level: bytes | None = None
        probe.node.create_subscription(
            DiagnosticArray, "/diagnostics", self._on_message, QoSProfile(depth=10)
        )

    def _on_message(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.name.endswith(self.name_suffix):
                self.latest = {kv.key: kv.value for kv in status.values}
                self.latest["message"] = status.message
                self.level = status.level
                self.received += 1

    def fresh(self, timeout_s: float = 5.0) -> dict[str, str]:
        """The next status published from now on (the nodes publish once a second)."""
        seen = self.received
        assert self.probe.spin_until(lambda: self.received > seen, timeout_s), (
            "no /diagnostics from the node"
        )
        return dict(self.latest)


LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
"""robot_state_publisher's robot_description QoS: a late subscriber still gets the latest
message."""


def parse_tokens(message: str) -> dict[str, str]:
    """``"a=1 b=2"`` -> ``{"a": "1", "b": "2"}``."""
    return dict(token.split("=", 1) for token in message.split() if "=" in token)


def stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def distance(point, xyz) -> float:
    return math.dist((point.x, point.y, point.z), tuple(xyz))


def package_root() -> Path:
    return ROOT


class SensorStream:
    """``imu`` and ``joint_states`` into a node, row by row at a fixed rate, as a robot (or a bag
    replay) would send them: each row's Imu first, then its JointState (or the other way round).
    """

    def __init__(self, probe: RosProbe, output_topic: str, timeout_s: float = 30.0) -> None:
        """Publishers (reliable, depth 1000); :attr:`ready` once the node subscribes to both and
        publishes ``output_topic``, and half a second more for its subscriptions to match ours.
        """
        self.probe = probe
        self.imu = probe.node.create_publisher(Imu, "imu", QoSProfile(depth=1000))
        self.joint_states = probe.node.create_publisher(
            JointState, "joint_states", QoSProfile(depth=1000)
        )
        self.ready = probe.spin_until(
            lambda: (
                self.imu.get_subscription_count() > 0
                and self.joint_states.get_subscription_count() > 0
                and probe.node.count_publishers(output_topic) > 0
            ),
            timeout_s,
        )
        if self.ready:
            probe.spin_for(0.5)

    def send(
        self,
        rows: int,
        messages: Callable[[int], tuple[Imu, JointState]],
        answered: Callable[[], int],
        rate_hz: float = 500.0,
        ahead: int = 40,
        imu_first: bool = True,
    ) -> None:
        """Publish ``messages(row)`` for every row at ``rate_hz``, unless the node (on a loaded
        machine) has answered (``answered()``) more than ``ahead`` rows fewer than were sent;
        each row's Imu first, or with ``imu_first`` false its JointState first.
        """
        probe = self.probe
        start = time.monotonic()
        for row in range(rows):
            imu, joint_state = messages(row)
            first, second = (
                (self.imu, self.joint_states) if imu_first else (self.joint_states, self.imu)
            )
            first.publish(imu if imu_first else joint_state)
            probe.executor.spin_once(timeout_sec=0.0002)  # the first one first, as in a bag
            second.publish(joint_state if imu_first else imu)
            delay = start + (row + 1) / rate_hz - time.monotonic()
            if delay > 0:
                probe.spin_for(delay)
            behind = row - ahead
            probe.spin_until(lambda: answered() >= behind, 10.0)  # noqa: B023 (used at once)


def to_ros(message, kind):
    """A rosbags message (bag_factory's) as the rclpy message of the same type."""
    out = kind()
    out.header.stamp.sec = message.header.stamp.sec
    out.header.stamp.nanosec = message.header.stamp.nanosec
    out.header.frame_id = message.header.frame_id
    if kind is JointState:
        out.name = list(message.name)
        out.position = message.position.tolist()
        out.velocity = message.velocity.tolist()
        out.effort = message.effort.tolist()
        return out
    for field in ("orientation", "angular_velocity", "linear_acceleration"):
        source, target = getattr(message, field), getattr(out, field)
        for axis in ("x", "y", "z", "w")[: 4 if field == "orientation" else 3]:
            setattr(target, axis, float(getattr(source, axis)))
    for field in ("orientation", "angular_velocity", "linear_acceleration"):
        setattr(out, f"{field}_covariance", getattr(message, f"{field}_covariance").tolist())
    return out
