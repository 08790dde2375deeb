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


SOLVE_EVERY = 8
"""A joint's least squares is solved once per this many samples learnt (its sums are kept every
sample): the estimate lags by at most 16 ms at 500 Hz, against a forgetting of seconds."""


def _shrunk(value: float, margin: float) -> float:
    """``value`` moved towards 0 by ``margin`` (>= 0), 0 within it."""
    if value > margin:
        return value - margin
    return value + margin if value < -margin else 0.0


class _Joint:
    """One joint's least squares in information form: ``info``, the regressors' information
    (symmetric 3x3 by its upper triangle, i00 i01 i02 i11 i12 i22, over the residual's noise
    variance, the prior's included) and ``moment``, the regressors times the residual [N m], both
    forgotten alike; from them the parameters ``theta`` (bias [N m], viscous [N m s/rad],
    Coulomb [N m]; unconstrained) and their covariance's ``diagonal``.
    """

    __slots__ = (
        "applied",
        "diagonal",
        "info",
        "moment",
        "pending",
        "squares",
        "theta",
        "variance",
    )

    def __init__(self, prior: Sequence[float], variance: float) -> None:
        self.info = [1.0 / prior[0], 0.0, 0.0, 1.0 / prior[1], 0.0, 1.0 / prior[2]]
        self.moment = [0.0, 0.0, 0.0]
        self.squares = [0.0, 0.0]
        """The residual's squares [N² m²] and the samples, forgotten alike (the fit's residual)."""
        self.pending = 0
        """Samples learnt since the last solution."""
        self.theta = (0.0, 0.0, 0.0)
        self.diagonal = tuple(prior)
        self.variance = variance
        """The residual's noise variance [N² m²] about the fit: the a priori errors' squares,
        averaged with forgetting from the prior ``noise_nm`` squared."""
        self.applied = (0.0, 0.0, 0.0)
        """The parameters taken off: each shrunk towards 0 by its significance margin."""


class ModelCorrections:
    """The twelve joints' corrections (slot order), learnt in swing and applied always."""

    def __init__(
        self,
        settings: CorrectionSettings | None = None,
        fixed: Sequence[tuple[float, float, float]] | None = None,
    ) -> None:
        """``fixed``: per joint (slot order) bias [N m], viscous [N m s/rad] and Coulomb [N m]
        as :attr:`parameters` gives them, taken off as they are and never learnt (a
        calibration's file); None: learnt online.
        """
        self.settings = settings or CorrectionSettings()
        self.fixed = fixed is not None
        noise = self.settings.noise_nm
        prior = [(bound / noise) ** 2 for bound in self.settings.bounds]
        self._prior_info = (1.0 / prior[0], 1.0 / prior[1], 1.0 / prior[2])
        """The prior's information per parameter (its variance over the noise's, inverted)."""
        self._joints = [_Joint(prior, noise**2) for _ in range(JOINT_COUNT)]
        self._latest: list[tuple[float, float] | None] = [None] * JOINT_COUNT
        """Per joint, the latest raw residual [N m] and rate [rad/s] (None: none)."""
        self.learnt_samples = 0
        """Joint samples the least squares took."""
        for state, (bias, viscous, coulomb) in zip(self._joints, fixed or (), strict=False):
            state.applied = (bias, -viscous, -coulomb)

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
        if self.fixed or not depths or not dt_s > 0.0:
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
        """One sample of ``joint`` into its least squares with forgetting ``forget`` (< 1; the
        prior's information is kept: what forgetting takes from it, each sample gives back),
        the residual's variance updated; solved every :data:`SOLVE_EVERY` samples. Written
        out: the per-sample path.
        """
        state = self._joints[joint]
        s = math.tanh(rate / self.settings.smooth_rate)  # the regressors: (1, rate, s)
        t0, t1, t2 = state.theta
        error = residual - (t0 + t1 * rate + t2 * s)
        state.variance = forget * state.variance + (1.0 - forget) * error * error
        i, m, keep = state.info, state.moment, 1.0 - forget
        p0, p1, p2 = self._prior_info
        state.info = [
            forget * i[0] + 1.0 + keep * p0,
            forget * i[1] + rate,
            forget * i[2] + s,
            forget * i[3] + rate * rate + keep * p1,
            forget * i[4] + rate * s,
            forget * i[5] + s * s + keep * p2,
        ]
        state.moment = [
            forget * m[0] + residual,
            forget * m[1] + rate * residual,
            forget * m[2] + s * residual,
        ]
        squares = state.squares
        state.squares = [forget * squares[0] + residual * residual, forget * squares[1] + 1.0]
        state.pending += 1
        if state.pending >= SOLVE_EVERY:
            self._solve(state)
        self.learnt_samples += 1

    def _solve(self, state: _Joint) -> None:
        """``state``'s parameters, their covariance's diagonal and the terms taken off, from its
        sums (the symmetric 3x3 inverted by cofactors; the prior keeps it positive definite).
        """
        a00, a01, a02, a11, a12, a22 = state.info
        c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
        c11, c12, c22 = a00 * a22 - a02 * a02, a01 * a02 - a00 * a12, a00 * a11 - a01 * a01
        scale = 1.0 / (a00 * c00 + a01 * c01 + a02 * c02)
        m0, m1, m2 = state.moment
        state.theta = (
            (c00 * m0 + c01 * m1 + c02 * m2) * scale,
            (c01 * m0 + c11 * m1 + c12 * m2) * scale,
            (c02 * m0 + c12 * m1 + c22 * m2) * scale,
        )
        state.diagonal = (c00 * scale, c11 * scale, c22 * scale)
        state.applied = self._applied(state.theta, state.diagonal, state.variance)
        state.pending = 0

    def _applied(
        self, theta: Sequence[float], diagonal: Sequence[float], variance: float
    ) -> tuple[float, float, float]:
        """The parameters taken off: each estimate shrunk towards 0 by ``significance`` of its
        standard deviation (the covariance's ``diagonal`` times the residual's ``variance``
        [N² m²]), so a term the data do not show stays 0, then held to its bound and its sign
        (friction opposes motion: viscous and Coulomb at most 0). The fit itself is left
        unconstrained: clipping it would break the least squares' covariance.
        """
        k, bounds = self.settings.significance, self.settings.bounds
        bias_bound, viscous_bound, coulomb_bound = bounds
        bias = _shrunk(theta[0], k * math.sqrt(diagonal[0] * variance))
        viscous = _shrunk(theta[1], k * math.sqrt(diagonal[1] * variance))
        coulomb = _shrunk(theta[2], k * math.sqrt(diagonal[2] * variance))
        return (
            min(bias_bound, max(-bias_bound, bias)),
            min(0.0, max(-viscous_bound, viscous)),
            min(0.0, max(-coulomb_bound, coulomb)),
        )

    @property
    def parameters(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order), the terms taken off: bias [N m], viscous [N m s/rad] and
        Coulomb [N m] friction as positive coefficients (the torque ``c(q̇) = bias - viscous q̇ -
        coulomb tanh(q̇/ε)``).
        """
        return [(j.applied[0], -j.applied[1], -j.applied[2]) for j in self._joints]

    def fit_residuals(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order): the swing samples learnt (forgotten alike), the residual's RMS
        [N m] in them before the fit and after it (the terms as fitted, before the shrinking).
        """
        out = []
        for state in self._joints:
            squares, samples = state.squares
            if not samples > 0.0:
                out.append((0.0, math.nan, math.nan))
                continue
            theta, moment = state.theta, state.moment
            a00, a01, a02, a11, a12, a22 = state.info
            p0, p1, p2 = self._prior_info  # the data's information alone
            info = ((a00 - p0, a01, a02), (a01, a11 - p1, a12), (a02, a12, a22 - p2))
            quadratic = sum(theta[i] * info[i][j] * theta[j] for i in range(3) for j in range(3))
            left = squares - 2.0 * sum(t * m for t, m in zip(theta, moment, strict=True))
            after = max(0.0, left + quadratic) / samples
            out.append((samples, math.sqrt(squares / samples), math.sqrt(after)))
        return out

    def terms_at(self, variances: Sequence[float]) -> list[tuple[float, float, float]]:
        """:attr:`parameters` with each joint's significance margin from ``variances`` [N² m²]
        (slot order) instead of the running estimate: a whole recording's fit judged by its own
        residual (:meth:`fit_residuals`).
        """
        out = []
        for state, variance in zip(self._joints, variances, strict=True):
            bias, viscous, coulomb = self._applied(state.theta, state.diagonal, variance)
            out.append((bias, -viscous, -coulomb))
        return out

    def solve(self) -> None:
        """Solve every joint's least squares now (the sums since the last solution taken in)."""
        for state in self._joints:
            if state.pending:
                self._solve(state)

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
        source = (
            "from a calibration's file"
            if self.fixed
            else f"online, learnt from {self.learnt_samples} joint samples in swing"
        )
        return (
            f"model corrections: {source}; per joint bias [N m], viscous [N m s/rad], "
            f"Coulomb [N m]: {legs}"
        )


def correction_values(corrections: ModelCorrections | None, refused: str = "") -> dict[str, str]:
    """The diagnostics' values of the corrections (None: off), for both nodes; ``refused``: why
    a calibration's file was refused ("" none).
    """
    out = {"model_corrections_refused": refused} if refused else {}
    if corrections is None:
        return {"model_corrections": OFF, **out}
    return {"model_corrections": "file" if corrections.fixed else ONLINE, **corrections.values()}
