"""Plots: the sampled reach region is right, and the PNGs exist, have size and show something."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from png_images import colour_share, load_png
from shared import cli_command

from a1_leg_fk.gait.demo_gait import Gait, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.plots import LEG_COLOURS, REGION_COLOUR, gait_feet, reach_samples

ROBOT = Quadruped.from_urdf()


CLI = cli_command()


def assert_not_blank(image: np.ndarray, min_width: int, min_height: int) -> None:
    height, width, _ = image.shape
    assert width >= min_width and height >= min_height
    assert image.std() > 0.05  # not a flat image
    distinct = np.unique((image * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(distinct) > 50  # lines, text, antialiasing: many colours
    assert colour_share(image, "white") > 0.3  # mostly background, as a plot is


@pytest.mark.parametrize("leg", ["FR", "RL"])
def test_reach_samples_lie_between_the_reach_radii(leg: str) -> None:
    points, edge = reach_samples(ROBOT, leg, samples=120)
    reach = ROBOT.reach(leg)
    radii = np.hypot(points[:, 0], points[:, 1])
    assert points.shape == (120 * 120, 2)
    assert radii.min() >= reach.min_m - 1e-9 and radii.max() <= reach.max_m + 1e-9
    assert radii.min() == pytest.approx(reach.min_m, abs=1e-6) and radii.max() == pytest.approx(
        reach.max_m, abs=1e-6
    )
    assert radii.max() < reach.max_unlimited_m == pytest.approx(0.4, abs=1e-9)
    edge_radii = np.hypot(edge[:, 0], edge[:, 1])
    assert edge_radii.min() == pytest.approx(
        reach.min_m, abs=1e-6
    ) and edge_radii.max() == pytest.approx(reach.max_m, abs=1e-6)
    # The stand pose's foot is in the region: below and near the hip-pitch joint.
    stand = ROBOT.legs[ROBOT.joint_names.index(f"{leg}_hip_joint") // 3].joint_points(
        (0.0, 0.8, -1.5)
    )
    foot = stand[3, [0, 2]] - stand[1, [0, 2]]
    assert np.min(np.hypot(*(points - foot).T)) < 0.01


def test_an_unknown_leg_is_named() -> None:
    with pytest.raises(LegFkError, match=r"unknown leg 'fr'.*\['FR', 'FL', 'RR', 'RL'\]"):
        reach_samples(ROBOT, "fr", samples=4)


def test_gait_feet_cover_two_trot_cycles() -> None:
    gait = Gait(limits_of(ROBOT))
    times, feet = gait_feet(ROBOT, gait, cycles=2.0)
    assert feet.shape == (len(times), 4, 3)
    assert times[0] >= gait.periodic_from_s
    assert times[-1] - times[0] == pytest.approx(2 * gait.period_s)
    np.testing.assert_allclose(feet[0], feet[-1], atol=1e-9)  # periodic: ends where it started
    lift = feet[:, :, 2].max(axis=0) - feet[:, :, 2].min(axis=0)
    assert (lift > 0.03).all()  # every foot steps


def test_plots_are_pngs_with_content(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    from a1_leg_fk.plots import plot_gait_feet, plot_reach

    reach_png = plot_reach(ROBOT, "FR", tmp_path / "reach_FR.png", samples=150)
    gait_png = plot_gait_feet(ROBOT, tmp_path / "demo_gait_feet.png")
    for path in (reach_png, gait_png):
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 20_000
    reach = load_png(reach_png)
    assert_not_blank(reach, 600, 600)
    assert abs(reach.shape[0] - reach.shape[1]) < 50  # square: equal aspect
    assert colour_share(reach, REGION_COLOUR, 0.03) > 0.15  # the filled region
    for circle in ("C3", "C2"):  # inner and outer radius
        assert colour_share(reach, circle) > 0.001
    gait = load_png(gait_png)
    assert_not_blank(gait, 1000, 400)
    for leg, colour in LEG_COLOURS.items():
        assert colour_share(gait, colour) > 0.0005, f"no {leg} trajectory ({colour}) in the plot"


@pytest.mark.slow
def test_plot_command_writes_both_files(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    out = tmp_path / "plots"
    result = subprocess.run(
        [*CLI, "plot", "--out", str(out), "--leg", "RL"],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    for name in ("reach_RL.png", "demo_gait_feet.png"):
        assert (out / name).stat().st_size > 20_000
        assert f"wrote {out / name}" in result.stdout
    assert_not_blank(load_png(out / "reach_RL.png"), 600, 600)


@pytest.mark.slow
def test_plot_command_without_matplotlib_says_how_to_install(tmp_path: Path) -> None:
    script = (
        # the next line makes `import matplotlib` raise ImportError
        "import sys; sys.modules['matplotlib'] = None\n"
        "from a1_leg_fk.cli import main\n"
        f"sys.exit(main(['plot', '--out', {str(tmp_path)!r}]))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], check=False, capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 1
    assert "pip install matplotlib" in result.stderr and "Traceback" not in result.stderr
    assert not list(tmp_path.iterdir())
