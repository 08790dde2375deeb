"""A recording's IMU read in the same pass as its joint states (:class:`ImuStream`), for the
odometry: the pass (:func:`~a1_leg_fk.recording.blocks.iter_foot_blocks`) hands every message
of the IMU's topic to :meth:`ImuStream.add` in bag order, and the odometry takes the samples up
to each joint state's bag time (:meth:`ImuStream.until`), as a live node receives them. What is
kept: the samples read ahead of the joint states being processed (at most a block of the pass),
never the whole recording's.

The IMU is a ``sensor_msgs/msg/Imu`` topic (each message decoded as it is read: one it cannot
decode is damage, :class:`~a1_leg_fk.recording.reads.RecordingReads`, and ends the pass there)
or the IMU inside a Unitree LowState (:class:`~a1_leg_fk.recording.lowstate.LowStateInput`:
the joint states' own messages, decoded together when the odometry reaches them).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from a1_leg_fk.estimation.imu import imu_reading

if TYPE_CHECKING:
    from rosbags.interfaces import Connection

    from a1_leg_fk.estimation.odometry import ImuReading
    from a1_leg_fk.recording.lowstate import LowStateInput
    from a1_leg_fk.recording.reads import RecordingReads

ImuSample = tuple[int, int, "ImuReading | None"]
"""(bag time [ns], stamp [ns], reading): the stamp is the bag time where the header's is zero
(a LowState has no header: always its bag time)."""


class ImuStream:
    """The IMU of ``connection`` (an Imu topic, or ``lowstate``'s), read along the joint states:
    ``count`` samples read so far, up to damage.
    """

    def __init__(
        self,
        reads: RecordingReads,
        connection: Connection,
        lowstate: LowStateInput | None = None,
    ) -> None:
        self.reads = reads
        self.connection = connection
        self.lowstate = lowstate
        self.count = 0
        self._read = 0  # messages of the topic handed over
        self._ended = False  # a message could not be decoded: none after it is taken
        self._samples: deque[ImuSample] = deque()
        self._raws: list[bytes] = []  # LowState messages not decoded yet
        self._times: list[int] = []

    def add(self, connection: Connection, bag_time: int, raw: bytes) -> None:
        """A message of the pass (any topic's; those of the IMU's are taken)."""
        if connection is not self.connection or self._ended:
            return
        self._read += 1
        if self.lowstate is not None:
            self._raws.append(raw)
            self._times.append(bag_time)
            return
        message: Any = self.reads.deserialize(connection, bag_time, self._read, raw)
        if message is None:
            self._ended = True
            return
        stamp = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
        q, w, a = message.orientation, message.angular_velocity, message.linear_acceleration
        reading = imu_reading(
            (q.x, q.y, q.z, q.w),
            message.orientation_covariance,
            (w.x, w.y, w.z),
            message.angular_velocity_covariance,
            (a.x, a.y, a.z),
            message.linear_acceleration_covariance,
        )
        self._samples.append((bag_time, stamp or bag_time, reading))
        self.count += 1

    def until(self, bag_time: int) -> Iterator[ImuSample]:
        """The samples not taken yet up to ``bag_time`` [ns] (inclusive), in bag order."""
        samples = self._samples
        while True:
            if samples and samples[0][0] <= bag_time:
                yield samples.popleft()
            elif not samples and self._raws:
                self._decode()
            else:
                return

    def finish(self) -> int:
        """The samples read over the whole pass (the pass is over): ``count``."""
        if self._raws:
            self._decode()
        self._samples.clear()
        return self.count

    def _decode(self) -> None:
        """The LowState messages waiting, decoded up to the first that cannot be (damage)."""
        assert self.lowstate is not None
        raws, times = self._raws, self._times
        before = self._read - len(raws)
        self._raws, self._times = [], []
        rows, bad = self.lowstate.decode(self.reads, raws, times, before)
        samples = self.lowstate.imu_samples(times, rows)
        self._samples.extend(samples)
        self.count += len(samples)
        self._ended = self._ended or bad
