"""The generated leg dynamics judged by PyBullet used directly (fixed base, the URDF's own inertia
tensors): the generalised momentum ``p = M(q) dq`` against ``calculateMassMatrix``, and ``dT/dq =
C^T dq = dM/dt dq - C dq`` against the mass matrix's change along ``dq`` (central differences) and
``calculateInverseDynamics`` with no gravity and no acceleration (``C dq``).

Two robots: the A1 (axes along x and y) and the synthetic robot of ``synthetic_urdf.py`` with
anisotropic, rotated inertia tensors, tilted joints and non-unit axes, where no term vanishes.
The calf's angular velocity that rolls a foot (:mod:`a1_leg_fk.estimation.leg_motion`, also
generated) is judged on both against the calf link's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet
import pybullet_data
import pytest
from synthetic_urdf import SYNTHETIC_JOINTS, SYNTHETIC_URDF

from a1_leg_fk.estimation.leg_motion import LegMotion
from a1_leg_fk.kinematics.leg_dynamics import LegDynamics
from a1_leg_fk.kinematics.quadruped import Quadruped

ISOTROPIC = 'ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"'
TILTED = 'ixx="0.003" ixy="0.0004" ixz="-0.0003" iyy="0.002" iyz="0.0002" izz="0.0015"'
# The base's inertial frame on the root frame: PyBullet's fixed base then puts the root frame at
# the world's origin, unrotated (world = base frame).
SYNTHETIC = SYNTHETIC_URDF.replace(ISOTROPIC, TILTED).replace(
    '<origin xyz="0.05 -0.02 0.03" rpy="0.2 0.1 0.3"/>', ""
)
A1_PATH = Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"


@pytest.fixture(scope="module", params=["a1", "synthetic"])
def robot(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory):
    """(our Quadruped, PyBullet client, body, our slot of each PyBullet degree of freedom)."""
    if request.param == "a1":
        path, quadruped = A1_PATH, Quadruped.from_urdf()
    else:
        assert SYNTHETIC.count(TILTED) == 20  # five links a leg
        path = tmp_path_factory.mktemp("urdf") / "synthetic.urdf"
        path.write_text(SYNTHETIC, encoding="utf-8")
        quadruped = Quadruped.from_urdf(str(path))
        assert list(quadruped.joint_names) == SYNTHETIC_JOINTS
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(
            str(path),
            useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=client,
        )
        infos = [
            pybullet.getJointInfo(body, j, physicsClientId=client)
            for j in range(pybullet.getNumJoints(body, physicsClientId=client))
        ]
        names = [info[1].decode() for info in infos if info[2] != pybullet.JOINT_FIXED]
        slots = [list(quadruped.joint_names).index(name) for name in names]
        yield quadruped, client, body, slots
    finally:
        pybullet.disconnect(client)


def ours(quadruped: Quadruped, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """(2, 12): dT/dq and p of every leg, slot order, the base not turning (the general
    function at omega = 0, and the one generated for an inertial base: the same numbers, to
    rounding)."""
    out = np.empty((2, 12))
    for slot, leg in enumerate(quadruped.legs):
        joints = slice(3 * slot, 3 * slot + 3)
        trig = np.stack([np.cos(angles[joints]), np.sin(angles[joints])], axis=1).ravel()
        dynamics = LegDynamics(quadruped.model, leg)
        terms = dynamics.kinetic_terms(*trig, *rates[joints], 0.0, 0.0, 0.0)
        inertial = dynamics.inertial_terms(*trig, *rates[joints])
        assert np.allclose(inertial, terms, rtol=1e-14, atol=1e-14)
        out[0, joints], out[1, joints] = terms[:3], terms[3:]
    return out


def test_momentum_and_coriolis_match_pybullet(robot) -> None:
    quadruped, client, body, slots = robot
    pybullet.setGravity(0, 0, 0, physicsClientId=client)
    rng = np.random.default_rng(11)
    worst = np.zeros(2)
    for _ in range(5):
        angles = rng.uniform(-1.0, 1.0, 12)
        angles[2::3] = rng.uniform(-2.2, -0.8, 4)
        rates = rng.uniform(-12.0, 12.0, 12)
        q, dq = angles[slots], rates[slots]  # PyBullet's order

        def mass_matrix(at: np.ndarray) -> np.ndarray:
            matrix = pybullet.calculateMassMatrix(body, at.tolist(), physicsClientId=client)
            return np.array(matrix)

        momentum = mass_matrix(q) @ dq
        step = 1e-6
        change = (mass_matrix(q + step * dq) - mass_matrix(q - step * dq)) / (2 * step)
        coriolis = np.array(
            pybullet.calculateInverseDynamics(
                body, q.tolist(), dq.tolist(), [0.0] * 12, physicsClientId=client
            )
        )
        expected = np.empty((2, 12))
        expected[0, slots], expected[1, slots] = change @ dq - coriolis, momentum
        got = ours(quadruped, angles, rates)
        assert np.abs(expected).max(axis=1).min() > 0.05  # the terms are not trivially small
        worst = np.maximum(worst, np.abs(got - expected).max(axis=1))
    assert worst[1] < 1e-12  # p [N m s]: exact
    assert worst[0] < 1e-7  # dT/dq [N m]: to the central difference's accuracy


def test_generated_code_drops_vanishing_terms() -> None:
    """The A1's axes lie along x and y: its code is shorter than the tilted robot's would be, and
    it runs on arrays as on floats."""
    a1 = Quadruped.from_urdf()
    leg = LegDynamics(a1.model, a1.legs[0])
    angles = np.array([[0.1, 0.8, -1.5], [0.2, 0.6, -1.2]])
    rates = np.array([[1.0, -2.0, 3.0], [0.5, 4.0, -6.0]])
    trig = [f(angles[:, k]) for k in range(3) for f in (np.cos, np.sin)]
    batch = np.array(leg.kinetic_terms(*trig, *rates.T, 0.1, -0.2, 0.3))
    for row in range(2):
        floats = leg.kinetic_terms(*[float(t[row]) for t in trig], *rates[row], 0.1, -0.2, 0.3)
        assert np.array_equal(batch[:, row], floats)
    assert leg.source.count("\n") < 400
    assert leg.inertial_source.count("\n") < leg.source.count("\n") / 1.5


def test_calf_rates_match_pybullet(robot) -> None:
    """:class:`LegMotion`'s generated calf rate: the rate of turn of PyBullet's calf link (its
    orientation's central difference along the rates; the fixed base is the world), on the A1
    and on the tilted robot, where no term vanishes. (Not PyBullet's link velocity: it scales
    a non-unit axis' rate by the axis' length.)"""
    quadruped, client, body, _ = robot
    joints = {
        pybullet.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
        for j in range(pybullet.getNumJoints(body, physicsClientId=client))
    }
    index = [joints[name] for name in quadruped.joint_names]  # PyBullet's joint of each slot
    motion = LegMotion(quadruped)
    rng = np.random.default_rng(5)
    step = 1e-3  # [s]: PyBullet's link orientations carry float32's rounding

    def calf_orientations(angles: np.ndarray) -> list[np.ndarray]:
        for slot, joint in enumerate(index):
            pybullet.resetJointState(body, joint, angles[slot], physicsClientId=client)
        return [
            np.array(
                pybullet.getMatrixFromQuaternion(
                    pybullet.getLinkState(
                        body,
                        index[3 * leg + 2],
                        computeForwardKinematics=1,
                        physicsClientId=client,
                    )[5]
                )
            ).reshape(3, 3)
            for leg in range(4)
        ]

    for _ in range(5):
        angles, rates = rng.uniform(-1.0, 1.0, 12), rng.uniform(-6.0, 6.0, 12)
        angles[2::3] = rng.uniform(-2.2, -0.8, 4)
        ahead, behind = (
            calf_orientations(angles + step * rates),
            calf_orientations(angles - step * rates),
        )
        for leg in range(4):
            turn = (ahead[leg] - behind[leg]) / (2 * step) @ ((ahead[leg] + behind[leg]) / 2).T
            theirs = np.array([turn[2, 1], turn[0, 2], turn[1, 0]])  # the skew matrix's vector
            legs = slice(3 * leg, 3 * leg + 3)
            ours = motion.calf_rate(leg, angles[legs].tolist(), rates[legs].tolist())
            assert np.linalg.norm(theirs) > 0.5
            assert np.allclose(ours, theirs, atol=2e-3), (leg, ours, theirs)
