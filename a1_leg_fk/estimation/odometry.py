"""Leg odometry: the base's velocity from its stance feet, and its pose integrated from it.

One sample at a time (:meth:`LegOdometry.step`), the same code for the live node and the bag
tool, in plain floats (a joint state at 1 kHz leaves no time for numpy's per-call overhead). Per
sample: the per-foot motion of :mod:`a1_leg_fk.estimation.leg_motion` (``v = e - w x r`` for
each stance foot), an IMU reading (:class:`ImuReading`, optional), and optionally contact
probabilities from elsewhere (the hook for a force-based contact estimate; without them, stance is
kinematic, see :mod:`a1_leg_fk.estimation.stance`).

- Angular velocity ``w`` [rad/s]: the IMU's gyro; without one, the least-squares ``(v, w)`` of
  two or more stance feet (:data:`MIN_RATE_FEET`), else zero (with a variance that says it is
  unknown).
- Linear velocity ``v`` [m/s]: the weighted mean of the consistent stance feet; its variance per
  axis is ``(s^2 + sigma_foot^2) / n``, ``s^2`` the feet's sample variance (one foot: nothing to
  check it against, ``s = threshold / 2``). No stance foot: the last velocity decays with
  ``decay_time_s`` and its variance grows by ``flight_growth^2 dt``.
- Orientation: the IMU's (when it has one); else planar, the yaw integrated from ``w_z``.
- Position [m]: the world-frame velocity integrated by the trapezoid rule over the stamps; its
  variance grows with the distance travelled, ``(drift_fraction * distance)^2``.

All covariances are diagonal and never zero. Frames: twist in the base frame, pose in ``odom``
(the first sample's position is the origin; z up when the IMU's orientation is used).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.stance import consistent_feet, kinematic_stance, stance_from_contacts
from a1_leg_fk.kinematics.frames import (
    Quaternion,
    Vector,
    rotate,
    unit_quaternion,
)
from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
UNKNOWN_VARIANCE = 1e6
"""The variance of what the estimate does not observe at all (roll, pitch and z when planar)."""
UNKNOWN_RATE_VARIANCE = 1.0
"""[(rad/s)^2]: the angular velocity's variance when it is taken as zero for want of feet."""
MIN_RATE_FEET = 2
"""Without a gyro, the stance feet it takes to estimate the angular velocity: two feet leave only
the rotation about the line through them unobserved (the minimum-norm solution sets it to zero),
which for a trot's diagonal pair on flat ground is a horizontal axis: the yaw rate is observed."""
MIN_VARIANCE = 1e-9
"""The floor of every variance [m^2, rad^2, (m/s)^2, (rad/s)^2]."""


def require_non_negative(settings: object, kind: str) -> None:
    """Raise ValueError naming the first of ``settings``' fields (a dataclass of floats) that is
    not a finite number >= 0; ``kind`` names the settings in the message.
    """
    for name, value in vars(settings).items():
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{kind} setting {name} must be a finite number >= 0: {value}")


@dataclass(frozen=True)
class OdometrySettings:
    """The estimate's tuning; units in the names."""

    slip_threshold_mps: float = 0.08
    """A stance foot whose estimate is further than this from the others' is dropped."""
    stance_band_m: float = 0.02
    """Kinematic stance: contact points within this of the lowest one's along gravity."""
    foot_noise_mps: float = 0.02
    """The standard deviation of one foot's estimate."""
    decay_time_s: float = 2.0
    """No stance foot: the velocity decays with this time constant."""
    flight_growth_mps: float = 0.3
    """No stance foot: the velocity's standard deviation grows as this * sqrt(seconds)."""
    gyro_noise_radps: float = 0.01
    """The gyro's standard deviation when the IMU gives no covariance."""
    orientation_noise_rad: float = 0.01
    """The IMU orientation's standard deviation when it gives no covariance."""
    drift_fraction: float = 0.02
    """Position standard deviation per metre travelled (and heading [rad] per m, planar)."""
    max_step_s: float = 0.1
    """Stamps further apart than this (or going back) are not integrated across."""

    def __post_init__(self) -> None:
        require_non_negative(self, "odometry")


class ImuReading(NamedTuple):
    """One IMU sample: ``orientation`` (x, y, z, w) of the base in the world (None: the IMU has
    none, ``orientation_covariance[0] == -1``), ``gyro`` [rad/s] in the base frame, the
    diagonals of their covariances (None where the message leaves them unknown, all zero), and
    the ``specific_force`` [m/s^2] in the base frame (None: no accelerometer).
    """

    orientation: tuple[float, float, float, float] | None
    gyro: tuple[float, float, float]
    orientation_variance: tuple[float, float, float] | None = None
    gyro_variance: tuple[float, float, float] | None = None
    specific_force: tuple[float, float, float] | None = None


class OdometrySample(NamedTuple):
    """The estimate at one stamp [ns]. Pose in odom: ``position`` [m], ``orientation`` (x, y, z,
    w); twist in the base frame: ``linear`` [m/s], ``angular`` [rad/s]; ``pose_variance`` (x, y,
    z, roll, pitch, yaw) and ``twist_variance`` (vx, vy, vz, wx, wy, wz), the covariances'
    diagonals; ``stance``: the legs taken for standing, ``used``: those averaged (slots 0..3).
    """

    stamp_ns: int
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    linear: tuple[float, float, float]
    angular: tuple[float, float, float]
    pose_variance: tuple[float, ...]
    twist_variance: tuple[float, ...]
    stance: tuple[int, ...]
    used: tuple[int, ...]
    planar: bool


@dataclass
class OdometryCounts:
    """What the estimate has seen: samples, samples without a stance foot, feet dropped as
    slipping (per leg), stamp gaps not integrated across, distance travelled [m].
    """

    samples: int = 0
    no_stance: int = 0
    slips: list[int] = field(default_factory=lambda: [0] * LEGS)
    gaps: int = 0
    distance_m: float = 0.0


def _cross(a: Vector, b: Vector) -> Vector:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _floored(values: Sequence[float]) -> tuple[float, float, float]:
    return (
        max(values[0], MIN_VARIANCE),
        max(values[1], MIN_VARIANCE),
        max(values[2], MIN_VARIANCE),
    )


class LegOdometry:
    """The running estimate: feed it one sample at a time with :meth:`step`."""

    def __init__(self, settings: OdometrySettings | None = None) -> None:
        self.settings = settings or OdometrySettings()
        self.counts = OdometryCounts()
        self._stamp_ns: int | None = None
        self._velocity: Vector | None = None  # the last estimate [m/s], base frame
        self._velocity_variance: Vector = (UNKNOWN_RATE_VARIANCE,) * 3
        self._world_velocity: Vector = (0.0, 0.0, 0.0)  # the last step's, for the trapezoid rule
        self._position = [0.0, 0.0, 0.0]
        self._yaw = 0.0  # planar mode
        self._turned_rad = 0.0  # planar mode: the heading change integrated, in absolute value

    def step(
        self,
        stamp_ns: int,
        feet: Sequence[FootMotion | None],
        imu: ImuReading | None = None,
        contacts: Sequence[float] | None = None,
    ) -> OdometrySample:
        """The estimate after one sample: each leg's :class:`FootMotion` (None for a leg without
        one), ``imu`` (None: none), ``contacts`` (4) probabilities in [0, 1] or None (kinematic
        stance): :meth:`stance`, then :meth:`estimate`.
        """
        weights = self.stance([None if foot is None else foot.depth for foot in feet], contacts)
        return self.estimate(stamp_ns, feet, weights, imu)

    def stance(
        self, depths: Sequence[float | None], contacts: Sequence[float] | None
    ) -> dict[int, float]:
        """Leg -> weight of the feet that stand: from ``contacts`` (probabilities in [0, 1]) when
        given, else kinematic; ``depths`` [m] of the contact points along gravity (None for a
        foot without one).
        """
        if contacts is None:
            return kinematic_stance(depths, self.settings.stance_band_m)
        return stance_from_contacts(contacts, [depth is not None for depth in depths])

    def estimate(
        self,
        stamp_ns: int,
        feet: Sequence[FootMotion | None],
        weights: dict[int, float],
        imu: ImuReading | None = None,
    ) -> OdometrySample:
        """The estimate after one sample, the stance decided (:meth:`stance`): ``feet`` must hold
        a :class:`FootMotion` for every leg in ``weights``; the others are not read.
        """
        settings = self.settings
        gyro = None if imu is None else imu.gyro
        stance = tuple(weights)
        omega, estimates = self._per_foot(feet, stance, gyro)
        used = consistent_feet(
            estimates,
            self._velocity,
            math.sqrt(max(self._velocity_variance)),
            settings.slip_threshold_mps,
        )
        if gyro is None and len(used) != len(stance):  # w again, from the consistent feet
            omega, estimates = self._per_foot(feet, used, None)
        for leg in stance:
            if leg not in used:
                self.counts.slips[leg] += 1
        dt = self._advance(stamp_ns)
        linear, linear_variance = self._linear(estimates, used, weights, dt)
        angular_variance = self._angular_variance(imu, feet, used, omega)
        orientation, orientation_variance, planar = self._orientation(imu, omega, dt)
        self._integrate(orientation, linear, dt, planar)
        self.counts.samples += 1
        position = self._position
        return OdometrySample(
            stamp_ns,
            (position[0], position[1], position[2]),
            orientation,
            linear,
            omega,
            self._position_variance(planar) + orientation_variance,
            linear_variance + angular_variance,
            stance,
            tuple(used),
            planar,
        )

    # --- velocities ------------------------------------------------------------------------

    @staticmethod
    def _per_foot(
        feet: Sequence[FootMotion | None], legs: Sequence[int], gyro: Vector | None
    ) -> tuple[Vector, dict[int, Vector]]:
        """(w [rad/s], leg -> estimate [m/s] for ``legs``) with the gyro's w, or without one the
        least-squares w of :data:`MIN_RATE_FEET` or more ``legs``, else zero.
        """
        standing = [foot for leg in legs if (foot := feet[leg]) is not None]
        omega = gyro if gyro is not None else (0.0, 0.0, 0.0)
        if gyro is None and len(standing) >= MIN_RATE_FEET:
            omega = _rate_from_feet(standing)
        estimates = {}
        for leg, foot in zip(legs, standing):
            e, turn = foot.e, _cross(omega, foot.r)
            estimates[leg] = (e[0] - turn[0], e[1] - turn[1], e[2] - turn[2])
        return omega, estimates

    def _linear(
        self, estimates: dict[int, Vector], used: list[int], weights: dict[int, float], dt: float
    ) -> tuple[Vector, Vector]:
        settings = self.settings
        count = len(used)
        if count == 0:
            self.counts.no_stance += 1
            previous = self._velocity or (0.0, 0.0, 0.0)
            decay = math.exp(-dt / settings.decay_time_s) if settings.decay_time_s > 0 else 0.0
            self._velocity = (previous[0] * decay, previous[1] * decay, previous[2] * decay)
            growth = settings.flight_growth_mps**2 * dt
            v = self._velocity_variance
            self._velocity_variance = (v[0] + growth, v[1] + growth, v[2] + growth)
            return self._velocity, _floored(self._velocity_variance)
        total = vx = vy = vz = 0.0
        for leg in used:
            weight, estimate = weights[leg], estimates[leg]
            total += weight
            vx += weight * estimate[0]
            vy += weight * estimate[1]
            vz += weight * estimate[2]
        velocity = (vx / total, vy / total, vz / total)
        noise = settings.foot_noise_mps**2
        if count > 1:
            sx = sy = sz = 0.0
            for leg in used:
                estimate = estimates[leg]
                sx += (estimate[0] - velocity[0]) ** 2
                sy += (estimate[1] - velocity[1]) ** 2
                sz += (estimate[2] - velocity[2]) ** 2
            spread = (sx / (count - 1), sy / (count - 1), sz / (count - 1))
        else:  # one foot: nothing to check it against
            lone = (settings.slip_threshold_mps / 2.0) ** 2
            spread = (lone, lone, lone)
        variance = _floored(
            ((spread[0] + noise) / count, (spread[1] + noise) / count, (spread[2] + noise) / count)
        )
        self._velocity = (velocity[0], velocity[1], velocity[2])
        self._velocity_variance = variance
        return self._velocity, variance

    def _angular_variance(
        self,
        imu: ImuReading | None,
        feet: Sequence[FootMotion | None],
        used: list[int],
        omega: Vector,
    ) -> Vector:
        if imu is not None:
            given = imu.gyro_variance
            default = self.settings.gyro_noise_radps**2
            return _floored(given if given is not None else (default, default, default))
        standing = [foot for leg in used if (foot := feet[leg]) is not None]
        if len(standing) < MIN_RATE_FEET:
            return (UNKNOWN_RATE_VARIANCE,) * 3
        mean = [sum(foot.r[axis] for foot in standing) / len(standing) for axis in range(3)]
        lever = sum((foot.r[axis] - mean[axis]) ** 2 for foot in standing for axis in range(3))
        residual = 0.0
        for foot in standing:
            turn = _cross(omega, foot.r)
            residual += sum((foot.e[axis] - turn[axis]) ** 2 for axis in range(3))
        noise = residual / len(standing) + self.settings.foot_noise_mps**2
        variance = max(noise / max(lever, 1e-6), MIN_VARIANCE)
        return (variance, variance, variance)

    # --- pose ------------------------------------------------------------------------------

    def _advance(self, stamp_ns: int) -> float:
        """The seconds since the previous sample's stamp, 0 at the first and across a gap."""
        previous, self._stamp_ns = self._stamp_ns, stamp_ns
        if previous is None:
            return 0.0
        dt = (stamp_ns - previous) / 1e9
        if not 0.0 < dt <= self.settings.max_step_s:
            self.counts.gaps += dt != 0.0
            return 0.0
        return dt

    def _orientation(
        self, imu: ImuReading | None, omega: Vector, dt: float
    ) -> tuple[Quaternion, Vector, bool]:
        """The base's orientation in odom, the variances of its roll, pitch, yaw [rad^2], and
        whether it is planar (no usable IMU orientation: the yaw integrated from ``w_z``).
        """
        settings = self.settings
        orientation = (
            None if imu is None or imu.orientation is None else unit_quaternion(imu.orientation)
        )
        if orientation is not None and imu is not None:
            given = imu.orientation_variance
            default = settings.orientation_noise_rad**2
            return orientation, _floored(given or (default, default, default)), False
        turn = omega[2] * dt
        self._yaw = math.remainder(self._yaw + turn, math.tau)
        self._turned_rad += abs(turn)
        heading = settings.drift_fraction * (self._turned_rad + self.counts.distance_m)
        half = self._yaw / 2.0
        return (
            (0.0, 0.0, math.sin(half), math.cos(half)),
            (UNKNOWN_VARIANCE, UNKNOWN_VARIANCE, max(heading**2, MIN_VARIANCE)),
            True,
        )

    def _integrate(self, orientation: Quaternion, linear: Vector, dt: float, planar: bool) -> None:
        """Move the position by the trapezoid rule over the world-frame velocity [m/s] (planar:
        in the horizontal plane only).
        """
        world = rotate(orientation, linear)
        if planar:
            world = (world[0], world[1], 0.0)
        if dt > 0.0:
            last = self._world_velocity
            moved = [0.5 * (last[axis] + world[axis]) * dt for axis in range(3)]
            position = self._position
            for axis in range(3):
                position[axis] += moved[axis]
            self.counts.distance_m += math.sqrt(moved[0] ** 2 + moved[1] ** 2 + moved[2] ** 2)
        self._world_velocity = world

    def _position_variance(self, planar: bool) -> Vector:
        drift = (self.settings.drift_fraction * self.counts.distance_m) ** 2
        horizontal = max(drift, MIN_VARIANCE)
        return (horizontal, horizontal, UNKNOWN_VARIANCE if planar else horizontal)


def _rate_from_feet(feet: Sequence[FootMotion]) -> Vector:
    """The minimum-norm least-squares w [rad/s] of ``v + w x r_i = e_i`` over n >= 2 feet; ``v``
    is eliminated by centring on the feet's means (numpy: only without a gyro).
    """
    e = np.array([foot.e for foot in feet])
    r = np.array([foot.r for foot in feet])
    de, dr = e - e.mean(axis=0), r - r.mean(axis=0)
    rows = np.zeros((len(dr), 3, 3))  # w x dr = -[dr]x w
    rows[:, 0, 1], rows[:, 0, 2] = dr[:, 2], -dr[:, 1]
    rows[:, 1, 0], rows[:, 1, 2] = -dr[:, 2], dr[:, 0]
    rows[:, 2, 0], rows[:, 2, 1] = dr[:, 1], -dr[:, 0]
    solution = np.linalg.lstsq(rows.reshape(-1, 3), de.reshape(-1), rcond=None)[0]
    return (float(solution[0]), float(solution[1]), float(solution[2]))
