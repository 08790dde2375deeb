"""``a1-leg-fk odom``: a PyBullet walk in a bag (joint_states, imu, the true base pose) -> CSV, PNG
and the comparison with the truth, checked against the simulation itself; the bag tool's
bad-input rules; and the node's wire formats (Imu read from bytes, Odometry patched into bytes)
against rclpy's own serialization."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest
from bag_factory import T0, BagSpec
from nav_msgs.msg import Odometry
from odometry_bags import IMU_TOPIC, TRUTH_TOPIC, write_sim_bag
from pybullet_sim import simulate, walking_targets
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Imu

from a1_leg_fk import cli
from a1_leg_fk.cli.odom import CSV_HEADER
from a1_leg_fk.ros.odometry_wire import SerializedOdometry, imu_message_fields
from a1_leg_fk.wire.imu import imu_fields

SIM_S = 4.0
LANDED_S = 0.5
"""[s] The robot is spawned above the plane: scores start once it stands."""


@pytest.fixture(scope="module")
def run():
    return simulate(walking_targets(), SIM_S)


@pytest.fixture(scope="module")
def bag(run, tmp_path_factory):
    return write_sim_bag(tmp_path_factory.mktemp("odom") / "walk", run)


def test_csv_plot_and_truth(run, bag, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out, png = tmp_path / "odom.csv", tmp_path / "odom.png"
    code = cli.main(
        ["odom", str(bag), "--truth", TRUTH_TOPIC, "--csv", str(out), "--plot", str(png)]
    )
    printed = capsys.readouterr().out
    print(printed)
    assert code == 0
    rows = list(csv.reader(out.open()))
    assert rows[0] == CSV_HEADER.strip().split(",")
    values = np.array(rows[1:], dtype=float)
    assert len(values) == len(run.stamps_s)
    stamps = np.array([int(row[0]) for row in rows[1:]])
    assert (stamps - T0 == np.round(run.stamps_s * 1e9)).all()
    assert np.allclose(np.linalg.norm(values[:, 4:8], axis=1), 1.0)
    # the state filter's orientation: the IMU's (the truth here) fused with the legs
    cosine = np.abs(np.einsum("ni,ni->n", values[:, 4:8], run.base_quaternions)).clip(max=1.0)
    angle = np.degrees(2.0 * np.arccos(cosine))
    print(f"orientation error: max {angle.max():.3f} deg")
    assert angle.max() < 1.0
    # honest velocity variances, both sides (issue 27's goals): the error within 3 sigma, and
    # sigma at most 5x the actual RMS error (after the drop from the spawn height)
    walking = run.stamps_s >= LANDED_S
    error = np.abs(values[:, 8:11] - run.body_velocities)[walking]
    sigma = np.sqrt(values[walking, 14:17])
    inside = (error <= 3.0 * sigma).all(axis=1).mean()
    ratio = (sigma.mean(axis=0) / np.sqrt((error**2).mean(axis=0))).max()
    print(f"velocity error within 3 sigma on {100 * inside:.1f} % of the samples; sigma / RMS "
          f"error at most {ratio:.2f}")  # fmt: skip
    assert (values[:, 14:17] > 0).all() and inside >= 0.95 and ratio <= 5.0
    # the local ground under the base: PyBullet's plane (z = 0), level, once a stride has stood
    stood = run.stamps_s >= LANDED_S + 0.5
    above = (values[:, 3] - values[:, 17])[stood]
    tilt = np.degrees(np.arccos(values[stood, 20].clip(max=1.0)))
    print(f"ground: base height error max {np.abs(above - run.base_positions[stood, 2]).max():.4f}"
          f" m, tilt max {tilt.max():.3f} deg")  # fmt: skip
    assert np.abs(above - run.base_positions[stood, 2]).max() <= 0.02 and tilt.max() <= 1.0
    assert (values[stood, 21:24] > 0).all()
    # the summary's numbers, recomputed from the CSV and the simulation
    moved = run.base_positions[-1] - run.base_positions[0]
    # odom and the truth share the IMU's yaw: no turn between them
    error = np.linalg.norm(values[-1, 1:4] - moved)
    distance = np.linalg.norm(np.diff(run.base_positions, axis=0), axis=1).sum()
    line = next(line for line in printed.splitlines() if line.startswith("truth:"))
    said = re.search(r"final position error ([\d.]+) m \(([\d.]+) % of ([\d.]+) m\)", line)
    assert said is not None, line
    # the CSV's positions are rounded: the last printed digit may differ by one
    for value, expected, digit in zip(
        said.groups(), (error, 100 * error / distance, distance), (1e-3, 1e-2, 1e-3)
    ):
        assert abs(float(value) - expected) <= digit, line
    assert "smoothed over the recording (RTS)" in printed
    assert png.stat().st_size > 10_000
    assert "imu:       /imu (2000 samples; 2000 of 2000 rows had one)" in printed


def test_causal_is_the_filters_own_estimate(bag, tmp_path: Path, capsys) -> None:
    """``--causal``: the rows of the filter alone (odometry_track's default, which the node's
    tests hold equal to leg_odometry_node), to the last bit; the default differs and says so."""
    from a1_leg_fk.recording.csv_text import format_rows
    from a1_leg_fk.recording.odometry import odometry_track

    causal, smoothed = tmp_path / "causal.csv", tmp_path / "smoothed.csv"
    assert cli.main(["odom", str(bag), "--causal", "--csv", str(causal)]) == 0
    assert "causal, as the node has it" in capsys.readouterr().out
    track = odometry_track(bag)
    floats = np.hstack(
        [track.positions, track.orientations, track.linear, track.angular,
         track.twist_variances[:, :3], track.grounds]
    )  # fmt: skip
    expected = CSV_HEADER.encode() + format_rows(track.stamps_ns[:, None], floats)
    assert causal.read_bytes() == expected
    assert cli.main(["odom", str(bag), "--csv", str(smoothed)]) == 0
    assert "smoothed over the recording (RTS)" in capsys.readouterr().out
    assert smoothed.read_bytes() != expected


def test_without_the_imu_the_pose_is_planar(bag, tmp_path: Path, capsys) -> None:
    out = tmp_path / "planar.csv"
    assert cli.main(["odom", str(bag), "--no-imu", "--csv", str(out), "--truth", TRUTH_TOPIC]) == 0
    values = np.array(list(csv.reader(out.open()))[1:], dtype=float)
    assert (values[:, 3] == 0).all() and (values[:, 4:6] == 0).all()  # z, qx, qy
    printed = capsys.readouterr().out
    assert "imu:       none (legs alone" in printed


@pytest.mark.parametrize(
    ("arguments", "culprit"),
    [
        (["--imu", "/nope"], "--imu /nope: no such topic"),
        (["--imu", TRUTH_TOPIC], "expected sensor_msgs/msg/Imu"),
        (["--truth", IMU_TOPIC], "--base-pose /imu is sensor_msgs/msg/Imu"),
        (["--imu", IMU_TOPIC, "--no-imu"], "contradict"),
        (["--foot-radius", "-1"], None),
        (["--contacts", "force"], "--contacts force needs joint efforts"),
        (["--contacts", "forces"], None),
    ],
)
def test_bad_input_is_one_line_and_exit_2(bag, tmp_path, capsys, arguments, culprit) -> None:
    out = tmp_path / "bad.csv"
    code: object
    try:
        code = cli.main(["odom", str(bag), "--csv", str(out), *arguments])
    except SystemExit as exit_:  # argparse's own refusal
        code = exit_.code
    assert code == 2
    error = capsys.readouterr().err.strip()
    if culprit:
        assert culprit in error and len(error.splitlines()) == 1, error
    assert not out.exists()


def test_contacts_from_the_efforts(run, bag, tmp_path: Path, capsys) -> None:
    """A bag whose joint states carry the motor torques: ``auto`` takes the foot forces for every
    joint state and meets the state filter's goals against the simulation once the robot has
    landed from its spawn height (issue 27: RMSE <= 0.03 m/s, drift <= 1 %); ``kinematic``
    ignores the efforts: the same rows as the bag without."""
    efforts_bag = write_sim_bag(tmp_path / "walk_efforts", run, efforts=True)
    auto, kinematic, without = (tmp_path / f"{name}.csv" for name in ("auto", "kin", "without"))
    assert cli.main(["odom", str(efforts_bag), "--csv", str(auto)]) == 0
    printed = capsys.readouterr().out
    samples = len(run.stamps_s)
    assert (
        f"contacts:  auto (evidence:  force + kinematic for {samples} samples, kinematic "
        "evidence alone for 0)" in printed
    )
    values = np.array(list(csv.reader(auto.open()))[1:], dtype=float)
    landed = run.stamps_s >= LANDED_S
    first = int(np.argmax(landed))
    error = (values[:, 8:11] - run.body_velocities)[landed]
    rmse = np.sqrt(np.mean(np.sum(error**2, axis=1)))
    moved = run.base_positions[-1] - run.base_positions[first]
    distance = np.linalg.norm(np.diff(run.base_positions[first:], axis=0), axis=1).sum()
    drift = 100 * np.linalg.norm(values[-1, 1:4] - values[first, 1:4] - moved) / distance
    print(f"force contacts: velocity RMSE {rmse:.4f} m/s, final position error {drift:.2f} %")
    assert rmse <= 0.03 and drift <= 1.0
    assert (
        cli.main(["odom", str(efforts_bag), "--contacts", "kinematic", "--csv", str(kinematic)])
        == 0
    )
    assert cli.main(["odom", str(bag), "--csv", str(without)]) == 0
    printed = capsys.readouterr().out
    for source in ("kinematic", "auto"):
        assert (
            f"contacts:  {source} (evidence:  force + kinematic for 0 samples, kinematic evidence "
            f"alone for {samples})" in printed
        )
    assert kinematic.read_text() == without.read_text() != auto.read_text()


def test_an_existing_output_is_kept_without_force(bag, tmp_path, capsys) -> None:
    out = tmp_path / "kept.csv"
    out.write_text("mine")
    assert cli.main(["odom", str(bag), "--csv", str(out)]) == 2
    assert "exists already" in capsys.readouterr().err
    assert out.read_text() == "mine"


def test_a_bag_without_velocities_gives_no_rows(tmp_path) -> None:
    from bag_factory import JointStateMsg, write_bag

    spec = BagSpec()
    names = [
        f"{leg}_{part}_joint"
        for leg in ("FR", "FL", "RR", "RL")
        for part in ("hip", "upper", "lower")
    ]
    for index in range(5):
        spec.add_joint_state(
            "/joint_states", T0 + index, JointStateMsg(T0 + index, names, [0.0, 0.8, -1.5] * 4)
        )
    out = tmp_path / "none.csv"
    assert cli.main(["odom", str(write_bag(tmp_path / "b", spec)), "--csv", str(out)]) == 0
    assert out.read_text() == CSV_HEADER


# --- the node's wire formats -------------------------------------------------------------------


def test_imu_fields_read_rclpys_bytes() -> None:
    msg = Imu()
    msg.header.stamp.sec, msg.header.stamp.nanosec = 1_700_000_000, 123_456_789
    for frame in ("", "i", "imu_link", "a_longer_frame_name"):  # every string padding
        msg.header.frame_id = frame
        o = msg.orientation
        o.x, o.y, o.z, o.w = 0.1, -0.2, 0.3, 0.9
        msg.orientation_covariance = [float(i) for i in range(9)]
        msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = 1.5, -2.5, 3.5
        msg.angular_velocity_covariance = [0.1 * i for i in range(9)]
        a = msg.linear_acceleration
        a.x, a.y, a.z = 0.25, -9.5, 1.75
        msg.linear_acceleration_covariance = [0.01 * i for i in range(9)]
        fields = imu_fields(serialize_message(msg))
        assert fields is not None and fields == imu_message_fields(msg)
        stamp, orientation, orientation_cov, gyro, gyro_cov, accel, accel_cov = fields
        assert accel == (0.25, -9.5, 1.75)
        assert list(accel_cov) == list(msg.linear_acceleration_covariance)
        assert stamp == 1_700_000_000_123_456_789
        assert orientation == (0.1, -0.2, 0.3, 0.9) and gyro == (1.5, -2.5, 3.5)
        assert list(orientation_cov) == list(msg.orientation_covariance)
        assert list(gyro_cov) == list(msg.angular_velocity_covariance)
    assert imu_fields(b"\x01\x00" + serialize_message(msg)[2:]) is None  # big-endian: not ours
    assert imu_fields(serialize_message(msg)[:-8]) is None  # truncated


def test_serialized_odometry_is_rclpys() -> None:
    def message(stamp_ns: int, values) -> Odometry:
        msg = Odometry(child_frame_id="trunk")
        msg.header.frame_id = "odom"
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        p.x, p.y, p.z, o.x, o.y, o.z, o.w = values[:7]
        msg.pose.covariance = values[7:43]
        t = msg.twist.twist
        t.linear.x, t.linear.y, t.linear.z = values[43:46]
        t.angular.x, t.angular.y, t.angular.z = values[46:49]
        msg.twist.covariance = values[49:85]
        return msg

    writer = SerializedOdometry(
        serialize_message(message(7_000_000_009, SerializedOdometry.probe_values()))
    )
    assert writer.usable
    values = np.random.default_rng(2).normal(size=85).tolist()
    stamp = T0 + 987_654_321
    ours = writer.serialized(stamp, values)
    assert deserialize_message(ours, Odometry) == message(stamp, values)
    assert len(ours) == len(serialize_message(message(stamp, values)))
