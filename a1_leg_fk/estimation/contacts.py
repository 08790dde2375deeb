"""Which feet are on the ground: a contact probability per foot from its normal force, with
hysteresis, without ROS. The node and the bag tools share :class:`ContactRule`.

A foot's normal force [N] is the part of the ground's force on it (see
:mod:`a1_leg_fk.kinematics.foot_forces`) along minus gravity: positive when the ground pushes it
up. A foot in the air goes to *stance* when its normal force reaches ``touchdown_n``; a foot in
stance goes back to *swing* when it falls below ``liftoff_n`` (lower). Both default to shares of
the robot's weight (its total URDF mass times g), so robots of any size work untuned; thresholds
low enough to see the first newtons of a touchdown ramp, as the load moves between feet gradually.

The contact *probability* (0..1) is >= 0.5 exactly in stance: in swing it rises as ``0.5 N /
touchdown`` towards the touchdown threshold, in stance it is ``0.5 + 0.5 (N - liftoff) /
(touchdown - liftoff)``, clipped to 1. A NaN force (no estimate) leaves the state as it was and
gives a NaN probability.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

TOUCHDOWN_SHARE = 0.08
"""Default touchdown threshold as a share of the robot's weight (9.8 N on the 12.5 kg A1): above
the 5-8 % of the weight that a quick swing (3 Hz) puts on the quasi-static estimate by the leg's
own inertia, which the estimate does not model."""
LIFTOFF_SHARE = 0.04
"""Default liftoff threshold as a share of the robot's weight (4.9 N on the A1)."""
LEGS = len(LEG_NAMES)


@dataclass(frozen=True)
class ContactThresholds:
    """Normal forces [N]: a foot touches down at ``touchdown_n`` and lifts off below
    ``liftoff_n``.
    """

    touchdown_n: float
    liftoff_n: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.touchdown_n) and math.isfinite(self.liftoff_n)):
            raise LegFkError(f"contact thresholds must be finite, got {self}")
        if not 0.0 < self.liftoff_n <= self.touchdown_n:
            raise LegFkError(
                f"contact thresholds need 0 < liftoff ({self.liftoff_n} N) <= touchdown "
                f"({self.touchdown_n} N)"
            )

    @classmethod
    def for_weight(
        cls, weight_n: float, touchdown_n: float | None = None, liftoff_n: float | None = None
    ) -> ContactThresholds:
        """The defaults for a robot of ``weight_n`` [N] (:data:`TOUCHDOWN_SHARE`,
        :data:`LIFTOFF_SHARE`), each replaced by the given value [N] if not ``None``.
        """
        touchdown = TOUCHDOWN_SHARE * weight_n if touchdown_n is None else touchdown_n
        liftoff = LIFTOFF_SHARE * weight_n if liftoff_n is None else liftoff_n
        return cls(touchdown, min(liftoff, touchdown) if liftoff_n is None else liftoff)


def normal_forces(forces: ArrayLike, gravity_base: ArrayLike) -> np.ndarray:
    """(N, 4) normal forces [N] along minus gravity for (N, 4, 3) foot forces [N] and gravity
    (3,) or (N, 3) [m/s^2], both in the base frame; NaN where a force is NaN.
    """
    force = np.asarray(forces, dtype=np.float64)
    gravity = np.broadcast_to(np.asarray(gravity_base, dtype=np.float64), (force.shape[0], 3))
    up = -gravity / np.linalg.norm(gravity, axis=1, keepdims=True)
    normal: np.ndarray = np.einsum("nli,ni->nl", force, up)
    return normal


class ContactRule:
    """The hysteresis of each foot, carried from one call to the next (a stream, or a recording
    read in blocks). Every foot starts in swing.
    """

    def __init__(self, thresholds: ContactThresholds) -> None:
        self.thresholds = thresholds
        self.stance = np.zeros(LEGS, dtype=bool)
        """Each foot's state after the latest row: True in stance."""

    def update(self, normal: Sequence[float]) -> list[float]:
        """4 contact probabilities for one row of 4 normal forces [N]: :meth:`update_batch` on
        floats, without numpy (the node's per-message path).
        """
        touchdown, liftoff = self.thresholds.touchdown_n, self.thresholds.liftoff_n
        span = max(touchdown - liftoff, 1e-12)
        stance = self.stance
        out = []
        for leg, force in enumerate(normal):
            if force >= touchdown:
                stance[leg] = True
            elif force < liftoff:
                stance[leg] = False
            if stance[leg]:
                share = 0.5 + 0.5 * (force - liftoff) / span
            else:
                share = 0.5 * force / touchdown
            out.append(share if 0.0 <= share <= 1.0 else min(max(share, 0.0), 1.0))
        return out

    def update_batch(self, normal: ArrayLike) -> np.ndarray:
        """(N, 4) contact probabilities for (N, 4) normal forces [N], in time order."""
        force = np.asarray(normal, dtype=np.float64)
        if force.ndim != 2 or force.shape[1] != LEGS:
            raise LegFkError(f"normal forces must have shape (N, {LEGS}), got {force.shape}")
        touchdown, liftoff = self.thresholds.touchdown_n, self.thresholds.liftoff_n
        with np.errstate(invalid="ignore"):
            event = np.where(force >= touchdown, 1, np.where(force < liftoff, -1, 0))
        # each row's state is the latest event at or before it, else the state carried in
        rows = np.arange(force.shape[0])[:, None]
        latest = np.maximum.accumulate(np.where(event != 0, rows, -1), axis=0)
        taken = np.take_along_axis(event, np.maximum(latest, 0), axis=0)
        stance = np.where(latest >= 0, taken > 0, self.stance[None, :])
        if force.shape[0]:
            self.stance = stance[-1].copy()
        swing_share = 0.5 * force / touchdown
        stance_share = 0.5 + 0.5 * (force - liftoff) / max(touchdown - liftoff, 1e-12)
        probability: np.ndarray = np.clip(np.where(stance, stance_share, swing_share), 0.0, 1.0)
        return probability
