"""Synthetic quadruped descriptions written by the tests: four three-joint legs under ``base``,
with one leg changed where a test needs it (a prismatic knee, an extra joint, another foot)."""

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
