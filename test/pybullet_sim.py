"""A free-base quadruped on a plane in PyBullet, recording what a robot's sensors would give.

Independent of the code under test (no a1_leg_fk import): this is the judge. Joints and links
are found by name in PyBullet's own model. :class:`QuadrupedSim` connects, loads the plane and the
robot, sets gravity and the time step; each :meth:`QuadrupedSim.step` drives the joints with
PyBullet's position control (or :meth:`QuadrupedSim.step_pd` with PD torque motors) and records a
:class:`Sample`:

- joint angles [rad], velocities [rad/s] and applied motor torques [N m] (``getJointState()[3]``:
  the torque the motor applies to the child link about the joint axis, as a JointState effort);
- the pose of the URDF root link (PyBullet's base pose is the root's centre-of-mass frame; it is
  converted here), world frame, and its linear [m/s] and angular [rad/s] velocity, world frame;
- an IMU aligned with the root: orientation (x, y, z, w) and gyro [rad/s] in the root frame;
- per foot, the force the ground exerts on it [N, world frame]: every contact point of the foot
  link with the plane, normal force plus both friction components, summed; whether it touches;
  and the foot link's frame [m, world].

Two gaits drive it: :func:`record_trot` (a trot in place, for the foot forces) and
:func:`simulate` with :func:`walking_targets` (a trot that walks and turns, for the odometry),
which gives a :class:`SimRun`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Self

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
    foot_positions: np.ndarray  # (4, 3) foot link frames, world
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


def quaternion_rpy(roll: float, pitch: float, yaw: float = 0.0) -> tuple[float, ...]:
    """(x, y, z, w) of fixed-axis roll, pitch, yaw [rad]."""
    return tuple(pybullet.getQuaternionFromEuler([roll, pitch, yaw]))


def gravity_in_root(orientation: Sequence[float], magnitude: float = GRAVITY) -> np.ndarray:
    """World gravity (0, 0, -magnitude) [m/s^2] in the frame of a root at ``orientation``."""
    result: np.ndarray = rotation(orientation).T @ np.array([0.0, 0.0, -magnitude])
    return result


class QuadrupedSim:
    """One robot and a plane in a DIRECT client of its own; use as a context manager.

    The robot is loaded with its root origin at ``spawn_height_m`` [m] above the plane.
    ``damped=False`` sets every link's and joint's damping to zero (PyBullet's default link
    damping, 0.04, stays on the base); ``lateral_friction``, when given, is set on the plane and
    the feet. ``inertia_from_file`` loads the links' inertia tensors from the URDF's
    ``<inertial>`` (``URDF_USE_INERTIA_FROM_FILE``; by default PyBullet computes them from the
    collision shapes).
    """

    def __init__(
        self,
        urdf_path: Path | str,
        joint_names: Sequence[str],
        foot_links: Sequence[str],
        step_s: float = STEP_S,
        *,
        spawn_height_m: float = 1.0,
        damped: bool = False,
        lateral_friction: float | None = None,
        inertia_from_file: bool = False,
    ) -> None:
        self.client = pybullet.connect(pybullet.DIRECT)
        self.step_s, self.steps = step_s, 0
        pb = {"physicsClientId": self.client}
        try:
            pybullet.setGravity(0, 0, -GRAVITY, **pb)
            pybullet.setTimeStep(step_s, **pb)
            data = pybullet_data.getDataPath()
            self.plane = pybullet.loadURDF(f"{data}/plane.urdf", **pb)
            flags = pybullet.URDF_USE_INERTIA_FROM_FILE if inertia_from_file else 0
            self.body = pybullet.loadURDF(
                str(urdf_path), [0, 0, spawn_height_m], flags=flags, **pb
            )
            infos = [
                pybullet.getJointInfo(self.body, j, **pb)
                for j in range(pybullet.getNumJoints(self.body, **pb))
            ]
        except BaseException:
            pybullet.disconnect(self.client)
            raise
        joint_index = {info[1].decode(): info[0] for info in infos}
        link_index = {info[12].decode(): info[0] for info in infos}
        self.joints = [joint_index[name] for name in joint_names]
        self.feet = [link_index[name] for name in foot_links]
        for joint in range(len(infos)):  # no default velocity motors
            pybullet.setJointMotorControl2(
                self.body, joint, pybullet.VELOCITY_CONTROL, force=0, **pb
            )
            if not damped:
                pybullet.changeDynamics(
                    self.body, joint, linearDamping=0, angularDamping=0, jointDamping=0, **pb
                )
        if lateral_friction is not None:
            pybullet.changeDynamics(self.plane, -1, lateralFriction=lateral_friction, **pb)
            for foot in self.feet:
                pybullet.changeDynamics(self.body, foot, lateralFriction=lateral_friction, **pb)
        inertial = pybullet.getDynamicsInfo(self.body, -1, **pb)[3:5]
        self._to_root = pybullet.invertTransform(*inertial)
        self._inertial = inertial

    @property
    def time_s(self) -> float:
        """Simulated time [s]: steps taken times the step."""
        return self.steps * self.step_s

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
        self.set_angles(angles)

    def set_angles(self, angles: Sequence[float]) -> None:
        """Put the joints at ``angles`` [rad], at rest (limits are not enforced)."""
        for joint, angle in zip(self.joints, angles):
            pybullet.resetJointState(self.body, joint, angle, 0.0, physicsClientId=self.client)

    def step(
        self,
        targets: Sequence[float],
        max_torque_nm: float,
        position_gain: float,
        velocity_gain: float = 1.0,
        target_rates: Sequence[float] | None = None,
    ) -> Sample:
        """Drive the joints towards ``targets`` [rad] (PyBullet's position control), step, and
        record. ``target_rates`` [rad/s], when given, are the motors' target velocities (default:
        0, PyBullet's).
        """
        client = self.client
        rates = {} if target_rates is None else {"targetVelocities": list(target_rates)}
        pybullet.setJointMotorControlArray(
            self.body,
            self.joints,
            pybullet.POSITION_CONTROL,
            targetPositions=list(targets),
            **rates,
            forces=[max_torque_nm] * len(self.joints),
            positionGains=[position_gain] * len(self.joints),
            velocityGains=[velocity_gain] * len(self.joints),
            physicsClientId=client,
        )
        pybullet.stepSimulation(physicsClientId=client)
        self.steps += 1
        return self.sample()

    def step_pd(
        self,
        targets: Sequence[float],
        gains: tuple[float, float],
        max_torque_nm: float,
        target_rates: Sequence[float] | None = None,
    ) -> Sample:
        """Drive the joints with PD torque motors, step, and record.

        From the joint state before the step, τ = clip(Kp (q* - q) + Kd (q̇* - q̇), ±max_torque_nm)
        [N m], ``gains`` = (Kp [N m/rad], Kd [N m s/rad]), ``targets`` q* [rad], ``target_rates``
        q̇* [rad/s] (default 0), is applied with ``TORQUE_CONTROL`` over the step (the velocity
        motors are off) and recorded as the sample's torques (as a JointState effort would).
        """
        client = self.client
        states = pybullet.getJointStates(self.body, self.joints, physicsClientId=client)
        angles = np.array([state[0] for state in states])
        rates = np.array([state[1] for state in states])
        goal_rates = np.zeros(len(self.joints)) if target_rates is None else target_rates
        kp, kd = gains
        torques = np.clip(
            kp * (np.asarray(targets) - angles) + kd * (np.asarray(goal_rates) - rates),
            -max_torque_nm,
            max_torque_nm,
        )
        pybullet.setJointMotorControlArray(
            self.body,
            self.joints,
            pybullet.TORQUE_CONTROL,
            forces=torques.tolist(),
            physicsClientId=client,
        )
        pybullet.stepSimulation(physicsClientId=client)
        self.steps += 1
        return dataclasses.replace(self.sample(), torques=torques)

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
        to_world = rotation_matrices(np.array([root_orientation]))[0]
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
            self.foot_positions(),
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
                # on body A: normal force along contactNormalOnB (from B to A), friction against
                # the lateral directions
                forces[slot] += (
                    point[9] * np.array(point[7])
                    - point[10] * np.array(point[11])
                    - point[12] * np.array(point[13])
                )
        return forces, touching

    def foot_positions(self) -> np.ndarray:
        """(4, 3) the foot link frames' origins [m, world] (``getLinkState(...)[4]``)."""
        return np.array(
            [
                pybullet.getLinkState(
                    self.body, foot, computeForwardKinematics=True, physicsClientId=self.client
                )[4]
                for foot in self.feet
            ]
        )

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


# --- the trot in place (foot forces) ---------------------------------------------------------


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


# --- the walking and turning trot (odometry) --------------------------------------------------


@dataclass(frozen=True)
class SimRun:
    """One simulated run, sampled after every physics step (N samples): the :class:`Sample`
    fields under the odometry tests' names. World frame: the plane's (z up). The base is the URDF
    root link's origin and orientation (not PyBullet's CoM frame).
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

    @classmethod
    def of(cls, joint_names: Sequence[str], samples: Sequence[Sample]) -> SimRun:
        """The samples of one run, stacked."""
        rows = stack(samples)
        return cls(
            stamps_s=rows["stamp_s"],
            joint_names=tuple(joint_names),
            angles=rows["angles"],
            rates=rows["rates"],
            torques=rows["torques"],
            base_positions=rows["root_position"],
            base_quaternions=rows["root_orientation"],
            base_velocities=rows["linear_velocity"],
            base_angular_velocities=rows["angular_velocity"],
            gyro=rows["gyro"],
            contacts=rows["foot_contact"],
            contact_forces=rows["foot_forces"],
            foot_positions=rows["foot_positions"],
        )

    @property
    def rotations(self) -> np.ndarray:
        """(N, 3, 3) root-to-world rotation matrices."""
        return rotation_matrices(self.base_quaternions)

    @property
    def specific_force(self) -> np.ndarray:
        """(N, 3) what an accelerometer at the root origin reads [m/s^2], root frame: Rᵀ (a - g),
        ``a`` the backward difference of the root origin's velocity (zero before the first).
        """
        velocities = np.vstack([np.zeros((1, 3)), self.base_velocities])
        steps = np.diff(np.concatenate([[0.0], self.stamps_s]))
        acceleration = np.diff(velocities, axis=0) / steps[:, None]
        result: np.ndarray = np.einsum(
            "nji,nj->ni", self.rotations, acceleration + np.array([0.0, 0.0, GRAVITY])
        )
        return result

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
    """Run ``targets`` (time [s] -> joint angles [rad], ``joint_names`` order) for ``seconds``,
    with PyBullet's default link damping.

    The robot starts at ``spawn_height_m`` above the plane with its joints at ``targets(0)`` and
    falls onto it. ``lateral_friction``, when given, is set on the plane and the feet.
    """
    with QuadrupedSim(
        urdf,
        joint_names,
        feet,
        step_s,
        spawn_height_m=spawn_height_m,
        damped=True,
        lateral_friction=lateral_friction,
    ) as sim:
        sim.set_angles(targets(0.0))
        samples = [
            sim.step(targets(sim.time_s), max_torque_nm, position_gain, velocity_gain)
            for _ in range(round(seconds / step_s))
        ]
    return SimRun.of(joint_names, samples)
