"""Foot forces and contacts over a recording (``a1-leg-fk bag --forces/--contacts``, ``gait``) and
in the node, one joint state at a time: the pipeline of
:mod:`a1_leg_fk.estimation.contact_estimator`, fed the JointState's angles, rates and efforts (a
recording without efforts still gets kinematic contacts). The IMU comes from an
``sensor_msgs/msg/Imu`` topic (the nearest sample in time; aligned with the base): gravity's
direction from its orientation, else the base taken as level; its gyro and accelerometer for the
legs' dynamics. No ROS install: the bag is read through
:class:`~a1_leg_fk.recording.reads.RecordingReads`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.estimation.contact_estimator import DYNAMIC, FILTER, ContactEstimator, ImuSample
from a1_leg_fk.estimation.imu import has_orientation, measured_vector
from a1_leg_fk.kinematics.frames import gravity_in_base
from a1_leg_fk.model.legs import JOINT_COUNT
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.wire.joint_state import JointStateDecoder, WireError

if TYPE_CHECKING:  # rosbags is imported when a bag is read
    from rosbags.interfaces import Connection

    from a1_leg_fk.kinematics.quadruped import Quadruped
    from a1_leg_fk.recording.reads import RecordingReads

IMU_TYPE = "sensor_msgs/msg/Imu"
Vector = tuple[float, float, float]


class MissingEfforts(LegFkError):
    """The recording's JointStates carry no joint efforts."""


@dataclass(frozen=True)
class ImuTrack:
    """An IMU (aligned with the base, at its origin) over time, base frame: ``stamps_ns`` sorted
    (M,); ``gravity`` (M, 3) [m/s^2] from the orientation, ``angular_velocity`` (M, 3) [rad/s]
    and ``specific_force`` (M, 3) [m/s^2]; NaN rows where a message had none of it
    (``*_covariance[0] == -1``, or not finite).
    """

    stamps_ns: np.ndarray
    gravity: np.ndarray
    angular_velocity: np.ndarray
    specific_force: np.ndarray
    topic: str

    @classmethod
    def read(cls, reads: RecordingReads, connection: Connection) -> ImuTrack:
        """Every message of ``connection``, up to damage; :class:`LegFkError` if none has an
        orientation (:func:`~a1_leg_fk.estimation.imu.has_orientation`;
        :class:`DamagedRecording` if damage came first).
        """
        stamps, quaternions, gyros, accelerations = [], [], [], []
        message: Any
        for bag_time, message in reads.decoded(connection):
            q = message.orientation
            quaternion = (q.x, q.y, q.z, q.w)
            usable = has_orientation(float(message.orientation_covariance[0]), quaternion)
            quaternions.append(quaternion if usable else (math.nan,) * 4)
            gyros.append(_vector(message.angular_velocity, message.angular_velocity_covariance))
            accelerations.append(
                _vector(message.linear_acceleration, message.linear_acceleration_covariance, True)
            )
            stamp = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
            stamps.append(stamp or bag_time)
        return cls.of(
            np.array(stamps, dtype=np.int64),
            np.array(quaternions, dtype=float).reshape(-1, 4),
            np.array(gyros, dtype=float).reshape(-1, 3),
            np.array(accelerations, dtype=float).reshape(-1, 3),
            connection.topic,
            reads,
        )

    @classmethod
    def of(
        cls,
        stamps_ns: np.ndarray,
        quaternions: np.ndarray,
        gyros: np.ndarray,
        accelerations: np.ndarray,
        topic: str,
        reads: RecordingReads,
    ) -> ImuTrack:
        """The track of (M,) stamps [ns], (M, 4) quaternions x, y, z, w (a row not a rotation,
        :func:`~a1_leg_fk.estimation.imu.has_orientation`, counts as none), (M, 3) gyro [rad/s]
        and specific force [m/s^2] (NaN rows: none), in any order; :class:`LegFkError` if no row
        has an orientation (:class:`DamagedRecording` if damage in ``reads`` came first).
        """
        usable = [has_orientation(0.0, row) for row in quaternions.tolist()]
        rotations = np.where(np.array(usable, dtype=bool)[:, None], quaternions, math.nan)
        if not usable or not any(usable):
            reads.check()
            raise LegFkError(
                f"--imu {topic}: no message with an orientation (a rotation quaternion "
                "with orientation_covariance[0] != -1)"
            )
        order = np.argsort(stamps_ns, kind="stable")
        unit = rotations[order] / np.linalg.norm(rotations[order], axis=1)[:, None]
        return cls(
            stamps_ns[order], gravity_in_base(unit), gyros[order], accelerations[order], topic
        )

    def at(self, stamps_ns: np.ndarray) -> np.ndarray:
        """(N,) index of the sample nearest in time to each stamp [ns]."""
        if len(self.stamps_ns) == 1:
            return np.zeros(len(stamps_ns), dtype=np.intp)
        after = np.clip(np.searchsorted(self.stamps_ns, stamps_ns), 1, len(self.stamps_ns) - 1)
        before = after - 1
        nearer: np.ndarray = np.where(
            stamps_ns - self.stamps_ns[before] <= self.stamps_ns[after] - stamps_ns, before, after
        )
        return nearer

    def sample(self, index: int) -> ImuSample:
        """Sample ``index`` as the contact estimator takes it (None for what it lacks)."""
        return ImuSample(*(_known(values[index]) for values in (
            self.gravity, self.angular_velocity, self.specific_force)))  # fmt: skip


def _vector(vector: Any, covariance: Sequence[float], zero_is_none: bool = False) -> Vector:
    """A message's measured 3-vector (:func:`~a1_leg_fk.estimation.imu.measured_vector`), NaN
    where it has none.
    """
    values = (vector.x, vector.y, vector.z)
    return measured_vector(values, covariance[0], zero_is_none) or (math.nan,) * 3


def vector_values(vectors: np.ndarray, zero_is_none: bool) -> np.ndarray:
    """(M, 3) measured vectors of an IMU without covariances (Unitree's): each row as
    :func:`~a1_leg_fk.estimation.imu.measured_vector` keeps it, else NaN.
    """
    kept = np.array([measured_vector(row, 0.0, zero_is_none) is not None for row in
                     vectors.tolist()], dtype=bool).reshape(-1)  # fmt: skip
    return np.where(kept[:, None], vectors, math.nan)


def _known(row: np.ndarray) -> list[float] | None:
    """A row as floats, None when it is not finite."""
    return row.tolist() if np.isfinite(row).all() else None


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
    """Forces and contact probabilities row by row over one pass, the node's messages or a
    recording's rows alike (:class:`~a1_leg_fk.estimation.contact_estimator.ContactEstimator`:
    its state is carried from block to block).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        imu: ImuTrack | None,
        thresholds: tuple[float | None, float | None] = (None, None),
        force_model: str = DYNAMIC,
        contact_rule: str = FILTER,
    ) -> None:
        """``thresholds``: touchdown and liftoff normal forces [N] of the ``"threshold"`` contact
        rule, ``None`` for the default (:meth:`ContactThresholds.for_weight` of the URDF's total
        mass); ``force_model`` and ``contact_rule`` as the estimator takes them.
        """
        self.estimator = ContactEstimator(quadruped, force_model, contact_rule, thresholds)
        self.thresholds = self.estimator.rule.thresholds
        self.name_to_slot: Mapping[str, int] = quadruped.name_to_slot
        self.imu = imu
        self.restart()

    def restart(self) -> None:
        """A new pass: the estimator's state and the counts anew."""
        self.estimator.reset()
        self.counts = ForceCounts()
        self._origin_ns: int | None = None

    def summary(self, forces: bool) -> str:
        """The summary's lines (joined by newlines): the force counts (with ``forces``), and
        where the contacts came from: the rule, the force model, the evidence per sample and
        what the IMU gave.
        """
        estimator = self.estimator
        imu = self.imu
        motion = "none (the base taken as inertial)"
        if imu is not None:
            parts = [
                name
                for name, values in (
                    ("gyro", imu.angular_velocity),
                    ("accelerometer", imu.specific_force),
                )
                if np.isfinite(values).all(axis=1).any()
            ]
            motion = f"{', '.join(parts)} of {imu.topic}" if parts else motion
        forces_used = f" on {estimator.force_model} forces" if self.counts.estimated else ""
        rule = (
            f"contacts:  the {estimator.contact_rule} rule{forces_used}; the base's motion from "
            f"{motion}"
        )
        lines = [self.counts.line()] if forces else []
        if estimator.contact_rule == FILTER:
            lines += [rule, estimator.counts.line()]
        else:
            lines.append(rule)
        return "\n".join(lines)

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
        self,
        stamps_ns: np.ndarray,
        joints: tuple[np.ndarray, np.ndarray, np.ndarray | None],
        feet: tuple[np.ndarray, np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N, 4, 3) forces [N, base frame], (N, 4) normal forces [N] along minus gravity and
        (N, 4) contact probabilities for rows of (N, 12) angles [rad], rates [rad/s] and efforts
        [N m] (NaN where unknown; efforts None: none), and (N, 4, 3) feet [m] and their
        velocities [m/s], base frame.
        """
        angles, rates, efforts = joints
        rows = len(stamps_ns)
        forces = np.full((rows, 4, 3), math.nan)
        normals, probabilities = np.full((rows, 4), math.nan), np.full((rows, 4), math.nan)
        nearest = None if self.imu is None else self.imu.at(stamps_ns)
        for row in range(rows):
            forces[row], normals[row], probabilities[row] = self.message(
                int(stamps_ns[row]),
                (angles[row].tolist(), rates[row].tolist(),
                 None if efforts is None else efforts[row].tolist()),
                [(foot, velocity) for foot, velocity in
                 zip(feet[0][row].tolist(), feet[1][row].tolist(), strict=True)],
                ImuSample() if nearest is None or self.imu is None
                else self.imu.sample(int(nearest[row])),
            )  # fmt: skip
        return forces, normals, probabilities

    def message(
        self,
        stamp_ns: int,
        joints: tuple[Sequence[float], Sequence[float], Sequence[float] | None],
        feet: Sequence[tuple[Sequence[float], Sequence[float]] | None],
        imu: ImuSample,
        phase_prior: Sequence[float] | None = None,
    ) -> tuple[list[list[float]], list[float], list[float]]:
        """:meth:`rows` for one joint state, on floats (the node's per-message path): 4 forces
        [N, base frame], 4 normal forces [N] and 4 contact probabilities; ``phase_prior``: a gait
        scheduler's probability of stance per foot, as the estimator takes it.
        """
        if self._origin_ns is None:  # seconds since the first stamp: float64 keeps their ns
            self._origin_ns = stamp_ns
        stamp_s = (stamp_ns - self._origin_ns) * 1e-9
        step = self.estimator.step(stamp_s, joints, feet, imu, phase_prior)
        counts = self.counts
        counts.missing += sum(step.missing)
        counts.singular += sum(step.singular)
        counts.estimated += sum(1 for value in step.normals if value == value)  # noqa: PLR0124
        return step.forces, step.normals, step.probabilities

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
