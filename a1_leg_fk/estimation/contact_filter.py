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
  ground's slope taken off (:mod:`a1_leg_fk.estimation.foot_ground`), whichever is lower (a foot
  low on either ground may stand: a slope's, or a staircase's tread, which no plane fits):
  ``(height_half_m - h) / height_scale_m``; for a foot the filter holds standing, at most
  ``(r_half - r) / rise_scale_m`` once its rise ``r`` above its own foothold
  (:mod:`a1_leg_fk.estimation.foot_rise`) is past ``r_half``, the larger of ``rise_half_m`` and
  ``rise_spread_factor`` times the standing feet's spread (a lifting foot that left a dip or a
  lower tread is "low" against the others well after its liftoff; against its own foothold it
  is not); at least 0 for a foot that *landed*, however high (it stays within ``rise_half_m``
  of where it came down to for 20 ms: a staircase's rise is no evidence of swing; forced too);
- its *speed* [m/s] relative to the other low feet (those whose height, as above, is within
  ``height_half_m``) that stood at the previous sample (a swing foot skimming rough ground is
  low, and its speed not the ground's), else the others that stood at any height (on stairs down
  the lowest may be a swing foot reaching for the lower tread), else every other low foot; for
  a foot with a force, every other low foot while it and the feet that stood are all low, else
  the feet that stood at any height: the distance between the base velocity this foot gives if
  it were still (:mod:`a1_leg_fk.estimation.leg_motion`) and the mean of theirs;
  ``(speed_half_mps - v) / speed_scale_mps``; where a standing foot is not low (stairs), with a
  force ``F`` log-odds, its swing side times ``1 - max(F, 0) / max_log_ratio`` (sliding, pressing);
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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from math import exp, isfinite, sqrt
from typing import NamedTuple

from a1_leg_fk.estimation.foot_ground import FootGround
from a1_leg_fk.estimation.foot_rise import FootRise
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

LEGS = len(LEG_NAMES)
NO_FORCES = (math.nan,) * LEGS
LOW, HIGH = 2e-9, 1.0 - 2e-9
"""The probabilities whose log-odds the filter takes are kept within these."""
Vector = tuple[float, float, float]


@dataclass(frozen=True)
class ContactModel:
    """The filter's transition and evidence scales (see the module text); units in the names."""

    switch_time_s: float
    force_half_n: float
    force_scale_n: float
    height_half_m: float
    height_scale_m: float
    speed_half_mps: float
    speed_scale_mps: float
    rise_half_m: float
    rise_scale_m: float
    fall_half_mps2: float = 0.3 * STANDARD_GRAVITY
    fall_scale_mps2: float = 0.05 * STANDARD_GRAVITY
    max_log_ratio: float = 4.0
    max_kinematic_stance: float = 0.5
    rise_spread_factor: float = 3.5
    """The rise at even odds is at least this many times the standing feet's spread."""
    phase_weight: float = 1.0

    def __post_init__(self) -> None:
        values = [getattr(self, name) for name in self.__dataclass_fields__]
        if not all(math.isfinite(value) and value > 0.0 for value in values):
            raise LegFkError(f"contact model values must be finite and positive: {self}")

    @classmethod
    def for_robot(cls, weight_n: float, leg_length_m: float) -> ContactModel:
        """The defaults for a robot of ``weight_n`` [N] with legs ``leg_length_m`` [m] long
        (thigh plus calf).
        """
        return cls(
            switch_time_s=SWITCH_TIME_S,
            force_half_n=FORCE_HALF_SHARE * weight_n,
            force_scale_n=FORCE_SCALE_SHARE * weight_n,
            height_half_m=HEIGHT_HALF_SHARE * leg_length_m,
            height_scale_m=HEIGHT_SCALE_SHARE * leg_length_m,
            speed_half_mps=SPEED_HALF_PER_S * leg_length_m,
            speed_scale_mps=SPEED_SCALE_PER_S * leg_length_m,
            rise_half_m=RISE_HALF_SHARE * leg_length_m,
            rise_scale_m=RISE_SCALE_SHARE * leg_length_m,
        )


SWITCH_TIME_S = 0.1
"""Mean time [s] between state changes in the transition model."""
FORCE_HALF_SHARE, FORCE_SCALE_SHARE = 0.03, 0.005
"""Normal force at even odds, and per unit of log-odds, as shares of the weight."""
HEIGHT_HALF_SHARE, HEIGHT_SCALE_SHARE = 0.04, 0.01
"""Height above the lowest foot at even odds, and per unit of log-odds, in leg lengths."""
RISE_HALF_SHARE, RISE_SCALE_SHARE = 0.00375, 0.00125
"""A standing foot's rise above its own foothold at even odds (at least), and per unit of
log-odds, in leg lengths (1.5 and 0.5 mm on the A1)."""
SPEED_HALF_PER_S, SPEED_SCALE_PER_S = 0.8, 0.2
"""Speed over the ground at even odds, and per unit of log-odds, in leg lengths per second."""


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
                common = min(0.0, _clip(fall, limit, limit))
        forces = NO_FORCES if normal_forces is None else normal_forces
        forced = [isfinite(forces[leg]) for leg in range(LEGS)]
        # the force's log-odds (free fall's without one); the kinematics' stance: weak while
        # falling or beside a force, none where that force says swing
        weak = model.max_kinematic_stance
        pushes, caps = [common] * LEGS, [weak if common < -1.0 else limit] * LEGS
        fades = [1.0] * LEGS  # the share of its speed's swing evidence a foot's force leaves
        for leg, force in enumerate(forces):
            if forced[leg]:
                push = _clip((force - model.force_half_n) / model.force_scale_n, limit, limit)
                pushes[leg], caps[leg] = push, 0.0 if push < 0.0 else weak
                fades[leg] = 1.0 - max(push, 0.0) / limit
        heights = None
        standing = [p >= 0.5 for p in self.probabilities]
        if down is not None:
            band = model.rise_half_m  # a swing foot lands within it (no spread: see foot_rise)
            heights = self.ground.heights(dt_s, feet, down, omega, standing, band)
        kinematic, taken, lowered = _kinematic(
            model,
            feet,
            (omega, standing),
            (forced, caps, fades),
            (heights, _rise_odds(model, self.ground.rise) if down is not None else None),
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


def _kinematic(
    model: ContactModel,
    feet: Sequence[FootMotion | None],
    motion: tuple[Sequence[float], Sequence[bool]],
    force: tuple[Sequence[bool], Sequence[float], Sequence[float]],
    terrain: tuple[Sequence[float] | None, Sequence[float] | None],
) -> tuple[list[float], list[float], list[float]]:
    """Each foot's height and speed evidence (log-odds; 0 for an unknown foot); asymmetric for
    the feet whose force is evidence too (``force``: per foot, whether it is, and the most
    stance its height and speed may each say); and the heights [m] it took (NaN: unknown):
    above the lowest foot, or from ``terrain``'s first (the slope taken off) where that is
    lower; its second bounds each foot's height log-odds (a foot risen above its own foothold,
    or at its own level: :func:`_rise_odds`); and how far each foot's evidence is from the flat
    rules' (no rise rule, speeds against every low foot), which the smoother takes. The rise
    above a foot's own foothold and the speeds against the feet that stood are for the feet
    without a force: with one, the causal filter's liftoffs moved ahead of the smoothed ones by
    1-2 foot-samples on three runs of the contact family, so a forced foot keeps the flat rules
    but one: landed, its height says no swing either (on stairs its tread is not the lowest's).
    ``motion``: the base's angular velocity [rad/s, base frame] and which feet stood at the
    previous sample (the speeds' reference); ``force``'s third: the speeds' fades.
    """
    lowest = math.nan  # the deepest contact point, as max() finds it
    known = False
    for foot in feet:
        if foot is not None and (not known or foot.depth > lowest):
            lowest, known = foot.depth, True
    if not isfinite(lowest):
        return [0.0] * LEGS, [math.nan] * LEGS, [0.0] * LEGS
    (wx, wy, wz), standing = motion
    forced, caps, fades = force
    ground, rises = terrain
    half, scale, limit = model.height_half_m, model.height_scale_m, model.max_log_ratio
    velocities: list[Vector | None] = [None] * LEGS
    heights = [math.nan] * LEGS
    for leg, foot in enumerate(feet):
        if foot is None:
            continue
        height = lowest - foot.depth
        if ground is not None and ground[leg] < height:  # low on either ground
            height = ground[leg]
        heights[leg] = height
        (ex, ey, ez), (rx, ry, rz), _ = foot  # the base velocity if it stands: e - w x r
        vx, vy, vz = ex - (wy * rz - wz * ry), ey - (wz * rx - wx * rz), ez - (wx * ry - wy * rx)
        if isfinite(vx + vy + vz):
            velocities[leg] = (vx, vy, vz)
    low = [h < half for h in heights]
    stepped = any(stood and not down for stood, down in zip(standing, low, strict=True))
    fades = fades if stepped else [1.0] * LEGS  # one level: in full (the smoother's goal)
    references = _references(velocities, (low, stepped), standing, forced)
    flats = references  # against every low foot: the same where every low foot stood
    if standing != low:  # the same feet low and standing: the same references
        flats = _references(velocities, (low, False), [False] * LEGS, forced)
    out, lowered = [], [0.0] * LEGS
    for leg in range(LEGS):
        cap = caps[leg]
        height, velocity, reference = heights[leg], velocities[leg], references[leg]
        evidence = 0.0
        if height == height:  # noqa: PLR0124 (NaN: an unknown foot)
            x = (half - height) / scale  # _clip written out: per foot and sample
            evidence = -limit if x < -limit else cap if x > cap else x  # noqa: FURB136
            rise = math.nan if rises is None else rises[leg]  # forced: the landed rule alone
            rise = math.nan if forced[leg] and rise != math.inf else rise
            if x > rise < 0.0 or x < 0.0 < rise == math.inf:  # risen; landed, however high
                x = min(rise, 0.0)
                risen = -limit if x < -limit else cap if x > cap else x  # noqa: FURB136
                lowered[leg], evidence = risen - evidence, risen
        if velocity is not None:
            speed = _speed_odds(velocity, reference, model, cap, fades[leg])
            evidence += speed
            if flats is not references and flats[leg] != reference:  # for the smoother
                lowered[leg] += speed - _speed_odds(velocity, flats[leg], model, cap, fades[leg])
        out.append(evidence)
    return out, heights, lowered


def _speed_odds(
    velocity: Vector, reference: Vector | None, model: ContactModel, cap: float, fade: float
) -> float:
    """A foot's speed log-odds: its base velocity [m/s] against the ``reference``'s (0: none),
    within ``-max_log_ratio`` and ``cap``, below 0 times ``fade`` (the share its force leaves).
    """
    if reference is None:
        return 0.0
    (vx, vy, vz), (gx, gy, gz) = velocity, reference
    dx, dy, dz = vx - gx, vy - gy, vz - gz
    speed = sqrt(dx * dx + dy * dy + dz * dz)  # absurd values: inf, not raise
    odds = _clip((model.speed_half_mps - speed) / model.speed_scale_mps, model.max_log_ratio, cap)
    return odds * fade if odds < 0.0 else odds


def _rise_odds(model: ContactModel, rise: FootRise) -> list[float]:
    """Per foot, its rise log-odds ``(half - rise) / rise_scale_m`` above its own foothold
    (:mod:`a1_leg_fk.estimation.foot_rise`; ``half`` the larger of ``rise_half_m`` and
    ``rise_spread_factor`` times the standing feet's spread): below 0 (risen past even odds),
    the most its height log-odds may say; else +inf for a foot that landed (its height says no
    swing: at least 0); NaN, or a rise's odds from 0 up: no bound.
    """
    half = max(model.rise_half_m, model.rise_spread_factor * rise.spread_m)
    odds = [(half - risen) / model.rise_scale_m for risen in rise.rises]
    return [math.inf if on and not x < 0.0 else x for x, on in zip(odds, rise.landed, strict=True)]


def _references(
    velocities: Sequence[Vector | None],
    levels: tuple[Sequence[bool], bool],
    standing: Sequence[bool],
    forced: Sequence[bool],
) -> list[Vector | None]:
    """Per foot, the ground's velocity its speed is taken against [m/s, base frame]: the mean
    base velocity of the other feet with a velocity that the filter held ``standing`` at the
    previous sample, the ``low`` ones among them for a foot without a force (else any: on stairs
    down the low foot may be one reaching for the lower tread), or of the other low feet when
    none stood (None: no other low foot). A swing foot skimming rough ground is low too, and
    moves: the standing feet leave it out. A foot whose force is evidence (``forced``) takes
    every other low foot while it and every standing foot are low (flat ground: its force places
    its edges, see :func:`_kinematic`), else the standing feet at any height: on stairs a foot
    stands on another tread than the lowest's, and the low feet are swing feet coming down.
    ``levels``: which feet are low, and whether a standing foot is not (on two levels).
    """
    low, stepped = levels
    sums = [[0, 0.0, 0.0, 0.0], [0, 0.0, 0.0, 0.0], [0, 0.0, 0.0, 0.0]]
    for o, velocity in enumerate(velocities):  # (count, x, y, z): low; low, standing; standing
        if velocity is None:
            continue
        for total in (
            sums if low[o] and standing[o] else sums[:1] if low[o] else sums[2:] if standing[o]
            else ()
        ):  # fmt: skip
            total[0] += 1
            total[1] += velocity[0]
            total[2] += velocity[1]
            total[3] += velocity[2]
    out: list[Vector | None] = []
    for leg, velocity in enumerate(velocities):
        known = velocity is not None  # its own velocity is in the sums: leave it out
        chosen = 1 if not forced[leg] else 0 if low[leg] and not stepped else 2  # as sums
        mine = known and standing[leg] and (chosen == 2 or low[leg])
        if chosen == 1 and not sums[1][0] > mine:  # no other low foot stood: any that stood
            chosen, mine = 2, known and standing[leg]
        if chosen == 0 or not sums[chosen][0] > mine:
            chosen, mine = 0, known and low[leg]
        count, sx, sy, sz = sums[chosen]
        if mine and velocity is not None:
            count, sx, sy, sz = count - 1, sx - velocity[0], sy - velocity[1], sz - velocity[2]
        out.append(None if count == 0 else (sx / count, sy / count, sz / count))
    return out


def _clip(log_ratio: float, limit: float, cap: float) -> float:
    """A log-likelihood ratio within ``-limit`` and ``cap``; NaN (absurd values): 0."""
    if log_ratio != log_ratio:  # noqa: PLR0124
        return 0.0
    return -limit if log_ratio < -limit else min(log_ratio, cap)


def _logit(probability: float) -> float:
    """The log-odds of a probability, kept finite (within +-20)."""
    p = LOW if probability < LOW else min(probability, HIGH)
    return math.log(p / (1.0 - p))
