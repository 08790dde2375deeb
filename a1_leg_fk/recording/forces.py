"""Foot forces and contacts over a recording (``a1-leg-fk bag --forces``): the JointState efforts
through :mod:`a1_leg_fk.kinematics.foot_forces` and :mod:`a1_leg_fk.estimation.contacts`, the same
rules the node uses. Gravity's direction comes from an ``sensor_msgs/msg/Imu`` topic (the nearest
sample in time; an IMU aligned with the base), else the base is taken as level. No ROS install:
the bag is read through :class:`~a1_leg_fk.recording.reads.RecordingReads`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_forces
from a1_leg_fk.estimation.imu import has_orientation
from a1_leg_fk.kinematics.foot_forces import LEVEL_GRAVITY, FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, gravity_in_base
from a1_leg_fk.model.legs import JOINT_COUNT
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.joint_state_wire import JointStateDecoder, WireError

if TYPE_CHECKING:  # rosbags is imported when a bag is read
    from rosbags.interfaces import Connection

    from a1_leg_fk.kinematics.quadruped import Quadruped
    from a1_leg_fk.recording.reads import RecordingReads

IMU_TYPE = "sensor_msgs/msg/Imu"


class MissingEfforts(LegFkError):
    """The recording's JointStates carry no joint efforts."""


@dataclass(frozen=True)
class ImuGravity:
    """Gravity [m/s^2] in the base frame over time, from an IMU's orientation (the IMU aligned
    with the base): ``stamps_ns`` sorted (M,), ``gravity`` (M, 3).
    """

    stamps_ns: np.ndarray
    gravity: np.ndarray
    topic: str

    @classmethod
    def read(cls, reads: RecordingReads, connection: Connection) -> ImuGravity:
        """Every message of ``connection`` that has an orientation
        (:func:`~a1_leg_fk.estimation.imu.has_orientation`), up to damage;
        :class:`LegFkError` if none has (:class:`DamagedRecording` if damage came first).
        """
        stamps, quaternions = [], []
        message: Any
        for bag_time, message in reads.decoded(connection):
            q = message.orientation
            if not has_orientation(float(message.orientation_covariance[0]), (q.x, q.y, q.z, q.w)):
                continue
            stamp = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
            stamps.append(stamp or bag_time)
            quaternions.append((q.x, q.y, q.z, q.w))
        if not quaternions:
            reads.check()
            raise LegFkError(
                f"--imu {connection.topic}: no message with an orientation (a rotation quaternion "
                "with orientation_covariance[0] != -1)"
            )
        order = np.argsort(np.array(stamps, dtype=np.int64), kind="stable")
        rotations = np.array(quaternions, dtype=float)[order]
        unit = rotations / np.linalg.norm(rotations, axis=1)[:, None]
        return cls(
            np.array(stamps, dtype=np.int64)[order], gravity_in_base(unit), connection.topic
        )

    def at(self, stamps_ns: np.ndarray) -> np.ndarray:
        """(N, 3) gravity [m/s^2] of the sample nearest in time to each stamp [ns]."""
        after = np.clip(np.searchsorted(self.stamps_ns, stamps_ns), 1, len(self.stamps_ns) - 1)
        if len(self.stamps_ns) == 1:
            return np.broadcast_to(self.gravity[0], (len(stamps_ns), 3))
        before = after - 1
        nearer = np.where(
            stamps_ns - self.stamps_ns[before] <= self.stamps_ns[after] - stamps_ns, before, after
        )
        return self.gravity[nearer]


@dataclass
class ForceCounts:
    """Legs of the rows of a pass: with a force, without (efforts missing or not finite, or a
    JointState whose effort array does not match its names), near-singular.
    """

    estimated: int = 0
    missing: int = 0
    singular: int = 0

    def line(self) -> str:
        """The summary line."""
        return (
            f"forces:    {self.estimated} leg forces; none for {self.missing} legs (efforts "
            f"missing, NaN or of the wrong length) and {self.singular} near-singular legs"
        )


class ForcePass:
    """Forces and contact probabilities row by row over one pass (the contact rule's state is
    carried from block to block).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        imu: ImuGravity | None,
        thresholds: Sequence[float | None] = (None, None),
    ) -> None:
        """``thresholds``: touchdown and liftoff normal forces [N], ``None`` for the default
        (:meth:`ContactThresholds.for_weight` of the URDF's total mass).
        """
        self.model = FootForces(quadruped)
        self.name_to_slot: Mapping[str, int] = quadruped.name_to_slot
        self.imu = imu
        weight = self.model.total_mass_kg * STANDARD_GRAVITY
        self.thresholds = ContactThresholds.for_weight(weight, *thresholds)
        self.restart()

    def restart(self) -> None:
        """A new pass: every foot in swing, counts zero."""
        self.rule = ContactRule(self.thresholds)
        self.counts = ForceCounts()

    def slot_efforts(self, names: Sequence[str], efforts: np.ndarray) -> np.ndarray:
        """(K, 12) efforts [N m] in slot order from the messages' (K, m) effort arrays; NaN for
        joints not named, and for every joint when ``m`` is not the number of names.
        """
        out = np.full((efforts.shape[0], JOINT_COUNT), math.nan)
        if efforts.shape[1] != len(names):
            return out
        known = [(i, self.name_to_slot.get(name)) for i, name in enumerate(names)]
        pairs = [(i, slot) for i, slot in known if slot is not None]
        if pairs:
            out[:, [slot for _, slot in pairs]] = efforts[:, [i for i, _ in pairs]]
        return out

    def rows(
        self, stamps_ns: np.ndarray, angles: np.ndarray, efforts: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, 4, 3) forces [N, base frame], (N, 4) normal forces [N] along minus gravity and
        (N, 4) contact probabilities for rows of (N, 12) angles [rad] and efforts [N m] (NaN
        where unknown).
        """
        gravity = LEVEL_GRAVITY if self.imu is None else self.imu.at(stamps_ns)
        estimate = self.model.estimate_batch(angles, efforts, gravity)
        self.counts.missing += int(estimate.missing.sum())
        self.counts.singular += int(estimate.singular.sum())
        self.counts.estimated += int(np.isfinite(estimate.forces).all(axis=2).sum())
        normal = normal_forces(estimate.forces, gravity)
        return estimate.forces, normal, self.rule.update_batch(normal)

    def message(
        self, angles: Sequence[float], efforts: Sequence[float], gravity: Sequence[float]
    ) -> tuple[list[list[float]], list[float], list[float]]:
        """:meth:`rows` for one message, on floats (the node's per-message path): 4 forces [N,
        base frame], 4 normal forces [N] and 4 contact probabilities for 12 angles [rad], 12
        efforts [N m] (NaN where unknown) and gravity (3,) [m/s^2] in the base frame.
        """
        forces, missing, singular = self.model.estimate_floats(angles, efforts, gravity)
        counts = self.counts
        counts.missing += sum(missing)
        counts.singular += sum(singular)
        gx, gy, gz = gravity
        scale = -1.0 / math.sqrt(gx * gx + gy * gy + gz * gz)  # up = -gravity / |gravity|
        ux, uy, uz = gx * scale, gy * scale, gz * scale
        normal = [x * ux + y * uy + z * uz for x, y, z in forces]
        counts.estimated += sum(1 for value in normal if value == value)  # noqa: PLR0124 (NaN)
        return forces, normal, self.rule.update(normal)

    def message_efforts(self, names: Sequence[str], efforts: Sequence[float]) -> list[float]:
        """One message's efforts [N m] in slot order (as :meth:`slot_efforts`): NaN for joints
        not named, and for every joint when there are not as many efforts as names.
        """
        out = [math.nan] * JOINT_COUNT
        if len(efforts) == len(names):
            slots = self.name_to_slot
            for name, value in zip(names, efforts, strict=True):
                slot = slots.get(name)
                if slot is not None:
                    out[slot] = value
        return out


def check_has_efforts(
    reads: RecordingReads, connection: Connection, ros1: bool, needs: str = "--forces"
) -> None:
    """:class:`LegFkError` if the first JointState of ``connection`` has no efforts (``needs``:
    the option that needs them, for the message). Damage before it or in it decides nothing:
    the pass over the JointStates ends there.
    """
    for _, bag_time, raw in reads.messages([connection]):
        try:
            efforts = JointStateDecoder(ros1).fields(raw).efforts
        except WireError as error:
            reads.undecodable(bag_time, 1, connection.topic, str(error))
            return
        if not efforts:
            raise MissingEfforts(
                f"{connection.topic}: its JointState messages carry no efforts (the first one's "
                f"effort array is empty); {needs} needs joint efforts"
            )
        return
