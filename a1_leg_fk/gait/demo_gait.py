"""The demo gait generator (for ``joint_state_demo``; gait *analysis* is
:mod:`a1_leg_fk.gait.analysis`).

A plausible A1 gait as a function of time: stand up from a crouch, then trot in place forever.

Pure Python (no ROS, no numpy needed): :class:`Gait` maps a time ``t`` [s] to the 12 joint
angles [rad] and their analytic rates [rad/s] in the package's slot order (FR, FL, RR, RL; hip
roll, hip pitch, knee per leg, see :mod:`a1_leg_fk.model.legs`).

Timeline (times in seconds from the start of the stream)::

    t <= 0                      crouched: knees at the most-bent end of their range (with a
                                margin), hip pitch half the knee angle, so each foot sits under
                                its hip
    0 .. stand_s                stand up: a cosine blend (zero velocity at both ends) to the
                                stand pose
    stand_s .. + ramp_s         the trot's amplitude fades in (smoothstep), so velocities stay
                                continuous
    after that                  periodic trot in place, ``trot_hz`` cycles per second

Trot: the diagonal pairs FR+RL and FL+RR alternate, half a cycle apart. A leg swings while the
sine of its phase is positive: the knee bends by ``knee_lift * sin(phase)**2`` while the hip
pitch turns by half that (which keeps the foot roughly under the hip, lifting it straight up), plus
a small fore-aft stroke (``cos(phase)``, forward in swing, backward in stance) and a small hip roll
sway (``sin(phase)``). Every term has a continuous first derivative.

Limits: the crouch is placed from the model's knee limits, and :class:`Gait` checks at
construction that every joint's whole trajectory stays inside ``[lower + margin, upper - margin]``
of the model it was built for (read from the URDF, never typed here), raising
:class:`a1_leg_fk.model.urdf.LegFkError` if a robot's limits do not allow this gait.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:  # kinematics needs numpy; this module does not
    from a1_leg_fk.kinematics.quadruped import Quadruped


STAND_POSE = (0.0, 0.8, -1.5)
"""Hip roll, hip pitch, knee [rad] of the A1's usual standing pose (a gait design choice, not a
limit)."""

PAIR_OF_LEG = {"FR": 0, "RL": 0, "FL": 1, "RR": 1}
"""Diagonal pair of each leg: pair 0 (FR+RL) and pair 1 (FL+RR) are half a trot cycle apart."""

Limits = Sequence[tuple[float | None, float | None]]


@dataclass(frozen=True)
class GaitParameters:
    """The gait's shape: durations [s], frequency [Hz], amplitudes and margins [rad]."""

    stand_s: float = 2.0
    ramp_s: float = 0.5
    trot_hz: float = 2.0
    knee_lift: float = 0.5  # extra knee bend at the top of the swing
    pitch_stroke: float = 0.08  # fore-aft hip pitch amplitude
    roll_sway: float = 0.04  # hip roll amplitude
    crouch_margin: float = 0.1  # how far inside the knee's most-bent limit the crouch stays
    limit_margin: float = 0.02  # every angle stays at least this far inside its limits


class Gait:
    """Joint angles and rates [rad, rad/s] over time for one robot's limits.

    ``limits`` holds 12 ``(lower, upper)`` pairs [rad] in slot order (``None`` for an unlimited
    side), e.g. from :func:`limits_of` on a :class:`a1_leg_fk.kinematics.quadruped.Quadruped`.
    """

    def __init__(self, limits: Limits, parameters: GaitParameters = GaitParameters()) -> None:
        if len(limits) != JOINT_COUNT:
            raise LegFkError(
                f"a gait needs {JOINT_COUNT} (lower, upper) limits, got {len(limits)}"
            )
        if parameters.stand_s <= 0 or parameters.ramp_s <= 0 or parameters.trot_hz <= 0:
            raise LegFkError(f"gait durations and frequency must be positive: {parameters}")
        self.limits = [tuple(pair) for pair in limits]
        self.parameters = parameters
        self.omega = 2.0 * math.pi * parameters.trot_hz
        self.crouch: list[float] = []
        self.stand: list[float] = []
        for leg_slot in range(len(LEG_NAMES)):
            knee_lower, knee_upper = self.limits[leg_slot * JOINTS_PER_LEG + 2]
            stand = STAND_POSE
            if (
                knee_lower is not None
                and knee_upper is not None
                and knee_upper < knee_lower + 2 * parameters.crouch_margin
            ):
                raise LegFkError(
                    f"leg {LEG_NAMES[leg_slot]}: knee range [{knee_lower}, {knee_upper}] is too "
                    "small"
                )
            # The most-bent end of the knee range is the one farther from the straight leg (0).
            if knee_lower is None or knee_upper is None:
                crouch_knee = -2.5
            elif abs(knee_lower) >= abs(knee_upper):
                crouch_knee = knee_lower + parameters.crouch_margin
            else:
                crouch_knee = knee_upper - parameters.crouch_margin
            self.crouch.extend((0.0, -crouch_knee / 2.0, crouch_knee))
            self.stand.extend(stand)
        self._check_limits()

    @property
    def trot_start_s(self) -> float:
        """When the trot begins (its amplitude then fades in over ``ramp_s``)."""
        return self.parameters.stand_s

    @property
    def periodic_from_s(self) -> float:
        """From this time on the gait repeats every :attr:`period_s`."""
        return self.parameters.stand_s + self.parameters.ramp_s

    @property
    def period_s(self) -> float:
        """One trot cycle [s]."""
        return 1.0 / self.parameters.trot_hz

    def phase(self, t: float, leg: str) -> float:
        """The leg's trot phase [rad] at time ``t`` (pair 1 lags pair 0 by pi)."""
        return self.omega * (t - self.trot_start_s) + math.pi * PAIR_OF_LEG[leg]

    def swinging(self, t: float, leg: str) -> bool:
        """True while the leg is in its swing half (foot in the air) of the trot."""
        return t > self.trot_start_s and math.sin(self.phase(t, leg)) > 0.0

    def angles(self, t: float) -> list[float]:
        """The 12 joint angles [rad] at time ``t`` [s], slot order."""
        return self.state(t)[0]

    def velocities(self, t: float) -> list[float]:
        """The 12 joint rates [rad/s] at time ``t`` [s]: the exact time derivatives of
        :meth:`angles`.
        """
        return self.state(t)[1]

    def state(self, t: float) -> tuple[list[float], list[float]]:
        """(angles [rad], rates [rad/s]) at time ``t`` [s]."""
        p = self.parameters
        if t < p.stand_s:
            # Stand up: s = (1 - cos(pi u)) / 2 for u = t / stand_s in [0, 1].
            u = min(max(t / p.stand_s, 0.0), 1.0)
            blend = 0.5 * (1.0 - math.cos(math.pi * u))
            blend_rate = 0.5 * math.pi / p.stand_s * math.sin(math.pi * u) if t > 0.0 else 0.0
            angles = [c + blend * (s - c) for c, s in zip(self.crouch, self.stand)]
            rates = [blend_rate * (s - c) for c, s in zip(self.crouch, self.stand)]
            return angles, rates
        # Amplitude envelope: smoothstep over ramp_s, then 1.
        u = min((t - p.stand_s) / p.ramp_s, 1.0)
        envelope = u * u * (3.0 - 2.0 * u)
        envelope_rate = 6.0 * u * (1.0 - u) / p.ramp_s if u < 1.0 else 0.0
        angles, rates = [], []
        for leg_slot, leg in enumerate(LEG_NAMES):
            offsets, offset_rates = self._trot_offsets(self.phase(t, leg))
            for joint_slot in range(JOINTS_PER_LEG):
                slot = leg_slot * JOINTS_PER_LEG + joint_slot
                angles.append(self.stand[slot] + envelope * offsets[joint_slot])
                rates.append(
                    envelope_rate * offsets[joint_slot] + envelope * offset_rates[joint_slot]
                )
        return angles, rates

    def _trot_offsets(
        self, phase: float
    ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Offsets from the stand pose [rad] and their rates [rad/s] for one leg at ``phase``."""
        p = self.parameters
        sin, cos = math.sin(phase), math.cos(phase)
        lift = sin * sin if sin > 0.0 else 0.0
        lift_rate = 2.0 * sin * cos * self.omega if sin > 0.0 else 0.0
        roll = p.roll_sway * sin
        pitch = 0.5 * p.knee_lift * lift + p.pitch_stroke * cos
        knee = -p.knee_lift * lift
        roll_rate = p.roll_sway * cos * self.omega
        pitch_rate = 0.5 * p.knee_lift * lift_rate - p.pitch_stroke * sin * self.omega
        knee_rate = -p.knee_lift * lift_rate
        return (roll, pitch, knee), (roll_rate, pitch_rate, knee_rate)

    def _check_limits(self) -> None:
        """Every joint's trajectory (its bounds, worked out per phase) inside its limits with
        margin.
        """
        p = self.parameters
        # Offsets bounds over a phase (envelope in [0, 1] scales them toward 0, which lies inside).
        roll_range = (-p.roll_sway, p.roll_sway)
        pitch_range = (-p.pitch_stroke, 0.5 * p.knee_lift + p.pitch_stroke)
        knee_range = (-p.knee_lift, 0.0)
        for slot, (lower, upper) in enumerate(self.limits):
            offset_low, offset_high = (roll_range, pitch_range, knee_range)[slot % JOINTS_PER_LEG]
            low = min(self.crouch[slot], self.stand[slot] + min(offset_low, 0.0))
            high = max(self.crouch[slot], self.stand[slot] + max(offset_high, 0.0))
            if (lower is not None and low < lower + p.limit_margin) or (
                upper is not None and high > upper - p.limit_margin
            ):
                raise LegFkError(
                    f"the gait moves slot {slot} (leg {LEG_NAMES[slot // JOINTS_PER_LEG]}, joint "
                    f"{slot % JOINTS_PER_LEG}) over [{low:.3f}, {high:.3f}] rad, outside its "
                    f"limits [{lower}, {upper}] less a {p.limit_margin} rad margin"
                )


def limits_of(quadruped: Quadruped) -> list[tuple[float | None, float | None]]:
    """The 12 ``(lower, upper)`` joint limits [rad] of a
    :class:`a1_leg_fk.kinematics.quadruped.Quadruped`.
    """
    return [(joint.lower, joint.upper) for joint in quadruped.joints]
