"""A picture a person would look at: ``a1-leg-fk view`` of a PyBullet walk, opened in Rerun's web
viewer in headless Chromium (Debian's package, software WebGL: ``bench/view_screenshot.py``, which
made docs/view.png and waits, screenshot after screenshot, until the viewer has drawn the
recording and the picture has settled). The screenshot (kept in the test's temporary folder, its
path printed) must show the robot in the 3D view and curves in the plots; a person looks at it
too. Skipped without chromium (not in CI's image: the browser's install and a minute of software
rendering would cost CI its time budget)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from odometry_bags import IMU_TOPIC, TRUTH_TOPIC, write_sim_bag
from png_images import load_png
from pybullet_sim import simulate, walking_targets

from a1_leg_fk import cli

pytest.importorskip("rerun")

SCRIPT = Path(__file__).resolve().parents[2] / "bench" / "view_screenshot.py"
VIEW_3D = (slice(60, 225), slice(200, 425))
"""The 3D view's cell [px] (rows, columns) in the pinned viewer's grid (rerun-sdk 0.41.0, a
1400 x 800 page): the top left of the viewport between the sources (200 px) and the selection
(300 px) panels, 225 x 188 px cells under a 24 px title; measured on the pictures looked at."""
PLOT_CELLS = [
    (slice(top + 24, top + 165), slice(left + 5, left + 220))
    for top in (36, 224)
    for left in (200, 425, 650, 875)
][1:]
"""The other cells of the grid's first two rows: time series (which ones the viewer picks varies
from one opening to the next)."""
SOLID_ORANGE_PX = 50
"""Pixels of the description's orange (the A1 URDF's material "orange", shaded) with all eight
neighbours orange too, at least: a body of the robot at least 9 px across, which the 2 px foot
trails, also orange, cannot make (206 px on each run's picture, 0 before the robot comes)."""
CURVE_COLUMNS = 0.5
"""The share of a plot cell's columns a curve crosses, at least: 0.45-0.92 on the 11 runs' pictures
(a curve that starts flat on the axis is grey there), 0 before the plots come."""


def coloured(image: np.ndarray) -> np.ndarray:
    """Pixels whose channels span more than a quarter of full scale (the viewer's own text, grid
    and panels are grey)."""
    return image.max(axis=2) - image.min(axis=2) > 0.25


def solid(mask: np.ndarray) -> np.ndarray:
    """``mask`` eroded by one pixel: true where a pixel and its eight neighbours are."""
    inner = mask[1:-1, 1:-1].copy()
    rows, columns = mask.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= mask[1 + dy : rows - 1 + dy, 1 + dx : columns - 1 + dx]
    return inner


@pytest.mark.accept
@pytest.mark.timeout(600)
@pytest.mark.skipif(shutil.which("chromium") is None, reason="needs Debian's chromium")
def test_the_web_viewer_draws_the_robot_and_the_plots(tmp_path: Path) -> None:
    bag = write_sim_bag(tmp_path / "walk", simulate(walking_targets(), 2.0), efforts=True)
    rrd, png = tmp_path / "walk.rrd", tmp_path / "view.png"
    argv = ["view", str(bag), "--imu", IMU_TOPIC, "--truth", TRUTH_TOPIC]
    assert cli.main([*argv, "--rrd", str(rrd), "--no-open", "--quiet"]) == 0
    done = subprocess.run(
        [sys.executable, str(SCRIPT), str(rrd), str(png), "--timeout", "400"],
        capture_output=True,
        text=True,
        timeout=500,
        check=False,
    )
    assert done.returncode == 0 and png.is_file(), done.stdout + done.stderr
    image = load_png(png)
    assert image.shape[:2] == (800, 1400)
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    orange = (red > 0.6) & (green > 0.25) & (green < 0.75 * red) & (blue < 0.45 * red)
    robot = int(solid(orange[VIEW_3D]).sum())
    curves = [float(coloured(image[cell]).any(axis=0).mean()) for cell in PLOT_CELLS]
    print(done.stdout, f"{png}: robot {robot} px, plot cells' columns crossed {curves}")
    assert robot >= SOLID_ORANGE_PX, "no robot in the 3D view"
    assert sum(share >= CURVE_COLUMNS for share in curves) >= 3, "no curves in the plots"
