"""Each foot's kinematic evidence of stance for the contact filter
(:mod:`a1_leg_fk.estimation.contact_filter`, whose docstring states the rules): its height above
the lowest foot or the local ground, bounded by its rise above its own foothold, and its speed
against the ground's, as clipped log-likelihood ratios; plain floats, per sample.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from math import isfinite, sqrt

from a1_leg_fk.estimation.contact_model import ContactModel
from a1_leg_fk.estimation.foot_rise import FootRise
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
Vector = tuple[float, float, float]
Scales = tuple[float, float]


def kinematic_odds(
    model: ContactModel,
    feet: Sequence[FootMotion | None],
    motion: tuple[Sequence[float], Sequence[bool]],
    force: tuple[Sequence[bool], Sequence[float], Sequence[float]],
    terrain: tuple[Sequence[float] | None, Sequence[float] | None, tuple[float, float]],
) -> tuple[list[float], list[float], list[float]]:
    """Each foot's height and speed evidence (log-odds; 0 for an unknown foot); asymmetric for
    the feet whose force is evidence too (``force``: per foot, whether it is, and the most
    stance its height and speed may each say); and the heights [m] it took (NaN: unknown):
    above the lowest foot, or from ``terrain``'s first (the slope taken off) where that is
    lower; its second bounds each foot's height log-odds (a foot risen above its own foothold,
    or at its own level: :func:`rise_odds`), its third the height [m] at even odds and per
    unit of log-odds (:func:`height_scales`); and how far each foot's evidence is from the flat
    rules' (no rise rule, the fixed height scales, speeds against every low foot by the fixed
    scales), which the smoother takes (the rigid feet's scales follow the feet the filter holds
    standing, as the rise does). The rise
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
    ground, rises, (half, scale) = terrain
    limit, fixed = model.max_log_ratio, model.height_half_m
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
    references = _references(velocities, (low, stepped), standing, forced)
    rigid = half != fixed  # the rigid feet's scales: the smoother keeps the fixed ones
    flats = references  # against every low foot: the same where every low foot stood
    if standing != low or rigid:  # the same feet low and standing: the same references
        lows = [h < fixed for h in heights] if rigid else low
        flats = _references(velocities, (lows, False), [False] * LEGS, forced)
    out, lowered = [], [0.0] * LEGS
    for leg in range(LEGS):
        cap = caps[leg]
        height, velocity, reference = heights[leg], velocities[leg], references[leg]
        evidence = 0.0
        if height == height:  # noqa: PLR0124 (NaN: an unknown foot)
            x = (half - height) / scale  # clip_odds written out: per foot and sample
            if height < fixed:  # rigid feet's rule: weaker swing below the fixed half
                x = max(x, -model.rigid_swing_odds)
            evidence = flat = -limit if x < -limit else cap if x > cap else x  # noqa: FURB136
            if rigid:  # the smoother's: the fixed scales
                y = (fixed - height) / model.height_scale_m
                flat = -limit if y < -limit else cap if y > cap else y  # noqa: FURB136
            rise = math.nan if rises is None else rises[leg]  # forced: the landed rule alone
            rise = math.nan if forced[leg] and rise != math.inf else rise
            landed = x < 0.0 < rise == math.inf and height >= fixed  # however high, past it
            if x > rise < 0.0 or landed:  # risen; landed
                x = min(rise, 0.0)
                evidence = -limit if x < -limit else cap if x > cap else x  # noqa: FURB136
            lowered[leg] = evidence - flat
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
    odds = clip_odds(
        (model.speed_half_mps - speed) / model.speed_scale_mps, model.max_log_ratio, cap
    )
    return odds * fade if odds < 0.0 else odds


def height_scales(model: ContactModel, height_spread_m: float, rise_spread_m: float) -> Scales:
    """The height [m] at even odds and per unit of log-odds: ``height_half_m`` and
    ``height_scale_m``, but for rigid feet (the standing feet's rise spread ``rise_spread_m``
    [m] below ``rigid_rise_share`` of ``rise_half_m``) ``height_spread_factor`` times the
    standing feet's height spread ``height_spread_m`` [m] where that is lower (at least
    ``height_floor_m``), and ``rigid_scale_share`` of it per unit.
    """
    half = max(model.height_floor_m, model.height_spread_factor * height_spread_m)
    rigid = rise_spread_m < model.rigid_rise_share * model.rise_half_m
    if not (rigid and half < model.height_half_m):
        return model.height_half_m, model.height_scale_m
    return half, model.rigid_scale_share * half


def rise_odds(model: ContactModel, rise: FootRise) -> list[float]:
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
    its edges, see :func:`kinematic_odds`), else the standing feet at any height: on stairs a foot
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


def clip_odds(log_ratio: float, limit: float, cap: float) -> float:
    """A log-likelihood ratio within ``-limit`` and ``cap``; NaN (absurd values): 0."""
    if log_ratio != log_ratio:  # noqa: PLR0124
        return 0.0
    return -limit if log_ratio < -limit else min(log_ratio, cap)
