"""What the state filter (:mod:`a1_leg_fk.estimation.state_filter`) did, step by step, for the
smoother (:mod:`a1_leg_fk.estimation.state_smoother`): an optional hook, attached offline only
(the live node never has one), that copies at every propagation into preallocated numpy arrays.

- the filtered state the step starts from: its stamp [ns], rotation (base -> world), nominal
  velocity, position and biases (12) and covariance (15 x 15);
- the transition's rows that change (``F[0:6]``: dθ and dv; the rest is the identity but for
  ``dp/dv = dt I``, whose ``dt`` is ``-F[0, 9]``);
- the predicted state's rotation and nominal part (its covariance ``F P Fᵀ + Q dt`` is
  recomputed by the smoother: the process noise is diagonal).

Memory: 2.9 kB per step (a 10 s window at 1 kHz: 29 MB); the arrays grow by doubling to a
window's steps and are reused for the next window (:meth:`FilterHistory.drop`).
"""

from __future__ import annotations

import numpy as np

STATE = 15
NOMINAL = STATE - 3
"""The nominal state besides the rotation: velocity, position, gyro and accelerometer biases."""
FIELDS: tuple[tuple[str, tuple[int, ...], type], ...] = (
    ("stamps_ns", (), np.int64),
    ("rotations", (3, 3), np.float64),
    ("nominals", (NOMINAL,), np.float64),
    ("covariances", (STATE, STATE), np.float64),
    ("transitions", (6, STATE), np.float64),
    ("predicted_rotations", (3, 3), np.float64),
    ("predicted_nominals", (NOMINAL,), np.float64),
)
"""Each step's arrays: name, shape of one step's, type."""


class FilterHistory:
    """The steps recorded since the last :meth:`drop` (``count`` of them, the arrays' first
    rows), with ``first``: the index of the first over the whole run. ``noise_density``: the
    filter's process noise densities (15, per second).
    """

    def __init__(self, noise_density: np.ndarray, capacity: int = 1024) -> None:
        self.noise_density = noise_density
        self.first = 0
        self.count = 0
        self.stamps_ns = self.nominals = self.predicted_nominals = np.zeros(0)
        self.rotations = self.covariances = self.transitions = np.zeros(0)
        self.predicted_rotations = np.zeros(0)
        self._allocate(capacity)

    def _allocate(self, capacity: int) -> None:
        """Arrays for ``capacity`` steps, the recorded ones copied over."""
        for name, shape, dtype in FIELDS:
            array: np.ndarray = np.zeros((capacity, *shape), dtype=dtype)
            if self.count:
                array[: self.count] = getattr(self, name)[: self.count]
            setattr(self, name, array)

    @property
    def steps(self) -> int:
        """The steps recorded over the whole run."""
        return self.first + self.count

    def before(
        self, stamp_ns: int, rotation: np.ndarray, nominal: np.ndarray, covariance: np.ndarray
    ) -> None:
        """A step begins from this filtered state (stamp [ns], rotation, nominal, covariance)."""
        row = self.count
        if row == len(self.stamps_ns):
            self._allocate(2 * row)
        self.stamps_ns[row] = stamp_ns
        self.rotations[row] = rotation
        self.nominals[row] = nominal
        self.covariances[row] = covariance

    def after(self, transition: np.ndarray, rotation: np.ndarray, nominal: np.ndarray) -> None:
        """The step's transition and the predicted rotation and nominal state it led to."""
        row = self.count
        self.transitions[row] = transition[0:6]
        self.predicted_rotations[row] = rotation
        self.predicted_nominals[row] = nominal
        self.count = row + 1

    def span_s(self) -> float:
        """The time the recorded steps cover [s]."""
        return (
            0.0 if self.count < 2 else (self.stamps_ns[self.count - 1] - self.stamps_ns[0]) / 1e9
        )

    def drop(self, steps: int) -> None:
        """Forget the first ``steps`` recorded steps (the rest move to the arrays' start)."""
        kept = self.count - steps
        for name, _, _ in FIELDS:
            array = getattr(self, name)
            array[:kept] = array[steps : self.count]
        self.first += steps
        self.count = kept


def transitions_of(rows: np.ndarray) -> np.ndarray:
    """The full transitions (N, 15, 15) of their recorded rows ``F[0:6]`` (N, 6, 15)."""
    full = np.broadcast_to(np.eye(STATE), (len(rows), STATE, STATE)).copy()
    full[:, 0:6] = rows
    dt = -rows[:, 0, 9]
    for k in range(3):
        full[:, 6 + k, 3 + k] = dt
    return full
