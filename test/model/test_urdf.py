"""URDF reading (a1_leg_fk.model.urdf): what is kept, what is ignored, and every refusal.

Expected values are copied from the URDF text of pybullet_data's ``a1/a1.urdf`` or from the small
URDF strings written here, never from the code under test.
"""

from __future__ import annotations

import math
import os
import time
import tracemalloc
from pathlib import Path

import pybullet_data
import pytest
from conftest import raises_leg_fk_error
from exported_urdf import ROBOTS, exported_quadruped
from shared import PYBULLET_NAMES

from a1_leg_fk.model.urdf import RobotModel, default_urdf_path, load_urdf, parse_urdf

A1_PATH = Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"

A1_FIXED_JOINTS = ["imu_joint"] + [
    f"{leg}_{part}" for leg in ("FR", "FL", "RR", "RL") for part in ("hip_fixed", "toe_fixed")
]

BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE robot [
  <!ENTITY lol "lol">
  <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
  <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
  <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
  <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
  <!ENTITY lol5 "&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;">
  <!ENTITY lol6 "&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;">
  <!ENTITY lol7 "&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;">
  <!ENTITY lol8 "&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;">
  <!ENTITY lol9 "&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;">
]>
<robot name="bomb"><link name="&lol9;"/></robot>
"""


def two_link_urdf(joint_body: str = "", extra: str = "") -> str:
    """A minimal robot: link ``base`` and link ``arm`` joined by joint ``j`` (body given)."""
    return f"""<robot name="tiny">
  <link name="base"/>
  <link name="arm"/>
  <joint name="j" type="revolute">
    <parent link="base"/><child link="arm"/>
    {joint_body or '<limit lower="-1" upper="1" effort="1" velocity="1"/>'}
  </joint>
  {extra}
</robot>"""


# --- the default model --------------------------------------------------------------------


def test_default_path_is_pybullet_data_a1() -> None:
    assert default_urdf_path() == A1_PATH
    assert A1_PATH.is_file()


@pytest.mark.parametrize(
    "source", [None, A1_PATH, str(A1_PATH)], ids=["default", "Path", "str-path"]
)
def test_a1_loads_from_every_kind_of_source(source) -> None:
    model = load_urdf(source)
    assert isinstance(model, RobotModel)
    assert model.name == "a1_description"
    assert model.root == "trunk"
    assert sorted(model.joints) == sorted(PYBULLET_NAMES + A1_FIXED_JOINTS)


def test_a1_loads_from_an_xml_string_with_leading_whitespace() -> None:
    model = load_urdf("\n  " + A1_PATH.read_text(encoding="utf-8"))
    assert model.root == "trunk"
    assert len(model.joints) == 21
    assert "<robot_description>" in model.source


def test_a1_joint_fields_match_the_urdf_text() -> None:
    model = load_urdf(A1_PATH)
    hip = model.joints["FR_hip_joint"]
    assert (hip.type, hip.parent, hip.child) == ("revolute", "trunk", "FR_hip")
    assert hip.origin_xyz == (0.183, -0.047, 0.0)
    assert hip.origin_rpy == (0.0, 0.0, 0.0)
    assert hip.axis == (1.0, 0.0, 0.0)
    assert (hip.lower, hip.upper) == (-0.802851455917, 0.802851455917)
    knee = model.joints["FR_lower_joint"]
    assert knee.origin_xyz == (0.0, 0.0, -0.2)
    assert knee.axis == (0.0, 1.0, 0.0)
    assert (knee.lower, knee.upper) == (-2.69653369433, -0.916297857297)
    assert knee.movable
    toe = model.joints["FR_toe_fixed"]
    assert (toe.type, toe.parent, toe.child, toe.movable) == ("fixed", "FR_lower", "FR_toe", False)
    assert (toe.lower, toe.upper) == (None, None)


def test_chain_to_the_toe_is_root_first_and_includes_fixed_joints() -> None:
    model = load_urdf(A1_PATH)
    names = [joint.name for joint in model.chain_to("FR_toe")]
    assert names == ["FR_hip_joint", "FR_upper_joint", "FR_lower_joint", "FR_toe_fixed"]
    assert model.chain_to("trunk") == ()
    assert (
        model.chain_to("FR_toe")[-1].child == "FR_toe"
    )  # the last joint is the link's parent joint
    assert set(model.child_links("FR_hip")) == {"FR_upper_shoulder", "FR_upper"}


def test_chain_to_an_unknown_link_names_it() -> None:
    with raises_leg_fk_error("'no_such_link'"):
        load_urdf(A1_PATH).chain_to("no_such_link")


# --- what is parsed, what is ignored ------------------------------------------------------


def test_transmission_joints_are_not_joints() -> None:
    """pybullet_data's A1 has 12 ``<transmission><joint name=...>``: only the 21 real ones
    count."""
    model = load_urdf(A1_PATH)
    assert A1_PATH.read_text(encoding="utf-8").count("<joint ") == 21 + 12
    assert len(model.joints) == 21


def test_a_transmission_joint_naming_a_missing_link_is_ignored() -> None:
    """Parsed as a joint, this one would fail (its parent link does not exist); it must be
    ignored."""
    extra = """<transmission name="t"><type>transmission_interface/SimpleTransmission</type>
      <joint name="ghost" type="revolute"><parent link="nowhere"/><child link="arm"/></joint>
      <actuator name="m"><mechanicalReduction>1</mechanicalReduction></actuator></transmission>"""
    model = parse_urdf(two_link_urdf(extra=extra))
    assert list(model.joints) == ["j"]
    assert "ghost" not in model.joints


def test_rpy_and_a_non_unit_axis_are_read() -> None:
    model = parse_urdf(
        two_link_urdf(
            '<origin xyz="0.1 -0.2 0.3" rpy="0.4 -0.5 0.6"/><axis xyz="0 2 0"/>'
            '<limit lower="-0.5" upper="1.5" effort="1" velocity="1"/>'
        )
    )
    joint = model.joints["j"]
    assert joint.origin_xyz == (0.1, -0.2, 0.3)
    assert joint.origin_rpy == (0.4, -0.5, 0.6)
    assert joint.axis == (0.0, 1.0, 0.0)
    assert (joint.lower, joint.upper) == (-0.5, 1.5)


def test_an_oblique_axis_is_normalised() -> None:
    joint = parse_urdf(two_link_urdf('<axis xyz="3 0 4"/><limit lower="-1" upper="1"/>')).joints[
        "j"
    ]
    assert joint.axis == pytest.approx((0.6, 0.0, 0.8), abs=1e-15)
    assert math.fsum(c * c for c in joint.axis) == pytest.approx(1.0, abs=1e-15)


def test_missing_origin_and_axis_take_the_urdf_defaults() -> None:
    joint = parse_urdf(two_link_urdf()).joints["j"]
    assert joint.origin_xyz == (0.0, 0.0, 0.0)
    assert joint.origin_rpy == (0.0, 0.0, 0.0)
    assert joint.axis == (1.0, 0.0, 0.0)  # the URDF specification's default


def test_continuous_joints_have_no_limits() -> None:
    xml = two_link_urdf().replace('type="revolute"', 'type="continuous"')
    joint = parse_urdf(xml).joints["j"]
    assert joint.movable
    assert (joint.lower, joint.upper) == (None, None)


# --- refusals -----------------------------------------------------------------------------


def test_malformed_xml_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "broken.urdf"
    path.write_text('<robot name="r"><link name="a"></robot>', encoding="utf-8")
    with raises_leg_fk_error(str(path), "malformed XML"):
        load_urdf(path)


def test_malformed_xml_string() -> None:
    with raises_leg_fk_error("<robot_description>", "malformed XML"):
        load_urdf('<robot name="r"><link name="a">')


def test_missing_file_names_the_path(tmp_path: Path) -> None:
    path = tmp_path / "absent.urdf"
    with raises_leg_fk_error(str(path)):
        load_urdf(path)


def test_root_element_must_be_robot() -> None:
    with raises_leg_fk_error("<sdf>", "<robot>"):
        parse_urdf('<sdf version="1.6"><model name="m"/></sdf>', "model.sdf")


def test_robot_without_links() -> None:
    with raises_leg_fk_error("<link>"):
        parse_urdf('<robot name="empty"/>')


def test_joint_parent_link_that_does_not_exist() -> None:
    xml = two_link_urdf().replace('<parent link="base"/>', '<parent link="basee"/>')
    with raises_leg_fk_error("'j'", "'basee'", "parent"):
        parse_urdf(xml)


def test_joint_child_link_that_does_not_exist() -> None:
    xml = two_link_urdf().replace('<child link="arm"/>', '<child link="ram"/>')
    with raises_leg_fk_error("'j'", "'ram'", "child"):
        parse_urdf(xml)


def test_cycle_names_a_link_on_it() -> None:
    xml = """<robot name="loop">
      <link name="base"/><link name="a"/><link name="b"/>
      <joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>
    </robot>"""
    with raises_leg_fk_error("cycle", "loop.urdf") as info:
        parse_urdf(xml, "loop.urdf")
    message = str(info.value)
    assert "'a'" in message or "'b'" in message


def test_link_with_two_parents() -> None:
    xml = two_link_urdf(
        extra='<link name="c"/><joint name="k" type="fixed"><parent link="c"/><child '
        'link="arm"/></joint>'
    )
    with raises_leg_fk_error("'arm'"):
        parse_urdf(xml)


def test_duplicate_joint_name() -> None:
    xml = two_link_urdf(
        extra='<link name="c"/><joint name="j" type="fixed"><parent link="arm"/><child '
        'link="c"/></joint>'
    )
    with raises_leg_fk_error("'j'", "duplicate"):
        parse_urdf(xml)


def test_unknown_joint_type_names_it() -> None:
    with raises_leg_fk_error("'j'", "'hinge'"):
        parse_urdf(two_link_urdf().replace('type="revolute"', 'type="hinge"'))


def test_non_numeric_origin_names_the_joint() -> None:
    with raises_leg_fk_error("'j'", "xyz"):
        parse_urdf(two_link_urdf('<origin xyz="0 zero 0"/><limit lower="-1" upper="1"/>'))


def test_non_finite_origin_names_the_joint() -> None:
    with raises_leg_fk_error("'j'", "rpy"):
        parse_urdf(two_link_urdf('<origin rpy="0 nan 0"/><limit lower="-1" upper="1"/>'))


@pytest.mark.parametrize("joint_type", ["revolute", "continuous", "prismatic"])
def test_zero_axis_on_a_moving_joint_names_the_joint(joint_type: str) -> None:
    xml = two_link_urdf('<axis xyz="0 0 0"/><limit lower="-1" upper="1"/>').replace(
        '"revolute"', f'"{joint_type}"'
    )
    with raises_leg_fk_error("'j'", "axis is the zero vector"):
        parse_urdf(xml)


@pytest.mark.parametrize("joint_type", ["fixed", "floating", "planar"])
@pytest.mark.parametrize(
    "axis",
    ['<axis xyz="0 0 0"/>', '<axis xyz="0 0 7"/>', '<axis xyz="zero"/>', "<axis/>", ""],
    ids=["zero", "not-unit", "not-numbers", "no-xyz", "missing"],
)
def test_the_axis_of_a_joint_that_has_none_is_ignored(joint_type: str, axis: str) -> None:
    """CAD exporters write <axis xyz="0 0 0"/> on fixed joints (Go2: 16 of them, B2: 8); urdfdom,
    robot_state_publisher and PyBullet ignore it, and so must we, whatever it says."""
    xml = two_link_urdf(f'<origin xyz="0.1 0 0"/>{axis}').replace('"revolute"', f'"{joint_type}"')
    joint = parse_urdf(xml).joints["j"]
    assert (joint.type, joint.axis, joint.origin_xyz) == (
        joint_type,
        (1.0, 0.0, 0.0),
        (0.1, 0.0, 0.0),
    )


def test_revolute_without_limit_names_the_joint() -> None:
    with raises_leg_fk_error("'j'", "<limit>"):
        parse_urdf(two_link_urdf('<axis xyz="0 1 0"/>'))


def test_inverted_limits_name_the_joint() -> None:
    with raises_leg_fk_error("'j'", "lower"):
        parse_urdf(two_link_urdf('<limit lower="1" upper="-1"/>'))


def test_a_small_entity_declaration_is_refused() -> None:
    xml = '<!DOCTYPE robot [<!ENTITY arm "arm">]>' + two_link_urdf().replace(
        'link="arm"', 'link="&arm;"'
    )
    with raises_leg_fk_error("entity", "'arm'"):
        parse_urdf(xml)


def test_billion_laughs_fails_fast_and_small() -> None:
    """Expanded, this payload is 3 * 10**9 characters; it must be refused before any expansion."""
    tracemalloc.start()
    try:
        start = time.perf_counter()
        with raises_leg_fk_error("entity", "'lol"):
            load_urdf(BILLION_LAUGHS)
        elapsed = time.perf_counter() - start
        _, peak_bytes = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert elapsed < 1.0, f"took {elapsed:.3f} s"
    assert peak_bytes < 50 * 2**20, f"peak {peak_bytes / 2**20:.1f} MiB"


def test_billion_laughs_from_a_file_fails_fast_without_growing_rss(tmp_path: Path) -> None:
    resource = pytest.importorskip("resource")  # POSIX only
    path = tmp_path / "bomb.urdf"
    path.write_text(BILLION_LAUGHS, encoding="utf-8")
    before_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    start = time.perf_counter()
    with raises_leg_fk_error(str(path), "entity"):
        load_urdf(os.fspath(path))
    elapsed = time.perf_counter() - start
    growth_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before_kib
    assert elapsed < 1.0, f"took {elapsed:.3f} s"
    assert growth_kib < 50 * 1024, f"max RSS grew by {growth_kib / 1024:.1f} MiB"


def test_empty_document() -> None:
    with raises_leg_fk_error("<robot_description>"):
        load_urdf("<")


# --- descriptions written by CAD exporters (Unitree's Go2 and B2 style) --------------------


@pytest.mark.parametrize("robot", ["go2", "b2"])
def test_an_exported_description_with_every_quirk_is_read(robot: str) -> None:
    xml = exported_quadruped(robot, root="base_link", crlf=True, rotors=True)
    assert (
        "\r\n" in xml and "Commit Version: 1.6.0" in xml and 'xyz="0 0 0" />\r\n  </joint>' in xml
    )
    model = load_urdf(xml)
    assert model.root == "base_link"
    fixed = [j for j in model.joints.values() if j.type == "fixed"]
    assert (
        len(fixed) == 4 * 3 + 4 + 4 * 3
    )  # per leg foot, two shin links and three rotors; four sensors
    assert all(j.axis == (1.0, 0.0, 0.0) for j in fixed)
    # The transmissions' <joint name=...> children are not joints of the tree.
    assert sum(j.movable for j in model.joints.values()) == 12
    geometry = ROBOTS[robot]
    hip = model.joints["RL_hip_joint"]
    assert hip.origin_xyz == (-geometry.hip_x, geometry.hip_y, 0.0)
    assert (hip.lower, hip.upper) == geometry.hip_limits


def test_an_exported_file_with_crlf_and_a_header_loads_from_disk(tmp_path: Path) -> None:
    path = tmp_path / "go2_like.urdf"
    path.write_bytes(exported_quadruped("go2", crlf=True).encode("utf-8"))
    model = load_urdf(path)
    assert model.source == str(path)
    assert model.joints["FR_calf_joint"].origin_xyz == (0.0, 0.0, -0.213)
