"""``a1-leg-fk gait`` end to end: the demo gait (joint_state_demo's stand-up + trot) in a bag with
a base pose this test makes, through the bag reader, the analysis, the JSON, the CSV and the plot.

The base pose: the demo trots in place in the base frame, its stance feet sweeping backwards; the
test moves the base forward by exactly the stance feet's mean sweep (from the FK), and holds it at
the height that puts the stance feet a foot radius above z = 0, so that in the world frame the
stance feet stand still on the ground, as a real robot's would. The truth is the demo gait's own
swing flag (:meth:`a1_leg_fk.demo_gait.Gait.swinging`), which the analysis never sees.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from bag_factory import BagSpec, JointStateMsg, T, header, write_bag
from test_plots import colour_share, load_png

from a1_leg_fk import cli
from a1_leg_fk.demo_gait import Gait, limits_of
from a1_leg_fk.kinematics import Quadruped
from a1_leg_fk.legs import LEG_NAMES
from a1_leg_fk.plots import LEG_COLOURS

JOINT_RATE_HZ = 250.0
POSE_RATE_HZ = 100.0
SECONDS = 6.0
FOOT_RADIUS_M = 0.02
START_NS = 1_700_000_000_000_000_000
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
        stamp = START_NS + round(t * 1e9)
        spec.add_joint_state(
            "/joint_states", stamp, JointStateMsg(stamp, quadruped.joint_names, row)
        )
    pose_times = np.arange(0.0, SECONDS, 1.0 / POSE_RATE_HZ)
    for t in pose_times:
        stamp = START_NS + round(t * 1e9)
        pose = T["geometry_msgs/msg/Pose"](
            T["geometry_msgs/msg/Point"](
                float(np.interp(t, times, base_x)), 0.0, float(np.interp(t, times, base_z))
            ),
            T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
        )
        spec.add(
            "/base_pose",
            "geometry_msgs/msg/PoseStamped",
            stamp,
            T["geometry_msgs/msg/PoseStamped"](header(stamp, "odom"), pose),
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
