"""Which feet are on the ground, as a probability: a two-state (swing, stance) Bayesian filter per
foot that fuses the foot's normal force with its kinematics, without ROS (plain floats, per
sample: the node runs it for every joint state).

Each foot is a hidden Markov model (after Bledt et al., ICRA 2018, and Camurri et al., RA-L 2017):
between two samples ``dt`` apart it changes state with probability ``1 - exp(-dt /
switch_time_s)`` (the transition model), then each piece of evidence multiplies the odds of
stance by its likelihood ratio. Each is the log-likelihood ratio of a logistic model, clipped so
that no single sample decides alone:

- the foot's *normal force* [N] (from the momentum observer or the statics), when there is one:
  ``(N - force_half_n) / force_scale_n``, within ``+-max_log_ratio``;
- its *height* [m] above the lowest foot along gravity, or above the lowest foot with the local
  ground's slope taken off (:mod:`a1_leg_fk.estimation.foot_ground`), or over the tread under it
  where the standing feet's footholds are on two levels (:mod:`a1_leg_fk.estimation.foot_rise`),
  whichever is lowest (a foot low on any ground may stand: a slope's, or a staircase's tread,
  which no plane fits):
  ``(height_half_m - h) / height_scale_m``; for a foot the filter holds standing, at most
  ``(r_half - r) / rise_scale_m`` once its rise ``r`` above its own foothold
  (:mod:`a1_leg_fk.estimation.foot_rise`) is past ``r_half``, the larger of ``rise_half_m`` and
  ``rise_spread_factor`` times the standing feet's spread (a lifting foot that left a dip or a
  lower tread is "low" against the others well after its liftoff; against its own foothold it
  is not); at least 0 for a foot that *landed* higher than ``height_half_m`` (it stays within
  ``rise_half_m`` of where it came down to for 20 ms: a staircase's rise is no evidence of
  swing; forced too); for *rigid feet* (no foot with a force, the standing feet's footholds on
  one level and their rise spread under ``rigid_rise_share`` of ``rise_half_m``) the height at
  even odds is ``height_spread_factor`` times the standing feet's RMS height (at least
  ``height_floor_m``; used only where below ``height_half_m``), ``rigid_scale_share`` of it per
  unit, a foot below ``height_half_m`` saying swing at most ``rigid_swing_odds``: under stiff
  position motors a swing foot hovers 0.3-0.7 mm off the ground, where the standing feet sit
  within 0.2 mm of each other (:func:`~a1_leg_fk.estimation.kinematic_evidence.height_scales`);
- its *speed* [m/s] relative to the other low feet (those whose height, as above, is within
  ``height_half_m``) that stood at the previous sample (a swing foot skimming rough ground is
  low, and its speed not the ground's), else the others that stood at any height (on stairs down
  the lowest may be a swing foot reaching for the lower tread), else every other low foot; for
  a foot with a force, every other low foot while it and the feet that stood are all low, else
  the feet that stood at any height: the distance between the base velocity this foot gives if
  it were still (:mod:`a1_leg_fk.estimation.leg_motion`) and the mean of theirs;
  ``(speed_half_mps - v) / speed_scale_mps``; with a force ``N``, its swing side times ``1 -
  P / max_log_ratio``, ``P`` the force's log-odds from ``force_half_n`` plus the RMS force the
  feet held in swing read (:mod:`a1_leg_fk.estimation.swing_force`), within 0 and
  ``max_log_ratio``: a foot surely pressing is in contact however it slides (a loaded foot over
  a tread's edge), and a swing foot's force noise is no proof that it presses;
- *free fall*, from the IMU's specific force ``f`` when there is one, for the feet without a
  force: no foot bears load while ``|f|`` (the total load over the mass) is far below gravity;
  ``(|f| - fall_half_mps2) / fall_scale_mps2``, at most 0;
- optionally a gait-phase prior: a probability of stance from a gait scheduler, its log-odds
  times ``phase_weight``.

The kinematic evidence is asymmetric: a foot high or fast is strong evidence of swing (down to
``-max_log_ratio``), one low and still only weak evidence of stance (up to
``max_kinematic_stance``; none beside a force that says swing), because an unloaded foot, or
every foot in a flight phase, is low and still too. Defaults scale with the robot
(:meth:`ContactModel.for_robot`): forces with its weight, heights and speeds with its leg length.
The heights' and speeds' log-odds are :mod:`a1_leg_fk.estimation.kinematic_evidence`'s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from math import exp, isfinite, sqrt
from typing import NamedTuple

from a1_leg_fk.estimation.contact_model import ContactModel
from a1_leg_fk.estimation.foot_ground import FootGround
from a1_leg_fk.estimation.kinematic_evidence import (
    clip_odds,
    height_scales,
    kinematic_odds,
    rise_odds,
)
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.swing_force import SwingForce
from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
NO_FORCES = (math.nan,) * LEGS
LOW, HIGH = 2e-9, 1.0 - 2e-9
"""The probabilities whose log-odds the filter takes are kept within these."""
Vector = tuple[float, float, float]


class SampleEvidence(NamedTuple):
    """One sample's transition and evidence per foot, as the filter used them: the probability
    ``switch`` of a change of state since the previous sample, the kinematic (height and speed)
    log-likelihood ratios by the flat rules (without the feet's rises above their own footholds
    or levels, the speeds against every low foot: the filter's own rules follow its own state),
    whether the foot's force was evidence, the ``total`` log-likelihood ratio (kinematic as kept
    here, force or free fall, phase prior) and the feet's ``heights`` [m] the kinematic evidence
    took (above the lowest foot along gravity, or the local ground's slope where lower; or NaN).
    """

    switch: float
    kinematic: list[float]
    forced: list[bool]
    total: list[float]
    heights: list[float]


class ContactFilter:
    """The four feet's filters, carried from one sample to the next, from even odds."""

    def __init__(self, model: ContactModel) -> None:
        self.model = model
        self.probabilities = [0.5] * LEGS
        """Each foot's probability of stance after the latest sample."""
        self.evidence = SampleEvidence(
            0.0, [0.0] * LEGS, [False] * LEGS, [0.0] * LEGS, [math.nan] * LEGS
        )
        """The latest sample's transition and evidence, for a smoother (kept by reference)."""
        self.ground = FootGround()
        """The feet's heights above the local ground (given gravity's direction)."""
        self.swing_force = SwingForce()
        """The RMS normal force [N] the feet held in swing read: the speeds' fade's margin."""

    def update(
        self,
        dt_s: float,
        feet: Sequence[FootMotion | None],
        imu: tuple[Sequence[float], Sequence[float] | None],
        normal_forces: Sequence[float] | None = None,
        phase_prior: Sequence[float] | None = None,
        down: Vector | None = None,
    ) -> list[float]:
        """The 4 probabilities of stance after a sample ``dt_s`` [s] after the previous one:
        each foot's motion (None: unknown); ``imu``: the base's angular velocity [rad/s, base
        frame; zeros if unknown] and specific force [m/s^2] (None: unknown); normal forces [N]
        (None: no force evidence; NaN: none for that foot); the gait phase's probabilities of
        stance (None: no prior); ``down``: gravity's unit direction in the base frame, for the
        feet's heights against the local ground's slope too (None: the lowest foot's alone).
        """
        model = self.model
        limit = model.max_log_ratio
        switch = 1.0 - exp(-max(dt_s, 0.0) / model.switch_time_s)
        omega, specific_force = imu
        common = 0.0
        if specific_force is not None:
            fx, fy, fz = specific_force
            felt = sqrt(fx * fx + fy * fy + fz * fz)
            if isfinite(felt):
                fall = (felt - model.fall_half_mps2) / model.fall_scale_mps2
                common = min(0.0, clip_odds(fall, limit, limit))
        forces = NO_FORCES if normal_forces is None else normal_forces
        forced = [isfinite(forces[leg]) for leg in range(LEGS)]
        # the force's log-odds (free fall's without one); the kinematics' stance: weak while
        # falling or beside a force, none where that force says swing
        weak = model.max_kinematic_stance
        pushes, caps = [common] * LEGS, [weak if common < -1.0 else limit] * LEGS
        fades = [1.0] * LEGS  # the share of its speed's swing evidence a foot's force leaves
        standing = [p >= 0.5 for p in self.probabilities]
        margin = model.force_half_n  # a swing foot's noise above even odds: no press
        if normal_forces is not None:
            margin += self.swing_force.update(dt_s, forces, [not on for on in standing])
        for leg, force in enumerate(forces):
            if forced[leg]:
                push = clip_odds((force - model.force_half_n) / model.force_scale_n, limit, limit)
                pushes[leg], caps[leg] = push, 0.0 if push < 0.0 else weak
                press = clip_odds((force - margin) / model.force_scale_n, limit, limit)
                fades[leg] = 1.0 - max(press, 0.0) / limit
        heights, ground = None, self.ground
        scales = model.height_half_m, model.height_scale_m
        if down is not None:
            band = model.rise_half_m  # a swing foot lands within it (no spread: see foot_rise)
            step = model.height_half_m  # footholds farther apart: on two levels (a staircase)
            heights = ground.heights(dt_s, feet, down, omega, standing, band, step)
            if ground.one_level and not any(forced):  # two levels: a tread's edge; forces
                # place a forced foot's edges (the rule is for the feet's kinematics alone)
                scales = height_scales(model, ground.height_spread_m, ground.rise.spread_m)
        kinematic, taken, lowered = kinematic_odds(
            model,
            feet,
            (omega, standing),
            (forced, caps, fades),
            (heights, rise_odds(model, ground.rise) if down is not None else None, scales),
        )
        posterior, totals = [], []
        for leg, previous in enumerate(self.probabilities):
            prior = _logit(previous + switch * (1.0 - 2.0 * previous))
            odds = prior + kinematic[leg] + pushes[leg]
            if phase_prior is not None and isfinite(phase_prior[leg]):
                odds += model.phase_weight * _logit(phase_prior[leg])
            posterior.append(1.0 / (1.0 + exp(-odds)))
            totals.append(odds - prior - lowered[leg])
        self.probabilities = posterior
        # the smoother's evidence by the flat rules: the rise rules and the speeds against the feet
        # that stood follow this filter's own state, which a backward pass does not share (with
        # the caps, 7 smoothed runs without efforts fell below 98 %; the speeds: 12 lost 0.01-0.67)
        plain = [k - off for k, off in zip(kinematic, lowered, strict=True)]
        self.evidence = SampleEvidence(switch, plain, forced, totals, taken)
        return posterior


def gait_phase_prior(names: Sequence[str], probabilities: Sequence[float]) -> list[float]:
    """The filter's gait-phase prior from a message naming its feet (``foot_fk_node``'s
    ``gait_phase``, the layout of its ``foot_contacts``): per leg in :data:`LEG_NAMES` order the
    probability of stance given for it, NaN (no prior for that foot) where it is not named, is
    named more than once, or its value is not within [0, 1]; all NaN when there are not as many
    values as names.
    """
    prior = [math.nan] * LEGS
    if len(names) != len(probabilities):
        return prior
    for leg, leg_name in enumerate(LEG_NAMES):
        given = [
            value for name, value in zip(names, probabilities, strict=True) if name == leg_name
        ]
        if len(given) == 1 and 0.0 <= given[0] <= 1.0:
            prior[leg] = given[0]
    return prior


def _logit(probability: float) -> float:
    """The log-odds of a probability, kept finite (within +-20)."""
    p = LOW if probability < LOW else min(probability, HIGH)
    return math.log(p / (1.0 - p))
