"""A free-base quadruped on a plane in PyBullet, recording what a robot's sensors would give.

Independent of the code under test (no a1_leg_fk import): joints and links are found by name in
PyBullet's own model. Each :meth:`QuadrupedSim.step` records a :class:`Sample`:

- joint angles [rad], velocities [rad/s] and applied motor torques [N m] (``getJointState()[3]``:
  the torque the motor applies to the child link about the joint axis, as a JointState effort);
- the pose of the URDF root link (PyBullet's base pose is the root's centre-of-mass frame; it is
  converted here), world frame, and its linear [m/s] and angular [rad/s] velocity, world frame;
- an IMU aligned with the root: orientation (x, y, z, w) and gyro [rad/s] in the root frame;
- per foot, the force the ground exerts on it [N, world frame]: every contact point of the foot
  link with the plane, normal force plus both friction components, summed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Self

import numpy as np
import pybullet
import pybullet_data

A1_URDF = Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"
STEP_S = 1.0 / 500.0
GRAVITY = 9.81
DIAGONAL_PAIR = (0, 1, 1, 0)
"""Per leg (FR, FL, RR, RL): which half of a trot's cycle it swings in."""


@dataclass(frozen=True)
class Sample:
    """One simulation step's sensor readings (see the module text for frames and units)."""

    stamp_s: float
    angles: np.ndarray  # (12,)
    rates: np.ndarray  # (12,)
    torques: np.ndarray  # (12,)
    root_position: np.ndarray  # (3,)
    root_orientation: np.ndarray  # (4,) x, y, z, w
    linear_velocity: np.ndarray  # (3,) world
    angular_velocity: np.ndarray  # (3,) world
    gyro: np.ndarray  # (3,) root frame
    foot_forces: np.ndarray  # (4, 3) world
    foot_contact: np.ndarray  # (4,) bool: any contact point of the foot with the plane
    other_contact: bool  # any other link touching the plane


def stack(samples: Sequence[Sample]) -> dict[str, np.ndarray]:
    """The samples' fields as arrays with a leading sample axis."""
    return {
        name: np.array([getattr(sample, name) for sample in samples])
        for name in Sample.__dataclass_fields__
    }


def rotation(quaternion: Sequence[float]) -> np.ndarray:
    """3x3 rotation matrix of a unit quaternion (x, y, z, w)."""
    return np.array(pybullet.getMatrixFromQuaternion(list(quaternion))).reshape(3, 3)


class QuadrupedSim:
    """One robot and a plane in a DIRECT client of its own; use as a context manager."""

    def __init__(
        self,
        urdf_path: Path | str,
        joint_names: Sequence[str],
        foot_links: Sequence[str],
        step_s: float = STEP_S,
    ) -> None:
        self.client = pybullet.connect(pybullet.DIRECT)
        self.step_s, self.time_s = step_s, 0.0
        try:
            pybullet.setGravity(0, 0, -GRAVITY, physicsClientId=self.client)
            pybullet.setTimeStep(step_s, physicsClientId=self.client)
            data = pybullet_data.getDataPath()
            self.plane = pybullet.loadURDF(f"{data}/plane.urdf", physicsClientId=self.client)
            self.body = pybullet.loadURDF(str(urdf_path), [0, 0, 1], physicsClientId=self.client)
            infos = [
                pybullet.getJointInfo(self.body, j, physicsClientId=self.client)
                for j in range(pybullet.getNumJoints(self.body, physicsClientId=self.client))
            ]
        except BaseException:
            pybullet.disconnect(self.client)
            raise
        joint_index = {info[1].decode(): info[0] for info in infos}
        link_index = {info[12].decode(): info[0] for info in infos}
        self.joints = [joint_index[name] for name in joint_names]
        self.feet = [link_index[name] for name in foot_links]
        for joint in range(len(infos)):  # no default velocity motors, no joint damping
            pybullet.setJointMotorControl2(
                self.body, joint, pybullet.VELOCITY_CONTROL, force=0, physicsClientId=self.client
            )
            pybullet.changeDynamics(
                self.body, joint, linearDamping=0, angularDamping=0, jointDamping=0,
                physicsClientId=self.client,
            )  # fmt: skip
        inertial = pybullet.getDynamicsInfo(self.body, -1, physicsClientId=self.client)[3:5]
        self._to_root = pybullet.invertTransform(*inertial)
        self._inertial = inertial

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *_: object) -> None:
        pybullet.disconnect(self.client)

    def place(
        self,
        root_position: Sequence[float],
        root_orientation: Sequence[float],
        angles: Sequence[float],
    ) -> None:
        """Put the root link at a pose (world) and the joints at ``angles`` [rad], at rest."""
        position, orientation = pybullet.multiplyTransforms(
            root_position, root_orientation, *self._inertial
        )
        pybullet.resetBasePositionAndOrientation(
            self.body, position, orientation, physicsClientId=self.client
        )
        pybullet.resetBaseVelocity(self.body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client)
        for joint, angle in zip(self.joints, angles):
            pybullet.resetJointState(self.body, joint, angle, 0.0, physicsClientId=self.client)

    def step(
        self,
        targets: Sequence[float],
        max_torque_nm: float,
        position_gain: float,
        velocity_gain: float = 1.0,
    ) -> Sample:
        """Drive the joints towards ``targets`` [rad] (PyBullet's position control), step, and
        record.
        """
        client = self.client
        pybullet.setJointMotorControlArray(
            self.body,
            self.joints,
            pybullet.POSITION_CONTROL,
            targetPositions=list(targets),
            forces=[max_torque_nm] * len(self.joints),
            positionGains=[position_gain] * len(self.joints),
            velocityGains=[velocity_gain] * len(self.joints),
            physicsClientId=client,
        )
        pybullet.stepSimulation(physicsClientId=client)
        self.time_s += self.step_s
        return self.sample()

    def sample(self) -> Sample:
        """The sensor readings now."""
        client = self.client
        states = pybullet.getJointStates(self.body, self.joints, physicsClientId=client)
        position, orientation = pybullet.getBasePositionAndOrientation(
            self.body, physicsClientId=client
        )
        root_position, root_orientation = pybullet.multiplyTransforms(
            position, orientation, *self._to_root
        )
        linear, angular = pybullet.getBaseVelocity(self.body, physicsClientId=client)
        to_world = rotation(root_orientation)
        # the root origin moves with the CoM velocity plus omega x (root - CoM)
        linear = np.array(linear) + np.cross(angular, np.subtract(root_position, position))
        forces, contact = self.foot_forces()
        return Sample(
            self.time_s,
            np.array([state[0] for state in states]),
            np.array([state[1] for state in states]),
            np.array([state[3] for state in states]),
            np.array(root_position),
            np.array(root_orientation),
            linear,
            np.array(angular),
            to_world.T @ np.array(angular),
            forces,
            contact,
            self._other_contact(),
        )

    def foot_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(4, 3) the force of the plane on each foot [N, world], and (4,) whether it touches."""
        forces = np.zeros((len(self.feet), 3))
        touching = np.zeros(len(self.feet), dtype=bool)
        for slot, foot in enumerate(self.feet):
            for point in pybullet.getContactPoints(
                self.body, self.plane, linkIndexA=foot, physicsClientId=self.client
            ):
                touching[slot] = True
                # on body A: normal force along contactNormalOnB (from B to A), friction along
                # the lateral directions
                forces[slot] += (
                    point[9] * np.array(point[7])
                    - point[10] * np.array(point[11])
                    - point[12] * np.array(point[13])
                )
        return forces, touching

    def _other_contact(self) -> bool:
        points = pybullet.getContactPoints(self.body, self.plane, physicsClientId=self.client)
        return any(point[3] not in self.feet for point in points)

    def push(self, force_world: Sequence[float]) -> None:
        """Apply ``force_world`` [N] at the base's centre of mass for the next step."""
        center = pybullet.getBasePositionAndOrientation(self.body, physicsClientId=self.client)[0]
        pybullet.applyExternalForce(
            self.body, -1, list(force_world), list(center), pybullet.WORLD_FRAME,
            physicsClientId=self.client,
        )  # fmt: skip


def trot_targets(
    t: float, stand: Sequence[float], hz: float, knee_lift_rad: float, start_s: float = 0.5
) -> list[float]:
    """12 joint targets [rad] at time ``t`` [s]: every leg at ``stand`` (hip roll, hip pitch,
    knee), then from ``start_s`` a trot in place: diagonal pairs half a cycle apart, a swing leg
    bends its knee by up to ``knee_lift_rad`` and turns its hip pitch by half that.
    """
    targets = []
    for pair in DIAGONAL_PAIR:
        phase = 2 * math.pi * hz * (t - start_s) + math.pi * pair
        bend = knee_lift_rad * max(0.0, math.sin(phase)) if t > start_s else 0.0
        targets += [stand[0], stand[1] + bend / 2, stand[2] - bend]
    return targets


def record_trot(
    sim: QuadrupedSim,
    stand: Sequence[float],
    stand_height_m: float,
    seconds: float,
    hz: float = 2.5,
    knee_lift_rad: float = 0.4,
    max_torque_nm: float = 33.5,
    position_gain: float = 0.3,
) -> dict[str, np.ndarray]:
    """Drop the robot standing from ``stand_height_m`` [m] (root origin) and trot in place
    (:func:`trot_targets`) for ``seconds``; every step's :class:`Sample`, stacked.
    """
    sim.place([0, 0, stand_height_m], [0, 0, 0, 1], trot_targets(0.0, stand, hz, knee_lift_rad))
    samples = [
        sim.step(trot_targets(sim.time_s, stand, hz, knee_lift_rad), max_torque_nm, position_gain)
        for _ in range(round(seconds / sim.step_s))
    ]
    return stack(samples)


def quaternion_rpy(roll: float, pitch: float, yaw: float = 0.0) -> tuple[float, ...]:
    """(x, y, z, w) of fixed-axis roll, pitch, yaw [rad]."""
    return tuple(pybullet.getQuaternionFromEuler([roll, pitch, yaw]))


def gravity_in_root(orientation: Sequence[float], magnitude: float = GRAVITY) -> np.ndarray:
    """World gravity (0, 0, -magnitude) [m/s^2] in the frame of a root at ``orientation``."""
    result: np.ndarray = rotation(orientation).T @ np.array([0.0, 0.0, -magnitude])
    return result


def level_angle(orientation: Sequence[float]) -> float:
    """The tilt [rad] of the root's z axis from the vertical."""
    return math.acos(max(-1.0, min(1.0, rotation(orientation)[2, 2])))
