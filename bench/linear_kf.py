"""The linear Kalman filter of MIT's Cheetah-Software and of legged_control (a peer for
``bench/estimators.py``), re-written from its published equations (Bledt et al., "MIT Cheetah 3",
IROS 2018; legged_control's ``LinearKalmanFilter``), not from its code.

State (18, world frame): the base position ``p`` and velocity ``v``, and the four feet's positions.
Input: the world-frame acceleration ``a = R f + g`` from the accelerometer and the orientation the
IMU reports (taken as true). Per foot, with a *trust* ``t`` in [0, 1] (1: in stance):

- its position relative to the base, ``R p_i`` = ``foot_i - p`` (always measured);
- the base velocity it gives, ``-R (ω x p_i + J q̇_i)``, blended ``t y + (1 - t) v̂`` (a swinging
  foot says nothing);
- its height, blended ``(1 - t) (p̂_z + (R p_i)_z)`` (0 in stance: the ground);

a swinging foot's process and measurement noise are scaled by ``1 + (1 - t) * HIGH_SUSPECT``.
Noise values are the published defaults (Cheetah-Software's ``user-parameters``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

HIGH_SUSPECT = 100.0
PROCESS_POSITION, PROCESS_VELOCITY, PROCESS_FOOT = 0.02, 0.02, 0.002
SENSOR_POSITION, SENSOR_VELOCITY, SENSOR_HEIGHT = 0.001, 0.1, 0.001
GRAVITY = np.array([0.0, 0.0, -9.80665])


class LinearKalmanFilter:
    """Step with :meth:`step` once per sample (IMU and joint state together)."""

    def __init__(self) -> None:
        self.x = np.zeros(18)
        self.covariance = np.eye(18) * 100.0
        self.started = False

    def step(
        self,
        dt: float,
        rotation: np.ndarray,
        gyro: Sequence[float],
        specific_force: Sequence[float],
        feet: np.ndarray,
        foot_velocities: np.ndarray,
        trust: Sequence[float],
    ) -> np.ndarray:
        """One sample: ``dt`` [s], the IMU's orientation (3 x 3, base -> world), gyro [rad/s] and
        specific force [m/s²] (base frame), the feet (4, 3) [m] and their velocities ``J q̇``
        (4, 3) [m/s] in the base frame, each foot's trust; the base velocity in the base frame.
        """
        world_feet = feet @ rotation.T
        if not self.started:  # the feet where they stand, the base at the origin
            self.x[6:] = world_feet.reshape(-1)
            self.started = True
        acceleration = rotation @ np.asarray(specific_force) + GRAVITY
        transition = np.eye(18)
        transition[0:3, 3:6] = dt * np.eye(3)
        self.x = transition @ self.x
        self.x[0:3] += 0.5 * dt * dt * acceleration
        self.x[3:6] += dt * acceleration
        noise = np.zeros(18)
        noise[0:3] = dt / 20.0 * PROCESS_POSITION
        noise[3:6] = dt * 9.8 / 20.0 * PROCESS_VELOCITY
        suspicion = [1.0 + (1.0 - t) * HIGH_SUSPECT for t in trust]
        for leg in range(4):
            noise[6 + 3 * leg : 9 + 3 * leg] = dt * PROCESS_FOOT * suspicion[leg]
        self.covariance = transition @ self.covariance @ transition.T + np.diag(noise)
        self._correct(rotation, gyro, feet, foot_velocities, world_feet, trust, suspicion)
        result: np.ndarray = rotation.T @ self.x[3:6]
        return result

    def _correct(
        self,
        rotation: np.ndarray,
        gyro: Sequence[float],
        feet: np.ndarray,
        foot_velocities: np.ndarray,
        world_feet: np.ndarray,
        trust: Sequence[float],
        suspicion: Sequence[float],
    ) -> None:
        """The 28 measurements (12 relative positions, 12 velocities, 4 heights)."""
        rows, values, noises = np.zeros((28, 18)), np.zeros(28), np.zeros(28)
        for leg in range(4):
            t, position = trust[leg], slice(3 * leg, 3 * leg + 3)
            foot_state = slice(6 + 3 * leg, 9 + 3 * leg)
            rows[position, 0:3] = -np.eye(3)
            rows[position, foot_state] = np.eye(3)
            values[position] = world_feet[leg]
            noises[position] = SENSOR_POSITION * suspicion[leg]
            velocity = slice(12 + 3 * leg, 15 + 3 * leg)
            moving = rotation @ (np.cross(gyro, feet[leg]) + foot_velocities[leg])
            rows[velocity, 3:6] = np.eye(3)
            values[velocity] = t * -moving + (1.0 - t) * self.x[3:6]
            noises[velocity] = SENSOR_VELOCITY * suspicion[leg]
            rows[24 + leg, 8 + 3 * leg] = 1.0
            values[24 + leg] = (1.0 - t) * (self.x[2] + world_feet[leg, 2])
            noises[24 + leg] = SENSOR_HEIGHT * suspicion[leg]
        covariance = self.covariance
        innovation = rows @ covariance @ rows.T + np.diag(noises)
        gain = np.linalg.solve(innovation, rows @ covariance).T
        self.x = self.x + gain @ (values - rows @ self.x)
        covariance = (np.eye(18) - gain @ rows) @ covariance
        self.covariance = 0.5 * (covariance + covariance.T)
