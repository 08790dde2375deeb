"""A leg's rigid *segments*: each movable joint's child link with every link fixed below it
(rotors, covers, the foot), as the statics and the dynamics of the leg see them.

Links under a movable joint outside the leg's chain are taken at that joint's zero angle; links
without an ``<inertial>`` have no mass. Everything is in the frame of the segment's joint (its
child link's frame): mass [kg], first moment ``m c`` [kg m] and the inertia tensor [kg m^2] about
the frame's origin.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.leg_stages import rpy_matrix
from a1_leg_fk.model.urdf import Inertial, RobotModel


@dataclass(frozen=True)
class Segment:
    """One segment's mass [kg], first moment [kg m] and inertia [kg m^2] about its frame's
    origin, in its frame (see the module text).
    """

    mass: float
    moment: np.ndarray  # (3,)
    inertia: np.ndarray  # (3, 3)


def leg_segments(model: RobotModel, leg: CompiledLeg) -> list[Segment]:
    """The three segments of ``leg``, root side first."""
    movable = leg.chain.movable
    return [
        segment(model, joint.child, movable[k + 1].name if k + 1 < len(movable) else None)
        for k, joint in enumerate(movable)
    ]


def segment(model: RobotModel, link: str, stop_joint: str | None) -> Segment:
    """The :class:`Segment` of ``link`` and everything below it, except below the joint named
    ``stop_joint``; other joints at their zero angle.
    """
    mass, moment, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
    pending = [(link, np.eye(3), np.zeros(3))]
    while pending:
        name, rotation, origin = pending.pop()
        inertial = model.inertials.get(name)
        if inertial is not None:
            center = origin + rotation @ np.array(inertial.center)
            mass += inertial.mass
            moment += inertial.mass * center
            inertia += _about_origin(inertial, rotation, center)
        pending.extend(
            (
                joint.child,
                rotation @ rpy_matrix(joint.origin_rpy),
                origin + rotation @ np.array(joint.origin_xyz),
            )
            for joint in model.joints.values()
            if joint.parent == name and joint.name != stop_joint
        )
    return Segment(mass, moment, inertia)


def _about_origin(inertial: Inertial, rotation: np.ndarray, center: np.ndarray) -> np.ndarray:
    """The inertia tensor [kg m^2] of one ``<inertial>`` about the segment frame's origin, in
    that frame: its own tensor turned by ``rotation`` (link to segment frame) and its inertial
    frame's ``rpy``, plus the parallel-axis term of its centre of mass ``center`` [m].
    """
    ixx, ixy, ixz, iyy, iyz, izz = inertial.inertia
    own = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    turn = rotation @ rpy_matrix(inertial.rpy)
    shift = inertial.mass * (center @ center * np.eye(3) - np.outer(center, center))
    result: np.ndarray = turn @ own @ turn.T + shift
    return result
