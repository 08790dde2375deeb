"""Leg odometry: the base's velocity from its stance feet, and its pose integrated from it.

One sample at a time (:meth:`LegOdometry.step`), the same code for the live node and the bag
tool. Per sample: the per-foot motion of :mod:`a1_leg_fk.estimation.leg_motion` (``v = e - w x
r`` for each stance foot), an IMU reading (:class:`ImuReading`, optional), and optionally contact
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

import numpy as np

from a1_leg_fk.estimation.stance import consistent_feet, kinematic_stance, stance_from_contacts
from a1_leg_fk.legs import LEG_NAMES

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


@dataclass(frozen=True)
class OdometrySettings:
    """The estimate's tuning; units in the names."""

    slip_threshold_mps: float = 0.15
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
        for name, value in vars(self).items():
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"odometry setting {name} must be a finite number >= 0: {value}")


@dataclass(frozen=True)
class ImuReading:
    """One IMU sample: ``orientation`` (x, y, z, w) of the base in the world (None: the IMU has
    none, ``orientation_covariance[0] == -1``), ``gyro`` [rad/s] in the base frame, and the
    diagonals of their covariances (None where the message leaves them unknown, all zero).
    """

    orientation: tuple[float, float, float, float] | None
    gyro: tuple[float, float, float]
    orientation_variance: tuple[float, float, float] | None = None
    gyro_variance: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class OdometrySample:
    """The estimate at one stamp [ns]. Pose in odom: ``position`` [m], ``orientation`` (x, y, z,
    w); twist in the base frame: ``linear`` [m/s], ``angular`` [rad/s]; ``pose_variance`` (x, y,
    z, roll, pitch, yaw) and ``twist_variance`` (vx, vy, vz, wx, wy, wz), the covariances'
    diagonals; ``stance``: the feet taken for standing, ``used``: those averaged.
    """

    stamp_ns: int
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    linear: tuple[float, float, float]
    angular: tuple[float, float, float]
    pose_variance: tuple[float, ...]
    twist_variance: tuple[float, ...]
    stance: tuple[bool, ...]
    used: tuple[bool, ...]
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


def down_direction(orientation: Sequence[float] | None) -> np.ndarray:
    """Gravity's unit direction in the base frame for a base orientation (x, y, z, w) in a z-up
    world; ``(0, 0, -1)`` (a level base) without one.
    """
    if orientation is None:
        return np.array([0.0, 0.0, -1.0])
    x, y, z, w = orientation
    return -np.array([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)])


def _rotate(q: Sequence[float], v: np.ndarray) -> np.ndarray:
    """``v`` rotated by the unit quaternion ``q`` (x, y, z, w)."""
    u = np.array(q[:3])
    t = 2.0 * np.cross(u, v)
    rotated: np.ndarray = v + q[3] * t + np.cross(u, t)
    return rotated


def _floored(values: Sequence[float]) -> tuple[float, float, float]:
    a, b, c = (max(float(value), MIN_VARIANCE) for value in values)
    return (a, b, c)


def _unit(q: Sequence[float]) -> tuple[float, float, float, float] | None:
    norm = math.sqrt(sum(value * value for value in q))
    if not (math.isfinite(norm) and norm > 0.5):  # not a rotation: a zero or broken quaternion
        return None
    return (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm)


class LegOdometry:
    """The running estimate: feed it one sample at a time with :meth:`step`."""

    def __init__(self, settings: OdometrySettings | None = None) -> None:
        self.settings = settings or OdometrySettings()
        self.counts = OdometryCounts()
        self._stamp_ns: int | None = None
        self._velocity: np.ndarray | None = None  # the last estimate [m/s], base frame
        self._velocity_variance = np.full(3, UNKNOWN_RATE_VARIANCE)
        self._world_velocity = np.zeros(3)  # the last step's, for the trapezoid rule
        self._position = np.zeros(3)
        self._yaw = 0.0  # planar mode
        self._turned_rad = 0.0  # planar mode: the heading change integrated, in absolute value

    def step(
        self,
        stamp_ns: int,
        e: np.ndarray,
        r: np.ndarray,
        depth: np.ndarray,
        imu: ImuReading | None = None,
        contacts: np.ndarray | None = None,
    ) -> OdometrySample:
        """The estimate after one sample: per foot ``e`` (4, 3) [m/s], ``r`` (4, 3) [m] and
        ``depth`` (4,) [m] (:class:`~a1_leg_fk.estimation.leg_motion.FootMotion` rows, NaN for
        feet without them), ``imu`` (None: none), ``contacts`` (4,) probabilities in [0, 1] or
        None (kinematic stance).
        """
        settings = self.settings
        usable = np.isfinite(e).all(axis=1) & np.isfinite(r).all(axis=1)
        if contacts is None:
            stance = kinematic_stance(depth, usable, settings.stance_band_m)
            weights = stance.astype(float)
        else:
            stance, weights = stance_from_contacts(contacts, usable)
        gyro = None if imu is None else np.array(imu.gyro, dtype=float)
        if gyro is not None and not np.isfinite(gyro).all():
            gyro = None
        omega, estimates = self._per_foot(e, r, stance, gyro)
        used = consistent_feet(
            estimates,
            stance,
            self._velocity,
            math.sqrt(float(self._velocity_variance.max())),
            settings.slip_threshold_mps,
        )
        if gyro is None and used.sum() != stance.sum():  # w again, from the consistent feet
            omega, estimates = self._per_foot(e, r, used, None)
        for leg in np.flatnonzero(stance & ~used):
            self.counts.slips[leg] += 1
        dt = self._advance(stamp_ns)
        linear, linear_variance = self._linear(estimates, used, weights, dt)
        angular_variance = self._angular_variance(imu, gyro, e, r, used, omega)
        orientation, orientation_variance, planar = self._orientation(imu, omega, dt)
        self._integrate(orientation, linear, dt, planar)
        self.counts.samples += 1
        return OdometrySample(
            stamp_ns,
            (float(self._position[0]), float(self._position[1]), float(self._position[2])),
            orientation,
            (float(linear[0]), float(linear[1]), float(linear[2])),
            (float(omega[0]), float(omega[1]), float(omega[2])),
            self._position_variance(planar) + orientation_variance,
            tuple(float(v) for v in np.concatenate([linear_variance, angular_variance])),
            tuple(bool(s) for s in stance),
            tuple(bool(u) for u in used),
            planar,
        )

    # --- velocities ------------------------------------------------------------------------

    @staticmethod
    def _per_foot(
        e: np.ndarray, r: np.ndarray, feet: np.ndarray, gyro: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(w [rad/s], per-foot estimates (4, 3) [m/s]) with the gyro's w, or without one the
        least-squares w of :data:`MIN_RATE_FEET` or more ``feet``, else zero.
        """
        omega = gyro if gyro is not None else np.zeros(3)
        if gyro is None and feet.sum() >= MIN_RATE_FEET:
            omega = _rate_from_feet(e[feet], r[feet])
        return omega, e - np.cross(omega, r)

    def _linear(
        self, estimates: np.ndarray, used: np.ndarray, weights: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        settings = self.settings
        count = int(used.sum())
        if count == 0:
            self.counts.no_stance += 1
            previous = self._velocity if self._velocity is not None else np.zeros(3)
            decay = math.exp(-dt / settings.decay_time_s) if settings.decay_time_s > 0 else 0.0
            self._velocity = previous * decay
            self._velocity_variance = self._velocity_variance + settings.flight_growth_mps**2 * dt
            return self._velocity, np.maximum(self._velocity_variance, MIN_VARIANCE)
        feet = estimates[used]
        weight = weights[used]
        velocity = (weight[:, None] * feet).sum(axis=0) / weight.sum()
        spread = (
            feet.var(axis=0, ddof=1)
            if count > 1
            else np.full(3, (settings.slip_threshold_mps / 2.0) ** 2)
        )
        variance = np.maximum((spread + settings.foot_noise_mps**2) / count, MIN_VARIANCE)
        self._velocity, self._velocity_variance = velocity, variance
        return velocity, variance

    def _angular_variance(
        self,
        imu: ImuReading | None,
        gyro: np.ndarray | None,
        e: np.ndarray,
        r: np.ndarray,
        used: np.ndarray,
        omega: np.ndarray,
    ) -> np.ndarray:
        if gyro is not None and imu is not None:
            given = imu.gyro_variance
            default = self.settings.gyro_noise_radps**2
            return np.maximum(np.array(given if given is not None else (default,) * 3), MIN_VARIANCE)
        if used.sum() < MIN_RATE_FEET:
            return np.full(3, UNKNOWN_RATE_VARIANCE)
        points = r[used]
        lever = float(((points - points.mean(axis=0)) ** 2).sum())  # [m^2]
        residual = e[used] - np.cross(omega, points)
        noise = float(residual.var(axis=0).sum()) + self.settings.foot_noise_mps**2
        return np.full(3, max(noise / max(lever, 1e-6), MIN_VARIANCE))

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
        self, imu: ImuReading | None, omega: np.ndarray, dt: float
    ) -> tuple[tuple[float, float, float, float], tuple[float, float, float], bool]:
        """The base's orientation in odom, the variances of its roll, pitch, yaw [rad^2], and
        whether it is planar (no usable IMU orientation: the yaw integrated from ``w_z``).
        """
        settings = self.settings
        orientation = None if imu is None or imu.orientation is None else _unit(imu.orientation)
        if orientation is not None and imu is not None:
            given = imu.orientation_variance
            default = (settings.orientation_noise_rad**2,) * 3
            variance = given if given is not None else default
            return orientation, _floored(variance), False
        turn = float(omega[2]) * dt
        self._yaw = math.remainder(self._yaw + turn, math.tau)
        self._turned_rad += abs(turn)
        heading = settings.drift_fraction * (self._turned_rad + self.counts.distance_m)
        half = self._yaw / 2.0
        return (
            (0.0, 0.0, math.sin(half), math.cos(half)),
            (UNKNOWN_VARIANCE, UNKNOWN_VARIANCE, max(heading**2, MIN_VARIANCE)),
            True,
        )

    def _integrate(
        self,
        orientation: tuple[float, float, float, float],
        linear: np.ndarray,
        dt: float,
        planar: bool,
    ) -> None:
        """Move the position by the trapezoid rule over the world-frame velocity [m/s] (planar:
        in the horizontal plane only).
        """
        world = _rotate(orientation, linear)
        if planar:
            world[2] = 0.0
        if dt > 0.0:
            moved = 0.5 * (self._world_velocity + world) * dt
            self._position = self._position + moved
            self.counts.distance_m += float(np.linalg.norm(moved))
        self._world_velocity = world

    def _position_variance(self, planar: bool) -> tuple[float, float, float]:
        drift = (self.settings.drift_fraction * self.counts.distance_m) ** 2
        horizontal = max(drift, MIN_VARIANCE)
        return (horizontal, horizontal, UNKNOWN_VARIANCE if planar else horizontal)


def _rate_from_feet(e: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The minimum-norm least-squares w [rad/s] of ``v - [r_i]x w = e_i`` over n >= 2 feet
    (``e``, ``r`` (n, 3)); ``v`` is eliminated by centring on the feet's means.
    """
    de = e - e.mean(axis=0)
    dr = r - r.mean(axis=0)
    # -[r]x w = w x r: stack the skew matrices of the centred points.
    rows = np.zeros((len(dr), 3, 3))
    rows[:, 0, 1], rows[:, 0, 2] = dr[:, 2], -dr[:, 1]
    rows[:, 1, 0], rows[:, 1, 2] = -dr[:, 2], dr[:, 0]
    rows[:, 2, 0], rows[:, 2, 1] = dr[:, 1], -dr[:, 0]
    solution, *_ = np.linalg.lstsq(rows.reshape(-1, 3), de.reshape(-1), rcond=None)
    return np.asarray(solution)
