"""The generated statics on a leg with everything tilted (full rpy origins, non-unit axes off the
coordinate axes, masses on fixed links above and below the joints), judged by PyBullet used
directly: its inverse dynamics for g(q), its point Jacobian for the contact point.

The A1 and Go2-like tests (test_foot_forces.py) have every axis along x or y, where most of the
generated terms vanish; this robot keeps them all.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet
import pytest
from synthetic_urdf import SYNTHETIC_JOINTS, SYNTHETIC_URDF

from a1_leg_fk.kinematics.foot_forces import MIN_JACOBIAN_CONDITION, FootForces
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES

# The base's inertial frame on the URDF root frame, so that PyBullet's fixed base (placed by its
# centre of mass) puts the root frame at the world's origin, unrotated: world = base frame.
URDF = SYNTHETIC_URDF.replace('<origin xyz="0.05 -0.02 0.03" rpy="0.2 0.1 0.3"/>', "")
GRAVITIES = [(0.0, 0.0, -9.81), (1.2, -2.5, -9.3), (-3.0, 0.8, -8.9)]  # [m/s^2], base frame
RADIUS_M = 0.03


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory):
    assert URDF != SYNTHETIC_URDF
    path: Path = tmp_path_factory.mktemp("urdf") / "synthetic.urdf"
    path.write_text(URDF, encoding="utf-8")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
        infos = [
            pybullet.getJointInfo(body, j, physicsClientId=client)
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))
        ]
        movable = [i for i, info in enumerate(infos) if info[2] != pybullet.JOINT_FIXED]
        assert [infos[i][1].decode() for i in movable] == SYNTHETIC_JOINTS
        feet = {info[12].decode(): i for i, info in enumerate(infos)}
        yield client, body, movable, feet
    finally:
        pybullet.disconnect(client)


def configurations(count: int) -> np.ndarray:
    rng = np.random.default_rng(5)
    angles = rng.uniform(-1.2, 1.2, (count, 12))
    angles[:, 2::3] = rng.uniform(-2.4, -0.6, (count, 4))
    return angles


def pybullet_gravity_torques(robot, angles: np.ndarray, gravity) -> np.ndarray:
    client, body, _, _ = robot
    pybullet.setGravity(*gravity, physicsClientId=client)
    zeros = [0.0] * 12
    return np.array(
        pybullet.calculateInverseDynamics(
            body, angles.tolist(), zeros, zeros, physicsClientId=client
        )
    )


def pybullet_contact_jacobians(robot, angles: np.ndarray, offset_world) -> list[np.ndarray]:
    """Per leg, (3, 3): d(contact point)/d(the leg's angles), the point ``offset_world`` [m]
    from the foot link's origin, carried by the foot."""
    client, body, movable, feet = robot
    for index, angle in zip(movable, angles, strict=True):
        pybullet.resetJointState(body, index, float(angle), physicsClientId=client)
    zeros = [0.0] * 12
    jacobians = []
    for leg, name in enumerate(LEG_NAMES):
        foot = feet[f"{name}_foot"]
        orientation = pybullet.getLinkState(body, foot, physicsClientId=client)[5]
        rotation = np.array(pybullet.getMatrixFromQuaternion(orientation)).reshape(3, 3)
        local = rotation.T @ np.asarray(offset_world)  # its inertial frame is its link frame
        linear, _ = pybullet.calculateJacobian(
            body, foot, local.tolist(), angles.tolist(), zeros, zeros, physicsClientId=client
        )
        jacobians.append(np.array(linear)[:, 3 * leg : 3 * leg + 3])
    return jacobians


def test_gravity_torques_match_pybullet_on_a_tilted_robot(robot) -> None:
    model = FootForces(Quadruped.from_urdf(URDF))
    for gravity in GRAVITIES:
        for angles in configurations(10):
            theirs = pybullet_gravity_torques(robot, angles, gravity)
            ours = model.gravity_torques_batch(angles[None], gravity)[0]
            np.testing.assert_allclose(ours, theirs, atol=1e-9)


@pytest.mark.parametrize("radius", [0.0, RADIUS_M])
def test_forces_invert_pybullets_statics_on_a_tilted_robot(robot, radius: float) -> None:
    """Efforts made by PyBullet for a known force at the contact point give that force back."""
    model = FootForces(Quadruped.from_urdf(URDF), foot_radius_m=radius)
    rng = np.random.default_rng(8)
    worst, legs, singular = 0.0, 0, 0
    for gravity in GRAVITIES:
        down = np.asarray(gravity) / np.linalg.norm(gravity)
        for angles in configurations(10):
            truth = rng.uniform(-20.0, 20.0, (4, 3)) + np.array([0.0, 0.0, 40.0])  # [N], base
            efforts = pybullet_gravity_torques(robot, angles, gravity)
            conditions = []
            jacobians = pybullet_contact_jacobians(robot, angles, radius * down)
            for leg, jacobian in enumerate(jacobians):
                efforts[3 * leg : 3 * leg + 3] -= jacobian.T @ truth[leg]
                conditions.append(
                    abs(np.linalg.det(jacobian)) / np.prod(np.linalg.norm(jacobian, axis=0))
                )
            estimate = model.estimate(angles, efforts, gravity)
            assert not estimate.missing.any()
            expected_singular = np.array(conditions) < MIN_JACOBIAN_CONDITION
            assert (estimate.singular == expected_singular).all(), conditions
            solved = ~expected_singular
            legs += 4
            singular += int(expected_singular.sum())
            worst = max(worst, float(np.abs(estimate.forces[solved] - truth[solved]).max()))
            assert np.isnan(estimate.forces[~solved]).all()
            batch = model.estimate_batch(angles[None], efforts[None], gravity).forces[0]
            np.testing.assert_allclose(batch, estimate.forces, atol=1e-9)
    print(
        f"radius {radius} m: {legs} legs, {singular} near-singular, |F - truth| <= {worst:.1e} N"
    )
    assert singular <= legs // 5
    # on the foot's origin PyBullet's Jacobian is exact; off it, the foot's orientation comes
    # from getLinkState in float32 (~1e-7), which moves the efforts by ~1e-7 N m
    assert worst <= (1e-9 if radius == 0.0 else 1e-5)


def test_the_contact_point_moves_the_forces() -> None:
    """Guard for the test above: the radius changes the answer on this robot."""
    quadruped = Quadruped.from_urdf(URDF)
    angles, efforts = configurations(1)[0], np.linspace(-3.0, 3.0, 12)
    on_origin = FootForces(quadruped, foot_radius_m=0.0).estimate(angles, efforts, GRAVITIES[1])
    on_sphere = FootForces(quadruped, foot_radius_m=RADIUS_M).estimate(
        angles, efforts, GRAVITIES[1]
    )
    assert np.abs(on_sphere.forces - on_origin.forces).max() > 0.1
