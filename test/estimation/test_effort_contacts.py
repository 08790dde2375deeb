"""The leg odometry's stance source (a1_leg_fk.estimation.effort_contacts): contacts from the
joint efforts agree with PyBullet's own foot contacts over a walk; ``auto`` falls back to the
kinematic stance joint state by joint state; ``force`` and ``kinematic`` hold; a robot without
masses has no force contacts and says why."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pybullet_sim import simulate, walking_targets
from synthetic_urdf import quadruped_urdf

from a1_leg_fk.estimation.effort_contacts import EffortContacts
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.kinematics.frames import DOWN, down_direction
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError, parse_urdf

SETTLED_S = 0.5  # after the drop onto the plane
TOUCHING_N = 5.0  # PyBullet's normal force above which a foot counts as on the ground
STAND = [0.0, 0.8, -1.5] * 4
STANDING_EFFORTS = [1.08, -2.88, 2.42, -1.0, -3.08, 2.26, -1.86, 2.71, 5.02, 1.71, 2.8, 5.22]
"""[N m]: the A1 standing in PyBullet at STAND (docs/forces.md), ~30 N on each foot."""


@pytest.fixture(scope="module")
def quadruped() -> Quadruped:
    return Quadruped.from_urdf()


def test_force_contacts_are_pybullets_over_a_walk(quadruped) -> None:
    """The motor torques of a PyBullet trot, gravity from the IMU's orientation: each foot's
    stance matches PyBullet's contact (normal force > 5 N) in >= 96 % of the samples."""
    walk = simulate(walking_targets(), 3.0)
    contacts = EffortContacts(quadruped, "force")
    rows = zip(walk.angles.tolist(), walk.torques.tolist(), walk.base_quaternions.tolist())
    stance = (
        np.array([contacts.probabilities(a, e, down_direction(tuple(q))) for a, e, q in rows])
        >= 0.5
    )
    touching = walk.contact_forces[:, :, 2] > TOUCHING_N
    settled = walk.stamps_s >= SETTLED_S
    agreement = (stance == touching)[settled].mean(axis=0)
    print(f"stance agrees with PyBullet's contacts: {np.round(agreement, 3).tolist()} (FR..RL)")
    assert (agreement >= 0.96).all()
    assert contacts.counts.force == len(walk.stamps_s) and contacts.counts.kinematic == 0


def test_auto_takes_forces_only_with_every_effort(quadruped) -> None:
    contacts = EffortContacts(quadruped)
    standing = contacts.probabilities(STAND, STANDING_EFFORTS, DOWN)
    assert standing is not None and min(standing) >= 0.5  # ~30 N > 9.8 N touchdown
    one_missing = [*STANDING_EFFORTS[:-1], math.nan]
    assert contacts.probabilities(STAND, one_missing, DOWN) is None
    assert contacts.probabilities(STAND, None, DOWN) is None
    assert contacts.counts.force == 1 and contacts.counts.kinematic == 2
    # the hysteresis held through the joint states without efforts: ~8 N stays in stance (above
    # the 4.9 N liftoff), where a foot in swing would need the 9.8 N touchdown
    lighter = [e / 5 for e in STANDING_EFFORTS]
    light = contacts.probabilities(STAND, lighter, DOWN)
    assert light is not None and min(light) >= 0.5
    fresh = EffortContacts(quadruped).probabilities(STAND, lighter, DOWN)
    assert fresh is not None and max(fresh) < 0.5


def test_force_and_kinematic_hold(quadruped) -> None:
    force = EffortContacts(quadruped, "force")
    probabilities = force.probabilities(STAND, None, DOWN)
    assert probabilities is not None and all(math.isnan(p) for p in probabilities)
    half = [*STANDING_EFFORTS[:6], *[math.nan] * 6]  # the rear legs' efforts unknown
    probabilities = force.probabilities(STAND, half, DOWN)
    assert probabilities is not None
    assert min(probabilities[:2]) >= 0.5 and all(math.isnan(p) for p in probabilities[2:])
    assert force.counts.force == 2
    kinematic = EffortContacts(quadruped, "kinematic")
    assert kinematic.probabilities(STAND, STANDING_EFFORTS, DOWN) is None
    assert kinematic.model is None and kinematic.counts.kinematic == 1
    with pytest.raises(LegFkError, match="contacts must be one of auto, force, kinematic"):
        EffortContacts(quadruped, "forces")


def test_force_contacts_without_efforts_stand_no_foot(quadruped) -> None:
    """``force`` on joint states without efforts: no foot stands (the odometry says so), where
    ``auto`` stands on the kinematic stance."""
    feet = quadruped.fk_batch(np.array([STAND])).tolist()[0]
    still = [(foot, [0.0, 0.0, 0.0]) for foot in feet]
    for source, no_stance in (("force", 1), ("auto", 0)):
        feed = OdometryFeed(quadruped, contacts=source)
        sample = feed.step(1, still, STAND, [0.0] * 12)
        assert sample is not None and len(sample.stance) == 4 - 4 * no_stance
        assert feed.odometry.counts.no_stance == no_stance


def test_a_robot_without_masses_has_no_force_contacts() -> None:
    massless = Quadruped(parse_urdf(quadruped_urdf()))
    contacts = EffortContacts(massless)
    assert "mass" in contacts.note and contacts.model is None
    assert contacts.probabilities([0.1] * 12, [1.0] * 12, DOWN) is None
    assert EffortContacts(massless, "kinematic").note == ""
