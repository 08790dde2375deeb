"""Bags of older recorders and of other robots (issue 20).

Old recorders: rosbag2 of Humble and Foxy (sqlite3, metadata version 5 / 4, no message
definitions; the fixtures reproduce real ``ros2 bag record`` output, see bag_factory) and ROS 1
bags whose definitions use ``roslib/Header``. The fixtures are checked to be what plain rosbags
cannot open, then read through a1_leg_fk: feet against Quadruped.fk, world feet against a
transform computed here, and every array bit for bit the same as from the same messages in a
current bag. Other robots: a JointState topic without the model's leg joints is an error naming
the joints, with nothing written.
"""

from __future__ import annotations

import json
import sqlite3
from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_factory import (
    T0,
    BagSpec,
    JointStateMsg,
    T,
    pose_message,
    rotation_z,
    write_bag,
)
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from a1_leg_fk import cli
from a1_leg_fk.gait.demo_gait import Gait, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.recording.trajectories import read_foot_trajectories

A1 = Quadruped.from_urdf()
NAMES = list(A1.joint_names)
MS = 1_000_000  # [ns]
# the errors: what rosbags alone says of such bags
NO_DEFINITIONS = "Bag contains no type definitions"
OLD_HEADER = "Type 'std_msgs/msg/Header' is unknown"
BUNDLED = (
    "rosbags' bundled ROS 2 Humble types and the package's Unitree definitions (the bag has no "
    "message definitions, as rosbag2 wrote before Iron; "
)
JOINT_STATE_MD5 = "3066dcd76a6cfaef579bd0f34173e9fd"  # sensor_msgs/JointState, ROS 1, since 2010


def bag_path(tmp_path: Path, kind: str, name: str = "run") -> Path:
    return tmp_path / (f"{name}.bag" if kind.startswith("ros1") else name)


def walking(spec: BagSpec, count: int = 40, seed: int = 3) -> list[list[float]]:
    """JointStates (positions and velocities, all twelve joints) every 10 ms; their angles."""
    rng = np.random.default_rng(seed)
    angles = []
    for index in range(count):
        q = rng.uniform(-1, 1, 12).tolist()
        angles.append(q)
        stamp = T0 + index * 10 * MS
        spec.add_joint_state(
            "/joint_states",
            stamp + 3,
            JointStateMsg(stamp, NAMES, q, rng.normal(size=12).tolist(), "trunk"),
        )
    return angles


@pytest.mark.parametrize(
    ("kind", "current", "problem", "types"),
    [
        (
            "humble",
            "mcap",
            NO_DEFINITIONS,
            BUNDLED + "ROS distro 'humble' from run_0.db3)",
        ),
        (
            "foxy",
            "sqlite3",
            NO_DEFINITIONS,
            BUNDLED + "no ROS distro recorded: Humble is the default)",
        ),
        (
            "ros1-roslib",
            "ros1",
            OLD_HEADER,
            "recorded in the bag (roslib/Header read as std_msgs/Header)",
        ),
    ],
)
def test_old_bags_read_like_current_ones(
    tmp_path: Path, kind: str, current: str, problem: str, types: str
) -> None:
    spec = BagSpec()
    angles = walking(spec)
    spec.add("/chatter", "std_msgs/msg/String", T0 + 5, T["std_msgs/msg/String"]("hello"))
    old = write_bag(bag_path(tmp_path, kind, "run"), spec, kind)
    new = write_bag(bag_path(tmp_path, current, "new"), spec, current)
    with pytest.raises(Exception, match=problem), AnyReader([old]):
        pass  # the fixture is a bag that rosbags alone cannot open
    got, want = read_foot_trajectories(old), read_foot_trajectories(new)
    assert got.summary.types == types and want.summary.types == "recorded in the bag"
    assert got.summary.rows == len(angles) == 40
    for row, q in zip(got.positions, angles, strict=True):
        assert np.abs(row - A1.fk(q)).max() <= 1e-12
    assert got.velocities is not None and want.velocities is not None
    for name in ("stamps_ns", "bag_times_ns", "positions", "velocities"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)


def test_roslib_header_fixture_is_the_old_definition(tmp_path: Path) -> None:
    """The ROS 1 fixture defines the header as the first ROS releases did, with the MD5 that
    sensor_msgs/JointState has had since (which rosbags checks when it opens the bag)."""
    spec = BagSpec()
    walking(spec, count=1)
    path = write_bag(tmp_path / "old.bag", spec, "ros1-roslib")
    data = path.read_bytes()
    assert b"MSG: roslib/Header\n" in data and b"std_msgs/Header" not in data
    assert b"message_definition=Header header\n" in data
    assert JOINT_STATE_MD5.encode() in data


@pytest.mark.parametrize(
    "msgtype",
    [
        "nav_msgs/msg/Odometry",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "tf2_msgs/msg/TFMessage",
    ],
)
def test_base_poses_from_a_humble_bag(tmp_path: Path, msgtype: str) -> None:
    spec = BagSpec()
    angles = walking(spec, count=20)
    topic = "/tf" if msgtype.startswith("tf2") else "/base_pose"
    poses = []
    for index in range(20):
        stamp = T0 + index * 10 * MS
        position, yaw = [0.05 * index, -0.01 * index, 0.3], 0.07 * index
        poses.append((np.array(position), yaw))
        spec.add(topic, msgtype, stamp, pose_message(msgtype, stamp, position, yaw))
    path = write_bag(tmp_path / "run", spec, "humble")
    result = read_foot_trajectories(path, base_pose=topic)
    assert result.world_frame == "odom" and result.summary.rows_without_pose == 0
    assert result.world_positions is not None
    for got, q, (origin, yaw) in zip(result.world_positions, angles, poses, strict=True):
        assert np.abs(got - (origin + A1.fk(q) @ rotation_z(yaw).T)).max() <= 1e-12


@pytest.mark.parametrize(
    ("distro", "where", "types"),
    [
        ("iron", "db3", BUNDLED.replace("Humble", "Iron") + "ROS distro 'iron' from run_0.db3)"),
        (
            "rolling",
            "db3",
            BUNDLED + "ROS distro 'rolling' from run_0.db3 has no bundled types: Humble is the "
            "default)",
        ),
        (
            "jazzy",
            "metadata.yaml",
            BUNDLED.replace("Humble", "Jazzy") + "ROS distro 'jazzy' from metadata.yaml)",
        ),
    ],
)
def test_the_recorded_distro_chooses_the_types(
    tmp_path: Path, distro: str, where: str, types: str
) -> None:
    """The distro in metadata.yaml (rosbag2 writes it from metadata version 8 on) comes first,
    then the one in the .db3's schema table (Humble's says humble)."""
    spec = BagSpec()
    walking(spec, count=3)
    path = write_bag(tmp_path / "run", spec, "humble")
    if where == "db3":
        with closing(sqlite3.connect(path / "run_0.db3")) as db, db:
            db.execute("UPDATE schema SET ros_distro = ?", (distro,))
    else:
        metadata = path / "metadata.yaml"
        metadata.write_text(metadata.read_text() + f"  ros_distro: {distro}\n")
    result = read_foot_trajectories(path)
    assert result.summary.types == types and result.summary.rows == 3


def test_standard_types_are_the_same_from_foxy_to_jazzy() -> None:
    """Why one bundled typestore reads them all: the types read here did not change."""
    stores = [get_typestore(s) for s in (Stores.ROS2_FOXY, Stores.ROS2_HUMBLE, Stores.ROS2_JAZZY)]
    for msgtype in (
        "sensor_msgs/msg/JointState",
        "nav_msgs/msg/Odometry",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "tf2_msgs/msg/TFMessage",
        "sensor_msgs/msg/Imu",
        "std_msgs/msg/String",
    ):
        assert len({store.generate_msgdef(msgtype) for store in stores}) == 1, msgtype


def test_copy_input_of_a_humble_bag(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Standard types are copied (with definitions now); a type nobody defines is named."""
    spec = BagSpec()
    walking(spec, count=5)
    spec.add("/chatter", "std_msgs/msg/String", T0 + 5, T["std_msgs/msg/String"]("hello"))
    path = write_bag(tmp_path / "run", spec, "humble")
    out = tmp_path / "out"
    assert cli.main(["bag", str(path), "--output-bag", str(out), "--copy-input"]) == 0
    with AnyReader([out]) as reader:
        copied = next(c for c in reader.connections if c.topic == "/chatter")
        message: Any = reader.deserialize(next(reader.messages([copied]))[2], copied.msgtype)
        assert message.data == "hello"
        assert {c.topic: c.msgcount for c in reader.connections}["/joint_states"] == 5
    spec.add("/custom", "my_robot_msgs/msg/Custom", T0 + 7, b"\x00\x01\x00\x00\x07")
    path = write_bag(tmp_path / "custom", spec, "humble")
    capsys.readouterr()
    assert cli.main(["bag", str(path), "--output-bag", str(tmp_path / "o2"), "--copy-input"]) == 2
    error = capsys.readouterr().err
    assert "--copy-input: /custom is my_robot_msgs/msg/Custom, which is not" in error
    assert not (tmp_path / "o2").exists() and len(error.splitlines()) == 1


# --- bags of other robots ------------------------------------------------------------------------

OTHER_ROBOTS = {
    "humanoid": [f"{side}_{part}_joint" for side in ("left", "right") for part in
                 ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll")],
    "arm": [f"joint_{index}" for index in range(6)],
    "wheels": ["wheel_left_joint", "wheel_right_joint"],
}  # fmt: skip


def other_robot_bag(path: Path, names: list[str], kind: str = "mcap") -> Path:
    spec = BagSpec()
    for index in range(30):
        stamp = T0 + index * 10 * MS
        spec.add_joint_state(
            "/joint_states", stamp, JointStateMsg(stamp, names, [0.01 * index] * len(names))
        )
        pose = pose_message("geometry_msgs/msg/PoseStamped", stamp, [0.0, 0.0, 0.3], 0.0)
        spec.add("/base_pose", "geometry_msgs/msg/PoseStamped", stamp, pose)
    spec.add_joint_state("/gripper/joint_states", T0, JointStateMsg(T0, ["finger"], [0.0]))
    return write_bag(path, spec, kind)


def expect_no_leg_joints(
    capsys: pytest.CaptureFixture, argv: list[str], names: list[str], folder: Path, bag: Path
) -> None:
    assert cli.main(argv) == 2
    error = capsys.readouterr().err
    assert len(error.splitlines()) == 1 and "Traceback" not in error
    assert "no JointState message on /joint_states names a leg joint of the model" in error
    assert f"it expects {', '.join(NAMES)};" in error
    shown = names[:8] + (["..."] if len(names) > 8 else [])
    assert f"its messages name {', '.join(shown)} ({len(names)} names)" in error
    for way_out in ("--joint-aliases NAME=joint", "--urdf FILE", "--topic"):
        assert way_out in error
    assert "(the bag also has /gripper/joint_states)" in error
    assert sorted(p.name for p in folder.iterdir()) == [bag.name]  # no output, no temporary


@pytest.mark.parametrize("robot", sorted(OTHER_ROBOTS))
def test_bag_of_another_robot_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, robot: str
) -> None:
    pytest.importorskip("matplotlib")
    names = OTHER_ROBOTS[robot]
    bag = other_robot_bag(tmp_path / "run", names, "humble" if robot == "arm" else "mcap")
    argv = ["bag", str(bag), "--topic", "/joint_states", "--csv", str(tmp_path / "feet.csv")]
    argv += ["--output-bag", str(tmp_path / "feet"), "--plot", str(tmp_path / "feet.png")]
    expect_no_leg_joints(capsys, argv, names, tmp_path, bag)


def test_gait_of_another_robot_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    pytest.importorskip("matplotlib")
    names = OTHER_ROBOTS["humanoid"]
    bag = other_robot_bag(tmp_path / "run", names)
    argv = ["gait", str(bag), "--topic", "/joint_states", "--base-pose", "/base_pose"]
    for option, name in (("--json", "g.json"), ("--csv-contacts", "c.csv"), ("--plot", "g.png")):
        argv += [option, str(tmp_path / name)]
    expect_no_leg_joints(capsys, argv, names, tmp_path, bag)


def test_leg_joints_after_other_messages_are_read(tmp_path: Path) -> None:
    """The rule is about the whole topic: a gripper's messages before the legs' do not count."""
    spec = BagSpec()
    for index in range(5):
        spec.add_joint_state("/joint_states", T0 + index, JointStateMsg(T0 + index, ["g"], [0.0]))
    angles = walking(spec, count=4)
    result = read_foot_trajectories(write_bag(tmp_path / "run", spec))
    assert result.summary.rows == 4 and result.summary.outcomes["no_leg_joints"] == 5
    for row, q in zip(result.positions, angles, strict=True):
        assert np.abs(row - A1.fk(q)).max() <= 1e-12


def test_gait_reads_a_humble_bag_as_a_current_one(tmp_path: Path) -> None:
    """The demo's gait (joint_state_demo's), base held still, through both kinds of bag: the
    same report."""
    gait = Gait(limits_of(A1))
    spec = BagSpec()
    for index in range(600):  # 6 s: standing up (feet still), then trotting
        stamp = T0 + index * 10 * MS
        angles = gait.angles(index * 0.01)
        spec.add_joint_state("/joint_states", stamp, JointStateMsg(stamp, NAMES, angles))
        pose = pose_message("nav_msgs/msg/Odometry", stamp, [0.0, 0.0, 0.3], 0.0)
        spec.add("/odom", "nav_msgs/msg/Odometry", stamp, pose)
    reports = []
    for kind in ("humble", "mcap"):
        bag = write_bag(tmp_path / kind, spec, kind)
        out = tmp_path / f"{kind}.json"
        assert cli.main(["gait", str(bag), "--base-pose", "/odom", "--json", str(out)]) == 0
        reports.append(json.loads(out.read_text()))
        reports[-1].pop("input")
    assert reports[0] == reports[1] and reports[0]["world_frame"] == "odom"
