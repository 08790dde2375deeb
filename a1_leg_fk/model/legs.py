"""Legs of a quadruped: RobotModel -> four :class:`LegChain` (FR, FL, RR, RL), and joint naming.

This module is the one place that decides the leg order, how feet are found, and which incoming
joint names mean which URDF joint.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from a1_leg_fk.model.urdf import Joint, LegFkError, RobotModel, Sphere

LEG_NAMES: tuple[str, ...] = ("FR", "FL", "RR", "RL")
"""Leg order everywhere in the package: front-right, front-left, rear-right, rear-left."""

JOINTS_PER_LEG = 3
JOINT_COUNT = len(LEG_NAMES) * JOINTS_PER_LEG
"""Joints of a configuration: three per leg, in :data:`LEG_NAMES` order (12)."""


def leg_slot(leg: str) -> int:
    """The slot 0..3 of ``leg`` in :data:`LEG_NAMES`; :class:`LegFkError` naming it if unknown."""
    try:
        return LEG_NAMES.index(leg)
    except ValueError:
        raise LegFkError(f"unknown leg '{leg}': legs are {list(LEG_NAMES)}") from None


FOOT_NAME_SUFFIXES: tuple[str, ...] = ("foot", "toe", "foot_link", "toe_link")
"""Where several leaf links of a leg qualify as its foot, the one named ``<leg>_<suffix>`` with one
of these suffixes (case-insensitive: ``FR_foot``, ``fr_toe``, ``FR_foot_link``) is the foot. Go2's
description has two qualifying leaves per leg: ``FR_foot`` and a shin collision link
``FR_calflower1``."""

UNITREE_NAME_PAIRS: tuple[tuple[str, str], ...] = (("upper", "thigh"), ("lower", "calf"))
"""Equivalent joint-name parts: pybullet_data's A1 says ``X_upper_joint``/``X_lower_joint`` where
Unitree's descriptions (unitree_ros, Gazebo, real-robot bridges) say
``X_thigh_joint``/``X_calf_joint``."""


@dataclass(frozen=True)
class LegChain:
    """One leg: the joints from the root link to the foot link, fixed joints included.

    ``movable`` holds the leg's three moving joints, root side first (hip roll, hip pitch, knee
    for the A1).
    """

    leg: str
    foot_link: str
    joints: tuple[Joint, ...]

    @property
    def movable(self) -> tuple[Joint, ...]:
        """The leg's moving joints, root side first."""
        return tuple(joint for joint in self.joints if joint.movable)


def find_legs(
    model: RobotModel, foot_links: Mapping[str, str] | None = None
) -> tuple[LegChain, ...]:
    """The four legs in :data:`LEG_NAMES` order.

    ``foot_links`` maps leg name -> foot link name; without it, the feet are the leaf links whose
    chain from the root holds exactly three movable joints, assigned to legs by name prefix
    (``FR_toe``, ``FR_foot``, ...); where a leg has several, the one named like a foot
    (:data:`FOOT_NAME_SUFFIXES`).
    """
    if foot_links:
        unknown_legs = sorted(set(foot_links) - set(LEG_NAMES))
        missing_legs = [leg for leg in LEG_NAMES if leg not in foot_links]
        if unknown_legs or missing_legs:
            raise LegFkError(
                f"{model.source}: foot_links must name exactly the legs {list(LEG_NAMES)}; "
                f"unknown {unknown_legs}, missing {missing_legs}"
            )
        feet = dict(foot_links)
    else:
        feet = _discover_feet(model)
    return tuple(_leg_chain(model, leg, feet[leg]) for leg in LEG_NAMES)


def _discover_feet(model: RobotModel) -> dict[str, str]:
    """Each leg's foot: its one leaf link with three movable joints above it, or, of several, the
    one named like a foot (:data:`FOOT_NAME_SUFFIXES`).
    """
    candidates = [
        link
        for link in model.links
        if not model.child_links(link)
        and sum(j.movable for j in _chain_or_empty(model, link)) == JOINTS_PER_LEG
    ]
    feet: dict[str, str] = {}
    for leg in LEG_NAMES:
        matching = [link for link in candidates if link.upper().startswith(leg)]
        if not matching:
            _explain_missing_foot(model, leg)
        if len(matching) > 1:
            named_foot = [link for link in matching if _named_like_a_foot(leg, link)]
            matching = named_foot if len(named_foot) == 1 else matching
        if len(matching) != 1:
            raise LegFkError(
                f"{model.source}: leg {leg}: expected one leaf link named '{leg}...' with three "
                "movable joints above it, or one of them named "
                f"{leg}_{'|'.join(FOOT_NAME_SUFFIXES)}; found {matching or 'none'} among "
                f"{candidates}; name the feet with foot_links"
            )
        feet[leg] = matching[0]
    return feet


def _named_like_a_foot(leg: str, link: str) -> bool:
    return link.lower() in {f"{leg.lower()}_{suffix}" for suffix in FOOT_NAME_SUFFIXES}


def _explain_missing_foot(model: RobotModel, leg: str) -> None:
    """Raise the chain error (e.g. a prismatic knee) of the leg's deepest leaf link, if it has
    one.
    """
    leaves = [
        link
        for link in model.links
        if link.upper().startswith(leg) and link != model.root and not model.child_links(link)
    ]
    if leaves:
        _leg_chain(model, leg, max(leaves, key=lambda link: len(model.chain_to(link))))


def _chain_or_empty(model: RobotModel, link: str) -> tuple[Joint, ...]:
    return model.chain_to(link) if link != model.root else ()


def _leg_chain(model: RobotModel, leg: str, foot_link: str) -> LegChain:
    if foot_link not in model.links:
        raise LegFkError(f"{model.source}: leg {leg}: foot link '{foot_link}' does not exist")
    chain = model.chain_to(foot_link)
    for joint in chain:
        if not joint.movable and joint.type != "fixed":
            raise LegFkError(
                f"{model.source}: leg {leg}: joint '{joint.name}' is {joint.type}; "
                "only revolute, continuous and fixed joints are supported"
            )
    movable = [joint.name for joint in chain if joint.movable]
    if len(movable) != JOINTS_PER_LEG:
        raise LegFkError(
            f"{model.source}: leg {leg}: the chain to foot link '{foot_link}' has {len(movable)} "
            f"movable joints {movable}, not {JOINTS_PER_LEG}"
        )
    return LegChain(leg, foot_link, chain)


def joint_name_index(
    legs: tuple[LegChain, ...], aliases: Mapping[str, str] | None = None
) -> dict[str, int]:
    """Map every accepted incoming joint name to its slot 0..11 (leg-major, root side first).

    Accepted: the URDF names, their Unitree/pybullet_data equivalents (see
    :data:`UNITREE_NAME_PAIRS`) where the model does not use that name itself, and the caller's
    ``aliases`` (incoming name -> URDF joint name), which take precedence.
    """
    index: dict[str, int] = {}
    for leg_slot, leg in enumerate(legs):
        for joint_slot, joint in enumerate(leg.movable):
            index[joint.name] = leg_slot * JOINTS_PER_LEG + joint_slot
    for name, slot in list(index.items()):
        for equivalent in _conventional_equivalents(name):
            index.setdefault(equivalent, slot)
    for incoming, urdf_name in (aliases or {}).items():
        if urdf_name not in index:
            raise LegFkError(
                f"joint alias '{incoming}={urdf_name}': '{urdf_name}' is not a leg joint of the "
                "model"
            )
        index[incoming] = index[urdf_name]
    return index


def _conventional_equivalents(joint_name: str) -> list[str]:
    """Other names the same joint goes by in the A1 naming conventions (may be empty)."""
    equivalents = []
    for first, second in UNITREE_NAME_PAIRS:
        for ours, theirs in ((first, second), (second, first)):
            suffix = f"_{ours}_joint"
            if joint_name.endswith(suffix):
                equivalents.append(joint_name[: -len(suffix)] + f"_{theirs}_joint")
    return equivalents


def foot_sphere(model: RobotModel, foot_link: str) -> Sphere | None:
    """The largest collision sphere of ``foot_link``, or ``None`` (a point foot at its origin)."""
    spheres = model.spheres.get(foot_link, ())
    return max(spheres, key=lambda sphere: sphere.radius) if spheres else None
