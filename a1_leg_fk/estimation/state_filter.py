"""The base's state from its IMU and its legs: an error-state extended Kalman filter (ESKF).

State: the base's orientation ``R`` (base -> world), the URDF root's velocity ``v`` and position
``p`` in the world (``odom``: z up, the first sample's position at the origin), the gyro's bias
``b_g`` [rad/s] and the accelerometer's ``b_a`` [m/s^2] (base frame); the error ``(dθ, dv, dp,
db_g, db_a)``, ``R = R̂ Exp(dθ)``, has a 15 x 15 covariance. Settings and counts:
:mod:`a1_leg_fk.estimation.filter_model`.

- **Propagation** at every IMU sample (:meth:`StateFilter.propagate`): ``ω = ω_m - b_g``,
  ``a = R (f_m - b_a) + g``; ``R <- R Exp(ω dt)``, ``p <- p + v dt + a dt²/2``, ``v <- v + a dt``;
  the covariance grows by the sensors' white noise and the biases' random walks.
- **Updates** at every joint state (:meth:`StateFilter.update`), stacked into one
  (:mod:`a1_leg_fk.estimation.filter_stack`): the IMU's own orientation when it gives one (``dθ``
  observed directly); per foot in stance the base's velocity in the base frame, ``z = e - ω_m x
  r = Rᵀ v + r x b_g`` (``e = -(J q̇ + ω_calf x c)`` at the rolling contact point ``r``,
  :class:`~a1_leg_fk.estimation.leg_motion.FootMotion`), noise
  :func:`~a1_leg_fk.estimation.filter_model.foot_noise` over the contact probability plus the
  touchdown's vertical transient (:class:`~a1_leg_fk.estimation.foot_impact.FootImpact`, its
  amplitude fitted to the landing feet's vertical innovations, since the foot's first joint
  state in stance; with ``give_s``, the larger of it and the feet's
  measured give, :mod:`~a1_leg_fk.estimation.foot_give`), and, on the feet the gate accepts,
  the last touchdown's sideways jolt of the feet standing (:mod:`~a1_leg_fk.estimation.foot_jolt`:
  a landing foot pushes them sideways, all alike); the stance feet's heights
  ``p_z + (R r)_z`` equal their footholds' anchored heights (``ground="footholds"``, the default,
  :mod:`a1_leg_fk.estimation.ground`) or, on a known flat floor (``ground="flat"``), the ground's
  taken at the first feet believed; standing
  still (every foot in stance, none moving) a zero-velocity update.
- **Gating** (:class:`~a1_leg_fk.estimation.foot_gate.FootGate`): each foot's innovation is
  tested alone (NIS against χ², 3 dof); a foot that fails (a slip, a swinging foot taken for
  standing) is left out and counted. When every foot has failed for ``max_rejected_s`` (at once
  while none was ever believed) the filter has lost its way: the feet that agree are taken again,
  the velocity's covariance widened by their innovation; until then the reported velocity's
  variance holds that alternative (:func:`~a1_leg_fk.estimation.filter_model.doubt`). The
  accepted feet's noises are widened by their scatter when they disagree beyond them
  (:func:`~a1_leg_fk.estimation.filter_model.scattered`), and scaled, horizontally and
  vertically, to keep their mean NIS at its expectation (covariance matching).

Why an ESKF (Bloesch et al., RSS 2012, in its error-state form) and not the invariant EKF
(Hartley et al., IJRR 2020): the leg measurement here is a velocity, not a foot position kept in
the state, so the state stays at 15 (no feet to add and drop at every touchdown), the biases that
break the invariant filter's log-linearity anyway are in it, and the rolling contact point, the
probability weighting and the per-foot gate work on the velocity directly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from a1_leg_fk.estimation.filter_history import FilterHistory
from a1_leg_fk.estimation.filter_model import (
    ACCEL_BIAS,
    DEFAULT_GROUND,
    FLAT,
    FOOTHOLDS,
    GROUND_MODELS,
    GYRO_BIAS,
    LEGS,
    POSITION,
    STATE,
    THETA,
    VELOCITY,
    FilterCounts,
    FilterSettings,
    LegMeasurement,
    doubt,
    normalised_squares,
    scattered,
    standing_still,
    stands,
)
from a1_leg_fk.estimation.filter_stack import Point, Stack
from a1_leg_fk.estimation.foot_gate import FootGate
from a1_leg_fk.estimation.foot_give import FootGive
from a1_leg_fk.estimation.foot_impact import FootImpact
from a1_leg_fk.estimation.foot_jolt import FootJolt
from a1_leg_fk.estimation.odometry import OdometrySample
from a1_leg_fk.estimation.so3 import exp_so3, exp_so3_rows, matrix_of
from a1_leg_fk.estimation.state_sample import floats_of, state_sample
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, Quaternion, Vector

DT_ENTRIES = np.array(
    [(THETA.start + k) * STATE + GYRO_BIAS.start + k for k in range(3)]
    + [(POSITION.start + k) * STATE + VELOCITY.start + k for k in range(3)]
)
"""The transition's flat entries that are ``-dt`` (dθ by db_g) and ``dt`` (dp by dv)."""
NO_DOUBT = (0.0, 0.0, 0.0)
"""The reported velocity's variance added while some foot is believed [m²/s²]."""


class StateFilter:
    """The running estimate (see the module text): :meth:`propagate` with every IMU sample,
    :meth:`update` with every joint state. It starts at the first IMU sample, oriented as that
    sample says (else level), at rest at the origin.

    The algebra is numpy on whole matrices, a few calls per step, the small parts in floats:
    numpy's cost per call, not the arithmetic, sets the filter's speed (``bench/``).
    """

    def __init__(
        self, settings: FilterSettings | None = None, ground: str = DEFAULT_GROUND
    ) -> None:
        if ground not in GROUND_MODELS:
            raise ValueError(f"ground must be one of {', '.join(GROUND_MODELS)}: {ground!r}")
        self.settings = s = settings or FilterSettings()
        self.ground = ground
        self.counts = FilterCounts()
        self.rotation = np.eye(3)
        self._nominal = np.zeros(STATE - 3)
        self.velocity, self.position, self.gyro_bias, self.accel_bias = (
            self._nominal[k : k + 3] for k in range(0, STATE - 3, 3)
        )
        self.covariance = np.zeros((STATE, STATE))
        self.started = False
        self.ground_z: float | None = None
        self._imu_stamp_ns = 0
        self._gyro: Vector = (0.0, 0.0, 0.0)
        self._touchdowns: list[int | None] = [None] * LEGS
        self.gate = FootGate(self.settings, self.counts)
        self.give = FootGive(self.settings)
        self.impact = FootImpact(self.settings)
        self.jolt = FootJolt(self.settings)
        self.doubt = NO_DOUBT
        """The reported velocity's variance added while the gate rejects every foot
        (:func:`~a1_leg_fk.estimation.filter_model.doubt`) [m²/s², base frame]."""
        self._transition = np.eye(STATE)
        self._noise_density = np.diag(
            np.repeat(
                [s.gyro_noise**2, s.accel_noise**2, 0.0, s.gyro_bias_walk**2,
                 s.accel_bias_walk**2],
                3,
            )
        )  # fmt: skip
        """The process noise's spectral densities (diagonal), per second."""
        self.history: FilterHistory | None = None
        """Each step's states and transition, for a smoother (offline only; None: not kept)."""

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
        history = self.history
        if history is not None:
            history.before(self._imu_stamp_ns, self.rotation, self._nominal, self.covariance)
        self._imu_stamp_ns = stamp_ns
        if dt > self.settings.max_step_s:
            self.counts.gaps += 1
            dt = self.settings.max_step_s
        bx, by, bz, cx, cy, cz = self._nominal[6:12].tolist()
        fx, fy, fz = specific_force[0] - cx, specific_force[1] - cy, specific_force[2] - cz
        (t0, t1, t2), (t3, t4, t5), (t6, t7, t8) = exp_so3_rows(
            ((gyro[0] - bx) * dt, (gyro[1] - by) * dt, (gyro[2] - bz) * dt)
        )
        # R times [-dt [f]x | -dt I | f | Exp(ω dt)]: the velocity's rows of the transition, the
        # acceleration and the next rotation in one product
        inputs = np.array(
            ((0.0, fz * dt, -fy * dt, -dt, 0.0, 0.0, fx, t0, t1, t2),
             (-fz * dt, 0.0, fx * dt, 0.0, -dt, 0.0, fy, t3, t4, t5),
             (fy * dt, -fx * dt, 0.0, 0.0, 0.0, -dt, fz, t6, t7, t8))
        )  # fmt: skip
        product = self.rotation.dot(inputs)
        transition = self._transition
        transition.ravel()[DT_ENTRIES] = (-dt, -dt, -dt, dt, dt, dt)  # dθ by db_g, dp by dv
        transition[THETA, THETA] = inputs[:, 7:10].T
        transition[VELOCITY, THETA] = product[:, 0:3]
        transition[VELOCITY, ACCEL_BIAS] = product[:, 3:6]
        covariance = transition.dot(self.covariance).dot(transition.T)
        covariance += self._noise_density * dt
        self.covariance = covariance
        ax, ay, az = product[:, 6].tolist()
        az -= STANDARD_GRAVITY
        vx, vy, vz, px, py, pz = self._nominal[0:6].tolist()
        half = 0.5 * dt
        self._nominal[0:6] = (
            vx + ax * dt, vy + ay * dt, vz + az * dt,
            px + (vx + half * ax) * dt, py + (vy + half * ay) * dt, pz + (vz + half * az) * dt,
        )  # fmt: skip
        self.rotation = product[:, 7:10].copy()
        if history is not None:
            history.after(transition, self.rotation, self._nominal)

    def update(
        self,
        stamp_ns: int,
        legs: Sequence[LegMeasurement | None],
        orientation: Quaternion | None = None,
        orientation_variance: Vector | None = None,
        grounds: Sequence[tuple[float, float] | None] | None = None,
    ) -> list[int]:
        """Correct the state with one joint state's standing feet (None: a foot that does not
        stand, or unknown) and the IMU's orientation (None: none); the legs used (the gate's).
        ``grounds`` (``ground="footholds"``): per leg, the ground's height [m] under its foot
        (its foothold's anchored height) and its variance [m²] (None: unknown; the heights count
        when every standing foot has one).

        One stacked update (:class:`~a1_leg_fk.estimation.filter_stack.Stack`: the orientation,
        every standing foot, their heights, the zero-velocity update); the feet's gate reads its
        innovation covariance, and the rows of the feet it rejects (and their heights) are
        dropped before the gain.
        """
        self.counts.updates += 1
        candidates, feet = self._standing(stamp_ns, legs)
        still = len(feet) == len(legs) and standing_still(legs, self.settings.still_speed_mps)
        self.doubt = NO_DOUBT
        if orientation is None and not candidates and not still:
            return []
        local = None
        if self.ground == FOOTHOLDS and grounds is not None:
            under = [grounds[leg] for leg in candidates]
            local = [ground for ground in under if ground is not None]
            local = local if len(local) == len(candidates) else None
        heights = local is not None or (self.ground == FLAT and self.ground_z is not None)
        imu = None if orientation is None else (orientation, orientation_variance)
        stack = Stack(self._point(local), self.settings, imu, feet, heights, still)
        self.counts.still += still
        cross = self.covariance.dot(stack.rows.T)
        innovation = stack.rows.dot(cross) + stack.noise
        if not candidates:
            self._correct(cross, innovation, stack.residual)
            return []
        sideways = self.jolt.sideways(stamp_ns, stack.up)
        used, reset = self._gate_feet(stamp_ns, candidates, stack, innovation, sideways)
        if reset:
            cross = self.covariance.dot(stack.rows.T)
            innovation = stack.rows.dot(cross) + stack.noise
        positions = [candidates.index(leg) for leg in used]
        residuals = [stack.foot_residuals[k] for k in positions]
        noises = [stack.foot_noises[k] for k in positions]
        transients = [feet[k][1] for k in positions]
        if self.settings.give_s > 0.0:  # the feet's give modelled
            landed = max([self._touchdowns[leg] or stamp_ns for leg in used] or [stamp_ns])
            covariance, up = self.covariance, stack.up
            self.give.observe(stamp_ns, up, residuals, noises, transients, covariance, landed)
        if self.settings.impact_window_s > 0.0:  # each landing's amplitude measured
            ages = [(stamp_ns - (self._touchdowns[leg] or stamp_ns)) / 1e9 for leg in used]
            rows = [stack.layout.feet.start + 3 * k for k in positions]
            landing = (used, ages, residuals)
            self.impact.observe(stamp_ns, landing, transients, stack.up, innovation, rows)
            self.jolt.observe(stamp_ns, residuals, stack.up, innovation, rows)
        spread = scattered(residuals, noises, self.settings.gate_chi2)
        added = [spread * np.eye(3)] if spread else []  # the feet disagree beyond their noises
        added += [] if sideways is None else [sideways]  # the last touchdown's jolt
        for k in positions if added else ():
            first = stack.layout.feet.start + 3 * k
            innovation[first : first + 3, first : first + 3] += sum(added)
        if len(used) < len(candidates):
            keep = stack.keep(positions)
            if keep.size:
                innovation = innovation.take(keep, axis=0).take(keep, axis=1)
                self._correct(cross.take(keep, axis=1), innovation, stack.residual.take(keep))
            return used
        self._correct(cross, innovation, stack.residual)
        return used

    def _standing(
        self, stamp_ns: int, legs: Sequence[LegMeasurement | None]
    ) -> tuple[list[int], list[tuple[LegMeasurement, float]]]:
        """The legs whose feet stand, and each one's measurement with its touchdown's vertical
        variance (:meth:`FootImpact.variance`, since its first joint state in stance); a
        touchdown while other feet stood starts a jolt (:meth:`FootJolt.land`).
        """
        candidates, feet = [], []
        stood = any(touchdown is not None for touchdown in self._touchdowns)
        for leg, measurement in enumerate(legs):
            if measurement is None or not stands(measurement.probability):
                self._touchdowns[leg] = None
                continue
            touchdown = self._touchdowns[leg]
            if touchdown is None:
                touchdown = self._touchdowns[leg] = stamp_ns
                self.impact.land(leg)
                if stood:  # a landing while other feet stand jolts them
                    self.jolt.land(stamp_ns)
            candidates.append(leg)
            impact = self.impact.variance(leg, (stamp_ns - touchdown) / 1e9)
            feet.append((measurement, impact))
        give = self.give.variance(len(feet))
        if give:  # the touchdown's transient is a give too: the larger of the two, not their sum
            feet = [(measurement, max(impact, give)) for measurement, impact in feet]
        return candidates, feet

    def _gate_feet(
        self,
        stamp_ns: int,
        candidates: list[int],
        stack: Stack,
        innovation: np.ndarray,
        jolt: np.ndarray | None,
    ) -> tuple[list[int], bool]:
        """The feet the gate lets through (:class:`FootGate`, on their NIS in ``innovation``, its
        scales matched with the ``jolt`` [m²/s², 3 x 3, base frame; None: none] in each foot's
        block), and whether it was reset (the velocity's covariance then widened by their
        innovation); the doubt while it rejects every foot; the ground at the first feet believed.
        """
        rows = stack.layout.feet
        residuals = stack.foot_residuals
        blocks = innovation[rows, rows]
        nis, along = normalised_squares(blocks.tolist(), residuals, stack.up)
        matched = nis
        if jolt is not None:  # the jolt is no white noise the scales should take up
            blocks = blocks + np.kron(np.eye(len(residuals)), jolt)
            matched = normalised_squares(blocks.tolist(), residuals, stack.up)[0]
        used, reset = self.gate(stamp_ns, candidates, (nis, along, matched), residuals)
        if not used:
            self.doubt = doubt(residuals, stack.foot_noises, nis, self.settings)
            return used, reset
        if reset:  # the filter had lost its way: widen the velocity by the feet's innovation
            taken = [residuals[candidates.index(leg)] for leg in used]
            spread = sum(x * x + y * y + z * z for x, y, z in taken) / len(taken)
            self.covariance[VELOCITY, VELOCITY] += spread * np.eye(3)
        if self.ground == FLAT and self.ground_z is None:
            heights = [stack.foot_heights[candidates.index(leg)] for leg in used]
            self.ground_z = sum(heights) / len(heights)
        return used, reset

    def _correct(self, cross: np.ndarray, innovation: np.ndarray, residual: np.ndarray) -> None:
        """One Kalman update (``cross = P Hᵀ``, ``innovation = H P Hᵀ + N``), and the error's
        injection into the nominal state.
        """
        gain_t = np.linalg.solve(innovation, cross.T)
        error = residual.dot(gain_t)
        covariance = self.covariance - cross.dot(gain_t)
        covariance += covariance.T
        covariance *= 0.5
        self.covariance = covariance
        self.rotation = self.rotation.dot(exp_so3(error[0:3].tolist()))
        self._nominal += error[3:]
        self.give.corrected(float(error[5]))

    def _floats(self) -> tuple[list[list[float]], Vector, list[float]]:
        """The rotation's rows, ``Rᵀ v`` and the nominal state's first 9 values
        (:func:`floats_of`).
        """
        return floats_of(self.rotation, self._nominal)

    def _point(self, grounds: list[tuple[float, float]] | None = None) -> Point:
        """The state an update linearises about (a :class:`Point`), with the local ground under
        each standing foot (``grounds``, None: the flat ground's, if any).
        """
        rows, local, (_, _, _, _, _, pz, bx, by, bz) = self._floats()
        scales = self.gate.scales
        return Point(rows, local, self._gyro, (bx, by, bz), pz, self.ground_z, scales, grounds)

    @property
    def gyro(self) -> Vector:
        """The gyro's last sample [rad/s, base frame]."""
        return self._gyro

    @property
    def nominal(self) -> np.ndarray:
        """The nominal velocity, position, gyro and accelerometer biases (12, odom and base)."""
        return self._nominal

    @property
    def noise_density(self) -> np.ndarray:
        """The process noise's spectral densities (15, per second)."""
        return self._noise_density.diagonal().copy()

    def keep_history(self) -> FilterHistory:
        """Keep each step's states from now on (:attr:`history`), for a smoother."""
        self.history = FilterHistory(self.noise_density)
        return self.history

    def sample(self, stamp_ns: int, stance: Sequence[int], used: Sequence[int]) -> OdometrySample:
        """The estimate as an :class:`OdometrySample` (:func:`state_sample`)."""
        state = (self.rotation, self._nominal, self.covariance)
        return state_sample(
            stamp_ns, state, (self._gyro, self.doubt), self.settings, (stance, used)
        )
