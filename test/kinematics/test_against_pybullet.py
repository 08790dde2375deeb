"""Foot positions against PyBullet itself, and PyBullet's traps documented.

The reference is PyBullet used directly here (never through package code): a DIRECT client, the
URDF loaded with a fixed base at the origin, ``resetJointState`` on every joint, and
``getLinkState(body, link, computeForwardKinematics=True)[4]``, the link (URDF) frame's origin.
Joints and links are matched by name through ``getJointInfo`` (index 1: joint name, 12: child
link name), and the joint names per slot are typed here, so a wrong slot order fails too.
PyBullet computes in float32 internally (about 3e-8 m of noise), hence the 1e-7 m tolerance.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet
import pybullet_data
import pybullet_reference
import pytest
from shared import A1_FEET, LEGS
from shared import PYBULLET_NAMES as A1_JOINTS
from synthetic_urdf import SYNTHETIC_FEET, SYNTHETIC_JOINTS, SYNTHETIC_URDF

from a1_leg_fk.kinematics.quadruped import Quadruped

DATA = Path(pybullet_data.getDataPath())
TOLERANCE_M = 1e-7
CHEETAH_LEGS = ("fr", "fl", "hr", "hl")
CHEETAH_JOINTS = [
    name
    for leg in CHEETAH_LEGS
    for name in (
        f"torso_to_abduct_{leg}_j",
        f"abduct_{leg}_to_thigh_{leg}_j",
        f"thigh_{leg}_to_knee_{leg}_j",
    )
]
CHEETAH_FEET = [f"toe_{leg}" for leg in CHEETAH_LEGS]


class PyBulletRobot(pybullet_reference.PyBulletRobot):
    """The shared PyBullet reference, plus what documents the parentFramePos trap."""

    # -- the trap ------------------------------------------------------------------------
    def chain(self, link: str) -> list[int]:
        """Joint indices from the base down to ``link`` (getJointInfo index 16: parent index)."""
        joints, index = [], self.link_index[link]
        while index != -1:
            joints.append(index)
            index = self.info[index][16]
        return joints[::-1]

    def _joint_rotation(self, index: int) -> np.ndarray:
        """Rotation by the joint's current angle about its getJointInfo axis (index 13), 3x3."""
        info = self.info[index]
        if info[2] == pybullet.JOINT_FIXED:
            return np.eye(3)
        angle = pybullet.getJointState(self.body, index, physicsClientId=self.client)[0]
        return axis_angle_matrix(info[13], angle)

    def naive_chain(self, link: str) -> np.ndarray:
        """The trap: take parentFramePos/Orn (getJointInfo 14, 15) as the joint's URDF origin."""
        rotation, position = np.eye(3), np.zeros(3)
        for index in self.chain(link):
            info = self.info[index]
            position = position + rotation @ np.array(info[14])
            rotation = rotation @ quaternion_matrix(info[15]) @ self._joint_rotation(index)
        return position

    def corrected_chain(self, link: str) -> np.ndarray:
        """What PyBullet's fields really mean, found empirically (see the tests below).

        - parentFramePos (14) is the joint origin in the *parent's inertial (CoM) frame*, which is
          the parent link frame moved by getDynamicsInfo(parent)[3] (local inertial pos) and
          rotated by getDynamicsInfo(parent)[4] (local inertial orn);
        - parentFrameOrn (15) is the *inverse* of the child's CoM frame orientation (at angle 0)
          relative to the parent's CoM frame: conj(parent_com^-1 * origin_rpy * child_com);
        - the joint axis (13) is expressed in the child's CoM frame, so the child's link frame
          is parent_com * (pos 14, conj(orn 15)) * Rot(axis 13, q) * child_com_orn^-1.

        Composed in float64 with numpy: pybullet.multiplyTransforms rounds to float32 at each step.
        """
        rotation, position = np.eye(3), np.zeros(3)
        for index in self.chain(link):
            info = self.info[index]
            parent_com_position, parent_com_orientation = pybullet.getDynamicsInfo(
                self.body, info[16], physicsClientId=self.client
            )[3:5]
            child_com_orientation = pybullet.getDynamicsInfo(
                self.body, index, physicsClientId=self.client
            )[4]
            position = position + rotation @ np.array(parent_com_position)
            rotation = rotation @ quaternion_matrix(parent_com_orientation)
            position = position + rotation @ np.array(info[14])
            rotation = (
                rotation
                @ quaternion_matrix(info[15]).T
                @ self._joint_rotation(index)
                @ quaternion_matrix(child_com_orientation).T
            )
        return position


def quaternion_matrix(quaternion) -> np.ndarray:
    """PyBullet quaternion (x, y, z, w) -> 3x3 rotation matrix, float64."""
    x, y, z, w = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def axis_angle_matrix(axis, angle: float) -> np.ndarray:
    """Rotation by ``angle`` [rad] about ``axis`` (any length), Rodrigues, float64."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * (cross @ cross)


def random_configurations(
    robot: PyBulletRobot, joint_names: list[str], count: int, seed: int
) -> np.ndarray:
    lower, upper = robot.limits(joint_names)
    return np.random.default_rng(seed).uniform(lower, upper, size=(count, len(joint_names)))


def max_error_against_pybullet(
    quadruped: Quadruped, robot: PyBulletRobot, joints, feet, configurations
) -> float:
    worst = 0.0
    batch = quadruped.fk_batch(configurations)
    for q, batch_feet in zip(configurations, batch):
        reference = robot.feet(joints, feet, q)
        worst = max(
            worst,
            float(np.abs(quadruped.fk(q) - reference).max()),
            float(np.abs(batch_feet - reference).max()),
        )
        for leg_slot, leg in enumerate(quadruped.legs):
            generated = leg.position(*q[3 * leg_slot : 3 * leg_slot + 3])
            worst = max(worst, float(np.abs(np.array(generated) - reference[leg_slot]).max()))
    return worst


# --- the package against PyBullet ---------------------------------------------------------


@pytest.fixture(scope="module")
def a1_robot():
    with PyBulletRobot(DATA / "a1" / "a1.urdf") as robot:
        yield robot


@pytest.fixture(scope="module")
def a1() -> Quadruped:
    return Quadruped.from_urdf()


def test_a1_matches_pybullet_on_2000_random_in_limit_configurations(
    a1: Quadruped, a1_robot: PyBulletRobot
) -> None:
    configurations = random_configurations(a1_robot, A1_JOINTS, 2000, seed=2)
    lower, upper = a1_robot.limits(A1_JOINTS)
    assert upper[2] == pytest.approx(-0.916297857297) and lower[1] == pytest.approx(-1.0471975512)
    assert a1.joints_outside_limits(configurations[0]) == []
    error = max_error_against_pybullet(a1, a1_robot, A1_JOINTS, A1_FEET, configurations)
    assert error <= TOLERANCE_M, f"max error {error:.3e} m"


def test_a1_matches_pybullet_outside_the_limits_too(
    a1: Quadruped, a1_robot: PyBulletRobot
) -> None:
    configurations = np.random.default_rng(5).uniform(-math.pi, math.pi, size=(300, 12))
    error = max_error_against_pybullet(a1, a1_robot, A1_JOINTS, A1_FEET, configurations)
    assert error <= TOLERANCE_M, f"max error {error:.3e} m"


def test_a1_jacobian_matches_pybullet(a1: Quadruped, a1_robot: PyBulletRobot) -> None:
    """PyBullet's calculateJacobian at the toe's link-frame origin, fixed base: the columns of our
    3 joints."""
    movable = [info[0] for info in a1_robot.info if info[2] != pybullet.JOINT_FIXED]
    for q in random_configurations(a1_robot, A1_JOINTS, 20, seed=9):
        a1_robot.set_joints(A1_JOINTS, q)
        positions = [
            pybullet.getJointState(a1_robot.body, j, physicsClientId=a1_robot.client)[0]
            for j in movable
        ]
        ours = a1.jacobians(q)
        for leg_slot, foot in enumerate(A1_FEET):
            linear, _ = pybullet.calculateJacobian(
                a1_robot.body,
                a1_robot.link_index[foot],
                [0.0, 0.0, 0.0],
                positions,
                [0.0] * len(movable),
                [0.0] * len(movable),
                physicsClientId=a1_robot.client,
            )
            columns = [
                movable.index(a1_robot.joint_index[name])
                for name in A1_JOINTS[3 * leg_slot : 3 * leg_slot + 3]
            ]
            np.testing.assert_allclose(
                ours[leg_slot], np.array(linear)[:, columns], rtol=0.0, atol=1e-6
            )


@pytest.mark.parametrize(
    ("urdf", "joints", "feet", "foot_links"),
    [
        ("aliengo/aliengo.urdf", A1_JOINTS, A1_FEET, None),
        (
            "mini_cheetah/mini_cheetah.urdf",
            CHEETAH_JOINTS,
            CHEETAH_FEET,
            dict(zip(LEGS, CHEETAH_FEET)),
        ),
    ],
    ids=["aliengo", "mini_cheetah"],
)
def test_other_pybullet_data_quadrupeds_match(urdf: str, joints, feet, foot_links) -> None:
    quadruped = Quadruped.from_urdf(str(DATA / urdf), foot_links=foot_links)
    assert list(quadruped.joint_names) == joints
    with PyBulletRobot(DATA / urdf) as robot:
        configurations = random_configurations(robot, joints, 500, seed=11)
        error = max_error_against_pybullet(quadruped, robot, joints, feet, configurations)
    assert error <= TOLERANCE_M, f"{urdf}: max error {error:.3e} m"


def test_mini_cheetah_has_minus_y_axes_and_continuous_joints() -> None:
    with PyBulletRobot(DATA / "mini_cheetah" / "mini_cheetah.urdf") as robot:
        for name in CHEETAH_JOINTS:
            info = robot.info[robot.joint_index[name]]
            assert info[8] > info[9], (
                f"{name} has limits {info[8]}..{info[9]}"
            )  # PyBullet's "no limit"
        assert robot.info[robot.joint_index["abduct_fr_to_thigh_fr_j"]][13] == (0.0, -1.0, 0.0)
        assert robot.info[robot.joint_index["thigh_fr_to_knee_fr_j"]][13] == (0.0, -1.0, 0.0)


# --- full rpy origins and non-unit axes ---------------------------------------------------


@pytest.fixture(scope="module")
def synthetic_robot(tmp_path_factory):
    path = tmp_path_factory.mktemp("urdf") / "synthetic.urdf"
    path.write_text(SYNTHETIC_URDF, encoding="utf-8")
    with PyBulletRobot(path) as robot:
        yield robot


def test_full_rpy_origins_and_non_unit_axes_match_pybullet(synthetic_robot: PyBulletRobot) -> None:
    quadruped = Quadruped.from_urdf(SYNTHETIC_URDF)  # the same text, as an XML string
    assert list(quadruped.joint_names) == SYNTHETIC_JOINTS
    configurations = random_configurations(synthetic_robot, SYNTHETIC_JOINTS, 300, seed=13)
    error = max_error_against_pybullet(
        quadruped, synthetic_robot, SYNTHETIC_JOINTS, SYNTHETIC_FEET, configurations
    )
    assert error <= TOLERANCE_M, f"max error {error:.3e} m"


def test_the_synthetic_robot_really_rotates(synthetic_robot: PyBulletRobot) -> None:
    """Guard for the test above: with rpy and axes ignored, the feet would be elsewhere."""
    flat = SYNTHETIC_URDF
    for old in ('rpy="0.4 0.25 -0.6"', 'rpy="0.5 0.6 0.7"', 'axis xyz="2 0 0.5"'):
        flat = flat.replace(old, 'rpy="0 0 0"' if old.startswith("rpy") else 'axis xyz="1 0 0"')
    q = random_configurations(synthetic_robot, SYNTHETIC_JOINTS, 1, seed=1)[0]
    reference = synthetic_robot.feet(SYNTHETIC_JOINTS, SYNTHETIC_FEET, q)
    assert np.abs(Quadruped.from_urdf(flat).fk(q) - reference).max() > 0.01


# --- PyBullet's traps, documented ---------------------------------------------------------


def test_summing_parent_frame_pos_is_7_to_14_cm_off_and_the_com_offset_fixes_it(
    a1_robot: PyBulletRobot,
) -> None:
    """getJointInfo()[14] (parentFramePos) is relative to the parent's CoM, not its link frame.

    Chaining it as if it were the URDF origin is off by 69..141 mm over uniform in-limit poses
    (the issue quotes 75..134 mm); adding the parent's local inertial position (and, in general,
    the rotations, see corrected_chain) gives PyBullet's answer back to float32 noise.
    """
    naive, corrected = [], []
    for q in random_configurations(a1_robot, A1_JOINTS, 500, seed=17):
        a1_robot.set_joints(A1_JOINTS, q)
        for foot in A1_FEET:
            reference = a1_robot.link_frame(foot)
            naive.append(np.linalg.norm(a1_robot.naive_chain(foot) - reference))
            corrected.append(np.abs(a1_robot.corrected_chain(foot) - reference).max())
    assert 0.06 <= min(naive) <= 0.085, f"naive error from {min(naive):.4f} m"
    assert 0.125 <= max(naive) <= 0.15, f"naive error up to {max(naive):.4f} m"
    assert max(corrected) <= TOLERANCE_M, f"corrected error {max(corrected):.3e} m"


def test_the_corrected_chain_also_holds_with_rpy_and_rotated_inertials(
    synthetic_robot: PyBulletRobot,
) -> None:
    """Evidence for corrected_chain's reading of the fields: rotated inertial frames, rpy, non-unit
    axes."""
    naive, corrected = [], []
    for q in random_configurations(synthetic_robot, SYNTHETIC_JOINTS, 100, seed=19):
        synthetic_robot.set_joints(SYNTHETIC_JOINTS, q)
        for foot in SYNTHETIC_FEET:
            reference = synthetic_robot.link_frame(foot)
            naive.append(np.abs(synthetic_robot.naive_chain(foot) - reference).max())
            corrected.append(np.abs(synthetic_robot.corrected_chain(foot) - reference).max())
    assert min(naive) > 0.01
    assert max(corrected) <= TOLERANCE_M, f"corrected error {max(corrected):.3e} m"


@pytest.mark.parametrize(
    ("joint", "parent_com_rpy", "origin_rpy", "child_com_rpy"),
    [
        ("FR_mount", (0.2, 0.1, 0.3), (0.1, -0.2, -0.3), (0.2, 0.0, 0.0)),
        ("FR_roll", (0.2, 0.0, 0.0), (0.4, 0.25, -0.6), (0.3, 0.2, 0.1)),
        ("RL_knee", (0.0, 0.5, 0.0), (0.0, 0.1, 0.0), (-0.1, 0.2, 0.3)),
    ],
)
def test_parent_frame_orn_is_the_inverse_com_to_com_rotation(
    synthetic_robot: PyBulletRobot, joint: str, parent_com_rpy, origin_rpy, child_com_rpy
) -> None:
    """getJointInfo()[15] = conj(parent_com^-1 * origin * child_com), rpy values typed from
    SYNTHETIC_URDF."""

    def matrix(rpy) -> np.ndarray:
        return quaternion_matrix(pybullet.getQuaternionFromEuler(rpy))

    expected = (matrix(parent_com_rpy).T @ matrix(origin_rpy) @ matrix(child_com_rpy)).T
    reported = quaternion_matrix(synthetic_robot.info[synthetic_robot.joint_index[joint]][15])
    np.testing.assert_allclose(reported, expected, atol=1e-6)
    assert np.abs(reported - expected.T).max() > 1e-2  # not the un-inverted rotation


def test_link_state_0_is_the_com_not_the_link_frame(a1_robot: PyBulletRobot) -> None:
    """For FR_lower, getLinkState()[0] is the CoM, 0.1076 m from the frame (URDF inertial xyz
    0.006435 0 -0.107388)."""
    a1_robot.set_joints(A1_JOINTS, [0.0, 0.8, -1.5] * 4)
    state = a1_robot.link_state("FR_lower")
    offset = np.array(state[0]) - np.array(state[4])
    assert np.linalg.norm(offset) == pytest.approx(math.hypot(0.006435, 0.107388), abs=1e-6)
    assert np.linalg.norm(offset) > 0.1
    # The toe's inertial origin is its frame, so there [0] and [4] agree: only [4] is right for
    # both.
    toe = a1_robot.link_state("FR_toe")
    assert np.abs(np.array(toe[0]) - np.array(toe[4])).max() <= TOLERANCE_M


def test_reset_joint_state_does_not_enforce_limits(a1: Quadruped, a1_robot: PyBulletRobot) -> None:
    """The knee's range (-2.697..-0.916 rad) excludes 0, yet PyBullet accepts and keeps 0."""
    lower, upper = a1_robot.limits(["FR_lower_joint"])
    assert lower[0] == pytest.approx(-2.69653369433) and upper[0] == pytest.approx(-0.916297857297)
    assert not lower[0] <= 0.0 <= upper[0]
    q = [0.0] * 12
    feet = a1_robot.feet(A1_JOINTS, A1_FEET, q)
    assert (
        pybullet.getJointState(
            a1_robot.body, a1_robot.joint_index["FR_lower_joint"], physicsClientId=a1_robot.client
        )[0]
        == 0.0
    )
    np.testing.assert_allclose(feet[0], (0.183, -0.13205, -0.4), rtol=0.0, atol=TOLERANCE_M)
    assert "FR_lower_joint" in [violation.joint for violation in a1.joints_outside_limits(q)]


def test_pybullet_places_the_urdf_root_frame_at_the_origin(a1_robot: PyBulletRobot) -> None:
    """The base *CoM* sits at the trunk's inertial xyz (0.012731 0.002186 0.000515): world = base
    frame."""
    position, orientation = pybullet.getBasePositionAndOrientation(
        a1_robot.body, physicsClientId=a1_robot.client
    )
    np.testing.assert_allclose(position, (0.012731, 0.002186, 0.000515), atol=1e-7)
    np.testing.assert_allclose(orientation, (0.0, 0.0, 0.0, 1.0), atol=1e-12)
    a1_robot.set_joints(A1_JOINTS, [0.3, 0.8, -1.5] * 4)
    np.testing.assert_allclose(
        a1_robot.link_frame("FR_hip"), (0.183, -0.047, 0.0), atol=TOLERANCE_M
    )
