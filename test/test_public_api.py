"""``from a1_leg_fk import ...``: the names the README shows, typed (PEP 561), and lazy (importing
the package alone imports neither numpy nor rclpy, so the console scripts catch Ctrl-C early)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import a1_leg_fk

ROOT = Path(__file__).resolve().parents[1]


def test_the_readme_names_import_from_the_package() -> None:
    from a1_leg_fk import LegFkError, Quadruped, analyze_gait, load_robot, read_foot_trajectories

    assert callable(analyze_gait) and callable(read_foot_trajectories)
    robot = load_robot().quadruped
    assert isinstance(robot, Quadruped)
    assert issubclass(LegFkError, ValueError)
    # FR at the zero pose of pybullet_data's a1.urdf, by hand: the hip joint's origin (0.183,
    # -0.047, 0), the thigh joint's (0, -0.08505, 0), then calf and toe 0.2 m each straight down.
    foot = robot.fk([0.0] * 12)[0]
    np.testing.assert_allclose(foot, [0.183, -0.047 - 0.08505, -0.4], rtol=0, atol=1e-15)


def test_every_name_in_all_resolves() -> None:
    assert sorted(a1_leg_fk.__all__) == sorted(a1_leg_fk._HOMES)
    for name in a1_leg_fk.__all__:
        assert getattr(a1_leg_fk, name) is not None, name
    assert set(a1_leg_fk.__all__) <= set(dir(a1_leg_fk))


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_name"):
        a1_leg_fk.no_such_name  # noqa: B018


def test_importing_the_package_imports_nothing_heavy() -> None:
    code = (
        "import sys, a1_leg_fk, a1_leg_fk.ros.executables; "
        "print(sorted(m for m in ('numpy', 'rclpy', 'pybullet') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_the_package_is_marked_typed() -> None:
    assert (ROOT / "a1_leg_fk" / "py.typed").is_file()
