"""``a1-leg-fk gait`` end to end: the demo gait (joint_state_demo's stand-up + trot) in a bag with
a base pose this test makes, through the bag reader, the analysis, the JSON, the CSV and the plot.

The base pose: the demo trots in place in the base frame, its stance feet sweeping backwards; the
test moves the base forward by exactly the stance feet's mean sweep (from the FK), and holds it at
the height that puts the stance feet a foot radius above z = 0, so that in the world frame the
stance feet stand still on the ground, as a real robot's would. The truth is the demo gait's own
swing flag (:meth:`a1_leg_fk.gait.demo_gait.Gait.swinging`), which the analysis never sees.
"""

from __future__ import annotations

import csv
import errno
import json
from pathlib import Path

import numpy as np
import pytest
from bag_factory import T0, BagSpec, JointStateMsg, T, header, pose, write_bag
from png_images import colour_share, load_png

from a1_leg_fk import cli, plots
from a1_leg_fk.cli import gait as gait_command
from a1_leg_fk.gait.demo_gait import Gait, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.plots import LEG_COLOURS

JOINT_RATE_HZ = 250.0
POSE_RATE_HZ = 100.0
SECONDS = 6.0
FOOT_RADIUS_M = 0.02
GAIT = Gait(limits_of(Quadruped.from_urdf()))


def demo_bag(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Write the bag; return (times [s], true swing flags (N, 4)) of its JointState rows."""
    quadruped = Quadruped.from_urdf()
    times = np.arange(0.0, SECONDS, 1.0 / JOINT_RATE_HZ)
    angles = np.array([GAIT.angles(float(t)) for t in times])
    feet = quadruped.fk_batch(angles)
    swinging = np.array([[GAIT.swinging(float(t), leg) for leg in LEG_NAMES] for t in times])
    # Base x: minus the mean x-velocity of the feet on the ground, integrated (trapezoid).
    stance_vx = np.gradient(feet[:, :, 0], times, axis=0)
    base_vx = -np.where(~swinging, stance_vx, 0.0).sum(axis=1) / np.maximum(
        (~swinging).sum(axis=1), 1
    )
    base_x = np.concatenate(
        ([0.0], np.cumsum(0.5 * (base_vx[1:] + base_vx[:-1]) * np.diff(times)))
    )
    # Base z: the feet on the ground (all four while standing up) a foot radius above z = 0.
    base_z = FOOT_RADIUS_M - np.where(~swinging, feet[:, :, 2], 0.0).sum(axis=1) / np.maximum(
        (~swinging).sum(axis=1), 1
    )
    spec = BagSpec()
    for t, row in zip(times, angles):
        stamp = T0 + round(t * 1e9)
        spec.add_joint_state(
            "/joint_states", stamp, JointStateMsg(stamp, quadruped.joint_names, row)
        )
    pose_times = np.arange(0.0, SECONDS, 1.0 / POSE_RATE_HZ)
    for t in pose_times:
        stamp = T0 + round(t * 1e9)
        position = (float(np.interp(t, times, base_x)), 0.0, float(np.interp(t, times, base_z)))
        spec.add(
            "/base_pose",
            "geometry_msgs/msg/PoseStamped",
            stamp,
            T["geometry_msgs/msg/PoseStamped"](
                header(stamp, "odom"), pose(position, (0.0, 0.0, 0.0, 1.0))
            ),
        )
    write_bag(path, spec)
    return times, swinging


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray, np.ndarray, int]:
    folder = tmp_path_factory.mktemp("gait")
    times, swinging = demo_bag(folder / "demo")
    code = cli.main(
        [
            "gait",
            str(folder / "demo"),
            "--base-pose",
            "/base_pose",
            "--quiet",
            "--json",
            str(folder / "gait.json"),
            "--plot",
            str(folder / "gait.png"),
            "--csv-contacts",
            str(folder / "contacts.csv"),
        ]
    )
    return folder, times, swinging, code


def test_demo_gait_through_a_bag(demo_run) -> None:
    folder, times, swinging, code = demo_run
    assert code == 0
    document = json.loads(
        (folder / "gait.json").read_text(),
        parse_constant=lambda name: pytest.fail(f"{name} in JSON"),
    )
    assert document["gait"] == "trot", document["gait_reason"]
    assert document["world_frame"] == "odom"
    for leg in LEG_NAMES:
        entry = document["legs"][leg]
        assert entry["status"] == "ok"
        assert abs(entry["stride_period_s"] - GAIT.period_s) < 0.01
        assert entry["step_length_m"] > 0.02  # the base walks forward
    assert (
        abs(document["phase_vs_FR"]["RL"]) < 0.05 or abs(document["phase_vs_FR"]["RL"] - 1) < 0.05
    )
    assert (
        abs(document["phase_vs_FR"]["FL"] - 0.5) < 0.05
        and abs(document["phase_vs_FR"]["RR"] - 0.5) < 0.05
    )
    with (folder / "contacts.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == times.size
    # Empty where the foot is unknown: the last joint states come after the last pose (100 Hz).
    stance = np.array([[int(row[f"{leg}_stance"] or -1) for leg in LEG_NAMES] for row in rows])
    assert (stance[times < times[-1] - 1.0 / POSE_RATE_HZ] >= 0).all()
    trotting = (times >= GAIT.periodic_from_s) & (stance >= 0).all(axis=1)
    agreement = ((stance[trotting] == 1) == ~swinging[trotting]).mean()
    print(
        f"demo trot through a bag: stance agrees with the demo's swing flag on {agreement:.1%} "
        "of the samples; duty "
        f"{[round(document['legs'][leg]['duty_factor'], 3) for leg in LEG_NAMES]}"
    )
    # The demo lifts a foot as sin^2 (zero speed and height at lift-off and touchdown), so the
    # detector sees the first and last few millimetres of each swing as stance.
    assert agreement > 0.9


def test_gait_plot_has_a_row_per_leg(demo_run) -> None:
    folder, *_ = demo_run
    image = load_png(folder / "gait.png")
    assert image.std() > 0.05
    top = image[: image.shape[0] * 2 // 5]  # the gait diagram
    rows = []
    for leg in LEG_NAMES:
        assert colour_share(top, LEG_COLOURS[leg]) > 0.005, leg
        rgb = np.array(pytest.importorskip("matplotlib.colors").to_rgb(LEG_COLOURS[leg]))
        ys = np.nonzero(np.abs(top - rgb).max(axis=2) < 0.06)[0]
        rows.append(np.median(ys))
    assert rows == sorted(rows)  # FR, FL, RR, RL from the top, each in its own row
    assert min(np.diff(rows)) > 20  # pixels


def test_refuses_without_base_pose(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert cli.main(["gait", str(tmp_path / "missing")]) == 2
    error = capsys.readouterr().err
    assert "--base-pose" in error and "world-frame" in error and "Traceback" not in error


def test_bad_thresholds_and_input(demo_run, capsys: pytest.CaptureFixture) -> None:
    folder, *_ = demo_run
    assert (
        cli.main(
            ["gait", str(folder / "demo"), "--base-pose", "/base_pose", "--height-on-m", "0.05"]
        )
        == 2
    )
    assert "off >= on" in capsys.readouterr().err
    assert cli.main(["gait", str(folder / "nope"), "--base-pose", "/base_pose"]) == 2
    assert capsys.readouterr().err.startswith("a1-leg-fk gait: ")


def files_of(folder: Path) -> dict[str, tuple[int, bytes]]:
    """Every file under ``folder``: its modification time [ns] and bytes."""
    return {
        str(path.relative_to(folder)): (path.stat().st_mtime_ns, path.read_bytes())
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def run_gait(folder: Path, *options: str) -> int:
    return cli.main(
        ["gait", str(folder / "demo"), "--base-pose", "/base_pose", "--quiet", *options]
    )


def never_read(options) -> None:
    pytest.fail(f"read {options.input} although an output was bad")


@pytest.mark.parametrize(
    ("option", "name", "message"),
    [
        ("--json", "no_such_folder/gait.json", "folder {folder}/no_such_folder does not exist"),
        ("--csv-contacts", ".", "{folder}: is a folder; give a file name"),
        ("--plot", "gait.png", "exists already (use --force to replace it)"),
        ("--json", "demo/gait.json", "inside the input bag"),
    ],
)
def test_bad_output_is_refused_before_the_input_is_read(
    demo_run, option, name, message, capsys: pytest.CaptureFixture, monkeypatch
) -> None:
    folder, *_ = demo_run
    before = files_of(folder)
    monkeypatch.setattr(gait_command, "trajectories_from_options", never_read)
    assert run_gait(folder, option, str(folder / name)) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"a1-leg-fk gait: {option} ")
    assert message.format(folder=folder) in captured.err
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert files_of(folder) == before  # the input and the earlier outputs untouched


def test_missing_matplotlib_is_found_before_the_input_is_read(
    demo_run, tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch
) -> None:
    folder, *_ = demo_run

    def no_matplotlib():
        raise plots.MissingMatplotlib(plots.INSTALL_HINT)

    monkeypatch.setattr(plots, "pyplot", no_matplotlib)
    monkeypatch.setattr(gait_command, "trajectories_from_options", never_read)
    assert run_gait(folder, "--plot", str(tmp_path / "gait.png")) == 2
    assert capsys.readouterr().err == f"a1-leg-fk gait: {plots.INSTALL_HINT}\n"
    assert list(tmp_path.iterdir()) == []


def test_unwritable_output_is_one_line_and_leaves_nothing(
    demo_run, tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch
) -> None:
    folder, *_ = demo_run

    def disk_full(_contacts, path: Path) -> None:
        path.write_text("time_s\n")  # a start, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(gait_command, "write_contacts_csv", disk_full)
    before = files_of(folder)
    code = run_gait(
        folder, "--json", str(tmp_path / "gait.json"), "--csv-contacts", str(tmp_path / "c.csv")
    )
    assert code == 2
    error = capsys.readouterr().err
    assert error == f"a1-leg-fk gait: cannot write {tmp_path / 'c.csv'}: No space left on device\n"
    assert list(tmp_path.iterdir()) == []  # neither output, nor a temporary
    assert files_of(folder) == before


def test_force_replaces_an_existing_output(demo_run, tmp_path: Path) -> None:
    folder, *_ = demo_run
    target = tmp_path / "gait.json"
    target.write_text("an older report\n")
    assert run_gait(folder, "--json", str(target), "--force") == 0
    assert target.read_text() == (folder / "gait.json").read_text()
    assert [path.name for path in tmp_path.iterdir()] == ["gait.json"]  # no temporary left


def test_limb_phase_region_and_thresholds_are_reported(
    demo_run, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    # The demo trots: diagonal feet together, so each fore foot lands half a stride after the
    # hind foot of its side (limb phase 0.5); its duty factor is ~0.53 (sin^2 lifts), a walking
    # trot. The summary and the JSON say so, and give each foot's thresholds.
    folder, *_ = demo_run
    document = json.loads((folder / "gait.json").read_text())
    assert document["gait_region"] == "walking trot" and document["gait_symmetric"] is True
    for key in ("limb_phase", "limb_phase_left", "limb_phase_right"):
        assert abs(document[key] - 0.5) < 0.05, key
    bounds = document["thresholds"]
    assert bounds["adaptive"] is True
    for used in document["thresholds_used"].values():
        assert bounds["speed_on_mps"] <= used["speed_on_mps"] <= bounds["speed_on_max_mps"]
        assert bounds["height_on_m"] <= used["height_on_m"] <= bounds["height_on_max_m"]
    capsys.readouterr()
    fixed = tmp_path / "fixed.json"
    assert run_gait(folder, "--fixed-thresholds", "--json", str(fixed)) == 0
    out = capsys.readouterr().out
    assert "; limb phase 0." in out and "walking trot" in out
    assert "thresholds: (fixed, on/off) FR 0.020/0.035 m 0.15/0.30 m/s;" in out
    fixed_document = json.loads(fixed.read_text())
    assert fixed_document["thresholds"]["adaptive"] is False
    assert all(
        {key: bounds[key] for key in used} == used
        for used in fixed_document["thresholds_used"].values()
    )
