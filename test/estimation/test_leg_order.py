"""Each leg's numbers stay its own, from the joint names to the filter: the tracker's feet
(a1_leg_fk.tracking) and the odometry feed's Jacobians (a1_leg_fk.estimation.odometry_feed),
judged by PyBullet's own forward kinematics (test/pybullet_reference.py) on a robot where one leg
moves at a time. On the A1 of pybullet_data, and on any URDFs named in ``A1_LEG_FK_EXTRA_URDFS``
(paths separated by ``os.pathsep``; e.g. Unitree's published Go2, meshes stripped).
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from pybullet_reference import A1_URDF, PyBulletRobot

from a1_leg_fk.estimation.odometry import ImuReading
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.tracking import FootTracker, leg_feet

ROBOTS = [
    str(A1_URDF),
    *filter(None, os.environ.get("A1_LEG_FK_EXTRA_URDFS", "").split(os.pathsep)),
]
STAND = (0.15, 0.8, -1.5)
"""One leg's hip roll, hip pitch and knee [rad]: a hip rolled out, so that no two legs' numbers
are mirror images of each other's."""
RATES = (0.7, -1.1, 1.9)
"""The moving leg's joint rates [rad/s]."""
STEP_RAD = 1e-3
"""The finite differences' step [rad] (central; PyBullet's link frames hold ~1e-8 m)."""


@pytest.fixture(scope="module", params=ROBOTS, ids=os.path.basename)
def robot(request: pytest.FixtureRequest):
    """(the Quadruped, PyBullet's twin, the foot links in leg order)."""
    quadruped = Quadruped.from_urdf(request.param)
    reference = PyBulletRobot(request.param)
    yield quadruped, reference, [leg.chain.foot_link for leg in quadruped.legs]
    reference.close()


def pybullet_feet(robot, angles: np.ndarray) -> np.ndarray:
    """(4, 3) PyBullet's foot link frames [m, base frame] at ``angles`` (slot order)."""
    quadruped, reference, feet = robot
    return reference.feet(list(quadruped.joint_names), feet, angles)


def test_only_the_moving_legs_foot_moves(robot) -> None:
    """One leg's joints turning, the others still: that leg's foot alone has a velocity, PyBullet's
    finite difference (central); every foot where PyBullet puts it."""
    quadruped = robot[0]
    angles = np.array(STAND * 4)
    expected = pybullet_feet(robot, angles)
    for leg in range(4):
        rates = np.zeros(12)
        rates[3 * leg : 3 * leg + 3] = RATES
        tracker = FootTracker(quadruped)
        feet = leg_feet(tracker.update(list(quadruped.joint_names), angles.tolist(),
                                       rates.tolist()))  # fmt: skip
        moved = pybullet_feet(robot, angles + STEP_RAD * rates)
        back = pybullet_feet(robot, angles - STEP_RAD * rates)
        for slot, foot in enumerate(feet):
            assert foot is not None
            position, velocity = np.array(foot[0]), np.array(foot[1])
            assert np.abs(position - expected[slot]).max() < 1e-6, (leg, slot)
            truth = (moved[slot] - back[slot]) / (2.0 * STEP_RAD)
            assert np.abs(velocity - truth).max() < 1e-3, (leg, slot)
        assert np.linalg.norm((moved - back)[leg]) / (2.0 * STEP_RAD) > 0.1  # it moves


def test_the_feed_gives_each_foot_its_own_jacobian(robot) -> None:
    """The ``J Jᵀ`` of each standing foot's measurement (its noise through the joint rates) is
    its own leg's, ``J`` by PyBullet's finite differences."""
    quadruped = robot[0]
    feed = OdometryFeed(quadruped)
    taken = []
    update = feed.filter.update

    def spy(stamp_ns, legs, *args):
        taken.append(list(legs))
        return update(stamp_ns, legs, *args)

    feed.filter.update = spy  # type: ignore[method-assign]
    angles = np.array(STAND * 4)
    feed.add_imu(0, ImuReading((0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0),
                               specific_force=(0.0, 0.0, STANDARD_GRAVITY)))  # fmt: skip
    feet = leg_feet(FootTracker(quadruped).update(list(quadruped.joint_names), angles.tolist(),
                                                  [0.0] * 12))  # fmt: skip
    feed.step(1_000_000, feet, angles.tolist(), [0.0] * 12, [1.0] * 4)
    for leg, measurement in enumerate(taken[-1]):
        assert measurement is not None
        jacobian = np.empty((3, 3))
        for joint in range(3):
            nudge = np.zeros(12)
            nudge[3 * leg + joint] = STEP_RAD
            ahead, back = (
                pybullet_feet(robot, angles + nudge),
                pybullet_feet(robot, angles - nudge),
            )
            jacobian[:, joint] = (ahead[leg] - back[leg]) / (2.0 * STEP_RAD)
        expected = jacobian @ jacobian.T
        assert np.abs(np.reshape(measurement.jjt, (3, 3)) - expected).max() < 1e-4, leg
