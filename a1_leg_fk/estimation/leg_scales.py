"""Online corrections of the legs' model, second part: one inertia scale per leg, learnt while the
foot is in the air beside the joints' friction (:mod:`a1_leg_fk.estimation.model_corrections`,
which owns it and decides when a leg learns), and applied to the momentum observer's model of
the leg; without ROS, plain floats per sample.

A real leg's thigh and calf are heavier or lighter than its URDF lists (cables, rubber, rotors).
A leg whose links are all ``a`` times the URDF's (masses and inertias: its mass matrix, Coriolis
and gravity terms ``a`` times the model's) needs the efforts ``a W`` where the model says ``W``
[N m] per joint (``W = M q̈ + C q̇ + g`` through the observer's lag: the observer's residual
plus its lagged efforts, :mod:`a1_leg_fk.estimation.momentum_observer`). In swing the observer,
built on the URDF, then reads ``r = (1 - a) W`` (plus the friction) as external torque. So per
leg the share ``λ = 1 - a`` is fitted by least squares, its three joints together,

    r - c(q̇) ≈ λ W        (c: the friction terms taken off, learnt beside it)

with the friction's own least squares seeing ``r - λ W``: alternating, the two reach the joint
least squares' solution. ``W`` carries the joint rates' noise through ``dp/dt`` and ``r`` the same
noise (``r = W - efforts``): plain least squares would read it as a share (on the family's noisy
light legs, 0.70-0.77 where 0.9 was simulated). So ``λ`` is an instrumental-variables fit,
``λ = Σ W' (r - c) / Σ W' W``, the instrument ``W'`` the mean of the leg's ``W`` :data:`DELAY`
samples before and after (its noise apart, a swing's torque changes little in a few ms): a
sample is learnt :data:`DELAY` samples late, if it and the sample then are both surely in the
air. Forgetting and prior as the friction's, its own bound and significance
(:class:`~a1_leg_fk.estimation.model_corrections.CorrectionSettings`): the share taken off is
the fit shrunk towards 0 by ``significance`` standard deviations (the fit's variance times the
residual's, learnt), then held within ``±bound``: a leg as its URDF keeps ``a = 1``. Where the
leg shows Coulomb friction, its joints slower than the smooth sign's width are left out: a stuck
joint's friction holds whatever its motor leaves, a share of ``W`` that is not mass (an Aliengo
trotting in place read 0.78-0.80 for exact legs, docs/forces.md). ``λ W`` is
taken off every residual, stance included (``W`` is the leg's own dynamics there too), which is
the observer run on the leg's mass matrix and gravity terms scaled by ``a``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
DELAY = 2
"""Samples between a leg's learnt sample and each of its instrument's two torques ``W``, before
and after it: their noise is (nearly) independent of its own (the observer's lag is half a sample
at 500 Hz), and a term in ``dW/dt`` (a lag) cancels in their mean. Measured on the family's light
legs (fit, clean / noisy): 2 samples 0.87-0.91 / 0.88-0.92 of the simulated 0.9, 3 samples
0.88-0.92 / 0.89-0.92; the least squares without an instrument 0.85-0.89 / 0.70-0.77."""
Triple = tuple[float, float, float]


class _Sample:
    """One sample of a leg: its torques ``model`` = W and ``target`` = r - c [N m], per joint
    whether its rate was beyond the stiction band (``moving``), and whether it was surely in the
    air (set when the leg learns).
    """

    __slots__ = ("in_air", "model", "moving", "target")

    def __init__(self, model: Triple, target: Triple, moving: tuple[bool, bool, bool]) -> None:
        self.model, self.target, self.moving, self.in_air = model, target, moving, False


class LegScales:
    """The four legs' inertia scales (slot order FR, FL, RR, RL): learnt in swing (see the module
    text), or ``fixed`` (a calibration's file) and never learnt.

    Per leg, with forgetting: ``_sums`` the swing samples' ``W'·W``, ``W'·(r - c)`` and ``W'·W'``
    summed over its joints [N² m²] (``W'`` the instrument), those beyond the stiction band first,
    then those slower (left out if the leg shows Coulomb friction), ``_variance`` [N² m²] the
    residual's about the fit (a priori errors' squares), ``_share`` the share ``λ`` taken off.
    """

    def __init__(
        self,
        forget_s: float,
        noise_nm: float,
        bound: float,
        significance: float,
        fixed: Sequence[float] | None = None,
        band: float = 0.0,
    ) -> None:
        """``forget_s`` [s] the forgetting's time constant (of learning time), ``noise_nm`` [N m]
        the residual's prior noise, ``bound`` the largest ``|1 - a|`` (the prior's standard
        deviation too), ``significance`` the shrinking in standard deviations; ``fixed``: per
        leg its scale ``a`` taken as it is (None: learnt); ``band`` [rad/s]: a joint slower than
        this may be stuck (see :meth:`keep`).
        """
        self.forget_s, self.bound, self.significance = forget_s, bound, significance
        self.band = band
        self.fixed = fixed is not None
        self._prior = (noise_nm / bound) ** 2
        """The prior's information on λ, times the noise's variance [N² m²]."""
        self._sums = [[0.0] * 6 for _ in range(LEGS)]
        self._variance = [noise_nm**2] * LEGS
        self._share = [1.0 - scale for scale in fixed] if fixed is not None else [0.0] * LEGS
        self._fit = list(self._share)
        self._latest: list[Triple | None] = [None] * LEGS
        """Per leg, the latest model torques W [N m]."""
        self._before: list[list[_Sample]] = [[] for _ in range(LEGS)]
        """Per leg, its last ``2 DELAY + 1`` samples, oldest first."""
        self.learnt_samples = [0] * LEGS
        """Per leg, the samples learnt from."""

    def correct(self, leg: int, residual: Triple, model: Triple) -> Triple:
        """Leg slot ``leg``'s residual [N m] with ``λ W`` taken off, for its model torques
        ``model`` = W [N m] (kept for :meth:`learn` with :meth:`keep`).
        """
        share = self._share[leg]
        self._latest[leg] = model
        if share == 0.0:
            return residual
        return (
            residual[0] - share * model[0],
            residual[1] - share * model[1],
            residual[2] - share * model[2],
        )

    def applied(self, leg: int) -> bool:
        """Whether leg slot ``leg``'s scale can change its residual: learnt, or given other than
        1 (a fixed scale of 1, the online default, takes nothing off and keeps nothing).
        """
        return not self.fixed or self._share[leg] != 0.0

    def keep(self, leg: int, left: Triple, rates: Triple) -> None:
        """The residual [N m] left of leg slot ``leg`` after every correction (friction too),
        with its torques ``W`` kept for the learning (``r - c = left + λ W``), at its joints'
        ``rates`` [rad/s]: a joint slower than :attr:`band` may be stuck, its friction then
        anything up to its Coulomb term (not the smooth sign's value): where the leg shows
        Coulomb friction it is not learnt from (:meth:`learn`).
        """
        model, self._latest[leg] = self._latest[leg], None
        if model is None or self.fixed:
            return
        share, before = self._share[leg], self._before[leg]
        w0, w1, w2 = model
        target = (left[0] + share * w0, left[1] + share * w1, left[2] + share * w2)
        q0, q1, q2 = rates
        band = self.band
        moving = (abs(q0) > band, abs(q1) > band, abs(q2) > band)
        before.append(_Sample(model, target, moving))
        if len(before) > 2 * DELAY + 1:
            del before[0]

    def learn(self, leg: int, step_s: float, sticks: bool = False) -> None:
        """Leg slot ``leg`` is surely in the air: its sample of :data:`DELAY` samples before
        into its least squares, ``step_s`` [s] of learning time since its previous one
        forgotten; ``sticks``: the leg's joints show Coulomb friction, so its joints slower than
        :attr:`band` (their sums kept apart) are left out of the fit (see :meth:`keep`).
        """
        before = self._before[leg]
        if self.fixed or len(before) <= 2 * DELAY:
            return
        before[-1].in_air = True
        if not before[DELAY].in_air:
            return
        sample = before[DELAY]
        (w0, w1, w2), (y0, y1, y2) = sample.model, sample.target
        (a0, a1, a2), (b0, b1, b2) = before[0].model, before[-1].model
        z0, z1, z2 = 0.5 * (a0 + b0), 0.5 * (a1 + b1), 0.5 * (a2 + b2)  # the instrument
        if not math.isfinite(y0 + y1 + y2 + w0 + w1 + w2 + z0 + z1 + z2):
            return
        sums, fit = self._sums[leg], self._fit[leg]
        keep = math.exp(-step_s / self.forget_s)
        error = (y0 - fit * w0) ** 2 + (y1 - fit * w1) ** 2 + (y2 - fit * w2) ** 2
        self._variance[leg] = keep * self._variance[leg] + (1.0 - keep) * error / 3.0
        for first in (0, 3):
            sums[first] *= keep
            sums[first + 1] *= keep
            sums[first + 2] *= keep
        for z, w, y, moving in zip((z0, z1, z2), (w0, w1, w2), (y0, y1, y2), sample.moving):
            first = 0 if moving else 3
            sums[first] += z * w
            sums[first + 1] += z * y
            sums[first + 2] += z * z
        self.learnt_samples[leg] += 1
        self._solve(leg, sticks)

    def _solve(self, leg: int, sticks: bool) -> None:
        """Leg ``leg``'s fit and the share taken off: the fit shrunk by ``significance``
        standard deviations (of the fit, with the residual's variance), within ``±bound``; the
        slow joints' sums left out if it ``sticks``.
        """
        sums = self._sums[leg]
        cross, moment, squares = (
            sums[:3] if sticks else [a + b for a, b in zip(sums[:3], sums[3:])]
        )
        information = max(cross, 0.0) + self._prior  # the instrument's, against W
        fit = moment / information
        margin = self.significance * math.sqrt(self._variance[leg] * (squares + self._prior))
        margin /= information
        shrunk = math.copysign(max(abs(fit) - margin, 0.0), fit)
        self._fit[leg] = fit
        self._share[leg] = min(self.bound, max(-self.bound, shrunk))

    @property
    def scales(self) -> list[float]:
        """Per leg (slot order), the scale ``a`` applied: its links' mass and inertia over the
        URDF's (1: as the URDF).
        """
        return [1.0 - share for share in self._share]

    @property
    def fit(self) -> list[float]:
        """Per leg, the least squares' scale before the significance and the bound."""
        return [1.0 - fit for fit in self._fit]

    def values(self) -> dict[str, str]:
        """The scales applied per leg (``leg_inertia_scales``: ``FR,FL,RR,RL``): the
        diagnostics' value and the summary's.
        """
        return {"leg_inertia_scales": ",".join(f"{scale:.3f}" for scale in self.scales)}
