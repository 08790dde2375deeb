"""How far a foot's load could be misstated by efforts whose scale is off: a noise term of the
contact filter's force evidence (issue #35: a torque constant off by up to +-10 %), without ROS.

A motor whose torque constant is off by a share ``k`` reports ``(1 + k) tau``: the foot's normal
force the efforts imply quasi-statically, ``S = n . J^-T (g(q) - tau)``
(:mod:`a1_leg_fk.kinematics.foot_forces`), is off by about ``k S`` (the leg's own weight, a few
per cent of it, counted too). In swing ``S`` is the leg's own dynamics, which the momentum
observer takes off; a share of it is what a scale error leaves as a ghost load. The spread

    sigma = k |S|  [N]

is what the contact filter (:mod:`a1_leg_fk.estimation.contact_filter`) adds to its force scale
where a load would be stance evidence. ``k`` is a budget, not an estimate (the scale is not
identified from a recording: a payload weighs alike, docs/forces.md): :data:`SCALE_BUDGET`.

A latency budget (``L dS/dt`` for ``L`` = 3 ms, as a falling load is overstated by late efforts)
was measured and left out: it makes an exact robot's unloading foot look lifted up to ``L``
early at every liftoff, 0.6 points of agreement on the exact fast trot (docs/forces.md).
"""

from __future__ import annotations

from collections.abc import Sequence

from a1_leg_fk.estimation.contacts import normal_force
from a1_leg_fk.kinematics.foot_forces import FootForces

SCALE_BUDGET = 0.1
"""The share by which the efforts' scale (a torque constant) may be off: the issue's range."""


class EffortDoubt:
    """Each foot's spread [N] of the normal force its efforts imply (see the module text)."""

    def __init__(self, statics: FootForces, scale: float = SCALE_BUDGET) -> None:
        self.statics, self.scale = statics, scale

    def spreads(
        self,
        joints: tuple[Sequence[float], Sequence[float]],
        gravity: Sequence[float],
        down: Sequence[float],
        legs: Sequence[bool],
    ) -> list[float]:
        """Per foot the spread [N]: ``joints`` the 12 angles [rad] and efforts [N m],
        ``gravity`` [m/s^2] and its unit direction ``down``, base frame; only for ``legs`` (the
        feet whose load is stance evidence: the filter needs no other), NaN for the others and
        where the load is unknown.
        """
        forces, _, _ = self.statics.estimate_floats(*joints, gravity, legs)
        return [self.scale * abs(normal_force(force, down)) for force in forces]
