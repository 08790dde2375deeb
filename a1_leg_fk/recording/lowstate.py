"""A recording of Unitree's ``LowState`` (``unitree_go/msg/LowState`` of a Go2 or B2,
``unitree_legged_msgs/LowState`` of an A1 or Go1) read as the joint states and IMU it carries.

The motors become joint states named by :data:`~a1_leg_fk.wire.lowstate.MOTOR_NAMES` (Unitree's
joint names, so the model's joints are found by leg and role as a JointState's are, and
``--joint-aliases`` maps them where a user's URDF names them otherwise): q, dq, tau_est ->
positions [rad], velocities [rad/s], efforts [N m]. The message has no header: every stamp is the
bag's receive time. The IMU inside the message is the IMU of the forces and the odometry (the
same rules as a ``sensor_msgs/msg/Imu``'s, :mod:`a1_leg_fk.estimation.imu`, its orientation
reordered from the message's (w, x, y, z)). The foot sensors' raw counts travel with the rows.
No ROS install: the bag is read through :class:`~a1_leg_fk.recording.reads.RecordingReads`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.estimation.imu import imu_reading
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.forces import ImuTrack, vector_values
from a1_leg_fk.wire.layout import LayoutError
from a1_leg_fk.wire.lowstate import KINDS, MOTOR_NAMES, LowStateDecoder, LowStateRows, layout_for
from a1_leg_fk.wire.unitree_types import HUMANOID_LOW_STATE

if TYPE_CHECKING:  # rosbags is imported when a bag is opened
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

    from a1_leg_fk.estimation.odometry import ImuReading
    from a1_leg_fk.recording.reads import RecordingReads
    from a1_leg_fk.tracking import TrackerCounts

LOWSTATE_TYPES = tuple(KINDS)
"""The LowState types a recording's joint states may come from."""
STAMP_NOTE = "the bag's receive time (a LowState has no header)"
"""Where a LowState row's stamp comes from, for the summaries."""
READ_MESSAGES = 4096
"""Messages decoded together when a pass reads the IMU."""
NO_COVARIANCE = (0.0,) * 9
"""A LowState's IMU states no covariance: "unknown" (REP 145), as an all-zero one says."""


@dataclass(frozen=True)
class LowStateInput:
    """The LowState topic a recording's joint states come from, and its decoder."""

    connection: Connection
    decoder: LowStateDecoder

    @property
    def names(self) -> list[str]:
        """The joint names of the motors, in motor order."""
        return list(MOTOR_NAMES)

    @classmethod
    def open(cls, reads: RecordingReads, connection: Connection) -> LowStateInput:
        """The input of ``connection``, its layout from the bag's definition (else the package's);
        :class:`LegFkError` if that layout is not Unitree's, or the first message does not fit it
        (truncated, another message). Damage before the first message decides nothing.
        """
        ros1 = not reads.reader.is2
        recorded = connection.msgdef.data if connection.msgdef.data.strip() else None
        try:
            decoder = LowStateDecoder(layout_for(connection.msgtype, recorded, ros1))
        except LayoutError as error:
            raise LegFkError(
                f"{connection.topic} ({connection.msgtype}): its recorded definition is not "
                f"Unitree's layout: {error}"
            ) from None
        messages = reads.messages([connection])
        for _, _, raw in messages:
            problem = decoder.check(raw)
            if problem:
                raise LegFkError(
                    f"{connection.topic}: its first message is not a whole "
                    f"{connection.msgtype}: {problem} (truncated, or another message)"
                )
            break
        messages.close()
        return cls(connection, decoder)

    def blocks(self, reads: RecordingReads) -> Iterator[tuple[np.ndarray, LowStateRows]]:
        """(bag times [ns], rows) of the messages in blocks of :data:`READ_MESSAGES`, up to the
        first damage or undecodable message (noted in ``reads``).
        """
        raws: list[bytes] = []
        times: list[int] = []
        read = 0
        for _, bag_time, raw in reads.messages([self.connection]):
            raws.append(raw)
            times.append(bag_time)
            if len(raws) >= READ_MESSAGES:
                rows, bad = self.decode(reads, raws, times, read)
                yield np.array(times[: len(rows.tick)], dtype=np.int64), rows
                if bad:
                    return
                read += len(raws)
                raws, times = [], []
        if raws:
            rows, _ = self.decode(reads, raws, times, read)
            yield np.array(times[: len(rows.tick)], dtype=np.int64), rows

    def decode(
        self, reads: RecordingReads, raws: list[bytes], times: list[int], before: int
    ) -> tuple[LowStateRows, bool]:
        """The rows of ``raws`` (after ``before`` earlier messages) up to the first that cannot be
        decoded, which is noted in ``reads`` as the end of the recording; and whether there was
        one.
        """
        rows, problem = self.decoder.rows(raws)
        if problem is None:
            return rows, False
        index, text = problem
        reads.undecodable(times[index], before + index + 1, self.connection.topic, text)
        return rows, True

    def imu_track(self, reads: RecordingReads) -> ImuTrack:
        """The IMU inside the messages, as an ``--imu`` topic's track (stamps: bag times)."""
        stamps, quaternions, gyros, accelerations = [], [], [], []
        for times, rows in self.blocks(reads):
            stamps.append(times)
            quaternions.append(rows.orientations)
            gyros.append(vector_values(rows.gyro, False))
            accelerations.append(vector_values(rows.accelerometer, True))
        return ImuTrack.of(
            np.concatenate(stamps) if stamps else np.zeros(0, dtype=np.int64),
            np.concatenate(quaternions) if quaternions else np.zeros((0, 4)),
            np.concatenate(gyros) if gyros else np.zeros((0, 3)),
            np.concatenate(accelerations) if accelerations else np.zeros((0, 3)),
            self.connection.topic,
            reads,
        )

    @staticmethod
    def imu_samples(
        times: list[int], rows: LowStateRows
    ) -> list[tuple[int, int, ImuReading | None]]:
        """(bag time [ns], stamp [ns], reading) of each decoded message's IMU (orientation, gyro
        and accelerometer), as the odometry takes an Imu topic's (the stamp is the bag time):
        ``rows`` decoded from the messages at ``times`` (the first ``len(rows.tick)``).
        """
        samples = []
        for bag_time, quaternion, gyro, force in zip(
            times[: len(rows.tick)],
            rows.orientations.tolist(),
            rows.gyro.tolist(),
            rows.accelerometer.tolist(),
            strict=True,
        ):
            reading = imu_reading(
                quaternion, NO_COVARIANCE, gyro, NO_COVARIANCE, force, NO_COVARIANCE
            )
            samples.append((bag_time, bag_time, reading))
        return samples


def refuse_humanoid(reader: AnyReader, wanted: str | None, joint_types: tuple[str, ...]) -> None:
    """:class:`LegFkError` when the input would be a humanoid's LowState (``unitree_hg``): the
    ``--topic`` asked for, or with none asked, the bag's only topic of motors (none of
    ``joint_types``).
    """
    humanoid = [c.topic for c in reader.connections if c.msgtype == HUMANOID_LOW_STATE]
    if wanted is None:
        if any(c.msgtype in joint_types for c in reader.connections):
            return
    elif wanted not in humanoid:
        return
    if humanoid:
        raise LegFkError(
            f"{wanted or humanoid[0]} is {HUMANOID_LOW_STATE}, a humanoid's (Unitree G1, H1) "
            f"motors, not a quadruped's: the legs are read from {', '.join(joint_types)}"
        )


def no_finite_motors(reads: RecordingReads, topic: str, counts: TrackerCounts) -> LegFkError:
    """The error of a pass over ``topic`` that gave no row: no message's motor angles were finite
    for a whole leg (:class:`DamagedRecording` if damage came first).
    """
    reads.check()
    return LegFkError(
        f"{reads.path}: no message of {counts.messages} on {topic} gives a leg: "
        f"{counts.non_finite_joints} motor angles are not finite (NaN or infinite q)"
    )
