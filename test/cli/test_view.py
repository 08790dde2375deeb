"""``a1-leg-fk view``: a PyBullet walk (joint states with efforts, IMU, the true pose) -> .rrd,
read back with Rerun's own reader and checked against ``bag --forces --contacts`` and ``odom``
CSV of the same bag, against the simulation's joint angles, and by composing the logged joint
transforms into the feet; bad inputs; no rerun-sdk."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bag_factory import BagSpec, write_bag
from exported_urdf import exported_quadruped
from odometry_bags import IMU_TOPIC, TRUTH_TOPIC, imu_message, stamps_of, write_sim_bag
from pybullet_sim import rotation_matrices as rotations
from pybullet_sim import simulate, walking_targets
from rrd_reader import read_rrd, series

from a1_leg_fk import cli

rr = pytest.importorskip("rerun")

SIM_S = 2.0
FLOAT32_M = 1e-6
"""[m] Rerun keeps positions and transforms as float32: 0.3 m to about 3e-8 m, four composed
transforms to about 1e-7 m; 1e-9 m is below what an .rrd holds."""


TRUTH_VELOCITY_M_S = 0.01
"""[m/s] The truth's velocity, differenced from its 2 ms poses, against PyBullet's: central
differences of a trot (accelerations of a few m/s^2, changing over tens of ms) are within a few
mm/s, a tenth of the estimate's errors it is drawn against."""


@pytest.fixture(scope="module")
def run():
    return simulate(walking_targets(), SIM_S)


@pytest.fixture(scope="module")
def bag(run, tmp_path_factory):
    return write_sim_bag(tmp_path_factory.mktemp("view") / "walk", run, efforts=True)


def read_csv(path: Path) -> dict[str, np.ndarray]:
    rows = list(csv.reader(path.open()))
    values = np.array(rows[1:], dtype=float)
    table = {name: values[:, i] for i, name in enumerate(rows[0])}
    table["stamp_ns"] = np.array([int(row[0]) for row in rows[1:]], dtype=np.int64)
    return table


@pytest.fixture(scope="module")
def outputs(bag, tmp_path_factory):
    folder = tmp_path_factory.mktemp("outputs")
    feet, odom, rrd = folder / "feet.csv", folder / "odom.csv", folder / "walk.rrd"
    common = ["--imu", IMU_TOPIC, "--quiet"]
    assert cli.main(["bag", str(bag), "--forces", "--contacts", "--csv", str(feet), *common]) == 0
    assert cli.main(["odom", str(bag), "--truth", TRUTH_TOPIC, "--csv", str(odom), "--quiet"]) == 0
    code = cli.main(
        ["view", str(bag), "--truth", TRUTH_TOPIC, "--rrd", str(rrd), "--no-open", *common]
    )
    assert code == 0
    return read_csv(feet), read_csv(odom), read_rrd(rrd)


def test_series_equal_the_csvs(run, outputs) -> None:
    feet, odom, entities = outputs
    for leg in ("FR", "FL", "RR", "RL"):
        stamps, height = series(entities, f"plots/foot_height/{leg}")
        assert (stamps == feet["stamp_ns"]).all()
        assert np.allclose(height, feet[f"{leg}_z"], rtol=0, atol=1e-9)
        stamps, p = series(entities, f"plots/p_stance/{leg}")
        assert (stamps == feet["stamp_ns"]).all()
        assert np.allclose(p, feet[f"{leg}_contact"], rtol=0, atol=1e-6)
        columns = entities[f"/feet/{leg}"]
        points = np.array([v[0] for v in columns["Points3D:positions"]])
        expected = np.stack([feet[f"{leg}_{a}"] for a in "xyz"], axis=1)
        assert np.abs(points - expected).max() < FLOAT32_M
        arrows = entities[f"/feet/{leg}/force"]
        vectors = np.array([v[0] for v in arrows["Arrows3D:vectors"]]) / 0.002
        forces = np.stack([feet[f"{leg}_f{a}"] for a in "xyz"], axis=1)
        assert np.allclose(vectors, forces, rtol=1e-6, atol=1e-5)
    for slot, joint in enumerate(run.joint_names):  # the simulation's angles, by construction
        stamps, angle = series(entities, f"plots/joint_angle/{joint}")
        assert (stamps == feet["stamp_ns"]).all()
        assert np.allclose(angle, run.angles[:, slot], rtol=0, atol=1e-12)
    for axis in "xyz":
        stamps, v = series(entities, f"plots/velocity/{axis}/estimate")
        assert (stamps == odom["stamp_ns"]).all()
        assert np.allclose(v, odom[f"v{axis}"], rtol=0, atol=1e-6)
        sigma = np.sqrt(odom[f"cov_v{axis}"])
        _, upper = series(entities, f"plots/velocity/{axis}/plus_3sigma")
        assert np.allclose(upper, odom[f"v{axis}"] + 3 * sigma, rtol=0, atol=1e-6)
        _, lower = series(entities, f"plots/velocity/{axis}/minus_3sigma")
        assert np.allclose(lower, odom[f"v{axis}"] - 3 * sigma, rtol=0, atol=1e-6)
    true_body = np.einsum("nji,nj->ni", rotations(run.base_quaternions), run.base_velocities)
    for slot, axis in enumerate("xyz"):  # the truth's: PyBullet's own velocity, in the base frame
        stamps, v = series(entities, f"plots/velocity/{axis}/truth")
        rows = np.searchsorted(stamps_of(run), stamps)
        assert len(stamps) == len(odom["stamp_ns"])
        error = np.abs(v - true_body[rows, slot])[5:-5]  # the ends: one-sided differences
        assert np.median(error) < TRUTH_VELOCITY_M_S, (axis, np.median(error), error.max())
    base = entities["/robot/base_pose"]
    assert (np.array(base["stamp"]) == odom["stamp_ns"]).all()
    translation = np.array([v[0] for v in base["Transform3D:translation"]])
    assert np.abs(translation - np.stack([odom[a] for a in "xyz"], axis=1)).max() < FLOAT32_M
    quaternion = np.array([v[0] for v in base["Transform3D:quaternion"]])
    expected = np.stack([odom[f"q{a}"] for a in "xyzw"], axis=1)
    assert np.abs(quaternion - expected).max() < 1e-6  # unit quaternions in float32
    for name in ("plots/filter/nis", "plots/gait/FR", "plots/normal_force/FR", "odom/path"):
        assert any(key.endswith(name) for key in entities), name
    summary = entities["static:/summary"]["TextDocument:text"][0][0]
    assert "filter:" in summary and "evidence:" in summary and "truth:" in summary


def _pose(translation, quaternion) -> np.ndarray:
    x, y, z, w = quaternion
    matrix = np.eye(4)
    matrix[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    matrix[:3, 3] = translation
    return matrix


def test_logged_transforms_compose_to_the_feet(outputs) -> None:
    """The joints' transforms as logged (parent and child frames, translation, quaternion: static,
    or per row where the joint moves; a row's component overrides nothing static, as Rerun reads
    them), composed here from the root to each foot link, give the feet of ``bag``'s CSV."""
    feet, _, entities = outputs
    joints: dict[str, tuple[str, list]] = {}  # child link -> (parent link, poses: 1 or per row)
    for key in entities:
        if not key.startswith("static:/robot/joints/"):
            continue
        fixed, moving = entities[key], entities.get(key.removeprefix("static:"), {})
        translations, quaternions = (
            fixed.get(name) or moving[name]
            for name in ("Transform3D:translation", "Transform3D:quaternion")
        )
        if len(translations) == 1:
            translations = translations * len(quaternions)
        child = fixed["Transform3D:child_frame"][0][0]
        parent = fixed["Transform3D:parent_frame"][0][0]
        joints[child] = (parent, [_pose(t[0], q[0]) for t, q in zip(translations, quaternions)])
    for leg in ("FR", "FL", "RR", "RL"):
        link, chain = f"{leg}_toe", []
        while link in joints:
            parent, poses = joints[link]
            chain.append(poses)
            link = parent
        assert link == "trunk" and len(chain) == 4
        for row in range(0, len(feet["stamp_ns"]), 97):
            pose = np.eye(4)
            for poses in reversed(chain):
                pose = pose @ (poses[row] if len(poses) > 1 else poses[0])
            expected = [feet[f"{leg}_{a}"][row] for a in "xyz"]
            assert np.abs(pose[:3, 3] - expected).max() < FLOAT32_M


def test_description_without_its_meshes(run, tmp_path: Path, capsys) -> None:
    """A Go2-like exported description whose package:// meshes are not installed: written, with
    the note."""
    urdf = tmp_path / "go2.urdf"
    urdf.write_text(exported_quadruped("go2"))
    bag = write_sim_bag(tmp_path / "walk", run, imu=False, truth=False)
    rrd = tmp_path / "go2.rrd"
    code = cli.main(["view", str(bag), "--urdf", str(urdf), "--rrd", str(rrd), "--no-open"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "meshes not found" in printed.out
    assert rrd.is_file()


def _one_line_exit_2(argv, capsys, rrd: Path) -> str:
    code = cli.main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert "\n" not in err and err.startswith("a1-leg-fk view:"), err
    assert not rrd.exists() and not list(rrd.parent.glob(f".{rrd.name}*"))
    return err


def test_bad_inputs(bag, tmp_path: Path, capsys) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    _one_line_exit_2(
        ["view", str(bag), "--rrd", str(blocker / "x.rrd"), "--no-open"], capsys, blocker / "x.rrd"
    )
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'/>")
    rrd = tmp_path / "u.rrd"
    err = _one_line_exit_2(
        ["view", str(bag), "--urdf", str(broken), "--rrd", str(rrd), "--no-open"], capsys, rrd
    )
    assert "broken.urdf" in err
    spec, run = BagSpec(), simulate(walking_targets(), 0.1)
    for row in range(10):
        spec.add(IMU_TOPIC, "sensor_msgs/msg/Imu", 10 + row, imu_message(run, row))
    imu_only = write_bag(tmp_path / "imu_only", spec)
    rrd = tmp_path / "imu.rrd"
    _one_line_exit_2(["view", str(imu_only), "--rrd", str(rrd), "--no-open"], capsys, rrd)


def test_without_rerun(bag, tmp_path: Path) -> None:
    rrd = tmp_path / "none.rrd"
    hide = (
        "import sys; sys.modules['rerun'] = None; from a1_leg_fk import cli; "
        f"sys.exit(cli.main(['view', {str(bag)!r}, '--rrd', {str(rrd)!r}, '--no-open']))"
    )
    done = subprocess.run(
        [sys.executable, "-c", hide], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "pip install" in done.stderr
    assert not rrd.exists()
