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
``r <- e^(-K dt) r + (1 - e^(-K dt)) ((p - p_prev) / dt - (s + s_prev) / 2)``, ``s = tau - beta``
(trapezoidal). The ground's force on the foot follows from ``J^T F = r`` (the contact point on the
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

import numpy as np
from numpy.typing import ArrayLike

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
"""The observer's gain K [1/s]: the external torque through a lag of 1 / K = 10 ms."""
MAX_GAP_S = 0.05
"""[s] A longer gap between joint states restarts the observers from the quasi-static estimate."""
LEGS = len(LEG_NAMES)
NO_ROTATION = (0.0, 0.0, 0.0)


class _LegState:
    """One leg's observer between joint states."""

    __slots__ = ("driving", "momentum", "residual", "stamp_s")

    def __init__(self) -> None:
        self.stamp_s = math.nan
        self.momentum = [0.0, 0.0, 0.0]  # p [N m s]
        self.driving = [0.0, 0.0, 0.0]  # s = tau - beta [N m]
        self.residual = [0.0, 0.0, 0.0]  # r [N m]

    def update(
        self, stamp_s: float, momentum: Sequence[float], driving: Sequence[float], gain: float,
        max_gap_s: float,
    ) -> list[float]:  # fmt: skip
        """The residual [N m] after a joint state at ``stamp_s`` [s] with momentum ``p`` and
        ``s = tau - beta``.
        """
        dt = stamp_s - self.stamp_s
        if dt <= 0.0:  # the same stamp, or older: hold
            return self.residual
        if dt <= max_gap_s:  # NaN (the first) is neither
            keep = math.exp(-gain * dt)
            self.residual = [
                keep * r + (1.0 - keep) * ((p - p0) / dt - s)
                for r, p, p0, s, s0 in zip(
                    self.residual, momentum, self.momentum, driving, self.driving, strict=True
                )
            ]
        else:  # quasi-static: dp/dt = 0
            self.residual = [-s for s in driving]
        self.stamp_s, self.momentum, self.driving = stamp_s, list(momentum), list(driving)
        return self.residual


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
        self._states = [_LegState() for _ in range(LEGS)]

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
        Per leg its force [N] (NaN when none), whether its values are missing, whether its
        Jacobian is near singular.
        """
        angles, rates, efforts = sample
        out = [[math.nan] * 3 for _ in range(LEGS)]
        missing, singular = [True] * LEGS, [False] * LEGS
        felt = gravity if specific_force is None else [-f for f in specific_force]
        omega = NO_ROTATION if angular_velocity is None else angular_velocity
        if not all(math.isfinite(v) for v in (*gravity, *felt, *omega)):
            self.reset()
            return out, missing, singular
        cos, sin, isfinite = math.cos, math.sin, math.isfinite
        for slot in range(LEGS):
            joints = slice(slot * JOINTS_PER_LEG, (slot + 1) * JOINTS_PER_LEG)
            q, dq, tau = angles[joints], rates[joints], efforts[joints]
            if not all(isfinite(v) for v in (*q, *tau)):
                self._states[slot] = _LegState()
                continue
            missing[slot] = False
            trig = (cos(q[0]), sin(q[0]), cos(q[1]), sin(q[1]), cos(q[2]), sin(q[2]))
            g0, g1, g2 = self._statics[slot].gravity_torques(*trig, *felt)
            if all(isfinite(v) for v in dq):
                dtdq0, dtdq1, dtdq2, *momentum = self._dynamics[slot].kinetic_terms(
                    *trig, *dq, *omega
                )
                driving = (tau[0] - g0 + dtdq0, tau[1] - g1 + dtdq1, tau[2] - g2 + dtdq2)
                residual = self._states[slot].update(
                    stamp_s, momentum, driving, self.gain_per_s, self.max_gap_s
                )
                if not all(isfinite(v) for v in residual):  # absurd values: start again
                    self._states[slot] = _LegState()
            else:  # no rates: the quasi-static estimate
                self._states[slot] = _LegState()
                residual = [g0 - tau[0], g1 - tau[1], g2 - tau[2]]
            x, y, z, det, size = self._statics[slot].solve_torques(*trig, *residual, *gravity)
            singular[slot] = not abs(det) >= self.min_condition * size
            if not singular[slot]:
                out[slot] = [x / det, y / det, z / det]
        return out, missing, singular

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
