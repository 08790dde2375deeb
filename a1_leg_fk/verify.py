"""The independent check: the same URDF in PyBullet, compared foot by foot with our FK.

PyBullet is imported lazily, so everything else in the package runs without it. Each
:class:`PyBulletFeet` owns a DIRECT client of its own with the robot's base fixed at the origin;
:meth:`PyBulletFeet.foot_positions` sets every joint with ``resetJointState`` (which ignores joint
limits) and reads each foot's *link frame* position, ``getLinkState(...,
computeForwardKinematics=True)[4]`` — not ``[0]``, the centre of mass. PyBullet computes in
float32, so agreement is ~3e-8 m, not 0.
"""

from __future__ import annotations

import importlib
import math
import os
import tempfile
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from xml.etree import ElementTree

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

INSTALL_HINT = (
    "pybullet is not installed: pip install pybullet (or apt/rosdep key python3-pybullet-pip)"
)
MAX_LINE_BYTES = 4096
"""The longest line the twin file may have [bytes]. PyBullet's URDF reader reads a file in lines
of at most 8,191 bytes and starts a new line after each such piece, so a longer line is cut at a
fixed offset (the load fails, or a name is silently split)."""
KEPT_ELEMENTS = ("link", "joint")
"""The children of ``<robot>`` the twin keeps: the tree. Materials, ``<gazebo>`` and
``<transmission>`` blocks play no part in link frames."""


@dataclass(frozen=True)
class VerifyResult:
    """Per-leg distance [m] between our foot positions and PyBullet's, for one configuration."""

    errors_m: Mapping[str, float]
    tolerance_m: float

    @property
    def max_error_m(self) -> float:
        """The largest per-leg error [m]."""
        return max(self.errors_m.values())

    @property
    def success(self) -> bool:
        """True when every foot is within the tolerance."""
        return self.max_error_m <= self.tolerance_m


def import_pybullet() -> ModuleType:
    """The ``pybullet`` module, or a :class:`LegFkError` that says how to install it."""
    if os.environ.get("A1_LEG_FK_HIDE_PYBULLET"):  # lets tests and users run as if it were absent
        raise LegFkError(INSTALL_HINT)
    try:
        return importlib.import_module("pybullet")  # untyped: its attributes are Any
    except ImportError as error:
        raise LegFkError(INSTALL_HINT) from error


class PyBulletFeet:
    """A quadruped loaded into a PyBullet DIRECT client of its own, fixed at the origin."""

    def __init__(self, quadruped: Quadruped, urdf_xml: str) -> None:
        """Load ``urdf_xml`` (the text the quadruped was built from); PyBullet errors become
        LegFkError.
        """
        self._pybullet = import_pybullet()
        self._quadruped = quadruped
        self._client = self._pybullet.connect(self._pybullet.DIRECT)
        try:
            self._body = self._load(urdf_xml)
            self._joint_index, self._link_index = self._index_joints_and_links()
            self._foot_links = [
                self._lookup(self._link_index, leg.chain.foot_link, "link")
                for leg in quadruped.legs
            ]
            self._movable_joints = [
                self._lookup(self._joint_index, name, "joint") for name in quadruped.joint_names
            ]
        except BaseException:
            self.close()
            raise

    def foot_positions(self, angles: Sequence[float]) -> list[tuple[float, float, float]]:
        """Foot link-frame positions [m] in the base frame for 12 angles [rad], FR, FL, RR, RL."""
        pybullet, client = self._pybullet, self._client
        for joint, angle in zip(self._movable_joints, angles):
            pybullet.resetJointState(self._body, joint, angle, physicsClientId=client)
        return [
            tuple(
                pybullet.getLinkState(
                    self._body, link, computeForwardKinematics=True, physicsClientId=client
                )[4]
            )
            for link in self._foot_links
        ]

    def verify(self, angles: Sequence[float], tolerance_m: float) -> VerifyResult:
        """Compare our FK with PyBullet's for one configuration [rad]."""
        ours = self._quadruped.fk(angles)
        theirs = self.foot_positions(angles)
        errors = {leg: math.dist(ours[slot], theirs[slot]) for slot, leg in enumerate(LEG_NAMES)}
        return VerifyResult(errors, tolerance_m)

    def close(self) -> None:
        """Disconnect the client (idempotent)."""
        if self._client is not None and self._client >= 0:
            self._pybullet.disconnect(physicsClientId=self._client)
        self._client = None

    def _load(self, urdf_xml: str) -> int:
        text = kinematic_urdf(urdf_xml)
        with tempfile.TemporaryDirectory(prefix="a1_leg_fk_") as folder:
            # a name never used before: PyBullet caches file contents by path
            path = os.path.join(folder, f"robot_{uuid.uuid4().hex}.urdf")
            with open(path, "w", encoding="utf-8") as file:
                file.write(text)
            try:
                return int(  # pybullet has no types: its body id, an int
                    self._pybullet.loadURDF(path, useFixedBase=True, physicsClientId=self._client)
                )
            except self._pybullet.error as error:
                raise LegFkError(f"PyBullet could not load the URDF: {error}") from error

    def _index_joints_and_links(self) -> tuple[dict[str, int], dict[str, int]]:
        joints, links = {}, {}
        for index in range(self._pybullet.getNumJoints(self._body, physicsClientId=self._client)):
            info = self._pybullet.getJointInfo(self._body, index, physicsClientId=self._client)
            joints[info[1].decode()] = index
            links[info[12].decode()] = index  # a link's index is that of the joint above it
        return joints, links

    @staticmethod
    def _lookup(index: Mapping[str, int], name: str, what: str) -> int:
        if name not in index:
            raise LegFkError(f"PyBullet's model has no {what} '{name}'")
        return index[name]


def kinematic_urdf(urdf_xml: str) -> str:
    """The URDF's links and joints without ``<visual>`` and ``<collision>``, one element per
    line: PyBullet then needs no mesh files, and reads every line whole, whatever the layout of
    ``urdf_xml`` (a description given with ``-p robot_description:=...`` arrives on one line).

    Geometry plays no part in the link frames compared here; joints, origins, axes and
    inertials are kept as they are. A :class:`LegFkError` if a line is still longer than
    :data:`MAX_LINE_BYTES` (an attribute of kilobytes).
    """
    robot = ElementTree.fromstring(urdf_xml)
    for element in list(robot):
        if element.tag not in KEPT_ELEMENTS:
            robot.remove(element)
    for link in robot.findall("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
    robot.text = robot.tail = None
    ElementTree.indent(robot)
    text = ElementTree.tostring(robot, encoding="unicode") + "\n"
    for number, line in enumerate(text.splitlines(), 1):
        if len(line.encode("utf-8")) > MAX_LINE_BYTES:
            raise LegFkError(
                f"the URDF has an element of {len(line.encode('utf-8'))} bytes on one line "
                f"(line {number} of its kinematic copy: {line[:80]}...); PyBullet reads lines of "
                f"at most {MAX_LINE_BYTES} bytes here"
            )
    return text
