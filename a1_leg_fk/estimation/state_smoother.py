"""The state filter's estimate given the whole recording: a Rauch-Tung-Striebel pass backward
over the steps the filter recorded (:class:`~a1_leg_fk.estimation.filter_history.FilterHistory`).

The filter, step ``k``: from its filtered state ``x_k`` (covariance ``P_k``) it predicts
``x⁻_{k+1}`` (``P⁻_{k+1} = F_k P_k F_kᵀ + Q_k``), then its updates correct that into
``x_{k+1}``. The smoothed state is kept as an error ``δˢ_k`` on the filtered one,
``xˢ_k = x_k ⊕ δˢ_k`` (orientation ``R_k Exp(δθ)``, the rest added). Backward, from
``δˢ_n = 0``, ``Pˢ_n = P_n`` at the window's last state:

- ``G_k = P_k F_kᵀ (P⁻_{k+1})⁻¹`` (batched solves over a chunk of steps);
- the smoothed state at ``k + 1`` as an error on the *prediction*:
  ``Δ_{k+1} + δˢ_{k+1}``, with ``Δ_{k+1} = x_{k+1} ⊖ x⁻_{k+1}`` (what the updates injected;
  ``Log(R⁻ᵀ R)`` for the orientation, composed to first order);
- ``δˢ_k = G_k (Δ_{k+1} + δˢ_{k+1})`` (the filtered error's mean at ``k`` is zero) and
  ``Pˢ_k = P_k + G_k (Pˢ_{k+1} - P⁻_{k+1}) G_kᵀ``.

The linearisation is the filter's own (its ``F`` at its nominal states), as in the
error-state RTS of Särkkä (Bayesian Filtering and Smoothing, 2013, ch. 8) on a manifold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from a1_leg_fk.estimation.filter_history import STATE, FilterHistory, transitions_of
from a1_leg_fk.estimation.so3 import exp_so3_batch, log_so3_batch

CHUNK = 512
"""Steps whose gains are solved in one batch (memory: about 5 kB a step)."""


@dataclass(frozen=True)
class SmoothedStates:
    """The smoothed states of a window's first steps: ``rotations`` (N, 3, 3) base -> world,
    ``nominals`` (N, 12: velocity [m/s], position [m], gyro bias [rad/s], accelerometer bias
    [m/s²], odom frame) and ``covariances`` (N, 15, 15) of the error state.
    """

    rotations: np.ndarray
    nominals: np.ndarray
    covariances: np.ndarray


def smooth(
    history: FilterHistory,
    end: tuple[np.ndarray, np.ndarray, np.ndarray],
    emit: int,
) -> SmoothedStates:
    """The smoothed states of the first ``emit`` recorded steps (``emit <= history.count``),
    given the filter's state after the last one, ``end`` (rotation, nominal, covariance: taken as
    smoothed). The covariances are written over the history's filtered ones of those steps
    (returned as views: read them before the history records or drops again).
    """
    count = history.count
    rotations = history.rotations[:count]
    nominals = history.nominals[:count]
    covariances = history.covariances[:count]
    next_rotations = np.concatenate([rotations[1:], end[0][None]])
    next_nominals = np.concatenate([nominals[1:], end[1][None]])
    injected = np.empty((count, STATE))
    predicted = history.predicted_rotations[:count]
    injected[:, 0:3] = log_so3_batch(np.einsum("nji,njk->nik", predicted, next_rotations))
    injected[:, 3:] = next_nominals - history.predicted_nominals[:count]
    errors = np.zeros((emit, STATE))
    error = np.zeros(STATE)
    covariance = end[2]
    for first in range(((count - 1) // CHUNK) * CHUNK, -1, -CHUNK):
        last = min(first + CHUNK, count)
        gains, predictions = _gains(history, first, last)
        for row in range(last - 1, first - 1, -1):
            gain = gains[row - first]
            error = gain.dot(injected[row] + error)
            filtered = covariances[row]
            covariance = filtered + gain.dot(covariance - predictions[row - first]).dot(gain.T)
            if row < emit:
                errors[row] = error
                filtered[...] = covariance
    return SmoothedStates(
        rotations[:emit] @ exp_so3_batch(errors[:, 0:3]),
        nominals[:emit] + errors[:, 3:],
        covariances[:emit],
    )


def _gains(history: FilterHistory, first: int, last: int) -> tuple[np.ndarray, np.ndarray]:
    """The gains ``G_k`` and predicted covariances ``P⁻_{k+1}`` of steps ``first:last``."""
    transitions = transitions_of(history.transitions[first:last])
    filtered = history.covariances[first:last]
    spread = transitions @ filtered
    predictions = spread @ transitions.transpose(0, 2, 1)
    steps = -history.transitions[first:last, 0, 9]
    diagonal = np.arange(STATE)
    predictions[:, diagonal, diagonal] += steps[:, None] * history.noise_density
    gains = np.linalg.solve(predictions, spread).transpose(0, 2, 1)
    return gains, predictions
