"""A joint state waits for its IMU sample (:class:`ImuPairing`, issue 34): the IMU's message may
come after its joint state's. Synthetic, by construction: an A1 standing on four feet while an
impact shakes its IMU (a 30 m/s^2 vertical jolt over 10 ms and a gyro swing), 500 Hz, both
stamped alike; the reference is the same stream with every IMU sample fed first (as the node
and the bag tools always had it right)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest

from a1_leg_fk.estimation.imu_pairing import DEFAULT_IMU_WAIT_S, ImuPairing
from a1_leg_fk.estimation.odometry import ImuReading, OdometrySample
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.kinematics.quadruped import Quadruped

STEP_NS = 2_000_000
ROWS = 300
IMPACT = range(100, 105)  # the jolt's samples
ANGLES = [0.0, 0.8, -1.5] * 4
Lost = frozenset[int] | set[int]


@pytest.fixture(scope="module")
def quadruped() -> Quadruped:
    return Quadruped.from_urdf()


def _imu(row: int) -> ImuReading:
    """Row ``row``'s IMU sample: still, but for the jolt and a slow gyro swing."""
    jolt = 30.0 if row in IMPACT else 0.0
    swing = 0.3 * math.sin(row * 0.05)
    return ImuReading(
        (0.0, 0.0, 0.0, 1.0), (swing, -swing, 0.0), specific_force=(0.0, 0.0, 9.80665 + jolt)
    )


def _joint(quadruped: Quadruped, row: int) -> tuple:
    """Row ``row``'s joint state: the standing feet, still (:meth:`OdometryFeed.step`'s)."""
    feet = quadruped.fk_batch(np.array([ANGLES]))[0].tolist()
    return (row + 1) * STEP_NS, [(foot, (0.0, 0.0, 0.0)) for foot in feet], ANGLES, [0.0] * 12


def _velocities(samples: Sequence[OdometrySample | None]) -> np.ndarray:
    return np.array([[s.stamp_ns, *s.linear, *s.position] for s in samples if s is not None])


def _imu_first(quadruped: Quadruped, lost: Lost = frozenset()) -> np.ndarray:
    """The reference: each IMU sample into the feed before its joint state (``lost``: rows
    without one)."""
    feed, samples = OdometryFeed(quadruped, contacts="kinematic"), []
    for row in range(ROWS):
        stamp, feet, angles, rates = _joint(quadruped, row)
        if row not in lost:
            feed.add_imu(stamp, _imu(row))
        samples.append(feed.step(stamp, feet, angles, rates))
    return _velocities(samples)


def _imu_second(quadruped: Quadruped, lost: Lost = frozenset(), **kwargs) -> tuple:
    """Each IMU sample after its joint state (``lost``: rows without one), through the pairing."""
    pairing = ImuPairing(OdometryFeed(quadruped, contacts="kinematic"), **kwargs)
    samples: list[OdometrySample] = []
    for row in range(ROWS):
        stamp, feet, angles, rates = _joint(quadruped, row)
        samples += pairing.joint(stamp, feet, angles, rates)
        if row not in lost:
            samples += pairing.imu(stamp, _imu(row))
    samples += pairing.flush()
    return _velocities(samples), pairing


def test_a_joint_state_before_its_imu_sample_gets_the_imu_first_estimate(quadruped) -> None:
    reference = _imu_first(quadruped)
    paired, pairing = _imu_second(quadruped)
    assert pairing.held == ROWS and pairing.released_by_wait == 0
    assert np.array_equal(paired, reference)
    stale, _ = _imu_second(quadruped, wait_s=0.0)  # as before: the previous IMU sample taken
    jolt = slice(IMPACT.start, IMPACT.stop + 5)
    gap = np.abs(stale[jolt, 1:4] - reference[jolt, 1:4]).max()
    print(f"IMU second, not waiting: {gap:.4f} m/s off the IMU-first velocity at the jolt")
    assert gap > 0.01  # a jolt's 2 ms of 30 m/s^2 is 0.06 m/s: the pairing matters here


def test_a_lost_imu_sample_holds_its_joint_state_for_the_wait_alone(quadruped) -> None:
    """IMU samples 50 to 55 never come: joint state 50 waits until a joint state stamped
    ``wait_s`` later arrives (row 53: 6 ms), then takes sample 49, as with the IMU first; 54 and
    55 go when IMU sample 56 comes, before it; none lost, none reordered."""
    lost = set(range(50, 56))
    paired, pairing = _imu_second(quadruped, lost=lost)
    assert pairing.released_by_wait == 4  # 50 to 53
    assert np.array_equal(paired, _imu_first(quadruped, lost))  # every one, in order
    assert DEFAULT_IMU_WAIT_S * 1e9 <= 3 * STEP_NS


def test_a_dead_imu_stalls_nothing(quadruped) -> None:
    """The IMU stops after row 20: each joint state comes out once a joint state stamped
    ``wait_s`` later arrives; the last ones at :meth:`expire` by their arrival (the node's
    wall-clock bound) or at the end."""
    pairing = ImuPairing(OdometryFeed(quadruped, contacts="kinematic"))
    out: list[OdometrySample] = []
    for row in range(40):
        stamp, feet, angles, rates = _joint(quadruped, row)
        out += pairing.joint(stamp, feet, angles, rates, arrived_ns=row)
        if row <= 20:
            out += pairing.imu(stamp, _imu(row))
    behind = math.ceil(DEFAULT_IMU_WAIT_S * 1e9 / STEP_NS)
    assert len(out) == 40 - behind  # at most wait_s of stamp time held
    assert list(pairing.expire(39 - behind)) == []  # arrived after: still held
    out += pairing.expire(39)
    assert not pairing.holding and [s.stamp_ns for s in out] == [
        (row + 1) * STEP_NS for row in range(40)
    ]


def test_without_an_imu_nothing_waits(quadruped) -> None:
    pairing = ImuPairing(OdometryFeed(quadruped, use_imu=False, contacts="kinematic"))
    stamp, feet, angles, rates = _joint(quadruped, 0)
    assert len(list(pairing.joint(stamp, feet, angles, rates))) == 1 and not pairing.holding
