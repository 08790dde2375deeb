"""Synthetic quadruped descriptions written by the tests: four three-joint legs under ``base``,
with one leg changed where a test needs it (a prismatic knee, an extra joint, another foot); and
a robot with everything tilted (:data:`SYNTHETIC_URDF`: rpy on every joint, non-unit axes off the
coordinate axes, rotated inertials on fixed links above and below the joints)."""

from __future__ import annotations

from a1_leg_fk.model.legs import LEG_NAMES


def leg_urdf(
    leg: str, knee_type: str = "revolute", extra_joint: bool = False, foot: str | None = None
) -> str:
    """One synthetic leg under link ``base``: hip roll, hip pitch, knee, fixed foot."""
    limit = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
    shank_parent = f"{leg}_thigh"
    extra = ""
    if extra_joint:  # a fourth movable joint between thigh and knee
        extra = (
            f'<link name="{leg}_extra"/>\n'
            f'  <joint name="{leg}_extra_joint" type="revolute"><parent link="{leg}_thigh"/>'
            f'<child link="{leg}_extra"/>\n'
            f'    <axis xyz="0 0 1"/>{limit}</joint>'
        )
        shank_parent = f"{leg}_extra"
    return (
        f'\n  <link name="{leg}_hip"/><link name="{leg}_thigh"/><link name="{leg}_shank"/>'
        f'<link name="{foot or leg + "_foot"}"/>\n'
        f'  <joint name="{leg}_hip_joint" type="revolute"><parent link="base"/>'
        f'<child link="{leg}_hip"/>\n'
        f'    <origin xyz="0.2 0.05 0"/><axis xyz="1 0 0"/>{limit}</joint>\n'
        f'  <joint name="{leg}_thigh_joint" type="revolute"><parent link="{leg}_hip"/>'
        f'<child link="{leg}_thigh"/>\n'
        f'    <origin xyz="0 0.08 0"/><axis xyz="0 1 0"/>{limit}</joint>\n'
        f"  {extra}\n"
        f'  <joint name="{leg}_calf_joint" type="{knee_type}"><parent link="{shank_parent}"/>'
        f'<child link="{leg}_shank"/>\n'
        f'    <origin xyz="0 0 -0.2"/><axis xyz="0 1 0"/>{limit}</joint>\n'
        f'  <joint name="{leg}_foot_fixed" type="fixed"><parent link="{leg}_shank"/>'
        f'<child link="{foot or leg + "_foot"}"/>\n'
        '    <origin xyz="0 0 -0.2"/></joint>'
    )


def quadruped_urdf(**per_leg: dict) -> str:
    """Four synthetic legs; ``per_leg={'FR': {'knee_type': 'prismatic'}}`` changes one leg."""
    legs = "".join(leg_urdf(leg, **per_leg.get(leg, {})) for leg in LEG_NAMES)
    return f'<robot name="synthetic"><link name="base"/>{legs}\n</robot>'


def synthetic_leg(leg: str, x: float, y: float) -> str:
    """A leg with rpy on every joint (fixed and movable), non-unit axes, and rotated inertials."""
    side = 1.0 if leg[1] == "L" else -1.0
    limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'

    def inertial(xyz: str, rpy: str) -> str:
        return (
            f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="0.5"/>'
            '<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>'
        )

    return (
        f'\n  <joint name="{leg}_mount" type="fixed"><parent link="base"/>'
        f'<child link="{leg}_mount"/>\n'
        f'    <origin xyz="{x} {y} 0.01" rpy="0.1 -0.2 {0.3 * side}"/></joint>\n'
        f'  <link name="{leg}_mount">{inertial("0.01 0 0", "0.2 0 0")}</link>\n'
        f'  <joint name="{leg}_roll" type="revolute"><parent link="{leg}_mount"/>'
        f'<child link="{leg}_hip"/>\n'
        f'    <origin xyz="0.01 {0.02 * side} -0.01" rpy="0.4 0.25 -0.6"/>'
        f'<axis xyz="2 0 0.5"/>{limit}</joint>\n'
        f'  <link name="{leg}_hip">{inertial("0.01 0.02 -0.03", "0.3 0.2 0.1")}</link>\n'
        f'  <joint name="{leg}_pitch" type="continuous"><parent link="{leg}_hip"/>'
        f'<child link="{leg}_thigh"/>\n'
        f'    <origin xyz="0 {0.08 * side} 0" rpy="-0.3 0 0.2"/><axis xyz="0 2 0"/></joint>\n'
        f'  <link name="{leg}_thigh">{inertial("0 0.01 -0.1", "0 0.5 0")}</link>\n'
        f'  <joint name="{leg}_knee" type="revolute"><parent link="{leg}_thigh"/>'
        f'<child link="{leg}_shank"/>\n'
        '    <origin xyz="0 0 -0.2" rpy="0 0.1 0"/><axis xyz="0 -1 0.1"/>'
        '<limit lower="-2.5" upper="-0.5" effort="1" velocity="1"/></joint>\n'
        f'  <link name="{leg}_shank">{inertial("0.01 0 -0.1", "-0.1 0.2 0.3")}</link>\n'
        f'  <joint name="{leg}_foot_fixed" type="fixed"><parent link="{leg}_shank"/>'
        f'<child link="{leg}_foot"/>\n'
        '    <origin xyz="0.02 0.01 -0.21" rpy="0.5 0.6 0.7"/></joint>\n'
        f'  <link name="{leg}_foot">{inertial("0 0 0", "0 0 0")}</link>'
    )


SYNTHETIC_URDF = (
    '<?xml version="1.0"?>\n'
    '<robot name="synthetic">\n'
    '  <link name="base"><inertial><origin xyz="0.05 -0.02 0.03" rpy="0.2 0.1 0.3"/>'
    '<mass value="5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'
    "</inertial></link>"
    + "".join(
        synthetic_leg(leg, x, y)
        for leg, x, y in (
            ("FR", 0.2, -0.05),
            ("FL", 0.2, 0.05),
            ("RR", -0.2, -0.05),
            ("RL", -0.2, 0.05),
        )
    )
    + "\n</robot>\n"
)
SYNTHETIC_JOINTS = [f"{leg}_{part}" for leg in LEG_NAMES for part in ("roll", "pitch", "knee")]
SYNTHETIC_FEET = [f"{leg}_foot" for leg in LEG_NAMES]
