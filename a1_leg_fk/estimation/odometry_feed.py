"""Joint states and IMU samples in, odometry samples out: the one pipeline of the node and the bag
tool (:class:`OdometryFeed`). Per joint state: the IMU sample that goes with it
(:class:`~a1_leg_fk.estimation.imu.ImuBuffer`), gravity's direction from its orientation, each
foot's motion (:class:`~a1_leg_fk.estimation.leg_motion.LegMotion`), the stance's source (foot
forces from the joint efforts, or kinematic: :class:`~a1_leg_fk.estimation.effort_contacts.
EffortContacts`), then one :meth:`~a1_leg_fk.estimation.odometry.LegOdometry.step`. Plain floats
throughout.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.estimation.effort_contacts import AUTO, EffortContacts
from a1_leg_fk.estimation.imu import DEFAULT_IMU_TIMEOUT_S, ImuBuffer
from a1_leg_fk.estimation.leg_motion import FootMotion, LegMotion
from a1_leg_fk.estimation.odometry import (
    ImuReading,
    LegOdometry,
    OdometrySample,
    OdometrySettings,
)
from a1_leg_fk.kinematics.frames import Vector, down_direction
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINTS_PER_LEG

Foot = tuple[Sequence[float], Sequence[float]]
"""A foot's position [m] and velocity [m/s] (``J q_dot``), base frame."""
MAX_BASE_SPEED_MPS = 1e3
"""[m/s] A standing foot that says the base moves faster (on some axis) says nothing: its joint
rates or foot velocity are corrupt (no leg comes near it), and the odometry's sums of squares
stay far from overflow."""


class OdometryFeed:
    """Leg odometry for one robot. ``radii``: the feet's rolling radii [m] (default: the URDF's
    collision spheres); ``use_imu`` false ignores IMU samples (legs alone); ``contacts``: the
    stance's source, ``auto``, ``force`` or ``kinematic`` (:mod:`~a1_leg_fk.estimation.
    effort_contacts`), with the contact rule's ``thresholds`` [N] (None: the defaults).
    """

    def __init__(
        self,
        quadruped: Quadruped,
        settings: OdometrySettings | None = None,
        radii: Sequence[float] | float | None = None,
        imu_timeout_s: float = DEFAULT_IMU_TIMEOUT_S,
        use_imu: bool = True,
        contacts: str = AUTO,
        thresholds: tuple[float | None, float | None] = (None, None),
    ) -> None:
        self.motion = LegMotion(quadruped, radii)
        self.contacts = EffortContacts(quadruped, contacts, thresholds)
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
        feet: Sequence[Foot | None],
        angles: Sequence[float],
        rates: Sequence[float],
        contacts: Sequence[float] | None = None,
        efforts: Sequence[float] | None = None,
    ) -> OdometrySample | None:
        """The estimate after one joint state: per leg its foot (None: not in this joint state, or
        without velocity), the 12 merged ``angles`` [rad], ``rates`` [rad/s] and ``efforts``
        [N m] (None: none) in slot order; ``contacts`` (4) probabilities from elsewhere, else the
        stance comes from :attr:`contacts` (the efforts' foot forces, or kinematic). None, and
        nothing changes, when no leg has a foot (a joint state without velocities says nothing
        about motion).
        """
        if all(foot is None for foot in feet):
            return None
        imu = self.imu.at(stamp_ns)
        self.samples_with_imu += imu is not None
        down = down_direction(None if imu is None else imu.orientation)
        if contacts is None:
            contacts = self.contacts.probabilities(angles, efforts, down)
        depths: list[float | None] = [None] * len(feet)
        points: list[Vector | None] = [None] * len(feet)
        motion = self.motion
        for leg, foot in enumerate(feet):
            if foot is not None:
                r, depth = motion.contact(leg, foot[0], down)
                if math.isfinite(depth):
                    points[leg], depths[leg] = r, depth
        odometry = self.odometry
        weights = odometry.stance(depths, contacts)
        motions: list[FootMotion | None] = [None] * len(feet)
        for leg in list(weights):
            motions[leg] = self._motion(leg, feet, points, depths, angles, rates, down)
            if motions[leg] is None:
                del weights[leg]
        return odometry.estimate(stamp_ns, motions, weights, imu)

    def _motion(
        self,
        leg: int,
        feet: Sequence[Foot | None],
        points: Sequence[Vector | None],
        depths: Sequence[float | None],
        angles: Sequence[float],
        rates: Sequence[float],
        down: Vector,
    ) -> FootMotion | None:
        """A standing leg's motion, or None when its numbers overflow or are beyond
        :data:`MAX_BASE_SPEED_MPS`.
        """
        first = leg * JOINTS_PER_LEG
        last = first + JOINTS_PER_LEG
        foot, r, depth = feet[leg], points[leg], depths[leg]
        assert foot is not None and r is not None and depth is not None  # it stands
        e = self.motion.still_base_velocity(
            leg, angles[first:last], rates[first:last], foot[1], down
        )
        fastest = MAX_BASE_SPEED_MPS
        usable = abs(e[0]) <= fastest and abs(e[1]) <= fastest and abs(e[2]) <= fastest
        return FootMotion(e, r, depth) if usable else None  # not for NaN either
