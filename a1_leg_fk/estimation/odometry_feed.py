"""Joint states and IMU samples in, odometry samples out: the one pipeline of the node and the bag
tool (:class:`OdometryFeed`). Per joint state: the IMU sample that goes with it
(:class:`~a1_leg_fk.estimation.imu.ImuBuffer`), gravity's direction from its orientation, each
foot's motion (:class:`~a1_leg_fk.estimation.leg_motion.LegMotion`), then one
:meth:`~a1_leg_fk.estimation.odometry.LegOdometry.step`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.imu import DEFAULT_IMU_TIMEOUT_S, ImuBuffer
from a1_leg_fk.estimation.leg_motion import LegMotion
from a1_leg_fk.estimation.odometry import (
    ImuReading,
    LegOdometry,
    OdometrySample,
    OdometrySettings,
    down_direction,
)
from a1_leg_fk.kinematics import Quadruped


class OdometryFeed:
    """Leg odometry for one robot. ``radii``: the feet's rolling radii [m] (default: the URDF's
    collision spheres); ``use_imu`` false ignores IMU samples (legs alone).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        settings: OdometrySettings | None = None,
        radii: Sequence[float] | float | None = None,
        imu_timeout_s: float = DEFAULT_IMU_TIMEOUT_S,
        use_imu: bool = True,
    ) -> None:
        self.motion = LegMotion(quadruped, radii)
        self.odometry = LegOdometry(settings)
        self.imu = ImuBuffer(imu_timeout_s)
        self.use_imu = use_imu
        self.samples_with_imu = 0

    def add_imu(self, stamp_ns: int, reading: ImuReading | None) -> None:
        """One IMU sample (None: unusable, ignored)."""
        if reading is not None and self.use_imu:
            self.imu.add(stamp_ns, reading)

    def step(
        self,
        stamp_ns: int,
        feet: np.ndarray,
        foot_velocities: np.ndarray,
        angles: np.ndarray,
        rates: np.ndarray,
        contacts: np.ndarray | None = None,
    ) -> OdometrySample:
        """The estimate after one joint state: ``feet`` (4, 3) [m] and ``foot_velocities`` (4, 3)
        [m/s] (``J q_dot``; NaN where unknown) in the base frame, ``angles`` (12) [rad], ``rates``
        (12) [rad/s], ``contacts`` (4) probabilities or None (kinematic stance).
        """
        imu = self.imu.at(stamp_ns)
        self.samples_with_imu += imu is not None
        down = down_direction(None if imu is None else imu.orientation)
        motion = self.motion(
            feet[np.newaxis], foot_velocities[np.newaxis], angles[np.newaxis], rates[np.newaxis],
            down[np.newaxis],
        )
        return self.odometry.step(stamp_ns, motion.e[0], motion.r[0], motion.depth[0], imu, contacts)
