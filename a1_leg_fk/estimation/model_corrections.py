"""Online corrections of the legs' model: per joint, the torque the URDF does not explain (a bias,
viscous and Coulomb friction), learnt while a foot is in the air, subtracted from the momentum
observer's residual before it becomes a foot force; without ROS, plain floats per sample.

A real leg is not its URDF: its joints have friction, its links carry cables and rotors, its
effort comes from a motor current. In swing the ground exerts nothing, so the observer's residual
``r`` [N m] (:mod:`a1_leg_fk.estimation.momentum_observer`, ``J^T F = r``) is the model's error
alone. Per joint it is fitted as

    r ≈ c(q̇) = bias + viscous q̇ + coulomb tanh(q̇ / ε)

(friction opposes motion: ``viscous`` [N m s/rad] and ``coulomb`` [N m] are at most 0; ``ε``
[rad/s] the smooth sign's width) by least squares with exponential forgetting (time constant
``forget_s`` of learning time; the samples kept as they come and taken in by :data:`BATCH`,
vectorized), left unconstrained (clipping a least squares'
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

import numpy as np

from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.leg_scales import LegScales
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
    samples move the estimate (the prior is the bounds, as standard deviations);
    ``scale_bound``, the largest ``|1 - a|`` of a leg's inertia scale ``a``
    (:mod:`a1_leg_fk.estimation.leg_scales`) and ``scale_significance``, its shrinking in
    standard deviations; ``learn_scales``, whether those scales are learnt (else 1, or a file's).
    """

    swing_probability: float = 0.05
    smooth_rate: float = 0.1
    forget_s: float = 10.0
    bounds: tuple[float, float, float] = (3.0, 0.5, 1.5)
    noise_nm: float = 0.5
    significance: float = 3.0
    scale_bound: float = 0.5
    scale_significance: float = 1.0
    """Tuned on the mismatch family's tuned runs (docs/forces.md): at 3 (the friction's) the
    light legs keep 1.20 % of their swing samples called stance, at 1 0.92 %."""
    learn_scales: bool = False
    """Off online: learnt live, the scales took the tuned light legs to 99.02 % but cost both
    held-out runs (a1_trot_turn+everything 97.84 -> 97.18 %, go2_walk+payload_scale 99.63 ->
    99.52 %: late efforts read as a scale), so they are fitted by ``calibrate`` (on: its
    settings) and given in its file (docs/forces.md)."""

    def __post_init__(self) -> None:
        values = (
            self.swing_probability,
            self.smooth_rate,
            self.forget_s,
            self.noise_nm,
            self.significance,
            self.scale_bound,
            self.scale_significance,
        )
        if not all(math.isfinite(v) and v > 0.0 for v in (*values, *self.bounds)):
            raise LegFkError(f"model corrections need positive finite settings: {self}")


BATCH = (24, 512)
"""Joint samples kept as they come (by leg: :data:`KEPT`) before they are taken into the twelve
least squares at once (numpy) and the joints that learnt solved: an eighth of the samples learnt
so far, within these bounds, so the first strides are solved as often as one by one (every ~8
samples of a joint) and a long run every ~0.2-0.35 s of a trot at 500 Hz, against a forgetting of
seconds. Taken one by one (the first way written) the least squares cost about twice as much per
sample (bench/contact_speed.py)."""
KEPT = 2 * JOINTS_PER_LEG + 2
"""Floats kept per leg sample: its joints' residuals [N m] and rates [rad/s] (r0, q̇0, r1, ...),
the leg's slot and the sample's step [s] (its joints' finiteness and learning clocks are found
in the batch)."""
NONE = (math.nan,) * (2 * JOINTS_PER_LEG)
"""A leg's latest residuals and rates when none came (not finite: not learnt)."""
INFO = [0, 1, 2, 1, 3, 4, 2, 4, 5]
"""The regressors' information (3x3) from a joint's sums (:class:`ModelCorrections`)."""
ZERO_TERMS = (0.0, 0.0, 0.0)
JOINT_SLOTS = np.arange(JOINT_COUNT)


def _shrunk(value: np.ndarray, margin: np.ndarray) -> np.ndarray:
    """``value`` moved towards 0 by ``margin`` (>= 0), 0 within it (elementwise)."""
    result: np.ndarray = np.sign(value) * np.maximum(np.abs(value) - margin, 0.0)
    return result


class ModelCorrections:
    """The twelve joints' corrections (slot order), learnt in swing and applied always.

    Each joint's least squares is kept in information form, the prior's information apart (what
    forgetting takes from it, each sample gives back, so it stays): the data's sums ``_sums``
    (12, 10), forgotten alike: of the regressors' products (1, q̇, s: 1, q̇, s, q̇², q̇ s, s²; the
    first is the samples' count), of the regressors times the residual r [N m] (r, q̇ r, s r) and
    of r²; ``_theta`` the parameters (bias [N m], viscous [N m s/rad], Coulomb
    [N m]; unconstrained), ``_diagonal`` their covariance's diagonal (over the noise variance),
    ``_variance`` [N² m²] the residual's about the fit (its a priori errors' squares averaged with
    forgetting from ``noise_nm`` squared), ``_applied`` the terms taken off.
    """

    def __init__(
        self,
        settings: CorrectionSettings | None = None,
        fixed: Sequence[tuple[float, float, float]] | None = None,
        scales: Sequence[float] | None = None,
    ) -> None:
        """``fixed``: per joint (slot order) bias [N m], viscous [N m s/rad] and Coulomb [N m]
        as :attr:`parameters` gives them, taken off as they are and never learnt (a
        calibration's file), with ``scales``, per leg its inertia scale (None: 1); None: learnt
        online.
        """
        self.settings = settings or CorrectionSettings()
        self.fixed = fixed is not None
        noise = self.settings.noise_nm
        learnt = self.settings.learn_scales and not self.fixed
        given = None if learnt else (scales or [1.0] * len(LEG_NAMES))
        settings = self.settings
        scale = (settings.scale_bound, settings.scale_significance)
        self.scales = LegScales(settings.forget_s, noise, *scale, given, settings.smooth_rate)
        """Each leg's inertia scale, learnt when its joints learn."""
        self._prior = np.array([(bound / noise) ** 2 for bound in self.settings.bounds])
        """The prior's variance per parameter, over the noise's."""
        self._prior_information = np.diag(1.0 / self._prior)
        """Its information (3x3, diagonal), added to each joint's."""
        self._sums = np.zeros((JOINT_COUNT, 10))
        self._theta = np.zeros((JOINT_COUNT, PARAMETERS))
        self._diagonal = np.tile(self._prior, (JOINT_COUNT, 1))
        self._variance = np.full(JOINT_COUNT, noise**2)
        self._applied = [ZERO_TERMS] * JOINT_COUNT
        self._latest = list(NONE * len(LEG_NAMES))
        """Per joint, the latest raw residual [N m] and rate [rad/s], flat (NaN: none)."""
        self._kept: list[float] = []
        """The leg samples not yet taken in, :data:`KEPT` floats each."""
        self._clock = np.zeros(JOINT_COUNT)
        """Per joint, its learning time [s]: the sum of its samples' steps (forgetting's time),
        up to the samples taken in."""
        self._taken = np.zeros(JOINT_COUNT)
        """Per joint, its learning clock when the sums were last taken in [s]."""
        self.learnt_samples = 0
        """Joint samples the least squares took (kept or taken in)."""
        self._taken_samples = 0
        """Joint samples taken into the sums."""
        self._due = BATCH[0]
        """:attr:`learnt_samples` at which the kept are taken in: :data:`BATCH`'s rule."""
        for joint, (bias, viscous, coulomb) in enumerate(fixed or ()):
            self._applied[joint] = (bias, -viscous, -coulomb)

    def correct(self, joint: int, residual: float, rate: float) -> float:
        """The residual [N m] of slot ``joint`` with its correction at ``rate`` [rad/s] taken
        off; the raw one kept for :meth:`learn`.
        """
        latest, index = self._latest, 2 * joint
        latest[index], latest[index + 1] = residual, rate
        bias, viscous, coulomb = self._applied[joint]
        if coulomb == 0.0:
            return residual - (bias + viscous * rate)
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
        ``dt_s`` [s] since the previous sample sets the forgetting (of each learning joint).
        """
        depths = [foot.depth for foot in feet if foot is not None]
        if self.fixed or not depths or not dt_s > 0.0:
            return
        lowest, step = max(depths), min(dt_s, 1.0)
        latest, threshold = self._latest, self.settings.swing_probability
        kept, width = self._kept, 2 * JOINTS_PER_LEG
        for leg, foot in enumerate(feet):
            if foot is None or not probabilities[leg] < threshold:
                continue
            if not lowest - foot.depth > height_half_m:
                continue
            joints = self._applied[leg * JOINTS_PER_LEG : (leg + 1) * JOINTS_PER_LEG]
            self.scales.learn(leg, step, any(coulomb != 0.0 for _, _, coulomb in joints))
            first = leg * width
            sample = latest[first : first + width]
            latest[first : first + width] = NONE
            kept += sample
            kept += (leg, step)
            r0, q0, r1, q1, r2, q2 = sample
            if math.isfinite((r0 + q0) + (r1 + q1) + (r2 + q2)):  # only if each joint's is
                self.learnt_samples += JOINTS_PER_LEG
            else:
                pairs = zip(sample[::2], sample[1::2], strict=True)
                self.learnt_samples += sum(math.isfinite(r + q) for r, q in pairs)
        if self.learnt_samples >= self._due:
            self._take_in()

    def _take_in(self) -> None:
        """The samples kept into the sums, each weighted by the forgetting over its joint's
        learning time since (as if taken one by one: sums = f sums + sample, f = exp(-step /
        forget_s)), the a priori errors' squares into the variance alike; then every joint that
        learnt solved.
        """
        forget_s = self.settings.forget_s
        joint, (residual, rate), clock, step = self._samples()
        now = self._clock
        weight = np.exp((clock - now[joint]) / forget_s)
        sign = np.tanh(rate / self.settings.smooth_rate)
        theta = self._theta[joint]
        error = residual - (theta[:, 0] + theta[:, 1] * rate + theta[:, 2] * sign)
        wr, ws, wy = weight * rate, weight * sign, weight * residual
        keep = -np.expm1(-step / forget_s)  # 1 - f per sample
        columns = np.stack(
            [weight, wr, ws, wr * rate, wr * sign, ws * sign, wy, wy * rate, wy * sign,
             wy * residual, weight * keep * error * error],
        )  # fmt: skip
        learnt = joint[:, None] == JOINT_SLOTS
        sums = columns @ learnt  # (11, 12): per joint
        decay = np.exp((self._taken - now) / forget_s)
        self._taken = now
        self._sums = decay[:, None] * self._sums + sums[:10].T
        self._variance = decay * self._variance + sums[10]
        self._taken_samples += len(joint)
        least, most = BATCH
        self._due = self._taken_samples + min(most, max(least, self._taken_samples // 8))
        self._solve(learnt.any(axis=0))

    def _samples(self) -> tuple[np.ndarray, ...]:
        """The joint samples kept (the leg samples split, in order, the non-finite dropped):
        their joint slots, residuals [N m], rates [rad/s], joints' learning clocks after them
        and steps [s]; the kept cleared and the joints' clocks advanced (each the running sum of
        its steps in order, as one by one: np.cumsum adds in order, and a 0 adds nothing).
        """
        data = np.fromiter(self._kept, float, len(self._kept)).reshape(-1, KEPT)
        self._kept.clear()
        rows, legs, every = len(data), data[:, -2].astype(np.intp), np.arange(len(data))
        pairs = data[:, :-2].reshape(rows, JOINTS_PER_LEG, 2)  # per joint: r, q̇
        finite = np.isfinite(pairs[:, :, 0] + pairs[:, :, 1])  # (rows, 3)
        steps = np.where(finite, data[:, -1:], 0.0)
        table = np.zeros((rows + 1, len(LEG_NAMES), JOINTS_PER_LEG))  # a column per joint
        table[0], table[every + 1, legs] = self._clock.reshape(table[0].shape), steps
        running = np.cumsum(table, axis=0)
        self._clock = running[-1].ravel()
        joints = legs[:, None] * JOINTS_PER_LEG + np.arange(JOINTS_PER_LEG)
        clocks = running[every + 1, legs]
        if finite.all():  # the usual: no masks
            return joints.ravel(), pairs.reshape(-1, 2).T.copy(), clocks.ravel(), steps.ravel()
        return joints[finite], pairs[finite].T.copy(), clocks[finite], steps[finite]

    def _solve(self, joints: np.ndarray) -> None:
        """The parameters, their covariance's diagonal and the terms taken off of the
        ``joints`` (a mask), from their sums and the prior (which keeps each 3x3 positive
        definite).
        """
        sums = self._sums[joints]
        info = sums[:, INFO].reshape(-1, PARAMETERS, PARAMETERS)
        covariance = np.linalg.inv(info + self._prior_information)
        theta = np.einsum("jab,jb->ja", covariance, sums[:, 6:9])
        diagonal = np.diagonal(covariance, axis1=1, axis2=2)
        self._theta[joints], self._diagonal[joints] = theta, diagonal
        applied = self._applied_terms(theta, diagonal, self._variance[joints])
        for joint, terms in zip(np.flatnonzero(joints), applied.tolist(), strict=True):
            self._applied[joint] = (terms[0], terms[1], terms[2])

    def _applied_terms(
        self, theta: np.ndarray, diagonal: np.ndarray, variance: np.ndarray
    ) -> np.ndarray:
        """The parameters taken off (rows of joints): each estimate shrunk towards 0 by
        ``significance`` of its standard deviation (the covariance's ``diagonal`` times the
        residual's ``variance`` [N² m²]), so a term the data do not show stays 0, then held to
        its bound and its sign (friction opposes motion: viscous and Coulomb at most 0). The fit
        itself is left unconstrained: clipping it would break the least squares' covariance.
        """
        margin = self.settings.significance * np.sqrt(diagonal * variance[:, None])
        shrunk = _shrunk(theta, margin)
        bias, viscous, coulomb = self.settings.bounds
        result: np.ndarray = np.clip(shrunk, (-bias, -viscous, -coulomb), (bias, 0.0, 0.0))
        return result

    @property
    def parameters(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order), the terms taken off: bias [N m], viscous [N m s/rad] and
        Coulomb [N m] friction as positive coefficients (the torque ``c(q̇) = bias - viscous q̇ -
        coulomb tanh(q̇/ε)``).
        """
        return [(bias, -viscous, -coulomb) for bias, viscous, coulomb in self._applied]

    def fit_residuals(self) -> list[tuple[float, float, float]]:
        """Per joint (slot order): the swing samples learnt (forgotten alike), the residual's RMS
        [N m] in them before the fit and after it (the terms as fitted, before the shrinking).
        """
        out = []
        for sums, theta in zip(self._sums, self._theta, strict=True):
            samples, squares = float(sums[0]), float(sums[9])
            if not samples > 0.0:
                out.append((0.0, math.nan, math.nan))
                continue
            info = sums[INFO].reshape(PARAMETERS, PARAMETERS)  # the data's information alone
            quadratic = float(theta @ info @ theta)
            left = squares - 2.0 * float(theta @ sums[6:9])
            after = max(0.0, left + quadratic) / samples
            out.append((samples, math.sqrt(squares / samples), math.sqrt(after)))
        return out

    def terms_at(self, variances: Sequence[float]) -> list[tuple[float, float, float]]:
        """:attr:`parameters` with each joint's significance margin from ``variances`` [N² m²]
        (slot order) instead of the running estimate: a whole recording's fit judged by its own
        residual (:meth:`fit_residuals`).
        """
        terms = self._applied_terms(self._theta, self._diagonal, np.asarray(variances, float))
        return [(bias, -viscous, -coulomb) for bias, viscous, coulomb in terms.tolist()]

    def solve(self) -> None:
        """Take in the samples kept and solve every joint's least squares now."""
        if self.learnt_samples > self._taken_samples:
            self._take_in()

    @property
    def fit(self) -> list[tuple[float, float, float]]:
        """Per joint, the least squares' estimates before the significance and the bounds, as
        :attr:`parameters` gives them.
        """
        return [(bias, -viscous, -coulomb) for bias, viscous, coulomb in self._theta.tolist()]

    def values(self) -> dict[str, str]:
        """The terms taken off, per leg (``model_corrections_FR``...: its three joints'
        ``bias,viscous,coulomb`` [N m, N m s/rad, N m] joined by ``/``) and the joint samples
        learnt from: the diagnostics' values and the summary's line.
        """
        out = {
            "model_corrections_learnt_samples": str(self.learnt_samples),
            **self.scales.values(),
        }
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
        scales = (
            f"the legs' inertia scales (FR,FL,RR,RL): {values['leg_inertia_scales']}"
            if self.fixed or self.settings.learn_scales
            else "the legs' inertia scales 1, not learnt online (calibrate fits them)"
        )
        return (
            f"model corrections: {source}; per joint bias [N m], viscous [N m s/rad], "
            f"Coulomb [N m]: {legs}; {scales}"
        )


def correction_values(corrections: ModelCorrections | None, refused: str = "") -> dict[str, str]:
    """The diagnostics' values of the corrections (None: off), for both nodes; ``refused``: why
    a calibration's file was refused ("" none).
    """
    out = {"model_corrections_refused": refused} if refused else {}
    if corrections is None:
        return {"model_corrections": OFF, **out}
    return {"model_corrections": "file" if corrections.fixed else ONLINE, **corrections.values()}
