"""Robot descriptions in the style of published, exporter-written quadruped URDFs, made by the
tests.

Unitree's own descriptions (unitreerobotics/unitree_ros, ``robots/*_description/urdf/``) were read
to learn their structure; none of their text is copied here. What they do that a hand-written URDF
does not, always present:

- an XML declaration, then a SolidWorks-exporter comment header with ``key: value`` text;
- ``<axis xyz="0 0 0"/>`` (and ``dont_collapse="true"``) on fixed joints;
- sensor and camera links (imu, lidar/radar, depth cameras with odd rpy), zero or 1e-15 masses,
  links with no ``<inertial>``;
- ``<gazebo>`` blocks (plugins, ``<visual>`` inside ``<gazebo reference>``) and ``<transmission>``
  blocks whose ``<joint>`` children are not joints of the tree;
- visuals that are ``package://`` meshes of packages that are not installed (unless
  ``meshes=False``).

Switchable, so that a test can isolate it:

- CRLF line endings;
- a shin collision link under the calf (``X_calflower`` -> ``X_calflower1``, Go2): a second leaf
  link per leg with three movable joints above it, beside the real foot ``X_foot``;
- rotor links (``X_hip_rotor``, ``X_thigh_rotor``, ``X_calf_rotor``, B2): fixed leaves with two,
  one or no movable joint above them.

Geometry: the published facts of each robot (origins, lengths, limits), listed in :data:`ROBOTS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TypedDict

from pybullet_reference import PyBulletRobot
from shared import LEGS

FEET = [f"{leg}_foot" for leg in LEGS]


class Quirks(TypedDict, total=False):
    """Options of :func:`exported_quadruped` that a robot's fixture sets."""

    root: str
    rotors: bool
    crlf: bool


QUIRKS: dict[str, Quirks] = {
    "go2": {},
    "b2": {"root": "base_link", "rotors": True, "crlf": True},
}
"""The quirks each robot's fixture carries in the tests (Go2: those of its defaults)."""


@dataclass(frozen=True)
class LegGeometry:
    """A Unitree-style leg: hip roll about x, thigh and calf pitch about y (metres, radians)."""

    hip_x: float  # hip joint origin in the root frame: (±hip_x, ±hip_y, 0)
    hip_y: float
    thigh_y: float  # hip -> thigh joint, along ±y (left +, right -)
    thigh_length: float  # thigh -> calf joint, along -z
    calf_length: float  # calf -> foot, along -z
    calf_y: float  # a small sideways calf offset some exports carry (B2: -8.6984e-05 m)
    hip_limits: tuple[float, float]
    front_thigh_limits: tuple[float, float]
    rear_thigh_limits: tuple[float, float]
    calf_limits: tuple[float, float]


ROBOTS = {
    "go2": LegGeometry(
        0.1934,
        0.0465,
        0.0955,
        0.213,
        0.213,
        0.0,
        (-1.0472, 1.0472),
        (-1.5708, 3.4907),
        (-0.5236, 4.5379),
        (-2.7227, -0.83776),
    ),
    "b2": LegGeometry(
        0.3285,
        0.072,
        0.11973,
        0.35,
        0.35,
        -8.6984e-05,
        (-0.87, 0.87),
        (-0.94, 4.69),
        (-0.94, 4.69),
        (-2.82, -0.43),
    ),
}

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- This URDF was automatically created by a CAD to URDF exporter (test fixture).
     Commit Version: 1.6.0-4-g7f85cfe  Build Version: 1.6.7995.38578
     For more information, please see: the exporter's wiki -->
"""


def exported_quadruped(
    robot: str = "go2",
    *,
    root: str = "base",
    crlf: bool = False,
    shin_links: bool = True,
    rotors: bool = False,
    meshes: bool = True,
    mesh_folder: str = "package://not_installed_description/dae",
) -> str:
    """URDF XML of a quadruped with ``robot``'s geometry and the chosen exporter quirks.

    With ``meshes=False`` the same robot carries no mesh (primitives only): the reference PyBullet
    loads that one, so the test's reference never depends on the code under test's mesh handling.
    ``mesh_folder`` is where the meshes would be: a ``package://`` URI or a file path.
    """
    geometry = ROBOTS[robot]
    parts = [HEADER, f'<robot\n  name="{robot}_like_description">\n']
    parts.append(
        _link(
            root,
            _box_visual(meshes, mesh_folder, "base"),
            mass="6.921",
            com="0.021112 0 -0.005366",
        )
    )
    parts.append(_sensors(root))
    parts.extend(
        _leg(leg, root, geometry, shin_links, rotors, meshes, mesh_folder) for leg in LEGS
    )
    parts.append(_gazebo_and_transmissions(root))
    parts.append("</robot>\n")
    text = "".join(parts)
    return text.replace("\n", "\r\n") if crlf else text


def _leg(
    leg: str,
    root: str,
    g: LegGeometry,
    shin_links: bool,
    rotors: bool,
    meshes: bool,
    mesh_folder: str,
) -> str:
    front, left = leg[0] == "F", leg[1] == "L"
    x, y = (g.hip_x if front else -g.hip_x), (g.hip_y if left else -g.hip_y)
    side = 1.0 if left else -1.0
    thigh_limits = g.front_thigh_limits if front else g.rear_thigh_limits
    text = [
        _link(
            f"{leg}_hip",
            _box_visual(meshes, mesh_folder, "hip"),
            mass="0.678",
            com="-0.0054 0.00194 -0.000105",
        ),
        _revolute(f"{leg}_hip_joint", root, f"{leg}_hip", f"{x!r} {y!r} 0", "1 0 0", g.hip_limits),
        _link(
            f"{leg}_thigh",
            _box_visual(meshes, mesh_folder, "thigh"),
            mass="1.152",
            com="-0.00374 -0.0223 -0.0327",
        ),
        _revolute(
            f"{leg}_thigh_joint",
            f"{leg}_hip",
            f"{leg}_thigh",
            f"0 {side * g.thigh_y!r} 0",
            "0 1 0",
            thigh_limits,
        ),
        _link(
            f"{leg}_calf",
            _box_visual(meshes, mesh_folder, "calf"),
            mass="0.154",
            com="0.00548 -0.000975 -0.115",
        ),
        _revolute(
            f"{leg}_calf_joint",
            f"{leg}_thigh",
            f"{leg}_calf",
            f"0 {g.calf_y!r} {-g.thigh_length!r}",
            "0 1 0",
            g.calf_limits,
        ),
        _link(f"{leg}_foot", _box_visual(meshes, mesh_folder, "foot"), mass="0.04", com="0 0 0"),
        _fixed(
            f"{leg}_foot_joint",
            f"{leg}_calf",
            f"{leg}_foot",
            f"0 0 {-g.calf_length!r}",
            "0 0 0",
            dont_collapse=True,
        ),
    ]
    if shin_links:  # collision-only links with no <inertial>, the second one a leaf under the calf
        text += [
            (
                f'  <link\n    name="{leg}_calflower">\n'
                "    <collision>\n"
                "      <geometry>\n"
                '        <cylinder length="0.065" radius="0.011" />\n'
                "      </geometry>\n"
                "    </collision>\n"
                "  </link>\n"
            ),
            _fixed(
                f"{leg}_calflower_joint",
                f"{leg}_calf",
                f"{leg}_calflower",
                "0.020 0 -0.148",
                "0 0.05 0",
            ),
            (
                f'  <link\n    name="{leg}_calflower1">\n'
                "    <collision>\n"
                "      <geometry>\n"
                '        <cylinder length="0.03" radius="0.0155" />\n'
                "      </geometry>\n"
                "    </collision>\n"
                "  </link>\n"
            ),
            _fixed(
                f"{leg}_calflower1_joint",
                f"{leg}_calflower",
                f"{leg}_calflower1",
                "-0.01 0 -0.04",
                "0 0.48 0",
            ),
        ]
    if rotors:  # fixed leaves with 0, 1 and 2 movable joints above them; written with no <axis>
        for rotor, parent, origin in (
            ("hip", root, f"{0.6 * x!r} {y!r} 0"),
            ("thigh", f"{leg}_hip", f"0 {-side * 0.008!r} 0"),
            ("calf", f"{leg}_thigh", f"0 {-side * 0.058!r} 0"),
        ):
            text.append(
                f'  <link name="{leg}_{rotor}_rotor">\n'
                "    <inertial>\n"
                '      <origin rpy="0 0 0" xyz="0.0 0.0 0.0"/>\n'
                '      <mass value="0.2734"/>\n'
                '      <inertia ixx="0.000144463" ixy="0.0" ixz="0.0" iyy="0.000144463" '
                'iyz="0.0" izz="0.000263053"/>\n'
                "    </inertial>\n"
                "  </link>\n"
            )
            text.append(
                f'  <joint name="{leg}_{rotor}_rotor_joint" type="fixed">\n'
                f'    <origin rpy="0 0 0" xyz="{origin}"/>\n'
                f'    <parent link="{parent}"/>\n'
                f'    <child link="{leg}_{rotor}_rotor"/>\n'
                "  </joint>\n"
            )
    return "".join(text)


def _sensors(root: str) -> str:
    links = []
    for name, origin, rpy, mass in (
        ("imu", "-0.02557 0 0.04232", "0 0 0", "0"),
        ("radar", "0.28945 0 -0.046825", "0 2.8782 0", "0"),
        ("lidar_link", "0.34218 0 0.17851", "0 0 0", "4.19E-15"),
        ("f_dc_link", "0.41251 0.024997 0.04765", "-2.3562 0 -1.5708", "4.19E-15"),
    ):
        links.append(
            _link(name, "", mass=mass, com="0 0 0", inertia="0" if mass == "0" else "1.68E-27")
        )
        links.append(_fixed(f"{name}_joint", root, name, origin, rpy))
    return "".join(links)


def _link(name: str, visual: str, mass: str, com: str, inertia: str = "9.6e-06") -> str:
    return (
        f'  <link\n    name="{name}">\n'
        "    <inertial>\n"
        "      <origin\n"
        f'        xyz="{com}"\n'
        '        rpy="0 0 0" />\n'
        "      <mass\n"
        f'        value="{mass}" />\n'
        "      <inertia\n"
        f'        ixx="{inertia}"\n'
        '        ixy="0"\n'
        '        ixz="0"\n'
        f'        iyy="{inertia}"\n'
        '        iyz="0"\n'
        f'        izz="{inertia}" />\n'
        "    </inertial>\n"
        f"{visual}  </link>\n"
    )


def _box_visual(meshes: bool, mesh_folder: str, part: str) -> str:
    geometry = (
        f'<mesh\n          filename="{mesh_folder}/{part}.dae" />'
        if meshes
        else '<box size="0.02 0.02 0.02" />'
    )
    collision = geometry if meshes else '<sphere radius="0.01" />'
    return (
        "    <visual>\n"
        "      <origin\n"
        '        xyz="0 0 0"\n'
        '        rpy="0 0 0" />\n'
        "      <geometry>\n"
        f"        {geometry}\n"
        "      </geometry>\n"
        "      <material\n"
        '        name="">\n'
        "        <color\n"
        '          rgba="1 1 1 1" />\n'
        "      </material>\n"
        "    </visual>\n"
        "    <collision>\n"
        '      <origin rpy="0 0 0" xyz="0 0 0" />\n'
        "      <geometry>\n"
        f"        {collision}\n"
        "      </geometry>\n"
        "    </collision>\n"
    )


def _revolute(
    name: str, parent: str, child: str, xyz: str, axis: str, limits: tuple[float, float]
) -> str:
    return (
        f'  <joint\n    name="{name}"\n'
        '    type="revolute">\n'
        "    <origin\n"
        f'      xyz="{xyz}"\n'
        '      rpy="0 0 0" />\n'
        "    <parent\n"
        f'      link="{parent}" />\n'
        "    <child\n"
        f'      link="{child}" />\n'
        "    <axis\n"
        f'      xyz="{axis}" />\n'
        "    <limit\n"
        f'      lower="{limits[0]!r}"\n'
        f'      upper="{limits[1]!r}"\n'
        '      effort="23.7"\n'
        '      velocity="30.1" />\n'
        "  </joint>\n"
    )


def _fixed(
    name: str, parent: str, child: str, xyz: str, rpy: str, dont_collapse: bool = False
) -> str:
    """A fixed joint, written with the exporters' ``<axis xyz="0 0 0"/>``."""
    collapse = ' dont_collapse="true"' if dont_collapse else ""
    return (
        f'  <joint\n    name="{name}"\n'
        f'    type="fixed"{collapse}>\n'
        "    <origin\n"
        f'      xyz="{xyz}"\n'
        f'      rpy="{rpy}" />\n'
        "    <parent\n"
        f'      link="{parent}" />\n'
        "    <child\n"
        f'      link="{child}" />\n'
        '    <axis\n      xyz="0 0 0" />\n'
        "  </joint>\n"
    )


def _gazebo_and_transmissions(root: str) -> str:
    blocks = [
        (
            "  <gazebo>\n"
            '    <plugin filename="libgazebo_ros_control.so" name="gazebo_ros_control">\n'
            "      <robotNamespace>/robot_gazebo</robotNamespace>\n"
            "    </plugin>\n"
            "  </gazebo>\n"
        ),
        f'  <gazebo reference="{root}">\n    <material>Gazebo/Green</material>\n  </gazebo>\n',
    ]
    for leg in LEGS:
        blocks.append(
            f'  <gazebo reference="{leg}_foot">\n'
            "    <visual>\n"
            '      <plugin filename="libDrawForce.so" name="drawForcePlugin">\n'
            f"        <topicName>{leg}_foot_contact</topicName>\n"
            "      </plugin>\n"
            "    </visual>\n"
            "  </gazebo>\n"
        )
        blocks.extend(
            (
                f'  <transmission name="{leg}_{joint}_tran">\n'
                "    <type>transmission_interface/SimpleTransmission</type>\n"
                f'    <joint name="{leg}_{joint}_joint">\n'
                "      <hardwareInterface>hardware_interface/EffortJointInterface"
                "</hardwareInterface>\n"
                "    </joint>\n"
                f'    <actuator name="{leg}_{joint}_motor">\n'
                "      <mechanicalReduction>1</mechanicalReduction>\n"
                "    </actuator>\n"
                "  </transmission>\n"
            )
            for joint in ("hip", "thigh", "calf")
        )
    return "".join(blocks)


def reference_robot(folder: Path, robot: str) -> PyBulletRobot:
    """PyBullet's own model of ``robot`` with its :data:`QUIRKS`, written with primitives only."""
    path = folder / f"{robot}_primitives.urdf"
    path.write_text(exported_quadruped(robot, meshes=False, **QUIRKS[robot]), encoding="utf-8")
    return PyBulletRobot(path)


def unitree_style_a1(mesh_folder: str = "package://a1_description/meshes") -> str:
    """pybullet_data's A1 renamed the way Unitree's own A1 description names it: root link ``base``
    (fixed to ``trunk``), joints ``X_thigh_joint``/``X_calf_joint``, feet ``X_foot``, meshes in
    ``mesh_folder``. The geometry stays pybullet_data's, so its feet are known independently."""
    import pybullet_data

    text = (Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf").read_text(encoding="utf-8")
    for ours, theirs in (("_upper", "_thigh"), ("_lower", "_calf"), ("_toe", "_foot")):
        text = text.replace(ours, theirs)
    text = text.replace('filename="meshes/', f'filename="{mesh_folder}/')
    robot_start = text.index(">", text.index("<robot")) + 1
    root = (
        '\n  <link name="base"/>\n'
        '  <joint name="floating_base" type="fixed">\n'
        '    <origin rpy="0 0 0" xyz="0 0 0"/>\n'
        '    <parent link="base"/>\n'
        '    <child link="trunk"/>\n'
        "  </joint>"
    )
    return text[:robot_start] + root + text[robot_start:]
