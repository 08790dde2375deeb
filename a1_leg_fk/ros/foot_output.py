"""What ``foot_fk_node`` publishes per JointState: the feet (``foot_positions/<leg>``,
``foot_velocities/<leg>``), the foot forces (``foot_forces/<leg>``) and the contacts
(``foot_contacts``).

Each goes out as bytes patched into a message serialized once (the feet:
:mod:`a1_leg_fk.ros.serialized_output`; the forces and contacts: the bag tools' CDR writers of
:mod:`a1_leg_fk.recording.bag_writer`, so the node and ``a1-leg-fk bag --output-bag`` write the
same bytes), published through :func:`~a1_leg_fk.ros.serialized_output.raw_publish`, or as
message objects where ``preserialized_output`` is off or the rmw's CDR is not the little-endian
one patched here.
"""

from __future__ import annotations

from collections.abc import Sequence

from geometry_msgs.msg import PointStamped, Vector3Stamped, WrenchStamped
from rclpy.node import Node
from rclpy.publisher import Publisher
from sensor_msgs.msg import JointState

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.ros.glue import OUTPUT_QOS
from a1_leg_fk.ros.serialized_output import SerializedStamped, raw_publish
from a1_leg_fk.tracking import Foot
from a1_leg_fk.wire.output import (
    contacts_bytes,
    contacts_layout,
    frame_bytes,
    wrench_bytes,
)


class FootOutput:
    """The node's per-message publishers, all in the base frame."""

    def __init__(self, node: Node) -> None:
        def publishers(kind: type, prefix: str) -> list[Publisher]:
            return [
                node.create_publisher(kind, f"{prefix}/{leg}", OUTPUT_QOS) for leg in LEG_NAMES
            ]

        self._positions = publishers(PointStamped, "foot_positions")
        self._velocities = publishers(Vector3Stamped, "foot_velocities")
        self._forces = publishers(WrenchStamped, "foot_forces")
        self._contacts = node.create_publisher(JointState, "foot_contacts", OUTPUT_QOS)
        self._position_msgs = [PointStamped() for _ in LEG_NAMES]
        self._velocity_msgs = [Vector3Stamped() for _ in LEG_NAMES]
        self._force_msgs = [WrenchStamped() for _ in LEG_NAMES]
        self._contacts_msg = JointState(name=list(LEG_NAMES))
        self._raw_positions, self._raw_velocities, self._raw_forces = (
            [raw_publish(publisher) for publisher in publishers]
            for publishers in (self._positions, self._velocities, self._forces)
        )
        self._raw_contacts = raw_publish(self._contacts)
        self.configure("", preserialized=False)

    def configure(self, base_frame: str, preserialized: bool) -> None:
        """Stamp every output with ``base_frame``; publish bytes if ``preserialized`` and the
        rmw's CDR is the one patched (checked on a probe message), else message objects.
        """
        messages = (
            *self._position_msgs,
            *self._velocity_msgs,
            *self._force_msgs,
            self._contacts_msg,
        )
        for msg in messages:
            msg.header.frame_id = base_frame
        writer = SerializedStamped(base_frame) if preserialized else None
        self._serialized = writer if writer is not None and writer.usable else None
        self._frame_head = frame_bytes(base_frame)
        self._contacts_layout = contacts_layout(base_frame)

    @property
    def preserialized(self) -> bool:
        """True while the outputs go out as patched bytes."""
        return self._serialized is not None

    def feet(self, feet: list[Foot], sec: int, nanosec: int, velocities: bool) -> None:
        """Publish each foot's position [m] and, if ``velocities`` and it has one, velocity
        [m/s], stamped ``sec``, ``nanosec``.
        """
        serialized = self._serialized
        if serialized is not None:
            for foot in feet:
                slot = foot.leg_slot
                self._raw_positions[slot](serialized.serialized(sec, nanosec, foot.position))
                if foot.velocity is not None and velocities:
                    self._raw_velocities[slot](serialized.serialized(sec, nanosec, foot.velocity))
            return
        for foot in feet:
            position_msg = self._position_msgs[foot.leg_slot]
            _stamp(position_msg, sec, nanosec)
            point = position_msg.point
            point.x, point.y, point.z = foot.position
            self._positions[foot.leg_slot].publish(position_msg)
            if foot.velocity is not None and velocities:
                velocity_msg = self._velocity_msgs[foot.leg_slot]
                _stamp(velocity_msg, sec, nanosec)
                vector = velocity_msg.vector
                vector.x, vector.y, vector.z = foot.velocity
                self._velocities[foot.leg_slot].publish(velocity_msg)

    def forces(
        self,
        forces: Sequence[Sequence[float]],
        normal: Sequence[float],
        probabilities: Sequence[float],
        sec: int,
        nanosec: int,
    ) -> None:
        """Publish ``foot_forces/<leg>`` for each leg with a force [N] (not NaN) and, if any
        has one or any leg has a contact probability, ``foot_contacts`` (the probabilities and
        normal forces [N], NaN for the legs without them).
        """
        serialized = self._serialized is not None
        published = False
        for slot, force in enumerate(forces):
            x, y, z = force
            if x != x or y != y or z != z:  # noqa: PLR0124 (NaN: no force)
                continue
            published = True
            if serialized:
                self._raw_forces[slot](wrench_bytes(self._frame_head, sec, nanosec, force))
                continue
            msg = self._force_msgs[slot]
            _stamp(msg, sec, nanosec)
            msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = x, y, z
            self._forces[slot].publish(msg)
        if not published and not any(p == p for p in probabilities):  # noqa: PLR0124 (NaN)
            return
        if serialized:
            self._raw_contacts(
                contacts_bytes(self._contacts_layout, sec, nanosec, probabilities, normal)
            )
            return
        contacts = self._contacts_msg
        _stamp(contacts, sec, nanosec)
        contacts.position, contacts.effort = list(probabilities), list(normal)
        self._contacts.publish(contacts)


def _stamp(
    msg: PointStamped | Vector3Stamped | WrenchStamped | JointState, sec: int, nanosec: int
) -> None:
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
