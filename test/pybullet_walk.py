"""A free-base quadruped in PyBullet, for tests: what a robot's sensors record, and the truth.

:func:`simulate` drops a URDF (default: pybullet_data's A1) onto a plane, drives its joints with
PyBullet's position control towards ``targets(t)`` and records, every step: joint angles [rad],
velocities [rad/s] and motor torques [N m] (``getJointState()[3]``); the base's pose and velocity
at the URDF root link's *origin* (PyBullet's base is the trunk's centre of mass: converted here);
an IMU fixed to the root link (orientation, and the gyro in the root frame); and per foot whether
it touches the plane and the contact force on the foot [N, world frame].

:func:`walking_targets` is a trot that walks forward and turns, from a standing pose. Nothing here
imports the package under test: this is the judge.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet
import pybullet_data

A1_URDF = Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"
A1_JOINTS = tuple(
    f"{leg}_{part}_joint" for leg in ("FR", "FL", "RR", "RL") for part in ("hip", "upper", "lower")
)
A1_FEET = ("FR_toe", "FL_toe", "RR_toe", "RL_toe")
STAND = (0.0, 0.8, -1.5)
"""Hip roll, hip pitch, knee [rad] of one standing A1 leg."""
STEP_S = 1.0 / 500.0


@dataclass(frozen=True)
class SimRun:
    """One simulated run, sampled after every physics step (N samples). World frame: the plane's
    (z up). The base is the URDF root link's origin and orientation (not PyBullet's CoM frame).
    """

    stamps_s: np.ndarray  # (N,) time after the step [s]
    joint_names: tuple[str, ...]
    angles: np.ndarray  # (N, J) [rad]
    rates: np.ndarray  # (N, J) [rad/s]
    torques: np.ndarray  # (N, J) applied motor torques [N m]
    base_positions: np.ndarray  # (N, 3) root origin [m], world
    base_quaternions: np.ndarray  # (N, 4) root orientation x, y, z, w (the IMU's orientation)
    base_velocities: np.ndarray  # (N, 3) root origin's velocity [m/s], world
    base_angular_velocities: np.ndarray  # (N, 3) [rad/s], world
    gyro: np.ndarray  # (N, 3) angular velocity [rad/s] in the root frame (the IMU's gyro)
    contacts: np.ndarray  # (N, F) bool: the foot link touches the plane
    contact_forces: np.ndarray  # (N, F, 3) force of the plane on the foot [N], world
    foot_positions: np.ndarray  # (N, F, 3) foot link frames [m], world

    @property
    def rotations(self) -> np.ndarray:
        """(N, 3, 3) root-to-world rotation matrices."""
        return rotation_matrices(self.base_quaternions)

    @property
    def body_velocities(self) -> np.ndarray:
        """(N, 3) the root origin's velocity [m/s] in the root frame."""
        return np.einsum("nji,nj->ni", self.rotations, self.base_velocities)


def rotation_matrices(quaternions: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) unit quaternions (x, y, z, w)."""
    x, y, z, w = np.asarray(quaternions, dtype=float).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=1,
    )


def walking_targets(
    start_s: float = 0.5,
    trot_hz: float = 2.0,
    duty: float = 0.6,
    knee_lift: float = 0.3,
    stride: float = 0.18,
    turn: float = 0.025,
    differential: float = 0.09,
    ramp_s: float = 0.5,
) -> Callable[[float], list[float]]:
    """Joint targets [rad] of an A1 trot: stand until ``start_s`` [s], then trot at ``trot_hz``.

    Diagonal pairs (FR+RL, FL+RR) are half a cycle apart; each leg stands for the fraction
    ``duty`` of the cycle and swings for the rest. A swing leg bends its knee by up to
    ``knee_lift`` [rad] and turns its hip pitch by half that, lifting the foot. The hip pitch also
    strokes by ``stride`` [rad]: back to front in swing, front to back at constant speed in
    stance, which walks the robot forward. The hip roll strokes likewise by ``turn`` [rad] on the
    front legs and the opposite on the rear ones: the stance feet sweep sideways in opposite
    directions, which turns the robot without making its feet slide. The strokes fade in over
    ``ramp_s`` [s].
    """
    offset = (0.0, 0.5, 0.5, 0.0)  # FR, FL, RR, RL: the cycle's fraction
    end = (1.0, 1.0, -1.0, -1.0)  # front +1
    side = (-1.0, 1.0, -1.0, 1.0)  # left +1
    swing = 1.0 - duty

    def targets(t: float) -> list[float]:
        out: list[float] = []
        running = t > start_s
        fade = min(1.0, (t - start_s) / ramp_s) if running else 0.0
        fade = fade * fade * (3.0 - 2.0 * fade)
        for leg in range(4):
            u = (trot_hz * (t - start_s) + offset[leg]) % 1.0
            if u < swing:  # swing: lift, and stroke from back (+1) to front (-1)
                bend = knee_lift * math.sin(math.pi * u / swing) if running else 0.0
                stroke = math.cos(math.pi * u / swing)
            else:  # stance: from front to back at constant speed
                bend, stroke = 0.0, -1.0 + 2.0 * (u - swing) / duty
            stroke *= fade
            out += [
                STAND[0] + turn * end[leg] * stroke,
                STAND[1] + bend / 2 + stride * (1.0 + differential * side[leg]) * stroke,
                STAND[2] - bend,
            ]
        return out

    return targets


def simulate(
    targets: Callable[[float], Sequence[float]],
    seconds: float,
    *,
    urdf: Path | str = A1_URDF,
    joint_names: Sequence[str] = A1_JOINTS,
    feet: Sequence[str] = A1_FEET,
    step_s: float = STEP_S,
    spawn_height_m: float = 0.30,
    position_gain: float = 0.3,
    velocity_gain: float = 1.0,
    max_torque_nm: float = 33.5,
    lateral_friction: float | None = None,
) -> SimRun:
    """Run ``targets`` (time [s] -> joint angles [rad], ``joint_names`` order) for ``seconds``.

    The robot starts at ``spawn_height_m`` above the plane with its joints at ``targets(0)`` and
    falls onto it. ``lateral_friction``, when given, is set on the plane and the feet.
    """
    client = pybullet.connect(pybullet.DIRECT)
    try:
        return _run(
            client,
            targets,
            seconds,
            str(urdf),
            list(joint_names),
            list(feet),
            step_s,
            spawn_height_m,
            (position_gain, velocity_gain, max_torque_nm),
            lateral_friction,
        )
    finally:
        pybullet.disconnect(client)


def _run(
    client: int,
    targets: Callable[[float], Sequence[float]],
    seconds: float,
    urdf: str,
    joint_names: list[str],
    feet: list[str],
    step_s: float,
    spawn_height_m: float,
    control: tuple[float, float, float],
    lateral_friction: float | None,
) -> SimRun:
    pb = {"physicsClientId": client}
    pybullet.setGravity(0, 0, -9.81, **pb)
    pybullet.setTimeStep(step_s, **pb)
    plane = pybullet.loadURDF(f"{pybullet_data.getDataPath()}/plane.urdf", **pb)
    body = pybullet.loadURDF(urdf, [0, 0, spawn_height_m], **pb)
    infos = [
        pybullet.getJointInfo(body, j, **pb) for j in range(pybullet.getNumJoints(body, **pb))
    ]
    joint_index = {info[1].decode(): info[0] for info in infos}
    link_index = {info[12].decode(): info[0] for info in infos}
    joints = [joint_index[name] for name in joint_names]
    foot_links = [link_index[name] for name in feet]
    if lateral_friction is not None:
        pybullet.changeDynamics(plane, -1, lateralFriction=lateral_friction, **pb)
        for link in foot_links:
            pybullet.changeDynamics(body, link, lateralFriction=lateral_friction, **pb)
    for joint, angle in zip(joints, targets(0.0)):
        pybullet.resetJointState(body, joint, angle, **pb)
    # PyBullet's base pose is the root link's inertial (CoM) frame: root = base * inertial^-1.
    inertial_position, inertial_orientation = pybullet.getDynamicsInfo(body, -1, **pb)[3:5]
    to_root = pybullet.invertTransform(inertial_position, inertial_orientation)
    gain, damping, torque = control
    rows: dict[str, list[object]] = {key: [] for key in SimRun.__dataclass_fields__}
    for step in range(round(seconds / step_s)):
        pybullet.setJointMotorControlArray(
            body,
            joints,
            pybullet.POSITION_CONTROL,
            targetPositions=list(targets(step * step_s)),
            forces=[torque] * len(joints),
            positionGains=[gain] * len(joints),
            velocityGains=[damping] * len(joints),
            **pb,
        )
        pybullet.stepSimulation(**pb)
        com_position, com_orientation = pybullet.getBasePositionAndOrientation(body, **pb)
        root_position, root_orientation = pybullet.multiplyTransforms(
            com_position, com_orientation, *to_root
        )
        com_velocity, angular = pybullet.getBaseVelocity(body, **pb)
        lever = np.subtract(root_position, com_position)
        rotation = rotation_matrices(np.array([root_orientation]))[0]
        states = pybullet.getJointStates(body, joints, **pb)
        forces, touching = [], []
        for link in foot_links:
            points = pybullet.getContactPoints(body, plane, linkIndexA=link, **pb)
            touching.append(bool(points))
            forces.append(sum((_contact_force(point) for point in points), np.zeros(3)))
        rows["stamps_s"].append((step + 1) * step_s)
        rows["angles"].append([state[0] for state in states])
        rows["rates"].append([state[1] for state in states])
        rows["torques"].append([state[3] for state in states])
        rows["base_positions"].append(root_position)
        rows["base_quaternions"].append(root_orientation)
        rows["base_velocities"].append(np.add(com_velocity, np.cross(angular, lever)))
        rows["base_angular_velocities"].append(angular)
        rows["gyro"].append(rotation.T @ np.array(angular))
        rows["contacts"].append(touching)
        rows["contact_forces"].append(forces)
        rows["foot_positions"].append(
            [
                pybullet.getLinkState(body, link, computeForwardKinematics=True, **pb)[4]
                for link in foot_links
            ]
        )
    arrays = {key: np.array(value) for key, value in rows.items() if key != "joint_names"}
    return SimRun(joint_names=tuple(joint_names), **arrays)


def _contact_force(point: tuple) -> np.ndarray:
    """The force of body B on body A at one ``getContactPoints`` entry [N, world]: the normal force
    along ``contactNormalOnB`` plus both lateral friction components along their directions.
    """
    normal = np.array(point[7]) * point[9]
    return normal + np.array(point[11]) * point[10] + np.array(point[13]) * point[12]
