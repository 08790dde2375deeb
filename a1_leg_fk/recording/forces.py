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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.estimation.contact_estimator import DYNAMIC, FILTER, ImuSample
from a1_leg_fk.estimation.contact_filter import SampleEvidence
from a1_leg_fk.estimation.contact_smoother import EvidenceRows, smoothing_line
from a1_leg_fk.estimation.force_pass import ForcePass
from a1_leg_fk.estimation.imu import has_orientation, measured_vector
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.kinematics.frames import gravity_in_base
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


class RecordingForces(ForcePass):
    """:class:`~a1_leg_fk.estimation.force_pass.ForcePass` over a recording's rows, its IMU from
    an Imu topic (:class:`ImuTrack`, None: none).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        imu: ImuTrack | None,
        thresholds: tuple[float | None, float | None] = (None, None),
        force_model: str = DYNAMIC,
        contact_rule: str = FILTER,
        model_corrections: str = DEFAULT_MODEL_CORRECTIONS,
    ) -> None:
        super().__init__(quadruped, thresholds, force_model, contact_rule, model_corrections)
        self.imu = imu
        self.smoothed = False
        """Keep the filter's evidence per row (:meth:`rows`), for contacts smoothed over the
        recording; False: the filter's own, causal contacts, as the node has them."""

    def summary(self, forces: bool, motion: str | None = None) -> str:
        """:meth:`ForcePass.summary`, the base's motion from the IMU track's gyro and
        accelerometer where they were measured.
        """
        imu = self.imu
        if motion is None and imu is not None:
            parts = [
                name
                for name, values in (
                    ("gyro", imu.angular_velocity),
                    ("accelerometer", imu.specific_force),
                )
                if np.isfinite(values).all(axis=1).any()
            ]
            motion = f"{', '.join(parts)} of {imu.topic}" if parts else None
        lines = super().summary(forces, motion)
        if self.estimator.contact_rule != FILTER:
            return lines
        return f"{lines}\n{smoothing_line(self.smoothed)}"

    def rows(
        self,
        stamps_ns: np.ndarray,
        joints: tuple[np.ndarray, np.ndarray, np.ndarray | None],
        feet: tuple[np.ndarray, np.ndarray],
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, EvidenceRows | None]:
        """(N, 4, 3) forces [N, base frame], (N, 4) normal forces [N] along minus gravity,
        (N, 4) contact probabilities (the filter's, causal) and, while :attr:`smoothed`, the
        filter's evidence per row (else None) for rows of (N, 12) angles [rad], rates [rad/s] and
        efforts [N m] (NaN where unknown; efforts None: none), and (N, 4, 3) feet [m] and their
        velocities [m/s], base frame.
        """
        angles, rates, efforts = joints
        rows = len(stamps_ns)
        forces = np.full((rows, 4, 3), math.nan)
        normals, probabilities = np.full((rows, 4), math.nan), np.full((rows, 4), math.nan)
        nearest = None if self.imu is None else self.imu.at(stamps_ns)
        kept: list[SampleEvidence] | None = [] if self.smoothed else None
        for row in range(rows):
            step = self.message(
                int(stamps_ns[row]),
                (angles[row].tolist(), rates[row].tolist(),
                 None if efforts is None else efforts[row].tolist()),
                [(foot, velocity) for foot, velocity in
                 zip(feet[0][row].tolist(), feet[1][row].tolist(), strict=True)],
                ImuSample() if nearest is None or self.imu is None
                else self.imu.sample(int(nearest[row])),
            )  # fmt: skip
            forces[row], normals[row], probabilities[row] = (
                step.forces,
                step.normals,
                step.probabilities,
            )
            if kept is not None:
                kept.append(self.estimator.filter.evidence)
        return (
            forces,
            normals,
            probabilities,
            None if kept is None else self._evidence(stamps_ns, kept, normals),
        )

    def _evidence(
        self, stamps_ns: np.ndarray, kept: list[SampleEvidence], normals: np.ndarray
    ) -> EvidenceRows:
        """The evidence of rows stamped ``stamps_ns`` as arrays, their stamps [s] since the
        first of the pass, with the (N, 4) ``normals`` [N] the filter was given.
        """
        switch, kinematic, forced, total, heights = zip(*kept, strict=True) if kept else ((),) * 5
        return EvidenceRows(
            (stamps_ns - (self._origin_ns or 0)) * 1e-9,
            np.array(switch, dtype=float),
            np.array(kinematic, dtype=float).reshape(-1, 4),
            np.array(forced, dtype=bool).reshape(-1, 4),
            np.array(total, dtype=float).reshape(-1, 4),
            normals,
            np.array(heights, dtype=float).reshape(-1, 4),
        )


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
