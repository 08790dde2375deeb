"""``a1-leg-fk bag``: CSV and output bag read back, and every bad input of the issue (one line on
stderr, exit 2, nothing under the final output name)."""

from __future__ import annotations

import csv
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from a1_leg_fk import cli
from a1_leg_fk.kinematics import Quadruped
from bag_factory import T, BagSpec, JointStateMsg, write_bag

A1 = Quadruped.from_urdf()
NAMES = list(A1.joint_names)
T0 = 1_700_000_000_000_000_000
LEGS = ("FR", "FL", "RR", "RL")


def steady_bag(path: Path, kind: str = "mcap", count: int = 30, velocities: bool = True, seed: int = 5) -> tuple[Path, list]:
    rng = np.random.default_rng(seed)
    spec, angles = BagSpec(), []
    for index in range(count):
        q = rng.uniform(-1, 1, 12).tolist()
        angles.append(q)
        rates = rng.normal(size=12).tolist() if velocities else []
        spec.add_joint_state("/joint_states", T0 + index * 1_000_000 + 9, JointStateMsg(T0 + index * 1_000_000, NAMES, q, rates, "base"))
    spec.add("/chatter", "std_msgs/msg/String", T0 + 5, T["std_msgs/msg/String"]("hello"))
    return write_bag(path, spec, kind), angles


def test_csv_columns_values_and_round_trip(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    bag, angles = steady_bag(tmp_path / "in")
    out = tmp_path / "feet.csv"
    assert cli.main(["bag", str(bag), "--csv", str(out), "--quiet"]) == 0
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["stamp_ns", "bag_time_ns", *[f"{leg}_{a}" for leg in LEGS for a in "xyz"], *[f"{leg}_v{a}" for leg in LEGS for a in "xyz"]]
    assert len(rows) == 1 + len(angles)
    for index, (row, q) in enumerate(zip(rows[1:], angles)):
        assert int(row[0]) == T0 + index * 1_000_000 and int(row[1]) == T0 + index * 1_000_000 + 9
        assert np.abs(np.array([float(v) for v in row[2:14]]).reshape(4, 3) - A1.fk(q)).max() <= 1e-12
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
    assert cli.main(["bag", str(bag), "--output-bag", str(out), "--storage", storage, "--copy-input", "--quiet"]) == 0
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
                message = reader.deserialize(raw, connection.msgtype)
                assert message.header.frame_id == "trunk"
                assert message.header.stamp.sec * 10**9 + message.header.stamp.nanosec == T0 + index * 1_000_000
                assert bag_time == T0 + index * 1_000_000 + 9
                point = np.array([message.point.x, message.point.y, message.point.z])
                assert np.abs(point - A1.fk(angles[index])[leg_slot]).max() <= 1e-12
        copied = next(c for c in reader.connections if c.topic == "/chatter")
        assert [reader.deserialize(raw, copied.msgtype).data for _, _, raw in reader.messages([copied])] == ["hello"]


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


def expect_bad(capsys: pytest.CaptureFixture, argv: list[str], fragment: str, outputs: list[Path], code: int = 2) -> None:
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
    expect_bad(capsys, ["bag", str(tmp_path / "missing"), "--csv", str(out)], "no such file or directory", [out])
    (tmp_path / "empty_dir").mkdir()
    expect_bad(capsys, ["bag", str(tmp_path / "empty_dir"), "--csv", str(out)], "a directory without a ROS 2 bag", [out])
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap at all")
    expect_bad(capsys, ["bag", str(tmp_path / "junk.mcap"), "--csv", str(out)], "cannot open as a ROS bag", [out])
    two = two_topic_bag(tmp_path / "two")
    expect_bad(capsys, ["bag", str(two), "--csv", str(out)], "several JointState topics, choose one with --topic: /a/joint_states, /b/joint_states", [out])
    expect_bad(capsys, ["bag", str(two), "--topic", "/c", "--csv", str(out)], "--topic /c: no such topic", [out])
    expect_bad(capsys, ["bag", str(two), "--topic", "/odom_string", "--csv", str(out)], "--topic /odom_string is std_msgs/msg/String, expected sensor_msgs/msg/JointState", [out])
    expect_bad(capsys, ["bag", str(two), "--topic", "/a/joint_states", "--base-pose", "/nothing", "--csv", str(out)], "--base-pose /nothing: no such topic", [out])
    expect_bad(capsys, ["bag", str(two), "--topic", "/a/joint_states", "--base-pose", "/odom_string", "--csv", str(out)],
               "--base-pose /odom_string is std_msgs/msg/String, expected nav_msgs/msg/Odometry or", [out])
    only_string = BagSpec()
    only_string.add("/odom_string", "std_msgs/msg/String", T0, T["std_msgs/msg/String"]("x"))
    no_joints = write_bag(tmp_path / "nojoints", only_string, "mcap")
    expect_bad(capsys, ["bag", str(no_joints), "--csv", str(out)], "no sensor_msgs/msg/JointState topic; topics: /odom_string (std_msgs/msg/String)", [out])
    expect_bad(capsys, ["bag", str(two), "--topic", "/a/joint_states"], "nothing to write", [])
    expect_bad(capsys, ["bag", str(two), "--csv", str(two / "feet.csv"), "--topic", "/a/joint_states"], "inside the input bag", [two / "feet.csv"])
    out.write_text("keep me")
    expect_bad(capsys, ["bag", str(two), "--csv", str(out), "--topic", "/a/joint_states"], "exists already (use --force to replace it)", [])
    assert out.read_text() == "keep me"
    assert cli.main(["bag", str(two), "--csv", str(out), "--topic", "/a/joint_states", "--force", "--quiet"]) == 0
    assert out.read_text().startswith("stamp_ns,")
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no temporary files left


@pytest.mark.parametrize("kind", ["mcap", "sqlite3"])
def test_truncated_bag_gives_what_was_read_and_exit_1(tmp_path: Path, capsys: pytest.CaptureFixture, kind: str) -> None:
    bag, _ = steady_bag(tmp_path / "in", kind=kind, count=3000, velocities=False)
    data = next(bag.glob("*.mcap" if kind == "mcap" else "*.db3"))
    before = data.read_bytes()
    if kind == "mcap":
        (bag / "metadata.yaml").unlink()
        data.write_bytes(before[: len(before) // 2])
    else:
        with sqlite3.connect(data) as db:  # corrupt the payload of one row in the middle
            db.execute("UPDATE messages SET data = x'0001' WHERE id = 1500")
    out = tmp_path / "feet.csv"
    code = cli.main(["bag", str(bag), "--csv", str(out), "--quiet"])
    error = capsys.readouterr().err
    assert "Traceback" not in error
    if kind == "mcap" and code == 2:  # rosbags cannot open an MCAP without its summary at all
        assert "cannot open as a ROS bag" in error and not out.exists()
        return
    assert code == 1 and "stopped early" in error
    rows = out.read_text().splitlines()
    assert 1 < len(rows) < 3001


@pytest.mark.slow
def test_installed_script(tmp_path: Path) -> None:
    bag, _ = steady_bag(tmp_path / "in")
    script = Path(sys.executable).with_name("a1-leg-fk")
    result = subprocess.run([str(script), "bag", str(bag), "--csv", str(tmp_path / "f.csv")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert "rows:      30" in result.stdout
    result = subprocess.run([str(script), "bag", str(tmp_path / "nope"), "--csv", str(tmp_path / "g.csv")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "no such file" in result.stderr
    shutil.rmtree(bag)
