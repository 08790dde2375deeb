"""Online corrections of the legs' model: per joint, the torque the URDF does not explain (a bias,
viscous and Coulomb friction), learnt while a foot is in the air, subtracted from the momentum
observer's residual before it becomes a foot force; without ROS, plain floats per sample.

A real leg is not its URDF: its joints have friction, its links carry cables and rotors, its
effort comes from a motor current. In swing the ground exerts nothing, so the observer's residual
``r`` [N m] (:mod:`a1_leg_fk.estimation.momentum_observer`, ``J^T F = r``) is the model's error
alone. Per joint it is fitted as

    r ≈ c(q̇) = bias + viscous q̇ + coulomb tanh(q̇ / ε)

(friction opposes motion: ``viscous`` [N m s/rad] and ``coulomb`` [N m] are at most 0; ``ε``
[rad/s] the smooth sign's width) by recursive least squares with exponential forgetting
(time constant ``forget_s`` of learning time), each parameter kept within its bound. It learns
only while the foot is confidently in the air: the contact filter's probability of stance below
``swing_probability`` and the foot higher than the filter's ``height_half_m`` above the lowest
(the kinematic evidence agrees); it is frozen otherwise. ``c(q̇)`` is subtracted from every
residual, stance included (friction acts there too).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

ONLINE, OFF = "online", "off"
MODEL_CORRECTIONS = (ONLINE, OFF)
"""``model_corrections`` of the nodes, ``--corrections`` of the bag tools."""
PARAMETERS = 3
"""Per joint: bias [N m], viscous [N m s/rad], Coulomb [N m]."""


@dataclass(frozen=True)
class CorrectionSettings:
    """The corrections' settings (one place): ``swing_probability``, the contact filter's
    probability of stance below which a foot is in swing (with its height); ``smooth_rate``
    [rad/s], the width ε of the smooth sign; ``forget_s`` [s], the forgetting's time constant
    (of learning time); ``bounds``, the largest |bias| [N m], |viscous| [N m s/rad] and
    |coulomb| [N m]; ``noise_nm`` [N m], the residual's noise, which sets how much the first
    samples move the estimate (the prior is the bounds, as standard deviations).
    """

    swing_probability: float = 0.05
    smooth_rate: float = 0.1
    forget_s: float = 10.0
    bounds: tuple[float, float, float] = (3.0, 0.5, 1.5)
    noise_nm: float = 0.5

    def __post_init__(self) -> None:
        values = (self.swing_probability, self.smooth_rate, self.forget_s, self.noise_nm)
        if not all(math.isfinite(v) and v > 0.0 for v in (*values, *self.bounds)):
            raise LegFkError(f"model corrections need positive finite settings: {self}")


class _Joint:
    """One joint's least squares: the parameters ``theta`` (bias [N m], viscous [N m s/rad],
    Coulomb [N m]) and their covariance ``p`` (3x3, rows) over the residual's noise variance.
    """

    __slots__ = ("p", "theta")

    def __init__(self, prior: Sequence[float]) -> None:
        self.theta = [0.0] * PARAMETERS
        self.p = [[prior[i] if i == j else 0.0 for j in range(PARAMETERS)] for i in range(3)]


class ModelCorrections:
    """The twelve joints' corrections (slot order), learnt in swing and applied always."""

    def __init__(self, settings: CorrectionSettings | None = None) -> None:
        self.settings = settings or CorrectionSettings()
        noise = self.settings.noise_nm
        self._prior = [(bound / noise) ** 2 for bound in self.settings.bounds]
        self._joints = [_Joint(self._prior) for _ in range(JOINT_COUNT)]
        self._latest: list[tuple[float, float] | None] = [None] * JOINT_COUNT
        """Per joint, the latest raw residual [N m] and rate [rad/s] (None: none)."""
        self.learnt_samples = 0
        """Joint samples the least squares took."""

    def correct(self, joint: int, residual: float, rate: float) -> float:
        """The residual [N m] of slot ``joint`` with its correction at ``rate`` [rad/s] taken
        off; the raw one kept for :meth:`learn`.
        """
        self._latest[joint] = (residual, rate)
        bias, viscous, coulomb = self._joints[joint].theta
        return residual - (
            bias + viscous * rate + coulomb * math.tanh(rate / self.settings.smooth_rate)
        )

    def learn(
        self,
        dt_s: float,
        probabilities: Sequence[float],
        feet: Sequence[FootMotion | None],
        height_half_m: float,
    ) -> None:
        """Learn from the latest residuals of the legs confidently in the air: ``probabilities``
        of stance (the contact filter's, this sample) below ``swing_probability`` and the foot
        (``feet``' motions, None: unknown) more than ``height_half_m`` [m] above the lowest.
        ``dt_s`` [s] since the previous sample sets the forgetting.
        """
        depths = [foot.depth for foot in feet if foot is not None]
        if not depths or not dt_s > 0.0:
            return
        lowest = max(depths)
        forget = math.exp(-min(dt_s, 1.0) / self.settings.forget_s)
        for leg, foot in enumerate(feet):
            if foot is None or not probabilities[leg] < self.settings.swing_probability:
                continue
            if not lowest - foot.depth > height_half_m:
                continue
            for joint in range(leg * JOINTS_PER_LEG, (leg + 1) * JOINTS_PER_LEG):
                latest = self._latest[joint]
                if latest is not None and math.isfinite(latest[0] + latest[1]):
                    self._update(joint, latest[0], latest[1], forget)
                self._latest[joint] = None

    def _update(self, joint: int, residual: float, rate: float, forget: float) -> None:
        """One recursive least-squares step of ``joint`` with forgetting ``forget`` (< 1): the
        parameters kept within the bounds, the covariance within the prior.
        """
        state, settings = self._joints[joint], self.settings
        phi = (1.0, rate, math.tanh(rate / settings.smooth_rate))
        p, theta = state.p, state.theta
        pphi = [p[i][0] * phi[0] + p[i][1] * phi[1] + p[i][2] * phi[2] for i in range(3)]
        gain_denominator = forget + phi[0] * pphi[0] + phi[1] * pphi[1] + phi[2] * pphi[2]
        gain = [value / gain_denominator for value in pphi]
        error = residual - (theta[0] * phi[0] + theta[1] * phi[1] + theta[2] * phi[2])
        for i in range(3):
            theta[i] += gain[i] * error
            for j in range(3):
                p[i][j] = (p[i][j] - gain[i] * pphi[j]) / forget
        for i in range(3):  # the covariance never grows past the prior (no wind-up)
            if p[i][i] > self._prior[i]:
                scale = math.sqrt(self._prior[i] / p[i][i])
                for j in range(3):
                    p[i][j] *= scale
                    p[j][i] *= scale
        bias, viscous, coulomb = settings.bounds
        theta[0] = min(bias, max(-bias, theta[0]))
        theta[1] = min(0.0, max(-viscous, theta[1]))
        theta[2] = min(0.0, max(-coulomb, theta[2]))
        self.learnt_samples += 1

    @property
    def parameters(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order): bias [N m], viscous [N m s/rad] and Coulomb [N m] friction as
        positive coefficients (the torque ``c(q̇) = bias - viscous q̇ - coulomb tanh(q̇/ε)``).
        """
        return [(j.theta[0], -j.theta[1], -j.theta[2]) for j in self._joints]

    def line(self) -> str:
        """The corrections in words, per leg the mean over its joints (summaries, diagnostics)."""
        parts = []
        values = self.parameters
        for leg, name in enumerate(LEG_NAMES):
            joints = values[leg * JOINTS_PER_LEG : (leg + 1) * JOINTS_PER_LEG]
            text = "/".join(f"{b:+.2f},{v:.2f},{c:.2f}" for b, v, c in joints)
            parts.append(f"{name} {text}")
        return (
            f"model corrections: online, learnt from {self.learnt_samples} joint samples in "
            f"swing; per joint bias [N m], viscous [N m s/rad], Coulomb [N m]: " + "; ".join(parts)
        )
