"""The contact filter's transition and evidence scales (:mod:`a1_leg_fk.estimation.contact_filter`
states the rules they enter), and their defaults for a robot, scaled with its weight and leg
length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.model.urdf import LegFkError


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
    height_floor_m: float = 5.0e-5
    """[m] the least height at even odds of the rigid feet's rule."""
    height_spread_factor: float = 2.0
    """Rigid feet: the height at even odds is this many times the standing feet's height spread
    (at least ``height_floor_m``, at most ``height_half_m``)."""
    rigid_rise_share: float = 0.4
    """The standing feet are rigid while their rise spread is below this share of
    ``rise_half_m``."""
    rigid_scale_share: float = 0.125
    """Rigid feet: the height per unit of log-odds, as a share of the height at even odds."""
    rigid_swing_odds: float = 3.0
    """Rigid feet: the most a foot's height below ``height_half_m`` says swing (log-odds)."""
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
            height_floor_m=HEIGHT_FLOOR_SHARE * leg_length_m,
        )


SWITCH_TIME_S = 0.1
"""Mean time [s] between state changes in the transition model."""
FORCE_HALF_SHARE, FORCE_SCALE_SHARE = 0.03, 0.005
"""Normal force at even odds, and per unit of log-odds, as shares of the weight."""
HEIGHT_HALF_SHARE, HEIGHT_SCALE_SHARE = 0.04, 0.01
"""Height above the lowest foot at even odds, and per unit of log-odds, in leg lengths."""
HEIGHT_FLOOR_SHARE = 1.25e-4
"""The rigid feet's least height at even odds, in leg lengths (0.05 mm on the A1)."""
RISE_HALF_SHARE, RISE_SCALE_SHARE = 0.00375, 0.00125
"""A standing foot's rise above its own foothold at even odds (at least), and per unit of
log-odds, in leg lengths (1.5 and 0.5 mm on the A1)."""
SPEED_HALF_PER_S, SPEED_SCALE_PER_S = 0.8, 0.2
"""Speed over the ground at even odds, and per unit of log-odds, in leg lengths per second."""
