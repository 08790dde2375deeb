"""Foot forces from the legs' dynamics: a generalised-momentum observer per leg, stepped with each
joint state, without ROS.

The quasi-static estimate (:mod:`a1_leg_fk.kinematics.foot_forces`) reads a swinging leg's own
accelerations as load. The observer (De Luca & Mattone 2005; Haddadin, De Luca & Albu-Schaeffer,
T-RO 2017) estimates the external joint torque without the joint accelerations: with the leg's
generalised momentum ``p = M(q) dq`` and Lagrange's equation ``dp/dt = tau + tau_ext - beta``,
``beta = g(q) - C(q, dq)^T dq`` (:mod:`a1_leg_fk.kinematics.leg_dynamics`), the residual

    r = K (p(t) - p(0) - integral(tau - beta + r) dt)

follows ``dr/dt = K (tau_ext - r)``: ``tau_ext`` through a first-order lag of time constant
``1 / K``. Between two joint states ``dt`` apart it is updated exactly for a constant input:
``r <- e^(-K dt) r + (1 - e^(-K dt)) ((p - p_prev) / dt - s)``, ``s = tau - beta`` taken at the
interval's end (a motor's effort reported with a joint state is the one it applied over the
interval before it; in PyBullet this leaves 0.22-0.25 N rms on legs in the air, the trapezoid
0.42 N). The ground's force on the foot follows from ``J^T F = r`` (the contact point on the
foot's sphere, as in the statics), base frame [N]: the same sign convention as the quasi-static
``F = J^-T (g(q) - tau)``, which the observer gives for a leg at rest.

The base's motion: its angular velocity ``omega`` [rad/s, base frame] (the IMU's gyro) enters
``p`` and ``C^T dq``; its linear acceleration enters through the IMU's specific force ``f``
[m/s^2, base frame; an accelerometer at the base origin], the legs feeling gravity ``g - a = -f``.
Without a gyro the base is taken as not turning, without an accelerometer as not accelerating
(gravity from the orientation, or level): an inertial base.

A leg's first joint state, one after a gap of more than ``max_gap_s``, or one after a joint
state with that leg's values missing (or absurd: a residual that is not finite) starts its
observer again from the quasi-static estimate (``dp/dt = 0``); a joint state without the leg's
rates gets the quasi-static estimate. Joint states at the same stamp or older hold the estimate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from math import cos, exp, isfinite, sin

import numpy as np
from numpy.typing import ArrayLike

from a1_leg_fk.estimation.model_corrections import ModelCorrections
from a1_leg_fk.kinematics.foot_forces import (
    MIN_JACOBIAN_CONDITION,
    ForceEstimate,
    LeggedRobot,
    batch_array,
    gravity_rows,
)
from a1_leg_fk.kinematics.leg_dynamics import LegDynamics
from a1_leg_fk.kinematics.leg_statics import LegStatics
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

DEFAULT_GAIN_PER_S = 1000.0
"""The observer's gain K [1/s]: the external torque through a lag of 1 / K = 1 ms (at K = 100 /s
the lag costs 18 N of stance force error on a fast trot; tuned on the contact family's tuning
runs, test/estimation/test_contact_family.py)."""
MAX_GAP_S = 0.05
"""[s] A longer gap between joint states restarts the observers from the quasi-static estimate."""
LEGS = len(LEG_NAMES)
NO_ROTATION = (0.0, 0.0, 0.0)


class _LegState:
    """One leg's observer between joint states: the latest stamp [s], momentum ``p`` [N m s],
    residual ``r`` [N m] and ``efforts`` [N m], the efforts through the residual's lag (so
    ``r + efforts`` is the URDF's torque ``W = M q̈ + C q̇ + g`` through it: the inertia scales'
    regressor, :mod:`a1_leg_fk.estimation.leg_scales`); a fresh state: no stamp, so the next
    joint state starts it.
    """

    __slots__ = ("efforts", "momentum", "residual", "stamp_s")

    def __init__(self) -> None:
        self.stamp_s = math.nan
        self.momentum = (0.0, 0.0, 0.0)
        self.residual = (0.0, 0.0, 0.0)
        self.efforts = (0.0, 0.0, 0.0)


class MomentumObserver:
    """Foot forces of a robot's four legs from their dynamics (see the module text), stepped with
    each joint state in time order.
    """

    def __init__(
        self,
        quadruped: LeggedRobot,
        gain_per_s: float = DEFAULT_GAIN_PER_S,
        min_condition: float = MIN_JACOBIAN_CONDITION,
        foot_radius_m: float | None = None,
        max_gap_s: float = MAX_GAP_S,
    ) -> None:
        """Generate each leg's dynamics and statics from ``quadruped``'s URDF. ``gain_per_s``:
        the observer gain K [1/s]; ``min_condition`` gates near-singular Jacobians and
        ``foot_radius_m`` places the contact point as in
        :class:`~a1_leg_fk.kinematics.foot_forces.FootForces`.
        """
        if not (math.isfinite(gain_per_s) and gain_per_s > 0.0):
            raise LegFkError(f"the observer gain must be a positive number [1/s]: {gain_per_s}")
        self.gain_per_s, self.min_condition, self.max_gap_s = gain_per_s, min_condition, max_gap_s
        self._dynamics = tuple(LegDynamics(quadruped.model, leg) for leg in quadruped.legs)
        self._statics = tuple(
            LegStatics(quadruped.model, leg, foot_radius_m) for leg in quadruped.legs
        )
        self._legs = tuple(
            (statics.gravity_torques, dynamics.kinetic_terms, statics.solve_torques)
            for statics, dynamics in zip(self._statics, self._dynamics, strict=True)
        )
        self._inertial_terms = tuple(dynamics.inertial_terms for dynamics in self._dynamics)
        """Per leg its generated functions, looked up once (the per-sample path); without a gyro,
        the base taken as not turning, ``inertial_terms`` stand in for ``kinetic_terms``."""
        self._states = [_LegState() for _ in range(LEGS)]
        self.corrections: ModelCorrections | None = None
        """The model's corrections, taken off each residual with the leg's rates (None: none)."""

    def reset(self) -> None:
        """Forget the past: the next joint state starts every leg quasi-statically."""
        self._states = [_LegState() for _ in range(LEGS)]

    def step_floats(
        self,
        stamp_s: float,
        sample: tuple[Sequence[float], Sequence[float], Sequence[float]],
        gravity: Sequence[float],
        specific_force: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
    ) -> tuple[list[list[float]], list[bool], list[bool]]:
        """One joint state at ``stamp_s`` [s] in plain floats (the node's path): ``sample`` is
        12 angles [rad], rates [rad/s] and efforts [N m] (slot order); ``gravity`` (3,) [m/s^2]
        and the IMU's ``specific_force`` [m/s^2] and ``angular_velocity`` [rad/s], base frame.
        Per leg its force [N] (NaN when none), whether its values are missing (or absurd: a
        force that is not finite), whether its Jacobian is near singular.
        """
        angles, rates, efforts = sample
        gx, gy, gz = gravity
        fx, fy, fz = gravity if specific_force is None else [-f for f in specific_force]
        wx, wy, wz = NO_ROTATION if angular_velocity is None else angular_velocity
        turning = angular_velocity is not None
        if not isfinite(gx + gy + gz + fx + fy + fz + wx + wy + wz):
            self.reset()
            return [[math.nan] * 3 for _ in range(LEGS)], [True] * LEGS, [False] * LEGS
        out, missing, singular = [], [], []
        states, gain, max_gap = self._states, self.gain_per_s, self.max_gap_s
        for slot, (gravity_torques, kinetic_terms, solve_torques) in enumerate(self._legs):
            first = slot * JOINTS_PER_LEG
            q0, q1, q2 = angles[first], angles[first + 1], angles[first + 2]
            t0, t1, t2 = efforts[first], efforts[first + 1], efforts[first + 2]
            if not isfinite(q0 + q1 + q2 + t0 + t1 + t2):
                states[slot] = _LegState()
                out.append([math.nan] * 3)
                missing.append(True)
                singular.append(False)
                continue
            c0, s0, c1, s1, c2, s2 = cos(q0), sin(q0), cos(q1), sin(q1), cos(q2), sin(q2)
            g0, g1, g2 = gravity_torques(c0, s0, c1, s1, c2, s2, fx, fy, fz)
            d0, d1, d2 = rates[first], rates[first + 1], rates[first + 2]
            if isfinite(d0 + d1 + d2):
                k0, k1, k2, p0, p1, p2 = (
                    kinetic_terms(c0, s0, c1, s1, c2, s2, d0, d1, d2, wx, wy, wz)
                    if turning
                    else self._inertial_terms[slot](c0, s0, c1, s1, c2, s2, d0, d1, d2)
                )
                state = states[slot]
                r0, r1, r2 = state.residual
                dt = stamp_s - state.stamp_s
                if not dt <= 0.0:  # else the same stamp, or older: hold (NaN: the first)
                    e0, e1, e2 = t0 - g0 + k0, t1 - g1 + k1, t2 - g2 + k2  # s = tau - beta
                    if dt <= max_gap:  # NaN (the first) is neither
                        keep = exp(-gain * dt)
                        m0, m1, m2 = state.momentum
                        change = (1.0 - keep) / dt
                        r0 = keep * r0 + change * (p0 - m0 - dt * e0)
                        r1 = keep * r1 + change * (p1 - m1 - dt * e1)
                        r2 = keep * r2 + change * (p2 - m2 - dt * e2)
                        f0, f1, f2 = state.efforts
                        state.efforts = (
                            f0 + (1.0 - keep) * (t0 - f0),
                            f1 + (1.0 - keep) * (t1 - f1),
                            f2 + (1.0 - keep) * (t2 - f2),
                        )
                    else:  # quasi-static: dp/dt = 0
                        r0, r1, r2 = -e0, -e1, -e2
                        state.efforts = (t0, t1, t2)
                    state.stamp_s, state.momentum = stamp_s, (p0, p1, p2)
                    state.residual = (r0, r1, r2)
                if not isfinite(r0 + r1 + r2):  # absurd values: start again
                    states[slot] = _LegState()
                elif self.corrections is not None:
                    r0, r1, r2 = self._corrected(slot, (r0, r1, r2), (d0, d1, d2))
            else:  # no rates: the quasi-static estimate
                states[slot] = _LegState()
                r0, r1, r2 = g0 - t0, g1 - t1, g2 - t2
            x, y, z, det, size = solve_torques(c0, s0, c1, s1, c2, s2, r0, r1, r2, gx, gy, gz)
            if abs(det) < self.min_condition * size:
                out.append([math.nan] * 3)
                missing.append(False)
                singular.append(True)
                continue
            force = [x / det, y / det, z / det]
            finite = isfinite(force[0] + force[1] + force[2])
            if not finite:  # absurd values (efforts of 1e300 N m): no force, start again
                states[slot] = _LegState()
            out.append(force if finite else [math.nan] * 3)
            missing.append(not finite)
            singular.append(False)
        return out, missing, singular

    def _corrected(
        self, slot: int, residual: tuple[float, float, float], rates: tuple[float, float, float]
    ) -> tuple[float, float, float]:
        """Leg ``slot``'s residual [N m] with the model's corrections taken off: its inertia
        scale's share of the URDF's torque (``r + efforts``, through the lag), then each
        joint's friction at its ``rates`` [rad/s]; what is left kept for the scale's learning.
        """
        corrections = self.corrections
        assert corrections is not None  # the caller's test
        f0, f1, f2 = self._states[slot].efforts
        r0, r1, r2 = residual
        scales, correct, first = corrections.scales, corrections.correct, slot * JOINTS_PER_LEG
        if scales.applied(slot):
            r0, r1, r2 = scales.correct(slot, residual, (r0 + f0, r1 + f1, r2 + f2))
        left = (
            correct(first, r0, rates[0]),
            correct(first + 1, r1, rates[1]),
            correct(first + 2, r2, rates[2]),
        )
        if not scales.fixed:  # fixed scales learn nothing: nothing to keep
            scales.keep(slot, left, rates)
        return left

    def step_batch(
        self,
        stamps_s: ArrayLike,
        samples: tuple[ArrayLike, ArrayLike, ArrayLike],
        gravity: ArrayLike | None = None,
        specific_force: ArrayLike | None = None,
        angular_velocity: ArrayLike | None = None,
    ) -> ForceEstimate:
        """:meth:`step_floats` over N joint states in time order (a recording, in blocks: the
        observers carry over): (N,) stamps [s], ``samples`` (N, 12) angles, rates, efforts;
        gravity (3,) or (N, 3) (default level), specific force and angular velocity (N, 3) or
        None. The same numbers as :meth:`step_floats` row by row.
        """
        angles, rates, efforts = (batch_array(v, w) for v, w in zip(samples, _WHAT, strict=True))
        rows = angles.shape[0]
        stamps = np.asarray(stamps_s, dtype=np.float64).reshape(rows)
        down = gravity_rows(gravity, rows)
        accel = None if specific_force is None else gravity_rows(specific_force, rows)
        omega = gravity_rows(NO_ROTATION if angular_velocity is None else angular_velocity, rows)
        forces = np.full((rows, LEGS, 3), math.nan)
        missing = np.ones((rows, LEGS), dtype=bool)
        singular = np.zeros((rows, LEGS), dtype=bool)
        for row in range(rows):
            out, missing[row], singular[row] = self.step_floats(
                float(stamps[row]),
                (angles[row].tolist(), rates[row].tolist(), efforts[row].tolist()),
                down[row].tolist(),
                None if accel is None else accel[row].tolist(),
                omega[row].tolist(),
            )
            forces[row] = out
        return ForceEstimate(forces, missing, singular)


_WHAT = ("angles", "rates", "efforts")
