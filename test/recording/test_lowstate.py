"""Unitree's LowState recordings (``unitree_go/msg/LowState`` of ROS 2, ``unitree_legged_msgs/
LowState`` of ROS 1) read by ``a1-leg-fk bag | gait | odom``: a PyBullet trot (contact family run
``a1_trot_slow``) recorded as LowState gives the same feet, forces, contacts and odometry as the
same float32 values recorded as JointState + Imu; the wire layouts equal rosbags' serializer's;
the w-first quaternion matters; bad input is one line with nothing written.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_factory import TYPESTORE, BagSpec, JointStateMsg, T, header, pose, write_bag
from conftest import family_folder
from contact_bags import stamp_of
from contact_runs import ContactRun, contact_runs
from lowstate_bags import (
    register_unitree_types,
    sensor_counts,
    write_lowstate_bag,
    write_reference_bag,
    zeroed,
)

from a1_leg_fk import cli
from a1_leg_fk.recording.odometry import OdometryOptions, odometry_track
from a1_leg_fk.recording.trajectories import read_foot_trajectories
from a1_leg_fk.wire.lowstate import LowStateDecoder, layout_for
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, HUMANOID_LOW_STATE, LEGGED_LOW_STATE

ROWS = 600  # 1.2 s at 500 Hz: the settling and the first trot steps
KINDS = {  # bag kind -> LowState type
    "mcap": GO_LOW_STATE,
    "sqlite3": GO_LOW_STATE,
    "humble": GO_LOW_STATE,  # no definitions: the package's own
    "ros1": LEGGED_LOW_STATE,
}


@pytest.fixture(scope="module")
def run() -> ContactRun:
    return contact_runs(family_folder(), ("a1_trot_slow",))["a1_trot_slow"]


@pytest.fixture(scope="module")
def reference(run: ContactRun, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_reference_bag(tmp_path_factory.mktemp("reference") / "bag", run, ROWS)


@pytest.mark.parametrize("msgtype", [GO_LOW_STATE, LEGGED_LOW_STATE])
@pytest.mark.parametrize("ros1", [False, True], ids=["cdr", "ros1"])
def test_layout_decodes_what_rosbags_serializes(run: ContactRun, msgtype: str, ros1: bool):
    register_unitree_types()
    raws = []
    for row in (0, 300, 599):
        cdr = TYPESTORE.serialize_cdr(_message(run, row, msgtype), msgtype)
        raws.append(bytes(TYPESTORE.cdr_to_ros1(cdr, msgtype) if ros1 else cdr))
    rows, problem = LowStateDecoder(layout_for(msgtype, None, ros1)).rows(raws)
    assert problem is None
    expected = np.float32(run.angles[[0, 300, 599]]).astype(float)
    np.testing.assert_array_equal(rows.positions, expected)
    np.testing.assert_array_equal(rows.efforts, np.float32(run.torques[[0, 300, 599]]))
    np.testing.assert_array_equal(rows.orientations, np.float32(run.quaternions[[0, 300, 599]]))
    np.testing.assert_array_equal(rows.foot_force[2], sensor_counts(run, 599))


@pytest.mark.parametrize("msgtype", [GO_LOW_STATE, LEGGED_LOW_STATE])
@pytest.mark.parametrize("ros1", [False, True], ids=["cdr", "ros1"])
def test_the_imu_quaternion_is_read_w_first(msgtype: str, ros1: bool):
    """A rotation no reordering of its quaternion's components gives (each component distinct,
    scipy's), written w first as Unitree's definitions say: read back as (x, y, z, w)."""
    from scipy.spatial.transform import Rotation

    register_unitree_types()
    x, y, z, w = Rotation.from_euler("xyz", (0.3, -0.5, 1.1)).as_quat()
    message = zeroed(msgtype)
    (message.imu_state if msgtype == GO_LOW_STATE else message.imu).quaternion[:] = [w, x, y, z]
    cdr = TYPESTORE.serialize_cdr(message, msgtype)
    raw = bytes(TYPESTORE.cdr_to_ros1(cdr, msgtype) if ros1 else cdr)
    rows, problem = LowStateDecoder(layout_for(msgtype, None, ros1)).rows([raw])
    assert problem is None
    np.testing.assert_allclose(rows.orientations[0], (x, y, z, w), atol=1e-7)  # float32


def _message(run: ContactRun, row: int, msgtype: str) -> Any:
    from lowstate_bags import lowstate_message

    return lowstate_message(run, row, msgtype)


@pytest.mark.parametrize("kind", KINDS)
def test_lowstate_gives_the_joint_state_paths_numbers(
    run: ContactRun, reference: Path, tmp_path: Path, kind: str
):
    name = "lowstate.bag" if kind == "ros1" else "lowstate"
    bag = write_lowstate_bag(tmp_path / name, run, ROWS, kind, KINDS[kind])
    ours = read_foot_trajectories(bag, forces=True)
    theirs = read_foot_trajectories(reference, forces=True, imu="/imu")
    assert ours.summary.rows == theirs.summary.rows == ROWS
    np.testing.assert_array_equal(ours.stamps_ns, theirs.stamps_ns)
    assert np.nanmax(np.abs(ours.positions - theirs.positions)) <= 1e-12
    np.testing.assert_array_equal(ours.velocities, theirs.velocities)
    np.testing.assert_array_equal(ours.forces, theirs.forces)
    np.testing.assert_array_equal(ours.contacts, theirs.contacts)
    assert ours.sensor is not None
    np.testing.assert_array_equal(ours.sensor[-1], sensor_counts(run, ROWS - 1))
    lines = "\n".join(ours.summary.lines())
    assert f"topic:     /lowstate ({KINDS[kind]})" in lines
    assert "stamps:    the bag's receive time (a LowState has no header)" in lines


def test_an_x_first_quaternion_changes_the_forces(
    run: ContactRun, reference: Path, tmp_path: Path
):
    """The equality above holds only for the w-first order: a recording written x-first (the
    reader taking it so would be the same mistake) gives other forces."""
    bag = write_lowstate_bag(tmp_path / "x_first", run, ROWS, x_first=True)
    ours = read_foot_trajectories(bag, forces=True)
    theirs = read_foot_trajectories(reference, forces=True, imu="/imu")
    assert ours.forces is not None and theirs.forces is not None
    assert np.nanmax(np.abs(ours.forces - theirs.forces)) > 1.0  # [N]


def test_odometry_equals_the_joint_state_and_imu_path(
    run: ContactRun, reference: Path, tmp_path: Path
):
    bag = write_lowstate_bag(tmp_path / "lowstate", run, ROWS)
    ours = odometry_track(bag)
    theirs = odometry_track(reference, OdometryOptions(imu_topic="/imu"))
    assert len(ours.stamps_ns) == len(theirs.stamps_ns) > ROWS // 2
    np.testing.assert_array_equal(ours.positions, theirs.positions)
    np.testing.assert_array_equal(ours.orientations, theirs.orientations)
    assert ours.imu_topic == "/lowstate" and ours.rows_with_imu == theirs.rows_with_imu


def test_joint_aliases_map_the_motors_to_another_urdfs_names(run: ContactRun, tmp_path: Path):
    renamed = {"hip": "abduct", "upper": "swing", "lower": "knee"}
    text = run.urdf_text
    for leg in ("FR", "FL", "RR", "RL"):
        for old, new in renamed.items():
            text = text.replace(f'"{leg}_{old}_joint"', f'"{leg.lower()}_{new}"')
    urdf = tmp_path / "renamed.urdf"
    urdf.write_text(text)
    bag = write_lowstate_bag(tmp_path / "lowstate", run, 50)
    code = cli.main(["bag", str(bag), "--urdf", str(urdf), "--csv", str(tmp_path / "no.csv")])
    assert code == 2 and not (tmp_path / "no.csv").exists()
    aliases = [
        f"{leg}_{unitree}_joint={leg.lower()}_{renamed[old]}"
        for leg in ("FR", "FL", "RR", "RL")
        for old, unitree in (("hip", "hip"), ("upper", "thigh"), ("lower", "calf"))
    ]
    mapped = read_foot_trajectories(bag, urdf=urdf, joint_aliases=aliases)
    plain = read_foot_trajectories(bag)
    np.testing.assert_array_equal(mapped.positions, plain.positions)


def test_bag_csv_has_the_sensors_and_the_summary_their_agreement(
    run: ContactRun, tmp_path: Path, capsys: pytest.CaptureFixture[str]
):
    bag = write_lowstate_bag(tmp_path / "lowstate", run, ROWS)
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--forces", "--csv", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "sensors:   our contacts agree with the foot sensors' (count > 30) in" in printed
    with out.open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == ROWS
    assert [float(rows[-1][f"{leg}_sensor"]) for leg in ("FR", "FL", "RR", "RL")] == list(
        sensor_counts(run, ROWS - 1).astype(float)
    )


def test_gait_takes_the_stance_from_the_sensors(
    run: ContactRun, tmp_path: Path, capsys: pytest.CaptureFixture[str]
):
    register_unitree_types()
    spec = BagSpec()
    for row in range(len(run.stamps_s)):
        stamp = stamp_of(run, row)
        spec.add("/lowstate", GO_LOW_STATE, stamp, _message(run, row, GO_LOW_STATE))
        spec.add(
            "/base_pose",
            "geometry_msgs/msg/PoseStamped",
            stamp,
            T["geometry_msgs/msg/PoseStamped"](
                header(stamp, "world"),
                pose(run.base_positions[row].tolist(), run.quaternions[row].tolist()),
            ),
        )
    bag = write_bag(tmp_path / "gait", spec)
    common = ["gait", str(bag), "--base-pose", "/base_pose"]
    assert cli.main([*common, "--contacts", "sensor"]) == 0
    printed = capsys.readouterr().out
    assert (
        "contacts:  sensor" in printed and "stance from the foot sensors (count > 30)" in printed
    )
    assert "trot" in printed


@pytest.mark.parametrize("problem", ["nan", "truncated", "humanoid"])
def test_bad_lowstate_input_is_one_line_and_writes_nothing(
    run: ContactRun, tmp_path: Path, capsys: pytest.CaptureFixture[str], problem: str
):
    register_unitree_types()
    spec = BagSpec()
    for row in range(20):
        message = _message(run, row, GO_LOW_STATE)
        raw = bytes(TYPESTORE.serialize_cdr(message, GO_LOW_STATE))
        if problem == "nan":
            for motor in message.motor_state[:12]:
                motor.q = math.nan
            spec.add("/lowstate", GO_LOW_STATE, stamp_of(run, row), message)
        elif problem == "truncated":
            spec.add("/lowstate", GO_LOW_STATE, stamp_of(run, row), raw[:-100])
        else:
            spec.add("/lowstate", HUMANOID_LOW_STATE, stamp_of(run, row), raw)
    bag = write_bag(tmp_path / "bad", spec, "humble")
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out)]) == 2
    error = capsys.readouterr().err
    assert len(error.splitlines()) == 1 and not out.exists()
    expected = {
        "nan": "motor angles are not finite",
        "truncated": "its first message is not a whole unitree_go/msg/LowState",
        "humanoid": "unitree_hg/msg/LowState, a humanoid's",
    }
    assert expected[problem] in error


def test_sportmodestate_feet_are_compared(run: ContactRun, tmp_path: Path):
    """Unitree's foot_position_body recorded as our own feet with FR moved 12 mm: the summary
    says FR is 12 mm off and the others 0, and that they match (within the tolerance)."""
    register_unitree_types()
    plain = read_foot_trajectories(write_lowstate_bag(tmp_path / "plain", run, 100))
    spec = BagSpec()
    for row in range(100):
        stamp = stamp_of(run, row)
        spec.add("/lowstate", GO_LOW_STATE, stamp, _message(run, row, GO_LOW_STATE))
        sport = zeroed("unitree_go/msg/SportModeState")
        feet = plain.positions[row].copy()
        feet[0, 2] += 0.012
        sport.foot_position_body[:] = feet.reshape(-1)
        spec.add("/sportmodestate", "unitree_go/msg/SportModeState", stamp + 1, sport)
    lines = read_foot_trajectories(write_bag(tmp_path / "sport", spec)).summary.lines()
    line = next(line for line in lines if line.startswith("unitree:"))
    assert "median distance FR 12.0, FL 0.0, RR 0.0, RL 0.0 mm; they match" in line


def test_topic_chooses_between_joint_states_and_lowstate(run: ContactRun, tmp_path: Path):
    """A bag with both: JointState unless --topic names the LowState."""
    register_unitree_types()
    spec = BagSpec()
    for row in range(10):
        stamp = stamp_of(run, row)
        spec.add("/lowstate", GO_LOW_STATE, stamp, _message(run, row, GO_LOW_STATE))
        spec.add_joint_state(
            "/joint_states",
            stamp,
            JointStateMsg(stamp, list(run.joint_names), [0.0, 0.8, -1.5] * 4),
        )
    bag = write_bag(tmp_path / "both", spec)
    assert read_foot_trajectories(bag).summary.input_type == "sensor_msgs/msg/JointState"
    chosen = read_foot_trajectories(bag, topic="/lowstate")
    assert chosen.summary.input_type == GO_LOW_STATE and chosen.summary.rows == 10
