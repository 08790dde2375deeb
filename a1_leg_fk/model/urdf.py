"""URDF reading: XML (a file path or a string) -> :class:`RobotModel`.

Only what kinematics and leg statics need is kept: the links, each link's mass and centre of mass
(``<inertial>``: ``<mass value>`` [kg], ``<origin xyz>`` [m]) and collision spheres (a foot's
radius), and for every joint its type,
parent, child, ``<origin xyz rpy>`` (metres, radians), unit ``<axis>`` and ``<limit>``. Inertia
tensors, meshes, transmissions and everything else are ignored. No ROS and no PyBullet here.

The parser refuses DTD entity declarations outright, so an entity-expansion bomb ("billion
laughs") fails at once instead of expanding; a URDF never needs them.
"""

from __future__ import annotations

import math
import xml.parsers.expat
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

Vector3 = tuple[float, float, float]

MOVABLE_JOINT_TYPES = frozenset({"revolute", "continuous"})
AXIS_JOINT_TYPES = frozenset({"revolute", "continuous", "prismatic"})
"""The joint types that move along their ``<axis>``; on every other type (fixed, floating, planar)
the axis is not read at all, as urdfdom, robot_state_publisher and PyBullet do: CAD exporters write
``<axis xyz="0 0 0"/>`` on fixed joints (Unitree's Go2 and B2 descriptions)."""
KNOWN_JOINT_TYPES = frozenset(
    {"revolute", "continuous", "prismatic", "fixed", "floating", "planar"}
)
DEFAULT_AXIS: Vector3 = (1.0, 0.0, 0.0)  # the URDF specification's default
MAX_URDF_CHARS = 16 * 1024 * 1024
"""The largest robot description accepted [characters]: far above any real robot (Go2's is
~60 kB), and a bound on the memory a bad parameter or topic message can make us use."""


class LegFkError(ValueError):
    """The package's one error type: a robot description, a leg or an input it cannot use.

    The message always names the file, joint, link or leg at fault.
    """


@dataclass(frozen=True)
class Joint:
    """One URDF joint.

    ``origin_xyz`` [m] and ``origin_rpy`` [rad, fixed-axis roll-pitch-yaw] place the joint frame
    in the parent link's frame; ``axis`` is a unit vector in the joint frame: the default (1, 0, 0)
    for the types that have none, whatever the file says (see :data:`AXIS_JOINT_TYPES`). ``lower``
    and ``upper`` [rad] are ``None`` where the joint has no position limit (continuous, fixed).
    """

    name: str
    type: str
    parent: str
    child: str
    origin_xyz: Vector3
    origin_rpy: Vector3
    axis: Vector3
    lower: float | None
    upper: float | None

    @property
    def movable(self) -> bool:
        """True for joints whose angle moves the child (revolute, continuous)."""
        return self.type in MOVABLE_JOINT_TYPES


@dataclass(frozen=True)
class Inertial:
    """A link's ``<inertial>``: mass [kg], centre of mass [m, in the link frame], the inertial
    frame's orientation ``rpy`` [rad] in the link frame, and the inertia tensor [kg m^2] about the
    centre of mass in that frame, ``(ixx, ixy, ixz, iyy, iyz, izz)`` (zeros without ``<inertia>``).
    """

    mass: float
    center: Vector3
    rpy: Vector3 = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (0.0,) * 6


@dataclass(frozen=True)
class Sphere:
    """A ``<collision>`` sphere: radius [m] and centre [m, in the link frame]."""

    radius: float
    center: Vector3


@dataclass(frozen=True)
class RobotModel:
    """The kinematic tree of a URDF: links, joints by name, and the root link (base frame);
    ``inertials`` holds the links that have an ``<inertial>`` (a link without one has no mass),
    ``spheres`` the ``<collision>`` spheres of the links that have any.
    """

    name: str
    source: str
    links: tuple[str, ...]
    joints: Mapping[str, Joint]
    root: str
    inertials: Mapping[str, Inertial] = field(default_factory=dict)
    spheres: Mapping[str, tuple[Sphere, ...]] = field(default_factory=dict)
    _parent_joints: Mapping[str, Joint] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_parent_joints", {j.child: j for j in self.joints.values()})

    def child_links(self, link: str) -> tuple[str, ...]:
        """The links attached below ``link``, in document order."""
        return tuple(j.child for j in self.joints.values() if j.parent == link)

    def chain_to(self, link: str) -> tuple[Joint, ...]:
        """Joints from the root down to ``link`` (fixed joints included), root side first."""
        if link not in self._parent_joints and link != self.root:
            raise LegFkError(f"{self.source}: link '{link}' does not exist")
        chain: list[Joint] = []
        joint = self._parent_joints.get(link)
        while joint is not None:
            chain.append(joint)
            joint = self._parent_joints.get(joint.parent)
        return tuple(reversed(chain))


def default_urdf_path() -> Path:
    """Path of the embedded default model, ``a1/a1.urdf`` in the ``pybullet_data`` package."""
    try:
        import pybullet_data
    except ImportError as error:
        raise LegFkError(
            "the default A1 model lives in the pybullet package's pybullet_data "
            "(pip install pybullet); give a URDF path or XML string instead"
        ) from error
    return Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"


def load_urdf(source: str | Path | None = None) -> RobotModel:
    """Read a URDF from a file path, an XML string, or (``None``) the embedded default A1."""
    return parse_urdf(*read_urdf_text(source))


def read_urdf_text(source: str | Path | None = None) -> tuple[str, str]:
    """``(XML text, name for messages)`` of a URDF path, an XML string, or ``None`` (the embedded
    A1).

    The one place that reads robot descriptions; the text passes :func:`checked_urdf_text`.
    """
    if source is None:
        source = default_urdf_path()
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return checked_urdf_text(source, "<robot_description>"), "<robot_description>"
    name = str(source)
    try:
        with open(source, encoding="utf-8") as file:
            text = file.read(MAX_URDF_CHARS + 1)  # a larger file is refused without reading it all
    except (OSError, UnicodeDecodeError) as error:
        raise LegFkError(f"{name}: cannot read URDF file: {error}") from error
    return checked_urdf_text(text, name), name


def checked_urdf_text(text: str, name: str) -> str:
    """``text`` without leading white space, if it can be a URDF of an accepted size.

    At most :data:`MAX_URDF_CHARS` characters; leading white space is removed (a triple-quoted
    string in a launch file would put the XML declaration "not at start of entity", which expat
    refuses); text that does not start with ``<`` is refused.
    """
    if len(text) > MAX_URDF_CHARS:
        raise LegFkError(
            f"{name}: more than the {MAX_URDF_CHARS} characters accepted for a robot description"
        )
    text = text.lstrip()
    if not text.startswith("<"):
        raise LegFkError(f"{name}: not URDF XML")
    return text


def parse_urdf(xml_text: str, source: str = "<string>") -> RobotModel:
    """Parse URDF XML text; ``source`` names it in error messages."""
    robot = _parse_xml(xml_text, source)
    if robot.tag != "robot":
        raise LegFkError(f"{source}: the root element is <{robot.tag}>, not <robot>")
    links = tuple(_required_attribute(e, "name", source) for e in robot.findall("link"))
    if not links:
        raise LegFkError(f"{source}: <robot> has no <link>")
    duplicate_links = sorted({name for name in links if links.count(name) > 1})
    if duplicate_links:
        raise LegFkError(f"{source}: duplicate link names {duplicate_links}")
    joints: dict[str, Joint] = {}
    for element in robot.findall("joint"):  # direct children only: not those of <transmission>
        joint = _parse_joint(element, source)
        if joint.name in joints:
            raise LegFkError(f"{source}: duplicate joint name '{joint.name}'")
        joints[joint.name] = joint
    root = _check_tree(links, joints, source)
    inertials = {
        link.get("name", ""): _parse_inertial(inertial, f"{source}: link '{link.get('name')}'")
        for link in robot.findall("link")
        if (inertial := link.find("inertial")) is not None
    }
    spheres = {
        link.get("name", ""): found
        for link in robot.findall("link")
        if (found := _collision_spheres(link, f"{source}: link '{link.get('name')}'"))
    }
    return RobotModel(robot.get("name", ""), source, links, joints, root, inertials, spheres)


def _parse_xml(xml_text: str, source: str) -> ElementTree.Element:
    """Parse with expat into an ElementTree, refusing DTD entity declarations."""
    builder = ElementTree.TreeBuilder()
    parser = xml.parsers.expat.ParserCreate()

    def refuse_entity(name: str, *_: object) -> None:
        raise LegFkError(
            f"{source}: XML entity declarations are not allowed in a URDF (entity '{name}')"
        )

    parser.EntityDeclHandler = refuse_entity
    parser.StartElementHandler = builder.start
    parser.EndElementHandler = builder.end
    try:
        parser.Parse(xml_text, True)
    except xml.parsers.expat.ExpatError as error:
        raise LegFkError(f"{source}: malformed XML: {error}") from error
    try:
        return builder.close()
    except AssertionError as error:  # TreeBuilder with no element at all
        raise LegFkError(f"{source}: no XML element found") from error


def _parse_joint(element: ElementTree.Element, source: str) -> Joint:
    name = _required_attribute(element, "name", source)
    where = f"{source}: joint '{name}'"
    joint_type = _required_attribute(element, "type", where)
    if joint_type not in KNOWN_JOINT_TYPES:
        raise LegFkError(f"{where}: unknown joint type '{joint_type}'")
    parent = _link_reference(element, "parent", where)
    child = _link_reference(element, "child", where)
    origin = element.find("origin")
    xyz = _vector(origin, "xyz", (0.0, 0.0, 0.0), where)
    rpy = _vector(origin, "rpy", (0.0, 0.0, 0.0), where)
    axis = DEFAULT_AXIS
    if joint_type in AXIS_JOINT_TYPES:
        axis = _unit_axis(_vector(element.find("axis"), "xyz", DEFAULT_AXIS, where), where)
    lower, upper = _limits(element, joint_type, where)
    return Joint(name, joint_type, parent, child, xyz, rpy, axis, lower, upper)


def _parse_inertial(element: ElementTree.Element, where: str) -> Inertial:
    """Mass [kg] (0 without ``<mass>``: FK never needed it), centre of mass [m], orientation and
    inertia tensor [kg m^2] of an ``<inertial>``.
    """
    mass_element = element.find("mass")
    text = "0" if mass_element is None else mass_element.get("value", "0")
    try:
        mass = float(text)
    except ValueError as error:
        raise LegFkError(f"{where}: <mass value='{text}'> is not a number") from error
    if not (math.isfinite(mass) and mass >= 0.0):
        raise LegFkError(f"{where}: <mass value='{text}'> is not a finite mass >= 0")
    origin = element.find("origin")
    return Inertial(
        mass,
        _vector(origin, "xyz", (0.0, 0.0, 0.0), where),
        _vector(origin, "rpy", (0.0, 0.0, 0.0), where),
        _inertia(element.find("inertia"), where),
    )


def _inertia(
    element: ElementTree.Element | None, where: str
) -> tuple[float, float, float, float, float, float]:
    """``(ixx, ixy, ixz, iyy, iyz, izz)`` [kg m^2] of an ``<inertia>`` (missing: zeros)."""
    values = []
    for name in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
        text = "0" if element is None else element.get(name, "0")
        try:
            values.append(float(text))
        except ValueError as error:
            raise LegFkError(f"{where}: <inertia {name}='{text}'> is not a number") from error
    if not all(math.isfinite(value) for value in values):
        raise LegFkError(f"{where}: <inertia> has a value that is not finite")
    ixx, ixy, ixz, iyy, iyz, izz = values
    return ixx, ixy, ixz, iyy, iyz, izz


def _collision_spheres(link: ElementTree.Element, where: str) -> tuple[Sphere, ...]:
    spheres = []
    for collision in link.findall("collision"):
        sphere = collision.find("geometry/sphere")
        if sphere is None:
            continue
        try:
            radius = float(sphere.get("radius", ""))
        except ValueError as error:
            raise LegFkError(f"{where}: <sphere radius> is not a number") from error
        if not (math.isfinite(radius) and radius >= 0.0):
            raise LegFkError(f"{where}: <sphere radius='{radius}'> is not a finite radius >= 0")
        spheres.append(Sphere(radius, _vector(collision.find("origin"), "xyz", (0.0,) * 3, where)))
    return tuple(spheres)


def _required_attribute(element: ElementTree.Element, attribute: str, where: str) -> str:
    value = element.get(attribute)
    if not value:
        raise LegFkError(f"{where}: <{element.tag}> has no '{attribute}' attribute")
    return value


def _link_reference(joint: ElementTree.Element, tag: str, where: str) -> str:
    element = joint.find(tag)
    if element is None:
        raise LegFkError(f"{where}: missing <{tag}>")
    return _required_attribute(element, "link", where)


def _vector(
    element: ElementTree.Element | None, attribute: str, default: Vector3, where: str
) -> Vector3:
    text = None if element is None else element.get(attribute)
    if text is None:
        return default
    try:
        values = tuple(float(part) for part in text.split())
    except ValueError as error:
        raise LegFkError(f"{where}: {attribute}='{text}' is not three numbers") from error
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise LegFkError(f"{where}: {attribute}='{text}' is not three finite numbers")
    return values


def _unit_axis(axis: Vector3, where: str) -> Vector3:
    norm = math.sqrt(sum(component * component for component in axis))
    if norm == 0.0:
        raise LegFkError(f"{where}: axis is the zero vector")
    return (axis[0] / norm, axis[1] / norm, axis[2] / norm)


def _limits(
    element: ElementTree.Element, joint_type: str, where: str
) -> tuple[float | None, float | None]:
    """(lower, upper) [rad] for revolute joints; (None, None) for every other type."""
    if joint_type != "revolute":
        return None, None
    limit = element.find("limit")
    if limit is None:
        raise LegFkError(f"{where}: a revolute joint needs a <limit>")
    try:
        lower = float(limit.get("lower", "0"))
        upper = float(limit.get("upper", "0"))
    except ValueError as error:
        raise LegFkError(f"{where}: <limit> lower/upper are not numbers") from error
    if not lower <= upper:
        raise LegFkError(f"{where}: <limit> lower={lower} is above upper={upper}")
    return lower, upper


def _check_tree(links: tuple[str, ...], joints: Mapping[str, Joint], source: str) -> str:
    """Check that the joints form one tree over the links; return its root link."""
    known = set(links)
    parent_of: dict[str, str] = {}
    for joint in joints.values():
        for role, link in (("parent", joint.parent), ("child", joint.child)):
            if link not in known:
                raise LegFkError(
                    f"{source}: joint '{joint.name}' names {role} link '{link}', which does not "
                    "exist"
                )
        if joint.child in parent_of:
            raise LegFkError(f"{source}: link '{joint.child}' is the child of more than one joint")
        parent_of[joint.child] = joint.parent
    cyclic = _link_on_cycle(parent_of)
    if cyclic is not None:
        raise LegFkError(f"{source}: the joints form a cycle through link '{cyclic}'")
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        raise LegFkError(f"{source}: expected one root link, found {len(roots)}: {roots[:10]}")
    return roots[0]


def _link_on_cycle(parent_of: Mapping[str, str]) -> str | None:
    """A link on a parent cycle, or ``None`` when every parent path ends at a root (linear
    time).
    """
    reaches_root: set[str] = set()
    for start in parent_of:
        path: list[str] = []
        on_path: set[str] = set()
        link: str | None = start
        while link is not None and link not in reaches_root:
            if link in on_path:
                return link
            path.append(link)
            on_path.add(link)
            link = parent_of.get(link)
        reaches_root.update(path)
    return None
