"""``a1-leg-fk bag --forces`` and ``a1-leg-fk gait --contacts``: a PyBullet trot recorded as a bag
(JointState with efforts, an IMU, the base pose) gives the same foot forces and contacts through
the bag tools as through the Python API; bad efforts cost their legs only; a bag without efforts
is refused in one line.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_factory import T0, BagSpec, JointStateMsg, T, header, pose, write_bag
from force_trot import A1, EMPTY_ROW, NAMES, NAN_FL_ROW, SHORT_ROW, a1_trot, recorded_efforts
from pybullet_sim import rotation
from rosbags.highlevel import AnyReader
from shared import LEGS, STAND_LEG

from a1_leg_fk import cli
from a1_leg_fk.estimation.contacts import ContactRule, ContactThresholds, normal_forces

STEP_NS = 2_000_000
G = 9.80665  # the tools' gravity (PyBullet's was 9.81: only the magnitude differs)
FORCE_COLUMNS = [f"{leg}_f{axis}" for leg in LEGS for axis in "xyz"]
CONTACT_COLUMNS = [f"{leg}_contact" for leg in LEGS]


@pytest.fixture(scope="module")
def trot() -> dict[str, np.ndarray]:
    """3 s of the A1 trotting in PyBullet, 1500 samples."""
    return a1_trot(3.0)


def write_trot_bag(path: Path, record: dict[str, np.ndarray], kind: str, efforts=True) -> Path:
    spec = BagSpec()
    recorded = recorded_efforts(record["torques"]) if efforts else [[]] * len(record["angles"])
    imu = T["sensor_msgs/msg/Imu"]
    vector = T["geometry_msgs/msg/Vector3"]
    for row in range(len(record["angles"])):
        stamp = T0 + STEP_NS * row
        spec.add_joint_state(
            "/joint_states",
            stamp + 5,
            JointStateMsg(
                stamp,
                NAMES,
                record["angles"][row].tolist(),
                record["rates"][row].tolist(),
                "",
                recorded[row],
            ),
        )
        x, y, z, w = record["root_orientation"][row].tolist()
        spec.add(
            "/imu",
            "sensor_msgs/msg/Imu",
            stamp + 7,
            imu(
                header(stamp + 300_000, "imu_link"),  # 0.3 ms late: the nearest is still its own
                T["geometry_msgs/msg/Quaternion"](x, y, z, w),
                np.zeros(9),
                vector(0.0, 0.0, 0.0),
                np.zeros(9),
                vector(0.0, 0.0, 0.0),
                np.zeros(9),
            ),
        )
        spec.add(
            "/base_pose",
            "geometry_msgs/msg/PoseStamped",
            stamp + 6,
            T["geometry_msgs/msg/PoseStamped"](
                header(stamp, "odom"),
                pose(record["root_position"][row].tolist(), [x, y, z, w]),
            ),
        )
    return write_bag(path, spec, kind)


def api_forces(record: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The Python API's forces (N, 4, 3) and contact probabilities (N, 4) for the recorded
    efforts, gravity from the IMU's orientation.
    """
    efforts = np.array(
        [row if len(row) == 12 else [math.nan] * 12 for row in recorded_efforts(record["torques"])]
    )
    gravity = np.array([rotation(q).T @ [0.0, 0.0, -G] for q in record["root_orientation"]])
    forces = A1.foot_forces_batch(record["angles"], efforts, gravity)
    mass = sum(inertial.mass for inertial in A1.model.inertials.values())
    rule = ContactRule(ContactThresholds.for_weight(mass * G))
    return forces, rule.update_batch(normal_forces(forces, gravity))


def csv_columns(path: Path, columns: list[str]) -> np.ndarray:
    rows = list(csv.DictReader(path.open()))
    return np.array([[float(row[c]) if row[c] else math.nan for c in columns] for row in rows])


@pytest.mark.parametrize("kind", ["mcap", "ros1"])
def test_bag_forces_equal_the_python_api(
    tmp_path: Path, trot: dict[str, np.ndarray], kind: str, capsys: pytest.CaptureFixture
) -> None:
    bag = write_trot_bag(tmp_path / ("in.bag" if kind == "ros1" else "in"), trot, kind)
    out, out_bag = tmp_path / "feet.csv", tmp_path / "out"
    arguments = ["bag", str(bag), "--topic", "/joint_states", "--csv", str(out), "--forces"]
    arguments += ["--imu", "/imu", "--output-bag", str(out_bag), "--quiet"]
    arguments += ["--force-model", "static", "--contact-rule", "threshold"]  # the API's rule
    assert cli.main(arguments) == 0
    printed = capsys.readouterr().out
    header_row = next(csv.reader(out.open()))
    assert header_row[-16:] == FORCE_COLUMNS + CONTACT_COLUMNS
    assert header_row[:14] == [
        "stamp_ns",
        "bag_time_ns",
        *[f"{leg}_{a}" for leg in LEGS for a in "xyz"],
    ]
    forces, contacts = api_forces(trot)
    ours = csv_columns(out, FORCE_COLUMNS).reshape(-1, 4, 3)
    np.testing.assert_allclose(ours, forces, rtol=0, atol=1e-9)  # NaN where NaN
    np.testing.assert_allclose(csv_columns(out, CONTACT_COLUMNS), contacts, rtol=0, atol=1e-12)
    assert np.isnan(ours[NAN_FL_ROW, 1]).all() and np.isfinite(ours[NAN_FL_ROW, [0, 2, 3]]).all()
    assert np.isnan(ours[[SHORT_ROW, EMPTY_ROW]]).all()
    assert "none for 9 legs (efforts missing, NaN or of the wrong length)" in printed
    assert ((contacts >= 0.5).mean(axis=0) > 0.3).all()  # a trot: every foot down a good share

    with AnyReader([out_bag]) as reader:
        topics = {c.topic: c for c in reader.connections}
        assert topics["/foot_forces/FR"].msgtype == "geometry_msgs/msg/WrenchStamped"
        fr: list[Any] = [
            reader.deserialize(raw, "geometry_msgs/msg/WrenchStamped")
            for _, _, raw in reader.messages(connections=[topics["/foot_forces/FR"]])
        ]
        states: list[Any] = [
            reader.deserialize(raw, "sensor_msgs/msg/JointState")
            for _, _, raw in reader.messages(connections=[topics["/foot_contacts"]])
        ]
    finite = np.isfinite(forces[:, 0]).all(axis=1)
    assert len(fr) == finite.sum() and fr[0].header.frame_id == A1.base_frame
    written = np.array([[m.wrench.force.x, m.wrench.force.y, m.wrench.force.z] for m in fr])
    np.testing.assert_allclose(written, forces[finite, 0], rtol=0, atol=1e-9)
    assert all(m.wrench.torque.x == m.wrench.torque.y == m.wrench.torque.z == 0.0 for m in fr)
    with_contacts = np.isfinite(contacts).any(axis=1)
    assert len(states) == with_contacts.sum()
    assert all(list(m.name) == list(LEGS) and len(m.velocity) == 0 for m in states)
    np.testing.assert_allclose(
        [m.position for m in states], contacts[with_contacts], rtol=0, atol=1e-12
    )
    gravity = np.array([rotation(q).T @ [0.0, 0.0, -G] for q in trot["root_orientation"]])
    np.testing.assert_allclose(
        [m.effort for m in states],
        normal_forces(forces, gravity)[with_contacts],
        rtol=0,
        atol=1e-9,
    )


def test_bag_without_efforts_is_refused_in_one_line(
    tmp_path: Path, trot: dict[str, np.ndarray], capsys: pytest.CaptureFixture
) -> None:
    bag = write_trot_bag(tmp_path / "in", trot, "mcap", efforts=False)
    out = tmp_path / "feet.csv"
    assert (
        cli.main(["bag", str(bag), "--topic", "/joint_states", "--csv", str(out), "--forces"]) == 2
    )
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "carry no efforts" in error and "--forces" in error
    assert not out.exists()
    assert cli.main(["bag", str(bag), "--csv", str(out), "--imu", "/imu"]) == 2
    assert "--imu needs --forces or --contacts" in capsys.readouterr().err
    assert cli.main(["bag", str(bag), "--csv", str(out), "--contacts", "--quiet"]) == 0
    header_row = next(csv.reader(out.open()))
    assert header_row[-4:] == CONTACT_COLUMNS and "FR_fx" not in header_row
    contacts = csv_columns(out, CONTACT_COLUMNS)[500:]  # kinematic evidence alone
    assert np.isfinite(contacts).all() and ((contacts >= 0.5).mean(axis=0) > 0.3).all()
    assert "kinematic evidence alone for 1500" in capsys.readouterr().out.replace("\n", " ")


@pytest.mark.parametrize("mode", ["auto", "force", "kinematic"])
def test_gait_contacts_from_forces(
    tmp_path: Path, trot: dict[str, np.ndarray], mode: str, capsys: pytest.CaptureFixture
) -> None:
    bag = write_trot_bag(tmp_path / "in", trot, "mcap")
    report = tmp_path / "gait.json"
    arguments = ["gait", str(bag), "--topic", "/joint_states", "--base-pose", "/base_pose"]
    arguments += ["--contacts", mode, "--json", str(report), "--quiet"]
    arguments += [] if mode == "kinematic" else ["--imu", "/imu"]
    assert cli.main(arguments) == 0, capsys.readouterr().err
    document = json.loads(report.read_text())
    assert document["contacts"] == ("kinematic" if mode == "kinematic" else "force")
    assert document["gait"] == "trot"


def test_gait_auto_contacts_without_efforts_are_kinematic(
    tmp_path: Path, trot: dict[str, np.ndarray]
) -> None:
    bag = write_trot_bag(tmp_path / "in", trot, "mcap", efforts=False)
    report = tmp_path / "gait.json"
    arguments = ["gait", str(bag), "--topic", "/joint_states", "--base-pose", "/base_pose"]
    assert cli.main([*arguments, "--json", str(report), "--quiet"]) == 0
    assert json.loads(report.read_text())["contacts"] == "kinematic"
    assert cli.main([*arguments, "--contacts", "force", "--quiet"]) == 2


def test_efforts_by_name_partial_unknown_and_wrong_length() -> None:
    """Efforts go to their joints by name (aliases too); joints a message does not name, and all
    joints of a message whose effort array does not match its names, have none.
    """
    from a1_leg_fk.recording.forces import RecordingForces

    forces = RecordingForces(A1, None)
    names = ["arm_joint", "FL_calf_joint", "FR_hip_joint", NAMES[1]]  # an alias, an unknown name
    efforts = forces.slot_efforts(names, np.array([[9.0, 1.0, 2.0, 3.0], [9.0, 4.0, 5.0, 6.0]]))
    expected = np.full((2, 12), math.nan)
    expected[:, 5], expected[:, 0], expected[:, 1] = [1.0, 4.0], [2.0, 5.0], [3.0, 6.0]
    np.testing.assert_array_equal(efforts, expected)
    assert np.isnan(forces.slot_efforts(names, np.ones((2, 3)))).all()
    angles = np.tile(list(STAND_LEG) * 4, (2, 1))
    feet = A1.fk_batch(angles)
    result = forces.rows(
        np.array([T0, T0 + 1]), (angles, np.zeros_like(angles), efforts), (feet, 0.0 * feet)
    )
    assert np.isnan(result[0]).all()  # no leg has its three efforts
    assert forces.counts.missing == 8 and forces.counts.estimated == 0


def test_imu_without_orientation_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """An IMU that says it has no orientation (orientation_covariance[0] == -1) cannot give
    gravity's direction: one line, exit 2.
    """
    spec = BagSpec()
    vector = T["geometry_msgs/msg/Vector3"](0.0, 0.0, 0.0)
    no_orientation = np.zeros(9)
    no_orientation[0] = -1.0
    for row in range(3):
        stamp = T0 + STEP_NS * row
        spec.add_joint_state(
            "/joint_states",
            stamp,
            JointStateMsg(stamp, NAMES, list(STAND_LEG) * 4, [], "", [1.0] * 12),
        )
        imu = T["sensor_msgs/msg/Imu"](
            header(stamp, "imu"),
            T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
            no_orientation,
            vector,
            np.zeros(9),
            vector,
            np.zeros(9),
        )
        spec.add("/imu", "sensor_msgs/msg/Imu", stamp, imu)
    bag = write_bag(tmp_path / "in", spec)
    out = tmp_path / "feet.csv"
    arguments = ["bag", str(bag), "--csv", str(out), "--forces", "--imu", "/imu"]
    assert cli.main(arguments) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--imu /imu: no message with an orientation" in error
    assert not out.exists()


def test_corrections_online_off_and_misplaced(
    tmp_path: Path, trot: dict[str, np.ndarray], capsys: pytest.CaptureFixture
) -> None:
    """``--corrections`` on ``bag``, ``gait`` and ``odom``: the calves' efforts 0.5 N m high (a
    torque the URDF does not explain, by construction) are learnt online (the default) as every
    calf's bias, between -0.55 and -0.15 N m (the fit less its significance margin), the hips
    and thighs untouched; ``off`` prints no corrections; without force estimation the option
    is refused in one line."""
    offset = np.zeros(12)
    offset[2::3] = 0.5
    bag = write_trot_bag(tmp_path / "in", {**trot, "torques": trot["torques"] + offset}, "mcap")
    base = ["bag", str(bag), "--topic", "/joint_states", "--imu", "/imu", "--quiet"]
    assert cli.main([*base, "--forces", "--csv", str(tmp_path / "on.csv")]) == 0
    line = next(
        text for text in capsys.readouterr().out.splitlines() if "model corrections" in text
    )
    for leg in LEGS:
        joints = line.split(f" {leg} ")[1].split(";")[0].split("/")
        terms = [[float(value) for value in joint.split(",")] for joint in joints]
        assert terms[0] == terms[1] == [0.0, 0.0, 0.0], (leg, line)
        assert -0.55 <= terms[2][0] <= -0.15 and terms[2][1:] == [0.0, 0.0], (leg, line)
    off = [*base, "--forces", "--csv", str(tmp_path / "off.csv"), "--corrections", "off"]
    assert cli.main(off) == 0
    assert "model corrections" not in capsys.readouterr().out
    gait = ["gait", str(bag), "--topic", "/joint_states", "--base-pose", "/base_pose", "--quiet"]
    gait += ["--contacts", "force"]
    assert cli.main([*gait, "--corrections", "off"]) == 0
    odom = ["odom", str(bag), "--topic", "/joint_states", "--quiet", "--corrections", "off"]
    assert cli.main(odom) == 0
    capsys.readouterr()
    alone = ["bag", str(bag), "--csv", str(tmp_path / "x.csv"), "--corrections", "off"]
    assert cli.main(alone) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--corrections needs --forces or --contacts" in error
