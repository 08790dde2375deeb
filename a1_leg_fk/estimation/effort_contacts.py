"""Where the leg odometry's stance comes from, per joint state: the foot forces of the joint
efforts (:mod:`a1_leg_fk.kinematics.foot_forces`) through the contact rule
(:mod:`a1_leg_fk.estimation.contacts`), or the kinematic stance. One rule for the node and the bag
tool (:class:`EffortContacts`, used by :class:`~a1_leg_fk.estimation.odometry_feed.OdometryFeed`).

Sources (the node's ``contacts`` parameter, ``a1-leg-fk odom --contacts``):

- ``auto`` (default): force contacts for a joint state whose merged efforts are finite for all 12
  joints, else kinematic stance for that joint state;
- ``force``: force contacts always; a leg without a force (efforts missing or not finite, or its
  Jacobian near singular) does not stand;
- ``kinematic``: the kinematic stance always (efforts ignored).

Gravity, for the forces and for the normal direction, is the odometry's: from the orientation of
the IMU sample paired with the joint state, else the base taken as level. The contact rule's
hysteresis is carried across joint states (a joint state without efforts leaves it as it was).
Thresholds default to shares of the robot's weight (:meth:`ContactThresholds.for_weight`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_force
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY, Vector
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError

AUTO, FORCE, KINEMATIC = "auto", "force", "kinematic"
CONTACT_SOURCES = (AUTO, FORCE, KINEMATIC)


@dataclass
class ContactCounts:
    """Joint states whose stance came from the foot forces, and from the kinematics."""

    force: int = 0
    kinematic: int = 0

    def line(self, source: str) -> str:
        """``source``'s counts in words."""
        return (
            f"{source}: force contacts for {self.force} samples, kinematic stance for "
            f"{self.kinematic}"
        )


class EffortContacts:
    """Contact probabilities of one robot's feet from the joint efforts, one joint state at a
    time (see the module text). ``thresholds``: touchdown and liftoff normal forces [N], None for
    the defaults of the robot's weight.
    """

    def __init__(
        self,
        quadruped: Quadruped,
        source: str = AUTO,
        thresholds: tuple[float | None, float | None] = (None, None),
    ) -> None:
        if source not in CONTACT_SOURCES:
            raise LegFkError(f"contacts must be one of {', '.join(CONTACT_SOURCES)}: {source!r}")
        self.source = source
        self.counts = ContactCounts()
        self.model: FootForces | None = None
        self.note = ""
        """Why there are no foot forces for this robot ("" when there are)."""
        if source != KINEMATIC:
            try:
                self.model = FootForces(quadruped)
            except LegFkError as error:  # a URDF without masses: no foot stands by force
                self.note = str(error)
        weight = self.model.total_mass_kg * STANDARD_GRAVITY if self.model else 1.0
        self.rule = ContactRule(ContactThresholds.for_weight(weight, *thresholds))

    def probabilities(
        self, angles: Sequence[float], efforts: Sequence[float] | None, down: Vector
    ) -> list[float] | None:
        """The 4 contact probabilities for one joint state's 12 merged ``angles`` [rad] and
        ``efforts`` [N m] (slot order; None: none) with gravity's unit direction ``down`` in the
        base frame; None where the stance is to be kinematic.
        """
        model = self.model
        if (
            model is None
            or efforts is None
            or (self.source == AUTO and not all(math.isfinite(value) for value in efforts))
        ):
            if self.source == FORCE:  # no force: no foot stands
                self.counts.force += 1
                return [math.nan] * len(self.rule.stance)
            self.counts.kinematic += 1
            return None
        self.counts.force += 1
        gravity = (
            down[0] * STANDARD_GRAVITY,
            down[1] * STANDARD_GRAVITY,
            down[2] * STANDARD_GRAVITY,
        )
        forces, _, _ = model.estimate_floats(angles, efforts, gravity)
        return self.rule.update([normal_force(force, down) for force in forces])
