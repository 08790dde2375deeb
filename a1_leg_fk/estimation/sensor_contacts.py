"""Contacts from a Unitree robot's own foot sensors (``LowState.foot_force``: raw counts, FR, FL,
RR, RL), and how often an estimate agrees with them: on a real robot the only contact reference
there is.

The rule: a foot is in contact while its count is above the threshold. Unitree publishes no scale
for the counts; the default threshold, :data:`DEFAULT_SENSOR_THRESHOLD_COUNTS`, is the count a
controller run on real A1s takes as a foot touching down (ShuoYangRobotics/A1-QP-MPC-Controller,
``A1Params.h``: ``FOOT_FORCE_LOW 30.0``, its early-contact test ``foot_force > FOOT_FORCE_LOW``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from a1_leg_fk.model.legs import LEG_NAMES

DEFAULT_SENSOR_THRESHOLD_COUNTS = 30.0
"""[counts] A foot whose sensor reads more is in contact (see the module text for the source)."""


def sensor_contacts(
    counts: np.ndarray, threshold: float = DEFAULT_SENSOR_THRESHOLD_COUNTS
) -> np.ndarray:
    """(N, 4) bool contacts of (N, 4) sensor counts: above ``threshold`` [counts]; False where a
    count is NaN.
    """
    with np.errstate(invalid="ignore"):
        result: np.ndarray = counts > threshold
    return result


@dataclass
class SensorAgreement:
    """How often estimated contacts (probability > 0.5) agree with the sensors', per leg, over
    the leg samples where both exist.
    """

    threshold: float = DEFAULT_SENSOR_THRESHOLD_COUNTS
    agree: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=np.int64))
    compared: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=np.int64))

    def add(self, probabilities: np.ndarray, counts: np.ndarray) -> None:
        """Count rows of (N, 4) contact probabilities (NaN: none) and (N, 4) sensor counts."""
        both = np.isfinite(probabilities) & np.isfinite(counts)
        with np.errstate(invalid="ignore"):
            same = (probabilities > 0.5) == sensor_contacts(counts, self.threshold)
        self.agree += (same & both).sum(axis=0)
        self.compared += both.sum(axis=0)

    def line(self) -> str:
        """The summary's line."""
        if not self.compared.any():
            return "sensors:   no leg sample with both a contact estimate and a sensor count"
        total = 100.0 * self.agree.sum() / self.compared.sum()
        legs = ", ".join(
            f"{leg} {100.0 * a / c:.1f}" if c else f"{leg} -"
            for leg, a, c in zip(
                LEG_NAMES, self.agree.tolist(), self.compared.tolist(), strict=True
            )
        )
        return (
            f"sensors:   our contacts agree with the foot sensors' (count > {self.threshold:g}) "
            f"in {total:.1f} % of {int(self.compared.sum())} leg samples ({legs} %)"
        )
