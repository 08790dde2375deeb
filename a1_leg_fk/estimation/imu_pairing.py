"""Joint states held for their IMU sample (:class:`ImuPairing`): the one rule of the node and the
bag tools for an IMU and joint states that come on separate topics, in either order.

An IMU sample is paired with a joint state by stamp (:class:`~a1_leg_fk.estimation.imu.
ImuBuffer`: the latest at or before it), but only among the samples that have arrived. When the
IMU sample stamped like a joint state arrives just after it, the previous one (an IMU period
stale; through a touchdown's impact, cm/s) would be used. So a joint state stamped after the
newest IMU sample is held until:

- an IMU sample stamped at or after it arrives (it is then processed after the IMU samples
  stamped at or before it, before the later ones: stamp order, an IMU sample first on a tie);
- or a joint state stamped at least ``wait_s`` later arrives (the stamps' bound: a lost or late
  IMU sample costs at most ``wait_s`` of stamp time);
- or :meth:`ImuPairing.expire` is called with a time ``arrived_ns`` passed its arrival (the
  node's wall-clock bound: a dead IMU never stalls the output);
- or :meth:`ImuPairing.flush` (the end of a bag, Ctrl-C).

It is then processed with the IMU samples that have arrived (:class:`ImuBuffer`'s rule, as
without the wait). Held joint states are processed in their arrival order, none dropped. Nothing
is held when ``wait_s`` is zero (an IMU inside the joint states' own message: a Unitree LowState)
or the feed ignores the IMU (``use_imu`` false, or no IMU topic).

Every method yields the samples it releases: iterate each to its end (the feed is stepped as it
is iterated, so each sample's ground and counts can be read before the next).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import NamedTuple

from a1_leg_fk.estimation.odometry import ImuReading, OdometrySample
from a1_leg_fk.estimation.odometry_feed import Foot, OdometryFeed

DEFAULT_IMU_WAIT_S = 0.005
"""[s] of stamp time a joint state waits for its IMU sample: two and a half periods of a 500 Hz
IMU, five of a 1 kHz one."""
WALL_WAIT_S = 0.1
"""[s] of wall time the node holds a joint state at most (:meth:`ImuPairing.expire`, checked every
half of it): the IMU's message may lag its joint state's on a loaded machine by far more than
the stamps' bound, and a joint state that comes last (no later one passes it by the stamps'
bound) is published within 0.15 s."""


class HeldJointState(NamedTuple):
    """A joint state waiting for its IMU sample: :meth:`OdometryFeed.step`'s arguments and its
    arrival time [ns] (the caller's clock).
    """

    stamp_ns: int
    feet: Sequence[Foot | None]
    angles: Sequence[float]
    rates: Sequence[float]
    efforts: Sequence[float] | None
    arrived_ns: int


class ImuPairing:
    """IMU samples and joint states into ``feed`` in stamp order (the module's rule); ``held``:
    the joint states held so far, ``released_by_wait`` those released without their IMU sample
    (by the stamps' bound, :meth:`expire` or :meth:`flush`).
    """

    def __init__(self, feed: OdometryFeed, wait_s: float = DEFAULT_IMU_WAIT_S) -> None:
        self.feed = feed
        self.wait_ns = round(wait_s * 1e9) if feed.use_imu else 0
        self.held = 0
        self.released_by_wait = 0
        self._queue: deque[HeldJointState] = deque()
        self._newest_imu: int | None = None

    @property
    def holding(self) -> bool:
        """Whether a joint state is waiting."""
        return bool(self._queue)

    def imu(self, stamp_ns: int, reading: ImuReading | None) -> Iterator[OdometrySample]:
        """One IMU sample stamped ``stamp_ns`` (None: unusable, it still releases the joint
        states stamped at or before it): the held joint states stamped before it first.
        """
        yield from self._release(lambda held: held.stamp_ns < stamp_ns, False)
        self.feed.add_imu(stamp_ns, reading)
        if self._newest_imu is None or stamp_ns > self._newest_imu:
            self._newest_imu = stamp_ns
        yield from self._release(lambda held: held.stamp_ns <= stamp_ns, False)

    def joint(
        self,
        stamp_ns: int,
        feet: Sequence[Foot | None],
        angles: Sequence[float],
        rates: Sequence[float],
        efforts: Sequence[float] | None = None,
        arrived_ns: int = 0,
    ) -> Iterator[OdometrySample]:
        """One joint state (:meth:`OdometryFeed.step`'s arguments; ``arrived_ns``: when it
        arrived, for :meth:`expire`): the held ones it passes by ``wait_s`` first, then it,
        unless it is held.
        """
        yield from self._release(lambda held: stamp_ns - held.stamp_ns >= self.wait_ns, True)
        state = HeldJointState(stamp_ns, feet, angles, rates, efforts, arrived_ns)
        newest = self._newest_imu
        if self._queue or (self.wait_ns > 0 and (newest is None or stamp_ns > newest)):
            self._queue.append(state)
            self.held += 1
            return
        yield from self._step(state)

    def expire(self, arrived_ns: int) -> Iterator[OdometrySample]:
        """The held joint states that arrived at or before ``arrived_ns``, released."""
        yield from self._release(lambda held: held.arrived_ns <= arrived_ns, True)

    def flush(self) -> Iterator[OdometrySample]:
        """Every held joint state, released (the end of the input)."""
        yield from self._release(lambda _: True, True)

    def _release(
        self, ready: Callable[[HeldJointState], bool], by_wait: bool
    ) -> Iterator[OdometrySample]:
        """The held joint states from the oldest while ``ready``, processed (``by_wait``: without
        their IMU sample, counted) in order.
        """
        queue = self._queue
        while queue and ready(queue[0]):
            state = queue.popleft()
            newest = self._newest_imu
            self.released_by_wait += by_wait and (newest is None or state.stamp_ns > newest)
            yield from self._step(state)

    def _step(self, state: HeldJointState) -> Iterator[OdometrySample]:
        """The feed's sample of one joint state, if it gives one."""
        sample = self.feed.step(
            state.stamp_ns, state.feet, state.angles, state.rates, efforts=state.efforts
        )
        if sample is not None:
            yield sample
