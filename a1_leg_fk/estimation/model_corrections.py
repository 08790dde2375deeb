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
(time constant ``forget_s`` of learning time), left unconstrained (clipping a least squares'
estimate breaks its covariance: on the first strides of an exact robot, with the rate of one
sign, bias and Coulomb are collinear and a clipped viscous term drove them to their bounds).
What is taken off is each estimate shrunk towards 0 by ``significance`` standard deviations
(its covariance times the residual's variance about the fit, both learnt), then held to its bound
and sign: a term the data do not show is 0, so an exact robot's residual is left as it is.
It learns only while the foot is confidently in the air: the contact filter's probability of
stance below ``swing_probability`` and the foot higher than the filter's ``height_half_m``
above the lowest (the kinematic evidence agrees); it is frozen otherwise. ``c(q̇)`` is
subtracted from every residual, stance included (friction acts there too).
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
DEFAULT_MODEL_CORRECTIONS = ONLINE
"""Measured: the exact robots of the mismatch and contact families lose nothing (their terms
stay below significance), the mismatched ones gain up to 2.8 points (docs/forces.md)."""
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
    significance: float = 3.0

    def __post_init__(self) -> None:
        values = (
            self.swing_probability,
            self.smooth_rate,
            self.forget_s,
            self.noise_nm,
            self.significance,
        )
        if not all(math.isfinite(v) and v > 0.0 for v in (*values, *self.bounds)):
            raise LegFkError(f"model corrections need positive finite settings: {self}")


class _Joint:
    """One joint's least squares: the parameters ``theta`` (bias [N m], viscous [N m s/rad],
    Coulomb [N m]; unconstrained) and their covariance ``p`` (3x3, rows) over the residual's
    noise variance.
    """

    __slots__ = ("applied", "p", "theta", "variance")

    def __init__(self, prior: Sequence[float], variance: float) -> None:
        self.theta = [0.0] * PARAMETERS
        self.p = [[prior[i] if i == j else 0.0 for j in range(PARAMETERS)] for i in range(3)]
        self.variance = variance
        """The residual's noise variance [N² m²] about the fit: the a priori errors' squares,
        averaged with forgetting from the prior ``noise_nm`` squared."""
        self.applied = (0.0, 0.0, 0.0)
        """The parameters taken off: each shrunk towards 0 by its significance margin."""


class ModelCorrections:
    """The twelve joints' corrections (slot order), learnt in swing and applied always."""

    def __init__(self, settings: CorrectionSettings | None = None) -> None:
        self.settings = settings or CorrectionSettings()
        noise = self.settings.noise_nm
        self._prior = [(bound / noise) ** 2 for bound in self.settings.bounds]
        self._joints = [_Joint(self._prior, noise**2) for _ in range(JOINT_COUNT)]
        self._latest: list[tuple[float, float] | None] = [None] * JOINT_COUNT
        """Per joint, the latest raw residual [N m] and rate [rad/s] (None: none)."""
        self.learnt_samples = 0
        """Joint samples the least squares took."""

    def correct(self, joint: int, residual: float, rate: float) -> float:
        """The residual [N m] of slot ``joint`` with its correction at ``rate`` [rad/s] taken
        off; the raw one kept for :meth:`learn`.
        """
        self._latest[joint] = (residual, rate)
        bias, viscous, coulomb = self._joints[joint].applied
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
        covariance kept within the prior, the residual's variance and the terms taken off
        updated.
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
        state.variance = forget * state.variance + (1.0 - forget) * error * error
        state.applied = self._applied(theta, p, state.variance)
        self.learnt_samples += 1

    def _applied(
        self, theta: Sequence[float], p: Sequence[Sequence[float]], variance: float
    ) -> tuple[float, float, float]:
        """The parameters taken off: each estimate shrunk towards 0 by ``significance`` of its
        standard deviation (``p``'s diagonal times the residual's ``variance`` [N² m²]), so a
        term the data do not show stays 0, then held to its bound and its sign (friction
        opposes motion: viscous and Coulomb at most 0). The fit itself is left unconstrained:
        clipping it would break the least squares' covariance.
        """
        k, bounds = self.settings.significance, self.settings.bounds
        shrunk = [
            math.copysign(max(0.0, abs(theta[i]) - k * math.sqrt(p[i][i] * variance)), theta[i])
            for i in range(PARAMETERS)
        ]
        return (
            min(bounds[0], max(-bounds[0], shrunk[0])),
            min(0.0, max(-bounds[1], shrunk[1])),
            min(0.0, max(-bounds[2], shrunk[2])),
        )

    @property
    def parameters(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order), the terms taken off: bias [N m], viscous [N m s/rad] and
        Coulomb [N m] friction as positive coefficients (the torque ``c(q̇) = bias - viscous q̇ -
        coulomb tanh(q̇/ε)``).
        """
        return [(j.applied[0], -j.applied[1], -j.applied[2]) for j in self._joints]

    @property
    def fit(self) -> list[tuple[float, float, float]]:
        """Per joint, the least squares' estimates before the significance and the bounds, as
        :attr:`parameters` gives them.
        """
        return [(j.theta[0], -j.theta[1], -j.theta[2]) for j in self._joints]

    def values(self) -> dict[str, str]:
        """The terms taken off, per leg (``model_corrections_FR``...: its three joints'
        ``bias,viscous,coulomb`` [N m, N m s/rad, N m] joined by ``/``) and the joint samples
        learnt from: the diagnostics' values and the summary's line.
        """
        out = {"model_corrections_learnt_samples": str(self.learnt_samples)}
        terms = self.parameters
        for leg, name in enumerate(LEG_NAMES):
            joints = terms[leg * JOINTS_PER_LEG : (leg + 1) * JOINTS_PER_LEG]
            text = "/".join(f"{b + 0.0:+.2f},{v + 0.0:.2f},{c + 0.0:.2f}" for b, v, c in joints)
            out[f"model_corrections_{name}"] = text
        return out

    def line(self) -> str:
        """The corrections in words (the bag tools' summaries)."""
        values = self.values()
        legs = "; ".join(f"{name} {values[f'model_corrections_{name}']}" for name in LEG_NAMES)
        return (
            f"model corrections: online, learnt from {self.learnt_samples} joint samples in "
            f"swing; per joint bias [N m], viscous [N m s/rad], Coulomb [N m]: {legs}"
        )


def correction_values(corrections: ModelCorrections | None) -> dict[str, str]:
    """The diagnostics' values of the corrections (None: off), for both nodes."""
    if corrections is None:
        return {"model_corrections": OFF}
    return {"model_corrections": ONLINE, **corrections.values()}
