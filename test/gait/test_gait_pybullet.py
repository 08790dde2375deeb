"""PyBullet as the judge of the kinematic contact detector.

The A1 (pybullet_data's a1/a1.urdf) stands on a plane with a free base; position-controlled joints
follow a trot generated here (diagonal pairs FR+RL / FL+RR half a cycle apart, a swing leg bends
its knee and turns its hip pitch by half that). The test records what a robot would: the base pose
and the joint angles (with a little encoder noise from a fixed seed). The feet in the world frame
come from our FK (embedded A1) and the recorded base pose, converted from PyBullet's base frame
(the trunk's centre of mass) to the URDF root origin. The reference is PyBullet's own
``getContactPoints`` between each toe and the plane.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet
import pybullet_data
from shared import STAND_LEG as STAND

from a1_leg_fk.gait.analysis import analyze_gait
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES

STEP_S = 1.0 / 500.0
SIM_S = 3.5
TROT_START_S = 0.5
TROT_HZ = 2.5
KNEE_LIFT_RAD = 0.4
POSITION_GAIN = 0.3
MAX_TORQUE_NM = 33.5
ENCODER_NOISE_RAD = 2e-4
COMPARE_FROM_S = 0.25  # after the drop from the spawn height onto the plane
DIAGONAL_PAIR = {"FR": 0, "RL": 0, "FL": 1, "RR": 1}


def trot_targets(t: float) -> list[float]:
    """12 joint targets [rad] at time ``t`` [s]: stand, then a trot in place from TROT_START_S."""
    targets = []
    for leg in LEG_NAMES:
        phase = 2 * math.pi * TROT_HZ * (t - TROT_START_S) + math.pi * DIAGONAL_PAIR[leg]
        bend = KNEE_LIFT_RAD * max(0.0, math.sin(phase)) if t > TROT_START_S else 0.0
        targets += [STAND[0], STAND[1] + bend / 2, STAND[2] - bend]
    return targets


def simulate(
    quadruped: Quadruped,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(stamps [s], joint angles (N, 12) [rad], root position (N, 3) [m], root quaternion xyzw (N,
    4), toe contact (N, 4))."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.setGravity(0, 0, -9.81, physicsClientId=client)
        pybullet.setTimeStep(STEP_S, physicsClientId=client)
        data = pybullet_data.getDataPath()
        plane = pybullet.loadURDF(f"{data}/plane.urdf", physicsClientId=client)
        body = pybullet.loadURDF(f"{data}/a1/a1.urdf", [0, 0, 0.30], physicsClientId=client)
        infos = [
            pybullet.getJointInfo(body, j, physicsClientId=client)
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))
        ]
        joint_index = {info[1].decode(): info[0] for info in infos}
        link_index = {info[12].decode(): info[0] for info in infos}
        joints = [joint_index[name] for name in quadruped.joint_names]
        toes = [link_index[f"{leg}_toe"] for leg in LEG_NAMES]
        for joint, angle in zip(joints, trot_targets(0.0)):
            pybullet.resetJointState(body, joint, angle, physicsClientId=client)
        # PyBullet's base pose is the trunk's inertial frame: root = base * inverse(local inertial
        # frame).
        inertial_position, inertial_orientation = pybullet.getDynamicsInfo(
            body, -1, physicsClientId=client
        )[3:5]
        to_root = pybullet.invertTransform(inertial_position, inertial_orientation)
        stamps, angles, positions, orientations, contact = [], [], [], [], []
        for step in range(round(SIM_S / STEP_S)):
            pybullet.setJointMotorControlArray(
                body,
                joints,
                pybullet.POSITION_CONTROL,
                targetPositions=trot_targets(step * STEP_S),
                forces=[MAX_TORQUE_NM] * 12,
                positionGains=[POSITION_GAIN] * 12,
                velocityGains=[1.0] * 12,
                physicsClientId=client,
            )
            pybullet.stepSimulation(physicsClientId=client)
            base_position, base_orientation = pybullet.getBasePositionAndOrientation(
                body, physicsClientId=client
            )
            root_position, root_orientation = pybullet.multiplyTransforms(
                base_position, base_orientation, *to_root
            )
            stamps.append((step + 1) * STEP_S)
            angles.append(
                [
                    state[0]
                    for state in pybullet.getJointStates(body, joints, physicsClientId=client)
                ]
            )
            positions.append(root_position)
            orientations.append(root_orientation)
            contact.append(
                [
                    bool(
                        pybullet.getContactPoints(
                            body, plane, linkIndexA=toe, physicsClientId=client
                        )
                    )
                    for toe in toes
                ]
            )
    finally:
        pybullet.disconnect(client)
    return (
        np.array(stamps),
        np.array(angles),
        np.array(positions),
        np.array(orientations),
        np.array(contact),
    )


def rotation_matrices(quaternions: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) unit quaternions (x, y, z, w)."""
    x, y, z, w = quaternions.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=1,
    )


def test_contacts_agree_with_pybullet() -> None:
    quadruped = Quadruped.from_urdf()
    stamps, angles, positions, orientations, contact = simulate(quadruped)
    noisy = angles + np.random.default_rng(7).normal(0.0, ENCODER_NOISE_RAD, angles.shape)
    feet = quadruped.fk_batch(noisy)
    world = (
        np.einsum("nij,nlj->nli", rotation_matrices(orientations), feet) + positions[:, None, :]
    )
    contacts, report = analyze_gait(stamps, world)
    compared = stamps >= COMPARE_FROM_S
    agreement = (contacts.stance[compared] == contact[compared]).mean(axis=0)
    print(
        f"stance vs PyBullet contact, {int(compared.sum())} samples at {1 / STEP_S:g} Hz: "
        + ", ".join(f"{leg} {share:.1%}" for leg, share in zip(LEG_NAMES, agreement))
        + f"; all {(contacts.stance[compared] == contact[compared]).mean():.1%}; gait "
        f"{report.gait} (fit {report.gait_fit:.2f}), ground {report.ground.level_m * 1e3:.1f} mm"
    )
    assert (agreement >= 0.95).all()
    assert report.gait == "trot"
    # The ground level is that of the toe sphere's centre (radius 0.02 m) on the plane z = 0.
    assert abs(report.ground.level_m - 0.02) < 0.003
