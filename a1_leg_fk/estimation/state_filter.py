"""The base's state from its IMU and its legs: an error-state extended Kalman filter (ESKF).

State: the base's orientation ``R`` (base -> world), the URDF root's velocity ``v`` and position
``p`` in the world (``odom``: z up, the first sample's position at the origin), the gyro's bias
``b_g`` [rad/s] and the accelerometer's ``b_a`` [m/s^2] (base frame); the error ``(dθ, dv, dp,
db_g, db_a)``, ``R = R̂ Exp(dθ)``, has a 15 x 15 covariance. Settings and counts:
:mod:`a1_leg_fk.estimation.filter_model`.

- **Propagation** at every IMU sample (:meth:`StateFilter.propagate`): ``ω = ω_m - b_g``,
  ``a = R (f_m - b_a) + g``; ``R <- R Exp(ω dt)``, ``p <- p + v dt + a dt²/2``, ``v <- v + a dt``;
  the covariance grows by the sensors' white noise and the biases' random walks.
- **Updates** at every joint state (:meth:`StateFilter.update`), stacked into one: the IMU's own
  orientation when it gives one (``dθ`` observed directly); per foot in stance the base's velocity
  in the base frame, ``z = e - ω_m x r = Rᵀ v + r x b_g`` (``e = -(J q̇ + ω_calf x c)`` at the
  rolling contact point ``r``, :class:`~a1_leg_fk.estimation.leg_motion.FootMotion`), noise
  :func:`~a1_leg_fk.estimation.filter_model.foot_noise` over the contact probability; on flat
  ground (``ground="flat"``) the stance feet's heights ``p_z + (R r)_z`` equal the ground's, taken
  at the first stance; standing still (every foot in stance, none moving) a zero-velocity update.
- **Gating**: each foot's innovation is tested alone (NIS against χ², 3 dof); a foot that fails
  (a slip, a swinging foot taken for standing) is left out and counted. When every foot has failed
  for ``max_rejected_s`` the filter has lost its way: the feet are taken again, the velocity's
  covariance widened by their disagreement. The feet's horizontal noise is scaled to keep their
  mean NIS at its expectation (covariance matching, ``noise_adapt_s``).

Why an ESKF (Bloesch et al., RSS 2012, in its error-state form) and not the invariant EKF
(Hartley et al., IJRR 2020): the leg measurement here is a velocity, not a foot position kept in
the state, so the state stays at 15 (no feet to add and drop at every touchdown), the biases that
break the invariant filter's log-linearity anyway are in it, and the rolling contact point, the
probability weighting and the per-foot gate work on the velocity directly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_model import (
    FLAT,
    GROUND_MODELS,
    STATE,
    FilterCounts,
    FilterSettings,
    LegMeasurement,
    block_diagonal,
    foot_noise,
    normalised_squares,
    standing_still,
    stands,
)
from a1_leg_fk.estimation.odometry import OdometrySample
from a1_leg_fk.estimation.so3 import exp_so3, log_so3, matrix_of, quaternion_of, skew
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, Quaternion, Vector

GRAVITY = np.array([0.0, 0.0, -STANDARD_GRAVITY])
"""[m/s²] in the world (odom) frame."""
THETA, VELOCITY, POSITION, GYRO_BIAS, ACCEL_BIAS = (slice(k, k + 3) for k in range(0, 15, 3))
Z = POSITION.start + 2
ORIENTATION_ROWS = np.eye(3, STATE)
"""The IMU's orientation observes dθ directly."""


class StateFilter:
    """The running estimate (see the module text): :meth:`propagate` with every IMU sample,
    :meth:`update` with every joint state. It starts at the first IMU sample, oriented as that
    sample says (else level), at rest at the origin.
    """

    def __init__(self, settings: FilterSettings | None = None, ground: str = FLAT) -> None:
        if ground not in GROUND_MODELS:
            raise ValueError(f"ground must be one of {', '.join(GROUND_MODELS)}: {ground!r}")
        self.settings = settings or FilterSettings()
        self.ground = ground
        self.counts = FilterCounts()
        self.rotation = np.eye(3)
        self.velocity = np.zeros(3)
        self.position = np.zeros(3)
        self.gyro_bias = np.zeros(3)
        self.accel_bias = np.zeros(3)
        self.covariance = np.zeros((STATE, STATE))
        self.started = False
        self.ground_z: float | None = None
        self._imu_stamp_ns = 0
        self._gyro: Vector = (0.0, 0.0, 0.0)
        self._rejected_since_ns: int | None = None
        self._orientation_noise = np.eye(3) * self.settings.orientation_noise_rad**2
        self._legs_stamp_ns: int | None = None
        self.noise_scale = 1.0
        """The feet's horizontal noise variance over the model's
        (:data:`FilterSettings.noise_adapt_s`)."""
        self._transition = np.eye(STATE)
        self._transition_dt = math.nan
        self._noise = np.zeros(STATE)
        s = self.settings
        self._noise_density = np.repeat(
            [s.gyro_noise**2, s.accel_noise**2, 0.0, s.gyro_bias_walk**2, s.accel_bias_walk**2],
            3,
        )

    def start(self, stamp_ns: int, orientation: Quaternion | None) -> None:
        """Begin at rest at the origin, oriented as ``orientation`` (None: level)."""
        settings = self.settings
        self.rotation = matrix_of(orientation) if orientation is not None else np.eye(3)
        theta = settings.orientation_noise_rad**2 if orientation is not None else 0.1
        variances = [theta] * 3 + [settings.initial_velocity_mps**2] * 3 + [1e-12] * 3
        variances += [settings.initial_gyro_bias_radps**2] * 3
        variances += [settings.initial_accel_bias_mps2**2] * 3
        self.covariance = np.diag(variances)
        self._imu_stamp_ns = stamp_ns
        self.started = True

    def propagate(
        self,
        stamp_ns: int,
        gyro: Vector,
        specific_force: Vector,
        orientation: Quaternion | None = None,
    ) -> None:
        """Move the state to ``stamp_ns`` [ns] with an IMU sample: angular velocity [rad/s] and
        specific force [m/s²], base frame, held over the step since the previous sample (a
        sample not after the previous one only sets the gyro the legs use).
        """
        if not self.started:
            self.start(stamp_ns, orientation)
        self._gyro = gyro
        dt = (stamp_ns - self._imu_stamp_ns) / 1e9
        if not dt > 0.0:
            return
        self._imu_stamp_ns = stamp_ns
        if dt > self.settings.max_step_s:
            self.counts.gaps += 1
            dt = self.settings.max_step_s
        bg, ba = self.gyro_bias, self.accel_bias
        fx, fy, fz = (specific_force[0] - ba[0], specific_force[1] - ba[1],
                      specific_force[2] - ba[2])  # fmt: skip
        turn = exp_so3(((gyro[0] - bg[0]) * dt, (gyro[1] - bg[1]) * dt, (gyro[2] - bg[2]) * dt))
        rotation = self.rotation
        acceleration = rotation @ (fx, fy, fz) + GRAVITY
        transition = self._transition_for(dt)
        transition[THETA, THETA] = turn.T
        force_skew = ((0.0, fz * dt, -fy * dt), (-fz * dt, 0.0, fx * dt), (fy * dt, -fx * dt, 0.0))
        transition[VELOCITY, THETA] = rotation @ force_skew  # -dt R [f]x
        transition[VELOCITY, ACCEL_BIAS] = rotation * -dt
        covariance = transition @ self.covariance @ transition.T
        covariance.flat[:: STATE + 1] += self._noise
        self.covariance = covariance
        self.position += (self.velocity + 0.5 * dt * acceleration) * dt
        self.velocity += acceleration * dt
        self.rotation = rotation @ turn

    def _transition_for(self, dt: float) -> np.ndarray:
        """The transition matrix with its ``dt``-only blocks (and the noise) set for ``dt``."""
        if dt != self._transition_dt:
            transition = self._transition
            transition[THETA, GYRO_BIAS] = -dt * np.eye(3)
            transition[POSITION, VELOCITY] = dt * np.eye(3)
            self._noise = self._noise_density * dt
            self._transition_dt = dt
        return self._transition

    def update(
        self,
        stamp_ns: int,
        legs: Sequence[LegMeasurement | None],
        orientation: Quaternion | None = None,
        orientation_variance: Vector | None = None,
    ) -> list[int]:
        """Correct the state with one joint state's standing feet (None: a foot that does not
        stand, or unknown) and the IMU's orientation (None: none); the legs used (the gate's).
        """
        self.counts.updates += 1
        rotation_t = self.rotation.T
        local = rotation_t @ self.velocity
        base = np.zeros((3, STATE))
        base[:, THETA] = skew(local)
        base[:, VELOCITY] = rotation_t
        blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        if orientation is not None:
            blocks.append(self._orientation_block(orientation, orientation_variance))
        used, leg_block = self._legs(stamp_ns, legs, local.tolist(), base)
        if leg_block is not None:
            blocks.append(leg_block)
            if self.ground == FLAT:
                blocks.extend(self._heights(used, legs))
        if standing_still(legs, self.settings.still_speed_mps):
            self.counts.still += 1
            blocks.append((base, -local, (self.settings.still_noise_mps**2) * np.eye(3)))
        if blocks:
            self._correct(blocks)
        return used

    def _orientation_block(
        self, orientation: Quaternion, variance: Vector | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The IMU's orientation observes dθ directly: ``Log(R̂ᵀ R_m)``."""
        residual = log_so3(self.rotation.T @ matrix_of(orientation))
        noise = self._orientation_noise if variance is None else np.diag(variance)
        return ORIENTATION_ROWS, residual, noise

    def _legs(
        self,
        stamp_ns: int,
        legs: Sequence[LegMeasurement | None],
        local: list[float],
        base: np.ndarray,
    ) -> tuple[list[int], tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
        """The standing feet's velocity measurements, each gated alone: the legs accepted and
        their stacked rows, residuals and noise (None: none accepted).
        """
        s = self.settings
        wx, wy, wz = self._gyro
        bx, by, bz = self.gyro_bias.tolist()
        lx, ly, lz = local
        rate2, gyro2 = s.joint_rate_noise_radps**2, s.gyro_sample_noise_radps**2
        foot2 = s.foot_noise_mps**2
        ux, uy, uz = self.rotation[2].tolist()  # world up in the base frame
        extra = s.foot_vertical_noise_mps**2 - foot2
        fixed = (
            rate2,
            gyro2,
            (foot2 + extra * ux * ux, extra * ux * uy, extra * ux * uz,
             extra * uy * ux, foot2 + extra * uy * uy, extra * uy * uz,
             extra * uz * ux, extra * uz * uy, foot2 + extra * uz * uz),
        )  # fmt: skip
        candidates, levers, residuals, noises = [], [], [], []
        for leg, measurement in enumerate(legs):
            if measurement is None or not stands(measurement.probability):
                continue
            (ex, ey, ez), (rx, ry, rz), _ = measurement.motion
            candidates.append(leg)
            levers.append(((0.0, -rz, ry), (rz, 0.0, -rx), (-ry, rx, 0.0)))
            residuals.append(
                (
                    ex - (wy * rz - wz * ry) - lx - (ry * bz - rz * by),
                    ey - (wz * rx - wx * rz) - ly - (rz * bx - rx * bz),
                    ez - (wx * ry - wy * rx) - lz - (rx * by - ry * bx),
                )
            )
            noises.append(foot_noise(measurement, fixed))
        if not candidates:
            return [], None
        rows = np.repeat(base[None], len(candidates), axis=0)
        rows[:, :, GYRO_BIAS] = levers
        up = self.rotation[2]  # world up in the base frame
        h = math.sqrt(self.noise_scale)
        shape = h * np.eye(3) + (1.0 - h) * np.outer(up, up)
        residual, noise = np.array(residuals), shape @ np.array(noises) @ shape
        innovation = rows @ self.covariance @ rows.transpose(0, 2, 1) + noise
        nis, along = normalised_squares(innovation.tolist(), residuals, up.tolist())
        accepted, reset = self._gate(stamp_ns, candidates, nis, along)
        if not accepted:
            return [], None
        if reset:  # the filter had lost its way: widen the velocity by the feet's disagreement
            spread = float((residual**2).sum(axis=1).mean())
            self.covariance[VELOCITY, VELOCITY] += spread * np.eye(3)
        keep = [candidates.index(leg) for leg in accepted]
        return accepted, (
            rows[keep].reshape(-1, STATE),
            residual[keep].reshape(-1),
            block_diagonal(noise[keep]),
        )

    def _gate(
        self, stamp_ns: int, candidates: list[int], nis: list[float], vertical: list[float]
    ) -> tuple[list[int], bool]:
        """The candidate legs whose NIS passes the gate, and whether the gate was reset (every
        foot failed for :data:`FilterSettings.max_rejected_s`: all taken); counts kept, the
        horizontal noise scale matched to the accepted feet's NIS (``vertical``: its part along
        world up, 1 dof).
        """
        s, counts = self.settings, self.counts
        accepted = [leg for leg, value in zip(candidates, nis) if value <= s.gate_chi2]
        reset = False
        if accepted:
            self._rejected_since_ns = None
        else:
            if self._rejected_since_ns is None:
                self._rejected_since_ns = stamp_ns
            if (stamp_ns - self._rejected_since_ns) / 1e9 >= s.max_rejected_s:
                accepted, self._rejected_since_ns, reset = list(candidates), None, True
                counts.gate_resets += 1
        total = up = 0.0
        for leg, value, along in zip(candidates, nis, vertical):
            if leg in accepted:
                counts.used[leg] += 1
                total += value
                up += along
            else:
                counts.rejected[leg] += 1
        if accepted:
            counts.nis_sum += total
            counts.nis_count += len(accepted)
            self._adapt(stamp_ns, max(total - up, 0.0) / (2.0 * len(accepted)))
        return accepted, reset

    def _adapt(self, stamp_ns: int, ratio: float) -> None:
        """Move the feet's horizontal noise scale towards consistency: ``ratio`` is the accepted
        feet's mean horizontal NIS over its expectation (2), held within [0.1, 10] for a step.
        The vertical noise stays the model's: a foot's vertical error (the ground's give, the
        impacts) is no white noise a mean NIS could measure.
        """
        previous, self._legs_stamp_ns = self._legs_stamp_ns, stamp_ns
        s = self.settings
        if previous is None or not s.noise_adapt_s > 0.0:
            return
        step = min(max((stamp_ns - previous) / 1e9, 0.0), s.max_step_s) / s.noise_adapt_s
        scale = self.noise_scale * (1.0 + step * (min(max(ratio, 0.1), 10.0) - 1.0))
        self.noise_scale = min(max(scale, s.min_noise_scale), 1.0)

    def _heights(
        self, used: list[int], legs: Sequence[LegMeasurement | None]
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Flat ground: each used foot's contact point at the ground's height, remembered from
        the first stance (``p_z + R₃·r``; its dθ row is ``r x R₃``, R₃ the third row of R).
        """
        r3x, r3y, r3z = self.rotation[2].tolist()
        z = float(self.position[2])
        rows, heights = np.zeros((len(used), STATE)), []
        for index, leg in enumerate(used):
            measurement = legs[leg]
            assert measurement is not None
            rx, ry, rz = measurement.motion.r
            heights.append(z + r3x * rx + r3y * ry + r3z * rz)
            rows[index, :3] = (ry * r3z - rz * r3y, rz * r3x - rx * r3z, rx * r3y - ry * r3x)
        if self.ground_z is None:
            self.ground_z = sum(heights) / len(heights)
            return []
        rows[:, Z] = 1.0
        residual = np.array([self.ground_z - height for height in heights])
        return [(rows, residual, (self.settings.height_noise_m**2) * np.eye(len(used)))]

    def _correct(self, blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
        """One Kalman update with the stacked ``blocks`` (rows, residual, noise), and the error's
        injection into the nominal state.
        """
        if len(blocks) == 1:
            rows, residual, noise = blocks[0]
        else:
            rows = np.concatenate([block[0] for block in blocks])
            residual = np.concatenate([block[1] for block in blocks])
            noise = block_diagonal([block[2] for block in blocks])
        covariance = self.covariance
        cross = covariance @ rows.T
        gain_t = np.linalg.solve(rows @ cross + noise, cross.T)
        error = (residual @ gain_t).tolist()
        covariance = covariance - cross @ gain_t
        self.covariance = 0.5 * (covariance + covariance.T)
        self.rotation = self.rotation @ exp_so3(error[0:3])
        self.velocity += error[3:6]
        self.position += error[6:9]
        self.gyro_bias += error[9:12]
        self.accel_bias += error[12:15]

    def sample(self, stamp_ns: int, stance: Sequence[int], used: Sequence[int]) -> OdometrySample:
        """The estimate as an :class:`OdometrySample` (twist in the base frame, pose in odom)
        with the diagonals of its covariances.
        """
        rotation, covariance = self.rotation, self.covariance
        rotation_t = rotation.T
        local = rotation_t @ self.velocity
        row = np.hstack((skew(local), rotation_t))  # d(Rᵀ v) / d(dθ, dv)
        twist = ((row @ covariance[:6, :6]) * row).sum(axis=1)
        attitude = ((rotation @ covariance[THETA, THETA]) * rotation).sum(axis=1)
        diagonal = covariance.diagonal()
        gyro_noise = self.settings.gyro_sample_noise_radps**2
        wx, wy, wz = self._gyro
        bx, by, bz = self.gyro_bias.tolist()
        px, py, pz = self.position.tolist()
        return OdometrySample(
            stamp_ns,
            (px, py, pz),
            quaternion_of(rotation),
            tuple(local.tolist()),
            (wx - bx, wy - by, wz - bz),
            tuple(diagonal[POSITION].tolist() + attitude.tolist()),
            tuple(twist.tolist() + (diagonal[GYRO_BIAS] + gyro_noise).tolist()),
            tuple(stance),
            tuple(used),
            False,
        )
