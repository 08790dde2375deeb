"""``a1-leg-fk bag``: CSV and output bag read back, and every bad input of the issue (one line on
stderr, exit 2, nothing under the final output name)."""

from __future__ import annotations

import csv
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data
import pytest
from bag_factory import T0, TYPESTORE, BagSpec, JointStateMsg, T, header, pose, write_bag
from pybullet_reference import PyBulletRobot
from rosbags.highlevel import AnyReader
from shared import LEGS

from a1_leg_fk import cli
from a1_leg_fk.kinematics.quadruped import Quadruped

A1 = Quadruped.from_urdf()
NAMES = list(A1.joint_names)


def steady_bag(
    path: Path, kind: str = "mcap", count: int = 30, velocities: bool = True, seed: int = 5
) -> tuple[Path, list]:
    rng = np.random.default_rng(seed)
    spec, angles = BagSpec(), []
    for index in range(count):
        q = rng.uniform(-1, 1, 12).tolist()
        angles.append(q)
        rates = rng.normal(size=12).tolist() if velocities else []
        spec.add_joint_state(
            "/joint_states",
            T0 + index * 1_000_000 + 9,
            JointStateMsg(T0 + index * 1_000_000, NAMES, q, rates, "base"),
        )
    spec.add("/chatter", "std_msgs/msg/String", T0 + 5, T["std_msgs/msg/String"]("hello"))
    return write_bag(path, spec, kind), angles


def test_csv_columns_values_and_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    bag, angles = steady_bag(tmp_path / "in")
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out), "--quiet"]) == 0
    rows = list(csv.reader(out.open()))
    assert rows[0] == [
        "stamp_ns",
        "bag_time_ns",
        *[f"{leg}_{a}" for leg in LEGS for a in "xyz"],
        *[f"{leg}_v{a}" for leg in LEGS for a in "xyz"],
    ]
    assert len(rows) == 1 + len(angles)
    for index, (row, q) in enumerate(zip(rows[1:], angles)):
        assert int(row[0]) == T0 + index * 1_000_000 and int(row[1]) == T0 + index * 1_000_000 + 9
        assert (
            np.abs(np.array([float(v) for v in row[2:14]]).reshape(4, 3) - A1.fk(q)).max() <= 1e-12
        )
    text = capsys.readouterr().out
    assert "messages:  30 read, 30 accepted, 0 rejected (none)" in text and "rows:      30" in text


def test_csv_without_velocities_has_no_velocity_columns(tmp_path: Path) -> None:
    bag, _ = steady_bag(tmp_path / "in", velocities=False)
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out), "--quiet"]) == 0
    rows = list(csv.reader(out.open()))
    assert len(rows[0]) == 14 and all(len(row) == 14 for row in rows)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_output_bag_read_back(tmp_path: Path, storage: str) -> None:
    bag, angles = steady_bag(tmp_path / "in.bag", kind="ros1")
    out = tmp_path / "feet_bag"
    assert (
        cli.main(
            [
                "bag",
                str(bag),
                "--output-bag",
                str(out),
                "--storage",
                storage,
                "--copy-input",
                "--quiet",
            ]
        )
        == 0
    )
    assert (out / "metadata.yaml").exists() and "version: 9" in (out / "metadata.yaml").read_text()
    with AnyReader([out]) as reader:
        topics = {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}
        assert topics["/joint_states"] == ("sensor_msgs/msg/JointState", 30)
        assert topics["/chatter"] == ("std_msgs/msg/String", 1)
        for leg_slot, leg in enumerate(LEGS):
            assert topics[f"/foot_positions/{leg}"] == ("geometry_msgs/msg/PointStamped", 30)
            assert topics[f"/foot_velocities/{leg}"] == ("geometry_msgs/msg/Vector3Stamped", 30)
            connection = next(c for c in reader.connections if c.topic == f"/foot_positions/{leg}")
            for index, (_, bag_time, raw) in enumerate(reader.messages([connection])):
                message: Any = reader.deserialize(raw, connection.msgtype)  # a PointStamped
                assert message.header.frame_id == "trunk"
                assert (
                    message.header.stamp.sec * 10**9 + message.header.stamp.nanosec
                    == T0 + index * 1_000_000
                )
                assert bag_time == T0 + index * 1_000_000 + 9
                point = np.array([message.point.x, message.point.y, message.point.z])
                assert np.abs(point - A1.fk(angles[index])[leg_slot]).max() <= 1e-12
        copied = next(c for c in reader.connections if c.topic == "/chatter")
        chatter: list[Any] = [  # std_msgs/msg/String
            reader.deserialize(raw, copied.msgtype) for _, _, raw in reader.messages([copied])
        ]
        assert [message.data for message in chatter] == ["hello"]


def test_plot_is_written(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    bag, _ = steady_bag(tmp_path / "in")
    assert cli.main(["bag", str(bag), "--plot", str(tmp_path / "feet.png"), "--quiet"]) == 0
    assert (tmp_path / "feet.png").read_bytes()[:4] == b"\x89PNG"


def two_topic_bag(path: Path) -> Path:
    spec = BagSpec()
    spec.add_joint_state("/a/joint_states", T0, JointStateMsg(T0, NAMES, [0.0] * 12))
    spec.add_joint_state("/b/joint_states", T0 + 1, JointStateMsg(T0, NAMES, [0.0] * 12))
    spec.add("/odom_string", "std_msgs/msg/String", T0 + 2, T["std_msgs/msg/String"]("x"))
    return write_bag(path, spec, "sqlite3")


def expect_bad(
    capsys: pytest.CaptureFixture,
    argv: list[str],
    fragment: str,
    outputs: list[Path],
    code: int = 2,
) -> None:
    assert cli.main(argv) == code
    error = capsys.readouterr().err.strip()
    assert fragment in error, error
    assert "Traceback" not in error
    if code == 2:
        assert len(error.splitlines()) == 1
    for output in outputs:
        assert not output.exists()


def test_bad_inputs(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out.csv"
    expect_bad(
        capsys,
        ["bag", str(tmp_path / "missing"), "--csv", str(out)],
        "no such file or directory",
        [out],
    )
    (tmp_path / "empty_dir").mkdir()
    expect_bad(
        capsys,
        ["bag", str(tmp_path / "empty_dir"), "--csv", str(out)],
        "a directory without a ROS 2 bag",
        [out],
    )
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap at all")
    expect_bad(
        capsys,
        ["bag", str(tmp_path / "junk.mcap"), "--csv", str(out)],
        "cannot open as a ROS bag",
        [out],
    )
    two = two_topic_bag(tmp_path / "two")
    expect_bad(
        capsys,
        ["bag", str(two), "--csv", str(out)],
        "several JointState topics, choose one with --topic: /a/joint_states, /b/joint_states",
        [out],
    )
    expect_bad(
        capsys,
        ["bag", str(two), "--topic", "/c", "--csv", str(out)],
        "--topic /c: no such topic",
        [out],
    )
    expect_bad(
        capsys,
        ["bag", str(two), "--topic", "/odom_string", "--csv", str(out)],
        "--topic /odom_string is std_msgs/msg/String, expected sensor_msgs/msg/JointState",
        [out],
    )
    expect_bad(
        capsys,
        [
            "bag",
            str(two),
            "--topic",
            "/a/joint_states",
            "--base-pose",
            "/nothing",
            "--csv",
            str(out),
        ],
        "--base-pose /nothing: no such topic",
        [out],
    )
    expect_bad(
        capsys,
        [
            "bag",
            str(two),
            "--topic",
            "/a/joint_states",
            "--base-pose",
            "/odom_string",
            "--csv",
            str(out),
        ],
        "--base-pose /odom_string is std_msgs/msg/String, expected nav_msgs/msg/Odometry or",
        [out],
    )
    only_string = BagSpec()
    only_string.add("/odom_string", "std_msgs/msg/String", T0, T["std_msgs/msg/String"]("x"))
    no_joints = write_bag(tmp_path / "nojoints", only_string, "mcap")
    expect_bad(
        capsys,
        ["bag", str(no_joints), "--csv", str(out)],
        "no sensor_msgs/msg/JointState topic; topics: /odom_string (std_msgs/msg/String)",
        [out],
    )
    expect_bad(capsys, ["bag", str(two), "--topic", "/a/joint_states"], "nothing to write", [])
    expect_bad(
        capsys,
        ["bag", str(two), "--csv", str(two / "feet.csv"), "--topic", "/a/joint_states"],
        "inside the input bag",
        [two / "feet.csv"],
    )
    out.write_text("keep me")
    expect_bad(
        capsys,
        ["bag", str(two), "--csv", str(out), "--topic", "/a/joint_states"],
        "exists already (use --force to replace it)",
        [],
    )
    assert out.read_text() == "keep me"
    folder = tmp_path / "results"  # a file output naming a folder: --force must not remove it
    (folder / "inner").mkdir(parents=True)
    (folder / "inner" / "notes.txt").write_text("keep me too")
    for option in ("--csv", "--plot"):
        expect_bad(
            capsys,
            ["bag", str(two), option, str(folder), "--topic", "/a/joint_states", "--force"],
            f"{option} {folder}: is a folder; give a file name",
            [],
        )
    assert (folder / "inner" / "notes.txt").read_text() == "keep me too"
    assert (
        cli.main(
            [
                "bag",
                str(two),
                "--csv",
                str(out),
                "--topic",
                "/a/joint_states",
                "--force",
                "--quiet",
            ]
        )
        == 0
    )
    assert out.read_text().startswith("stamp_ns,")
    assert (
        sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
    )  # no temporary files left


@pytest.mark.parametrize("kind", ["mcap", "mcap file", "sqlite3"])
def test_truncated_bag_gives_what_was_read_and_exit_1(
    tmp_path: Path, capsys: pytest.CaptureFixture, kind: str
) -> None:
    bag, angles = steady_bag(
        tmp_path / "in",
        kind="sqlite3" if kind == "sqlite3" else "mcap",
        count=3000,
        velocities=False,
    )
    data = next(bag.glob("*.db3" if kind == "sqlite3" else "*.mcap"))
    before = data.read_bytes()
    if kind == "sqlite3":
        with sqlite3.connect(data) as db:  # corrupt the payload of one message in the middle
            db.execute("UPDATE messages SET data = x'0001' WHERE id = 1500")
        # ids 1 (/chatter) .. 1499 before it: the 1,499th JointState is damaged
        expected_rows = 1498
        where = "the recording is damaged: message 1,499 of /joint_states (bag time"
    else:
        data.write_bytes(before[: len(before) // 2])  # the recorder died half way
        expected_rows, where = None, "is truncated or has no readable summary: read its first"
        bag = data if kind == "mcap file" else bag
    damaged = data.read_bytes()
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out), "--quiet"]) == 1
    captured = capsys.readouterr()
    assert (
        "Traceback" not in captured.err
        and where in captured.err
        and "stopped early" in captured.err
    )
    rows = list(csv.reader(out.open()))[1:]
    assert 1000 < len(rows) < 3000 and (expected_rows is None or len(rows) == expected_rows)
    for index, row in enumerate(rows):  # what was read is right
        assert (
            np.abs(
                np.array([float(v) for v in row[2:14]]).reshape(4, 3) - A1.fk(angles[index])
            ).max()
            <= 1e-12
        )
    assert data.read_bytes() == damaged  # the input is never modified


@pytest.mark.slow
def test_installed_script(tmp_path: Path) -> None:
    bag, _ = steady_bag(tmp_path / "in")
    script = Path(sys.executable).with_name("a1-leg-fk")
    result = subprocess.run(
        [str(script), "bag", str(bag), "--csv", str(tmp_path / "f.csv")],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert "rows:      30" in result.stdout
    result = subprocess.run(
        [str(script), "bag", str(tmp_path / "nope"), "--csv", str(tmp_path / "g.csv")],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert (
        result.returncode == 2
        and result.stderr.count("\n") == 1
        and "no such file" in result.stderr
    )
    shutil.rmtree(bag)


def test_velocities_that_start_late_get_their_columns(tmp_path: Path) -> None:
    """The first block of rows has no velocities, a later one has: earlier rows get empty cells."""
    spec = BagSpec()
    rng = np.random.default_rng(9)
    angles, rates = [], []
    for index in range(6000):  # more than one block (4096 messages)
        q = rng.uniform(-1, 1, 12).tolist()
        dq = rng.normal(size=12).tolist() if index >= 5000 else []
        angles.append(q)
        rates.append(dq)
        spec.add_joint_state(
            "/joint_states",
            T0 + index * 1_000_000,
            JointStateMsg(T0 + index * 1_000_000, NAMES, q, dq),
        )
    bag = write_bag(tmp_path / "late", spec, "mcap")
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out), "--quiet"]) == 0
    rows = list(csv.reader(out.open()))
    assert len(rows[0]) == 26 and all(len(row) == 26 for row in rows)
    for row, q, dq in zip(rows[1:], angles, rates):
        velocity = row[14:]
        if dq:
            assert (
                np.abs(
                    np.array([float(v) for v in velocity]).reshape(4, 3)
                    - A1.foot_velocities(q, dq)
                ).max()
                <= 1e-12
            )
        else:
            assert velocity == [""] * 12


def test_interrupted_run_leaves_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    from a1_leg_fk.recording import outputs as recording_outputs

    bag, _ = steady_bag(tmp_path / "in", count=5000)
    written = []

    def interrupt(self, block) -> None:
        written.append(len(block.stamps_ns))
        if len(written) == 2:
            raise KeyboardInterrupt  # as Ctrl-C in the middle of the run
        original(self, block)

    original = recording_outputs.CsvWriter.write
    monkeypatch.setattr(recording_outputs.CsvWriter, "write", interrupt)
    out, out_bag = tmp_path / "feet.csv", tmp_path / "feet_bag"
    assert (
        cli.main(["bag", str(bag), "--csv", str(out), "--output-bag", str(out_bag), "--quiet"])
        == 130
    )
    assert "interrupted" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in"]  # no output, no temporary folder


def test_world_feet_in_csv_and_output_bag(tmp_path: Path) -> None:
    spec = BagSpec()
    rng = np.random.default_rng(21)
    angles = []
    for index in range(20):
        stamp = T0 + index * 10_000_000
        q = rng.uniform(-1, 1, 12).tolist()
        angles.append(q)
        spec.add_joint_state("/joint_states", stamp + 1, JointStateMsg(stamp, NAMES, q))
        base = pose((1.0 + index, 2.0, 0.5), (0.0, 0.0, 1.0, 0.0))
        spec.add(
            "/pose",
            "geometry_msgs/msg/PoseStamped",
            stamp,
            T["geometry_msgs/msg/PoseStamped"](header(stamp, "map"), base),
        )
    bag = write_bag(tmp_path / "in", spec, "sqlite3")
    out, out_bag = tmp_path / "feet.csv", tmp_path / "feet_bag"
    assert (
        cli.main(
            [
                "bag",
                str(bag),
                "--base-pose",
                "/pose",
                "--csv",
                str(out),
                "--output-bag",
                str(out_bag),
                "--storage",
                "sqlite3",
                "--copy-input",
                "--quiet",
            ]
        )
        == 0
    )
    rows = list(csv.reader(out.open()))
    assert rows[0][14:] == [f"{leg}_w{a}" for leg in LEGS for a in "xyz"] and len(rows) == 21
    yaw_pi = np.diag([-1.0, -1.0, 1.0])  # the quaternion (0, 0, 1, 0): half a turn about z
    for index, (row, q) in enumerate(zip(rows[1:], angles)):
        want = np.array([1.0 + index, 2.0, 0.5]) + A1.fk(q) @ yaw_pi.T
        assert np.abs(np.array([float(v) for v in row[14:]]).reshape(4, 3) - want).max() <= 1e-12
    with AnyReader([out_bag]) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        assert topics == {
            **{f"/foot_positions/{leg}": "geometry_msgs/msg/PointStamped" for leg in LEGS},
            **{f"/foot_positions_world/{leg}": "geometry_msgs/msg/PointStamped" for leg in LEGS},
            "/joint_states": "sensor_msgs/msg/JointState",
            "/pose": "geometry_msgs/msg/PoseStamped",
        }
        copied = next(c for c in reader.connections if c.topic == "/pose")
        poses: list[Any] = [
            reader.deserialize(raw, copied.msgtype) for _, _, raw in reader.messages([copied])
        ]
        assert [p.pose.position.x for p in poses] == [1.0 + index for index in range(20)]
        connection = next(c for c in reader.connections if c.topic == "/foot_positions_world/RL")
        messages: list[Any] = [
            reader.deserialize(raw, connection.msgtype)
            for _, _, raw in reader.messages([connection])
        ]
        assert {m.header.frame_id for m in messages} == {"map"} and len(messages) == 20
        assert messages[3].point.x == float(rows[4][14 + 9]) and messages[3].point.z == float(
            rows[4][14 + 11]
        )


def test_output_mcap_read_by_the_reference_mcap_library(tmp_path: Path) -> None:
    """The format's own reader (CRCs checked) sees a ros2 profile, ros2msg schemas, CDR messages
    whose bytes decode (rosbags) to the feet, and a summary that counts them."""
    from mcap.reader import make_reader

    bag, angles = steady_bag(tmp_path / "in", count=25)
    out = tmp_path / "feet_bag"
    assert cli.main(["bag", str(bag), "--output-bag", str(out), "--quiet"]) == 0
    with (out / "feet_bag.mcap").open("rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == 8 * 25
        seen = {}
        for schema, channel, message in reader.iter_messages(topics=["/foot_positions/RR"]):
            assert schema is not None
            assert (schema.name, schema.encoding, channel.message_encoding) == (
                "geometry_msgs/msg/PointStamped",
                "ros2msg",
                "cdr",
            )
            decoded: Any = TYPESTORE.deserialize_cdr(message.data, schema.name)  # a PointStamped
            point = decoded.point
            seen[message.log_time] = (point.x, point.y, point.z)
    assert len(seen) == 25
    for index, q in enumerate(angles):
        assert np.abs(np.array(seen[T0 + index * 1_000_000 + 9]) - A1.fk(q)[2]).max() <= 1e-12


def test_unwritable_output_folder_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    bag, _ = steady_bag(tmp_path / "in", count=5)
    expect_bad(
        capsys,
        ["bag", str(bag), "--csv", str(tmp_path / "no_such_folder" / "feet.csv")],
        "folder",
        [],
    )
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.access(locked, os.W_OK):
            pytest.skip("running as root: permissions are not enforced")
        expect_bad(
            capsys,
            ["bag", str(bag), "--csv", str(locked / "feet.csv")],
            "Permission denied",
            [locked / "feet.csv"],
        )
    finally:
        locked.chmod(0o700)


def test_urdf_foot_links_and_joint_aliases_for_the_mini_cheetah(tmp_path: Path) -> None:
    """--urdf, --foot-links and --joint-aliases as the node's parameters; feet against PyBullet."""
    urdf = Path(pybullet_data.getDataPath()) / "mini_cheetah" / "mini_cheetah.urdf"
    feet = {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"}
    robot = Quadruped.from_urdf(str(urdf), feet)
    names = ["fr_roll", *robot.joint_names[1:]]
    rng = np.random.default_rng(8)
    spec, angles = BagSpec(), []
    for index in range(10):
        q = rng.uniform(-0.7, 0.7, 12).tolist()
        angles.append(q)
        spec.add_joint_state("/joint_states", T0 + index, JointStateMsg(T0 + index, names, q))
    bag = write_bag(tmp_path / "cheetah", spec, "mcap")
    out = tmp_path / "feet.csv"
    assert (
        cli.main(
            [
                "bag",
                str(bag),
                "--urdf",
                str(urdf),
                "--foot-links",
                *(f"{leg}={link}" for leg, link in feet.items()),
                "--joint-aliases",
                "fr_roll=torso_to_abduct_fr_j",
                "--csv",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    rows = list(csv.reader(out.open()))[1:]
    with PyBulletRobot(urdf) as reference:
        for row, q in zip(rows, angles, strict=True):
            got = np.array([float(v) for v in row[2:14]]).reshape(4, 3)
            assert (
                np.abs(got - reference.feet(list(robot.joint_names), list(feet.values()), q)).max()
                <= 1e-7
            )
