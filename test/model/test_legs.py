"""Legs (a1_leg_fk.model.legs): foot discovery, leg order, joint naming, and refusals of odd
legs."""

from __future__ import annotations

from pathlib import Path

import pybullet_data
import pytest
from conftest import raises_leg_fk_error
from exported_urdf import exported_quadruped
from synthetic_urdf import quadruped_urdf

from a1_leg_fk.model.legs import LEG_NAMES, find_legs, joint_name_index
from a1_leg_fk.model.urdf import load_urdf, parse_urdf

DATA = Path(pybullet_data.getDataPath())
A1_PATH = DATA / "a1" / "a1.urdf"
MINI_CHEETAH_PATH = DATA / "mini_cheetah" / "mini_cheetah.urdf"
MINI_CHEETAH_FEET = {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"}


# --- the A1 -------------------------------------------------------------------------------


def test_a1_legs_in_order_with_their_feet_and_joints() -> None:
    legs = find_legs(load_urdf(A1_PATH))
    assert LEG_NAMES == ("FR", "FL", "RR", "RL")
    assert [leg.leg for leg in legs] == ["FR", "FL", "RR", "RL"]
    assert [leg.foot_link for leg in legs] == ["FR_toe", "FL_toe", "RR_toe", "RL_toe"]
    for leg in legs:
        assert [j.name for j in leg.movable] == [
            f"{leg.leg}_hip_joint",
            f"{leg.leg}_upper_joint",
            f"{leg.leg}_lower_joint",
        ]
        assert [j.name for j in leg.joints] == [j.name for j in leg.movable] + [
            f"{leg.leg}_toe_fixed"
        ]


def test_a1_explicit_feet_equal_discovered_feet() -> None:
    model = load_urdf(A1_PATH)
    explicit = find_legs(model, {leg: f"{leg}_toe" for leg in LEG_NAMES})
    assert explicit == find_legs(model)


def test_a1_lower_link_as_foot_gives_the_same_three_joints() -> None:
    legs = find_legs(load_urdf(A1_PATH), {leg: f"{leg}_lower" for leg in LEG_NAMES})
    assert [j.name for j in legs[0].joints] == ["FR_hip_joint", "FR_upper_joint", "FR_lower_joint"]


def test_mini_cheetah_needs_foot_links_and_works_with_them() -> None:
    model = load_urdf(MINI_CHEETAH_PATH)
    with raises_leg_fk_error("FR", "foot_links"):
        find_legs(model)
    legs = find_legs(model, MINI_CHEETAH_FEET)
    assert [leg.foot_link for leg in legs] == ["toe_fr", "toe_fl", "toe_hr", "toe_hl"]
    assert [j.name for j in legs[2].movable] == [
        "torso_to_abduct_hr_j",
        "abduct_hr_to_thigh_hr_j",
        "thigh_hr_to_knee_hr_j",
    ]


# --- joint naming -------------------------------------------------------------------------


@pytest.mark.parametrize(("leg_slot", "leg"), list(enumerate(LEG_NAMES)))
def test_unitree_names_map_to_the_pybullet_data_slots(leg_slot: int, leg: str) -> None:
    index = joint_name_index(find_legs(load_urdf(A1_PATH)))
    first = 3 * leg_slot
    assert index[f"{leg}_hip_joint"] == first
    assert index[f"{leg}_upper_joint"] == index[f"{leg}_thigh_joint"] == first + 1
    assert index[f"{leg}_lower_joint"] == index[f"{leg}_calf_joint"] == first + 2


def test_pybullet_data_names_map_to_a_unitree_named_model() -> None:
    text = (
        A1_PATH.read_text(encoding="utf-8")
        .replace("_upper_joint", "_thigh_joint")
        .replace("_lower_joint", "_calf_joint")
    )
    index = joint_name_index(find_legs(load_urdf(text)))
    assert index["RL_thigh_joint"] == index["RL_upper_joint"] == 10
    assert index["RL_calf_joint"] == index["RL_lower_joint"] == 11


def test_user_aliases_map_to_their_joint_and_override() -> None:
    legs = find_legs(load_urdf(A1_PATH))
    index = joint_name_index(
        legs,
        {
            "fr_abduction": "FR_hip_joint",
            "rl_knee": "RL_lower_joint",
            "FR_thigh_joint": "FL_upper_joint",
        },
    )
    assert index["fr_abduction"] == 0
    assert index["rl_knee"] == 11
    assert index["FR_thigh_joint"] == 4  # the caller's alias wins over the built-in equivalent


def test_alias_to_an_unknown_joint_names_both() -> None:
    with raises_leg_fk_error("'knee", "'FR_knee_joint'"):
        joint_name_index(find_legs(load_urdf(A1_PATH)), {"knee": "FR_knee_joint"})


def test_alias_to_a_fixed_joint_is_refused() -> None:
    with raises_leg_fk_error("'FR_toe_fixed'"):
        joint_name_index(find_legs(load_urdf(A1_PATH)), {"toe": "FR_toe_fixed"})


# --- refusals -----------------------------------------------------------------------------


def test_synthetic_quadruped_is_accepted() -> None:
    legs = find_legs(parse_urdf(quadruped_urdf()))
    assert [leg.foot_link for leg in legs] == ["FR_foot", "FL_foot", "RR_foot", "RL_foot"]


def test_foot_link_that_does_not_exist() -> None:
    feet = {leg: f"{leg}_toe" for leg in LEG_NAMES} | {"RL": "RL_tow"}
    with raises_leg_fk_error("RL", "'RL_tow'"):
        find_legs(load_urdf(A1_PATH), feet)


def test_foot_links_with_an_unknown_or_missing_leg() -> None:
    feet = {"FR": "FR_toe", "FL": "FL_toe", "RR": "RR_toe", "LH": "RL_toe"}
    with raises_leg_fk_error("'LH'", "'RL'"):
        find_legs(load_urdf(A1_PATH), feet)


def test_prismatic_knee_names_the_joint_and_leg() -> None:
    model = parse_urdf(quadruped_urdf(RR={"knee_type": "prismatic"}))
    with raises_leg_fk_error("leg RR", "'RR_calf_joint'", "prismatic"):
        find_legs(model, {leg: f"{leg}_foot" for leg in LEG_NAMES})


def test_prismatic_knee_without_foot_links_is_not_discovered_as_a_leg() -> None:
    with raises_leg_fk_error("FL"):
        find_legs(parse_urdf(quadruped_urdf(FL={"knee_type": "prismatic"})))


def test_four_movable_joints_in_a_leg() -> None:
    model = parse_urdf(quadruped_urdf(FL={"extra_joint": True}))
    with raises_leg_fk_error("leg FL", "'FL_foot'", "4 movable", "FL_extra_joint"):
        find_legs(model, {leg: f"{leg}_foot" for leg in LEG_NAMES})


def test_two_movable_joints_in_a_leg() -> None:
    """Taking the shank as the foot leaves the hip roll and hip pitch only."""
    feet = {leg: f"{leg}_foot" for leg in LEG_NAMES} | {"FR": "FR_thigh"}
    with raises_leg_fk_error("leg FR", "'FR_thigh'", "2 movable"):
        find_legs(parse_urdf(quadruped_urdf()), feet)


def test_ambiguous_discovery_asks_for_foot_links() -> None:
    model = parse_urdf(quadruped_urdf().replace("RL_foot", "FR_foot2"))
    with raises_leg_fk_error("FR", "FR_foot2", "foot_links"):
        find_legs(model)


# --- several leaf links per leg (exported descriptions) -----------------------------------


def test_go2_like_shin_leaves_lose_to_the_foot_named_link() -> None:
    """Go2's description has two leaves with three movable joints above them per leg: X_foot and
    the shin collision link X_calflower1; the one named like a foot is the foot."""
    legs = find_legs(parse_urdf(exported_quadruped("go2")))
    assert [leg.foot_link for leg in legs] == ["FR_foot", "FL_foot", "RR_foot", "RL_foot"]
    assert [j.name for j in legs[0].joints] == [
        "FR_hip_joint",
        "FR_thigh_joint",
        "FR_calf_joint",
        "FR_foot_joint",
    ]


def test_b2_like_rotor_leaves_are_not_feet() -> None:
    """Rotor links are fixed leaves with two, one or no movable joints above them."""
    model = parse_urdf(exported_quadruped("b2", root="base_link", rotors=True, shin_links=False))
    assert {"FR_hip_rotor", "FR_thigh_rotor", "FR_calf_rotor"} <= set(model.links)
    assert [leg.foot_link for leg in find_legs(model)] == [
        "FR_foot",
        "FL_foot",
        "RR_foot",
        "RL_foot",
    ]


@pytest.mark.parametrize("foot", ["FR_toe", "fr_FOOT", "FR_foot_link", "Fr_Toe_Link"])
def test_every_documented_foot_name_wins_case_insensitively(foot: str) -> None:
    xml = exported_quadruped("go2").replace('"FR_foot"', f'"{foot}"')
    assert find_legs(parse_urdf(xml))[0].foot_link == foot


@pytest.mark.parametrize(
    "renamed",
    [{"FR_foot": "FR_tip"}, {"FR_calflower1": "FR_toe"}],
    ids=["none-named-like-a-foot", "two-named-so"],
)
def test_several_leaves_without_one_foot_name_ask_for_foot_links(renamed: dict) -> None:
    xml = exported_quadruped("go2")
    for old, new in renamed.items():
        xml = xml.replace(f'"{old}"', f'"{new}"')
    candidates = sorted(
        {"FR_foot", "FR_calflower1", "FR_tip", "FR_toe"} & set(parse_urdf(xml).links)
    )
    with raises_leg_fk_error(
        "leg FR", *candidates, "foot_links", "FR_foot|toe|foot_link|toe_link"
    ):
        find_legs(parse_urdf(xml))
