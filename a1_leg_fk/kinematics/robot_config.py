"""Which robot: the model settings (a description or a file, foot links, joint aliases) -> a
compiled :class:`~a1_leg_fk.kinematics.quadruped.Quadruped` and the URDF text it was built from.

One place for what ``foot_fk_node``, ``foot_ik_node`` and the bag tool accept as a robot, so that
a description is read, capped and validated the same way wherever it comes from. No ROS here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError, checked_urdf_text, parse_urdf, read_urdf_text


@dataclass(frozen=True)
class RobotConfig:
    """A compiled robot with the URDF text it came from (for the PyBullet twin) and its source:
    ``"robot_description"``, a file path, or the embedded A1's path.
    """

    quadruped: Quadruped
    urdf_xml: str
    source: str


def load_robot(
    robot_description: str = "",
    urdf_file: str = "",
    foot_links: Sequence[str] = (),
    joint_aliases: Sequence[str] = (),
    description_name: str = "robot_description",
) -> RobotConfig:
    """The robot for these settings; :class:`LegFkError` names what is wrong.

    ``robot_description`` (URDF XML) wins over ``urdf_file`` (a path); with neither, the embedded
    A1. ``foot_links`` and ``joint_aliases`` are ``KEY=value`` entries (see :func:`key_values`);
    ``description_name`` names the description in messages (e.g. a topic).
    """
    if robot_description:
        xml, source = checked_urdf_text(robot_description, description_name), description_name
    else:
        xml, source = read_urdf_text(urdf_file or None)
    quadruped = Quadruped(
        parse_urdf(xml, source),
        key_values(foot_links, "foot_links") or None,
        key_values(joint_aliases, "joint_aliases"),
    )
    return RobotConfig(quadruped, xml, source)


def key_values(entries: Sequence[str], setting: str) -> Mapping[str, str]:
    """``["A=b", ...]`` -> ``{"A": "b"}`` (white space around keys and values removed); empty
    entries are skipped. ``setting`` names the list in the error for a malformed entry.
    """
    pairs = {}
    for entry in entries:
        if not entry:
            continue
        key, separator, value = entry.partition("=")
        if not separator or not key.strip() or not value.strip():
            raise LegFkError(f"{setting}: entry '{entry}' is not of the form key=value")
        pairs[key.strip()] = value.strip()
    return pairs
