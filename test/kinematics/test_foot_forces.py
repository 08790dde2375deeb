"""Foot forces and contacts from joint efforts, judged by PyBullet.

- g(q) against PyBullet's inverse dynamics (fixed base, zero velocity and acceleration);
- static poses of a free-base A1 on a plane (body height, roll, pitch, three-leg stances):
  efforts = PyBullet's applied motor torques, truth = the contact forces of the plane on each foot;
- trots (A1 and a Go2-like robot, default thresholds): stance from the contact rule against
  PyBullet's contacts (a contact point with a positive normal force);
- bad input: NaN, missing or wrong-length efforts.
"""

from __future__ import annotations

import math
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pybullet
import pytest
from conftest import raises_leg_fk_error
from exported_urdf import exported_quadruped
from pybullet_sim import (
    A1_URDF,
    GRAVITY,
    QuadrupedSim,
    gravity_in_root,
    quaternion_rpy,
    record_trot,
    rotation,
    stack,
)
from shared import STAND_LEG

from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_forces
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import down_direction, gravity_in_base
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES

MAX_TORQUE_NM = 33.5
POSITION_GAIN = 0.3
SETTLE_STEPS = 300
POSES = 40
TROT_HZ = 2.5
KNEE_LIFT_RAD = 0.4
TROT_S = 3.5
COMPARE_FROM_S = 0.25


GO2_FOOT_SPHERE = ("0.022", "-0.002 0 0")
"""Radius and centre [m] of the published Go2 description's foot spheres: 2 mm behind the foot
link's origin."""


def go2_like(folder: Path) -> tuple[Quadruped, Path]:
    """The Go2-like fixture (15.0 kg, 0.213 m thigh and calf; the A1 is 12.5 kg, 0.2 m), with
    primitive geometry only (a 1 cm collision sphere on every link) and the Go2's feet
    (:data:`GO2_FOOT_SPHERE`). Without the shin links: they have no ``<inertial>``, and PyBullet
    gives such a link 1 kg (urdfdom: none).
    """
    robot = ElementTree.fromstring(exported_quadruped("go2", meshes=False, shin_links=False))
    for link in robot.iter("link"):
        if link.get("name", "").endswith("_foot"):
            collision = link.find("collision")
            assert collision is not None
            collision.find("origin").set("xyz", GO2_FOOT_SPHERE[1])  # type: ignore[union-attr]
            collision.find("geometry/sphere").set("radius", GO2_FOOT_SPHERE[0])  # type: ignore[union-attr]
    text = ElementTree.tostring(robot, encoding="unicode")
    path = folder / "go2_primitives.urdf"
    path.write_text(text, encoding="utf-8")
    return Quadruped.from_urdf(text), path


def feet_of(quadruped: Quadruped) -> list[str]:
    return [leg.chain.foot_link for leg in quadruped.legs]


def in_base(forces_world: np.ndarray, orientations: np.ndarray) -> np.ndarray:
    """(N, 4, 3) world forces -> base frame, for (N, 4) root orientations (x, y, z, w)."""
    rotations = np.array([rotation(o) for o in orientations])
    return np.einsum("nlj,nji->nli", forces_world, rotations)


def static_poses(quadruped: Quadruped, radius_m: float, seed: int = 3, count: int = POSES):
    """(root position, orientation, angles) of ``count`` stances the IK can reach: body height
    0.20-0.32 m, roll and pitch within +-0.15 rad, every other pose on three legs (the body moved
    away from the lifted foot, which is 5 cm up).
    """
    footprint = quadruped.fk(list(STAND_LEG) * 4)[:, :2]
    rng = np.random.default_rng(seed)
    poses: list[tuple[np.ndarray, tuple[float, ...], np.ndarray]] = []
    while len(poses) < count:
        height = rng.uniform(0.20, 0.32)
        roll, pitch = rng.uniform(-0.15, 0.15, 2)
        lifted = None if len(poses) % 2 == 0 else len(poses) // 2 % 4
        origin = np.array([0.0, 0.0, height])
        world = np.c_[footprint, np.full(4, radius_m)]
        if lifted is not None:
            origin[:2] -= 0.045 * np.sign(footprint[lifted])
            world[lifted, 2] += 0.05
        orientation = quaternion_rpy(roll, pitch)
        result = quadruped.ik((world - origin) @ rotation(orientation))
        if all(status == "ok" for status in result.status):
            poses.append((origin, orientation, result.angles))
    return poses


def settle(sim: QuadrupedSim, origin, orientation, angles) -> dict[str, np.ndarray]:
    """Hold a pose until it is at rest; the last 10 samples."""
    sim.place(origin, orientation, angles)
    samples = [sim.step(angles, MAX_TORQUE_NM, POSITION_GAIN) for _ in range(SETTLE_STEPS)]
    return stack(samples[-10:])


def test_gravity_torques_match_pybullet_inverse_dynamics(tmp_path: Path) -> None:
    go2, go2_path = go2_like(tmp_path)
    rng = np.random.default_rng(11)
    for quadruped, path in ((Quadruped.from_urdf(), A1_URDF), (go2, go2_path)):
        client = pybullet.connect(pybullet.DIRECT)
        try:
            pybullet.setGravity(0, 0, -GRAVITY, physicsClientId=client)
            body = pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
            infos = [
                pybullet.getJointInfo(body, j, physicsClientId=client)
                for j in range(pybullet.getNumJoints(body, physicsClientId=client))
            ]
            names = [info[1].decode() for info in infos if info[2] != pybullet.JOINT_FIXED]
            assert names == list(quadruped.joint_names)
            model = FootForces(quadruped)
            for _ in range(5):
                angles = rng.uniform(-1.0, 1.0, 12)
                angles[2::3] = rng.uniform(-2.5, -1.0, 4)
                theirs = pybullet.calculateInverseDynamics(
                    body, angles.tolist(), [0.0] * 12, [0.0] * 12, physicsClientId=client
                )
                ours = model.gravity_torques_batch(angles[None], (0, 0, -GRAVITY))[0]
                np.testing.assert_allclose(ours, theirs, atol=1e-9)
        finally:
            pybullet.disconnect(client)


@pytest.mark.parametrize("robot", ["a1", "go2_like"])
def test_static_poses_match_pybullet_contact_forces(robot: str, tmp_path: Path) -> None:
    if robot == "a1":
        quadruped, path, radius, count = Quadruped.from_urdf(), A1_URDF, 0.02, POSES
    else:
        (quadruped, path), radius, count = go2_like(tmp_path), 0.022, POSES // 2
    model = FootForces(quadruped)
    point_feet = FootForces(quadruped, foot_radius_m=0.0)
    assert model.foot_radii_m == (radius,) * 4  # the feet's collision spheres
    found: tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]] = ([], [], [])
    with QuadrupedSim(path, quadruped.joint_names, feet_of(quadruped)) as sim:
        for origin, orientation, angles in static_poses(quadruped, radius, count=count):
            rest = settle(sim, origin, orientation, angles)
            assert not rest["other_contact"].any()
            assert np.abs(rest["rates"]).max() < 0.02  # at rest [rad/s]
            truth = in_base(rest["foot_forces"], rest["root_orientation"]).mean(axis=0)
            q, tau = rest["angles"].mean(axis=0), rest["torques"].mean(axis=0)
            gravity = gravity_in_root(rest["root_orientation"][-1])
            level = (0.0, 0.0, -GRAVITY)  # no IMU: the base assumed level
            for estimator, out, g in (
                (model, found[0], gravity),
                (model, found[1], level),
                (point_feet, found[2], gravity),
            ):
                forces = estimator.estimate(q, tau, g).forces
                out.append(np.linalg.norm(forces - truth, axis=1))
    errors, level_errors, point_errors = (np.array(values) for values in found)
    print(
        f"{robot}: {count} static poses, |F - PyBullet| per foot: with the IMU's gravity max "
        f"{errors.max():.3f} N, rms {np.sqrt((errors**2).mean()):.4f} N; base assumed level: max "
        f"{level_errors.max():.2f} N; point feet (no foot sphere): max {point_errors.max():.2f} N"
    )
    assert errors.max() <= 2.0
    assert level_errors.max() <= 2.0
    assert point_errors.max() > errors.max()  # the contact point matters


def test_the_harness_friction_sign() -> None:
    """PyBullet's lateral friction on body A points against its lateralFrictionDir: pushing the
    standing robot forwards, the plane must push its feet backwards by as much.
    """
    quadruped = Quadruped.from_urdf()
    with QuadrupedSim(A1_URDF, quadruped.joint_names, feet_of(quadruped)) as sim:
        origin, orientation, angles = static_poses(quadruped, 0.02)[0]
        settle(sim, origin, orientation, angles)
        for _ in range(200):
            sim.push([20.0, 0.0, 0.0])
            sample = sim.step(angles, MAX_TORQUE_NM, POSITION_GAIN)
    total = sample.foot_forces.sum(axis=0)
    weight = FootForces(quadruped).total_mass_kg * GRAVITY
    np.testing.assert_allclose(total, [-20.0, 0.0, weight], atol=0.5)


@pytest.mark.parametrize("robot", ["a1", "go2_like"])
def test_trot_contacts_agree_with_pybullet(robot: str, tmp_path: Path) -> None:
    if robot == "a1":
        quadruped, path = Quadruped.from_urdf(), A1_URDF
    else:
        quadruped, path = go2_like(tmp_path)
    stand_height = 0.02 - quadruped.fk(list(STAND_LEG) * 4)[:, 2].mean() + 0.01
    with QuadrupedSim(path, quadruped.joint_names, feet_of(quadruped)) as sim:
        record = record_trot(sim, STAND_LEG, stand_height, TROT_S, TROT_HZ, KNEE_LIFT_RAD)
    model = FootForces(quadruped)
    gravity = np.array([gravity_in_root(o) for o in record["root_orientation"]])
    forces = model.estimate_batch(record["angles"], record["torques"], gravity).forces
    normal = normal_forces(forces, gravity)
    truth_base = in_base(record["foot_forces"], record["root_orientation"])
    true_normal = normal_forces(truth_base, gravity)
    weight = model.total_mass_kg * GRAVITY
    thresholds = ContactThresholds.for_weight(weight)
    stance = ContactRule(thresholds).update_batch(normal) >= 0.5
    compared = record["stamp_s"] >= COMPARE_FROM_S
    truth = true_normal > 0.0
    agreement = (stance == truth)[compared].mean(axis=0)
    overall = (stance == truth)[compared].mean()
    in_stance = compared[:, None] & truth
    found = stance[in_stance].mean()  # of PyBullet's contact samples, those we call stance
    rms = math.sqrt(((normal - true_normal)[in_stance] ** 2).mean())
    print(
        f"{robot} ({model.total_mass_kg:.2f} kg) trot, {int(compared.sum())} samples: thresholds "
        f"{thresholds.touchdown_n:.1f}/{thresholds.liftoff_n:.1f} N; stance agrees with "
        f"PyBullet's contacts on "
        + ", ".join(f"{leg} {share:.2%}" for leg, share in zip(LEG_NAMES, agreement))
        + f" (all {overall:.2%}; of its contact samples {found:.2%})"
        + f"; normal-force rms error in stance {rms:.2f} N"
        + f" = {100 * rms / weight:.1f} % of weight"
    )
    assert not record["other_contact"].any()
    assert 0.3 < truth[compared].mean() < 0.8  # a trot: feet both in the air and on the ground
    assert overall >= 0.97
    assert found >= 0.97  # the touchdown ramps are not missed
    assert (agreement >= 0.95).all()
    assert rms < 0.1 * weight


def test_bad_efforts_give_no_force_for_that_leg_only() -> None:
    quadruped = Quadruped.from_urdf()
    angles = np.tile(list(STAND_LEG) * 4, (4, 1))
    efforts = np.tile([0.5, 2.0, -6.0] * 4, (4, 1))
    efforts[1, 4] = math.nan  # FL
    efforts[2, 9] = math.inf  # RL
    angles[3, 0] = math.nan  # FR's angle
    estimate = FootForces(quadruped).estimate_batch(angles, efforts)
    np.testing.assert_array_equal(
        estimate.missing,
        [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1], [1, 0, 0, 0]],
    )
    assert np.isnan(estimate.forces[estimate.missing]).all()
    assert np.isfinite(estimate.forces[~estimate.missing]).all()
    np.testing.assert_allclose(estimate.forces[1:, 2], estimate.forces[[0, 0, 0], 2])  # RR intact
    straight = np.array(list(STAND_LEG) * 4)
    straight[2] = 0.0  # FR's knee straight: singular
    single = quadruped.foot_forces(straight, efforts[0])
    assert np.isnan(single[0]).all() and np.isfinite(single[1:]).all()
    reasons = FootForces(quadruped).estimate(straight, efforts[1])  # FL's effort NaN
    assert reasons.singular.tolist() == [True, False, False, False]
    assert reasons.missing.tolist() == [False, True, False, False]
    with raises_leg_fk_error("efforts must be 12 numbers"):
        quadruped.foot_forces(straight, [1.0] * 11)
    with raises_leg_fk_error("gravity_base must have shape"):
        quadruped.foot_forces_batch(angles, efforts, np.zeros((3, 3)))


def test_foot_forces_balance_a_hand_computed_pose() -> None:
    """A massless leg: with the gravity torques zero, ``J^T F = -tau`` exactly (Jacobian by finite
    differences of our FK, a reference independent of the solve).
    """
    quadruped = Quadruped.from_urdf()
    angles = np.array([0.1, 0.7, -1.4, -0.1, 0.9, -1.7, 0.05, 0.8, -1.5, 0.0, 1.0, -1.9])
    force = np.array([[3.0, -2.0, 40.0], [1.0, 4.0, 25.0], [-2.0, 0.0, 30.0], [0.0, 1.5, 35.0]])
    step = 1e-6
    jacobians = np.zeros((4, 3, 3))
    for joint in range(12):
        delta = np.zeros(12)
        delta[joint] = step
        column = (quadruped.fk(angles + delta) - quadruped.fk(angles - delta)) / (2 * step)
        jacobians[joint // 3, :, joint % 3] = column[joint // 3]
    efforts = -np.einsum("lji,lj->li", jacobians, force).ravel()
    model = FootForces(quadruped, foot_radius_m=0.0)
    gravity_free = model.estimate(angles, efforts, (0.0, 0.0, -1e-12)).forces
    np.testing.assert_allclose(gravity_free, force, atol=1e-5)


def test_contact_rule_hysteresis_batch_equals_stream() -> None:
    thresholds = ContactThresholds(touchdown_n=10.0, liftoff_n=5.0)
    normal = np.array([0.0, 6.0, 9.9, 10.0, 7.0, 5.0, 4.9, 7.0, math.nan, 12.0, math.nan, 3.0])
    forces = np.stack([normal, normal[::-1], np.full(12, 20.0), np.zeros(12)], axis=1)
    batch = ContactRule(thresholds).update_batch(forces)
    stream_rule = ContactRule(thresholds)
    stream = np.array([stream_rule.update(row) for row in forces])
    np.testing.assert_array_equal(batch, stream)
    stance = batch[:, 0] >= 0.5
    # swing until 10 N, stance down to 5 N, swing below; NaN keeps the state, with no value
    assert stance.tolist() == [0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 0, 0]
    assert np.isnan(batch[[8, 10], 0]).all()
    assert batch[0, 0] == 0.0 and batch[3, 0] == 1.0 and batch[2, 0] == pytest.approx(0.495)
    assert (batch[:, 2] == 1.0).all() and (batch[:, 3] == 0.0).all()
    split = ContactRule(thresholds)
    halves = np.concatenate([split.update_batch(forces[:5]), split.update_batch(forces[5:])])
    np.testing.assert_array_equal(halves, batch)


def test_default_thresholds_scale_with_weight(tmp_path: Path) -> None:
    a1 = FootForces(Quadruped.from_urdf()).total_mass_kg
    go2 = FootForces(go2_like(tmp_path)[0]).total_mass_kg
    assert a1 == pytest.approx(12.458)  # pybullet_data's a1.urdf, summed by hand
    assert go2 == pytest.approx(6.921 + 4 * (0.678 + 1.152 + 0.154 + 0.04))
    low, high = (ContactThresholds.for_weight(m * GRAVITY) for m in (a1, go2))
    assert high.touchdown_n / low.touchdown_n == pytest.approx(go2 / a1)
    assert ContactThresholds.for_weight(100.0, touchdown_n=20.0).touchdown_n == 20.0
    with raises_leg_fk_error("liftoff"):
        ContactThresholds(5.0, 6.0)


def test_gravity_in_base_from_orientation() -> None:
    """Gravity in the base frame from the base's orientation, against PyBullet's rotation."""
    quaternions = np.array(
        [quaternion_rpy(*angles) for angles in np.random.default_rng(2).uniform(-1, 1, (20, 3))]
    )
    expected = [rotation(q).T @ [0.0, 0.0, -9.80665] for q in quaternions]
    np.testing.assert_allclose(gravity_in_base(quaternions), expected, atol=1e-12)
    # The scalar form (the leg odometry's, one sample at a time) is the same rule.
    scalar = [np.array(down_direction(tuple(q))) * 9.80665 for q in quaternions]
    np.testing.assert_allclose(scalar, expected, atol=1e-12)


def test_one_configuration_equals_the_batch() -> None:
    """``foot_forces`` (floats, the per-message path) and ``foot_forces_batch`` (numpy) agree,
    NaN legs included.
    """
    quadruped = Quadruped.from_urdf()
    rng = np.random.default_rng(4)
    angles = np.tile(list(STAND_LEG) * 4, (30, 1)) + rng.uniform(-0.4, 0.4, (30, 12))
    efforts = rng.uniform(-10.0, 10.0, (30, 12))
    angles[3, 2] = 0.0  # FR singular
    efforts[4, 7] = math.nan  # RR
    gravity = np.c_[rng.uniform(-2.0, 2.0, (30, 2)), np.full(30, -9.5)]
    batch = quadruped.foot_forces_batch(angles, efforts, gravity)
    single = np.array([quadruped.foot_forces(*row) for row in zip(angles, efforts, gravity)])
    np.testing.assert_allclose(single, batch, rtol=1e-12, atol=1e-9)
    assert np.isnan(batch[3, 0]).all() and np.isnan(batch[4, 2]).all()
    assert np.isfinite(batch).all(axis=2).sum() == 30 * 4 - 2


def test_the_legs_asked_for_are_the_batch_and_the_others_missing() -> None:
    """``estimate_floats(..., legs)`` (the contact filter's effort doubt asks only for loaded
    feet): each asked leg's force is the batch's, every other leg NaN and missing."""
    quadruped = Quadruped.from_urdf()
    statics = FootForces(quadruped)
    rng = np.random.default_rng(5)
    angles = np.array(list(STAND_LEG) * 4) + rng.uniform(-0.3, 0.3, 12)
    efforts, gravity = rng.uniform(-10.0, 10.0, 12), [0.5, -0.3, -9.7]
    batch = statics.estimate_batch(angles[None], efforts[None], gravity).forces[0]
    legs = [True, False, False, True]
    forces, missing, _ = statics.estimate_floats(angles.tolist(), efforts.tolist(), gravity, legs)
    np.testing.assert_allclose(np.array(forces)[[0, 3]], batch[[0, 3]], rtol=1e-12, atol=1e-9)
    assert np.isnan(np.array(forces)[[1, 2]]).all() and missing == [False, True, True, False]


def test_urdf_masses_and_foot_spheres_are_read() -> None:
    """<inertial> mass and centre (defaults: 0 kg without <mass>, the link origin without
    <origin>), <collision> spheres; bad values name the link.
    """
    from a1_leg_fk.model.urdf import parse_urdf

    def robot(inertial: str, collision: str = "") -> str:
        return (
            '<robot name="r"><link name="base"/><link name="tip">'
            f"{inertial}{collision}</link>"
            '<joint name="j" type="fixed"><parent link="base"/><child link="tip"/></joint>'
            "</robot>"
        )

    model = parse_urdf(
        robot(
            '<inertial><origin xyz="0.1 0 -0.2"/><mass value="1.5"/></inertial>',
            '<collision><origin xyz="-0.002 0 0"/><geometry><sphere radius="0.022"/></geometry>'
            "</collision><collision><geometry><box size='1 1 1'/></geometry></collision>",
        )
    )
    assert model.inertials["tip"].mass == 1.5 and model.inertials["tip"].center == (0.1, 0, -0.2)
    assert "base" not in model.inertials
    assert [(s.radius, s.center) for s in model.spheres["tip"]] == [(0.022, (-0.002, 0, 0))]
    assert parse_urdf(robot("<inertial/>")).inertials["tip"].mass == 0.0
    with raises_leg_fk_error("link 'tip'", "mass"):
        parse_urdf(robot('<inertial><mass value="-1"/></inertial>'))
    with raises_leg_fk_error("link 'tip'", "radius"):
        parse_urdf(robot("", '<collision><geometry><sphere radius="x"/></geometry></collision>'))
