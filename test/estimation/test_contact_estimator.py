"""The contact estimate's forces (a1_leg_fk.estimation.contact_estimator, the path of the node's
and the bag tools' force output) on a tilted base, judged by PyBullet: an A1 hung in the air by its
base at a known roll and pitch, its legs held still by PD motors, touches nothing, so every foot
force must be zero; its motors hold the legs' weight, which points along the *tilted* gravity.
"""

from __future__ import annotations

import numpy as np
import pybullet
import pytest
from pybullet_sim import A1_JOINTS, A1_URDF, STAND, STEP_S, gravity_in_root, quaternion_rpy

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.kinematics.quadruped import Quadruped

A1 = Quadruped.from_urdf()
TILT = quaternion_rpy(0.5, -0.4)  # x, y, z, w


def hung(seconds: float = 1.0) -> dict[str, np.ndarray]:
    """The A1's base fixed 1 m up at :data:`TILT`, its joints held at the stand by PD torques
    (PyBullet's default damping off): per step the angles [rad], rates [rad/s], torques [N m]."""
    client = pybullet.connect(pybullet.DIRECT)
    pb = {"physicsClientId": client}
    try:
        pybullet.setGravity(0, 0, -9.81, **pb)
        pybullet.setTimeStep(STEP_S, **pb)
        body = pybullet.loadURDF(str(A1_URDF), [0, 0, 1], TILT, useFixedBase=True,
                                 flags=pybullet.URDF_USE_INERTIA_FROM_FILE, **pb)  # fmt: skip
        count = pybullet.getNumJoints(body, **pb)
        index = {pybullet.getJointInfo(body, j, **pb)[1].decode(): j for j in range(count)}
        joints = [index[name] for name in A1_JOINTS]
        for joint in range(count):
            pybullet.setJointMotorControl2(body, joint, pybullet.VELOCITY_CONTROL, force=0, **pb)
            pybullet.changeDynamics(body, joint, linearDamping=0, angularDamping=0,
                                    jointDamping=0, **pb)  # fmt: skip
        targets = np.array(STAND * 4)
        rows: dict[str, list] = {"q": [], "dq": [], "tau": []}
        for _ in range(round(seconds / STEP_S)):
            states = pybullet.getJointStates(body, joints, **pb)
            q, dq = np.array([s[0] for s in states]), np.array([s[1] for s in states])
            tau = np.clip(80.0 * (targets - q) - 2.0 * dq, -33.5, 33.5)
            pybullet.setJointMotorControlArray(body, joints, pybullet.TORQUE_CONTROL,
                                               forces=tau.tolist(), **pb)  # fmt: skip
            pybullet.stepSimulation(**pb)
            states = pybullet.getJointStates(body, joints, **pb)
            rows["q"].append([s[0] for s in states])
            rows["dq"].append([s[1] for s in states])
            rows["tau"].append(tau)
    finally:
        pybullet.disconnect(client)
    return {key: np.array(value) for key, value in rows.items()}


@pytest.fixture(scope="module")
def hanging() -> dict[str, np.ndarray]:
    return hung()


def largest_force(hanging: dict[str, np.ndarray], model: str, imu: ImuSample) -> float:
    """The largest foot force [N] over the last 0.2 s (the legs settled), from ``model``."""
    estimator = ContactEstimator(A1, force_model=model)
    largest = 0.0
    rows = len(hanging["q"])
    for row in range(rows):
        joints = (hanging["q"][row].tolist(), hanging["dq"][row].tolist(),
                  hanging["tau"][row].tolist())  # fmt: skip
        step = estimator.step(row * STEP_S, joints, [None] * 4, imu)
        if row * STEP_S >= rows * STEP_S - 0.2:
            largest = max(largest, float(np.abs(step.forces).max()))
            assert np.abs(step.normals).max() <= largest + 1e-9
    return largest


@pytest.mark.parametrize("model", ["dynamic", "static"])
def test_a_tilted_leg_in_the_air_feels_no_force(hanging, model: str) -> None:
    """With gravity rotated into the tilted base (the IMU's orientation; no accelerometer) the
    forces vanish; taken as level, the legs' weight reads as load (about a newton)."""
    gravity = gravity_in_root(TILT).tolist()
    tilted = largest_force(hanging, model, ImuSample(gravity, (0.0, 0.0, 0.0), None))
    level = largest_force(hanging, model, ImuSample(None, (0.0, 0.0, 0.0), None))
    print(f"{model}: largest foot force {tilted:.3f} N tilted, {level:.2f} N taken as level")
    assert tilted < 0.1  # [N]
    assert level > 0.5
