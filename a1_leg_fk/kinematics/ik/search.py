"""Damped least squares on a leg's compiled FK and Jacobian (see
:mod:`a1_leg_fk.kinematics.ik.four_legs`): the solver of legs without a closed form, and the
nearest in-limit point search. No ROS.
"""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg

REACHED_M = 1e-9
"""The damped-least-squares solver counts a target as reached within this distance [m]."""
MAX_ITERATIONS = 60
"""Iterations of one damped-least-squares run (every start runs them at once, vectorised)."""
STALLED_ITERATIONS = 6
"""The search stops when its best distance has not improved for this many iterations."""
MAX_STEP_RAD = 0.3
"""The largest change of any joint angle in one least-squares step [rad] (a trust region)."""


def _positions(leg: CompiledLeg, angles: np.ndarray) -> np.ndarray:
    """(K, 3) feet [m] for (K, 3) angles [rad]."""
    return leg.positions_batch(np.cos(angles), np.sin(angles))


def _jacobians(leg: CompiledLeg, angles: np.ndarray) -> np.ndarray:
    """(K, 3, 3) d foot / d angles for (K, 3) angles [rad]."""
    return leg.jacobians_batch(np.cos(angles), np.sin(angles))


# A target 1e200 m away: squared distances overflow to inf.
@np.errstate(over="ignore", invalid="ignore")
def least_squares(
    leg: CompiledLeg, point: np.ndarray, starts: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[np.ndarray, float]:
    """Minimise |FK(q) - point| over ``lower <= q <= upper`` from every start at once.

    Damped Newton steps on ``0.5 |FK(q) - point|^2``: the Hessian is ``J^T J`` plus the residual
    times the FK's second derivatives (central differences of the Jacobian), so a target out of
    reach (a large residual) converges as fast as one in reach. A joint at a bound that the
    gradient pushes outward is held; the damping grows until a step lowers the cost. At most
    :data:`MAX_ITERATIONS` iterations. Returns the best angles [rad] and their distance [m].
    """
    q = np.clip(starts, lower, upper)
    error = _positions(leg, q) - point
    cost = np.einsum("ki,ki->k", error, error)
    damping = np.full(q.shape[0], 1e-4)
    identity = np.eye(3)
    previous_best, stalled = cost.min(), 0
    for _ in range(MAX_ITERATIONS):
        jacobian, curvature = _jacobian_and_curvature(leg, q, error)
        gradient = np.einsum("kij,ki->kj", jacobian, error)
        held = ((q <= lower) & (gradient > 0.0)) | ((q >= upper) & (gradient < 0.0))
        free = ~held
        hessian = np.einsum("kij,kil->kjl", jacobian, jacobian) + curvature
        mask = free[:, :, np.newaxis] & free[:, np.newaxis, :]
        hessian = np.where(mask, hessian, 0.0) + held[:, :, np.newaxis] * identity
        system = hessian + damping[:, np.newaxis, np.newaxis] * identity
        try:
            step = -np.linalg.solve(system, (gradient * free)[:, :, np.newaxis])[:, :, 0]
        except np.linalg.LinAlgError:
            # A singular system (vanishingly rare): more damping, try again.
            damping = damping * 8.0
            continue
        step *= np.minimum(1.0, MAX_STEP_RAD / np.maximum(np.abs(step).max(axis=1), 1e-300))[
            :, np.newaxis
        ]
        trial = np.clip(q + step, lower, upper)
        trial_error = _positions(leg, trial) - point
        trial_cost = np.einsum("ki,ki->k", trial_error, trial_error)
        better = trial_cost < cost
        moved = np.abs(trial - q).max(axis=1)
        q = np.where(better[:, np.newaxis], trial, q)
        error = np.where(better[:, np.newaxis], trial_error, error)
        cost = np.where(better, trial_cost, cost)
        damping = np.where(
            better, np.maximum(damping / 4.0, 1e-12), np.minimum(damping * 8.0, 1e12)
        )
        if np.all((moved < 1e-12) | (damping >= 1e6)) or cost.min() <= (REACHED_M * 1e-3) ** 2:
            break
        best_cost = cost.min()
        stalled = stalled + 1 if best_cost >= previous_best * (1.0 - 1e-12) else 0
        if stalled >= STALLED_ITERATIONS:
            break
        previous_best = best_cost
    best = int(np.argmin(cost))
    # Not sqrt(cost): no overflow for far targets.
    return q[best], math.hypot(*error[best].tolist())


def _jacobian_and_curvature(
    leg: CompiledLeg, q: np.ndarray, error: np.ndarray, step: float = 1e-6
) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3, 3) Jacobians at (K, 3) angles [rad], and (K, 3, 3) sum over axes i of
    ``error_i d^2 FK_i / dq_j dq_l`` by central differences of the Jacobian (one batched call).
    """
    rows = q.shape[0]
    shifts = np.concatenate([np.zeros((1, 3)), step * np.eye(3), -step * np.eye(3)])
    jacobians = _jacobians(leg, (q[np.newaxis] + shifts[:, np.newaxis]).reshape(-1, 3)).reshape(
        7, rows, 3, 3
    )
    derivatives = (jacobians[1:4] - jacobians[4:7]) / (2.0 * step)  # (joint, K, axis, column)
    curvature = np.einsum("ki,jkil->klj", error, derivatives)
    return jacobians[0], (curvature + curvature.transpose(0, 2, 1)) / 2.0
