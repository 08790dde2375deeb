"""``a1-leg-fk ik``: the printed angles put the foot on the target (checked with the A1 closed-form
FK typed in test_kinematics), statuses and their exit codes (0 ok, 1 outside the limits or
unreachable), the seed, and bad input (one line on stderr, exit 2)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from references import a1_foot_closed_form

from a1_leg_fk import cli


def run(capsys: pytest.CaptureFixture, *arguments: str) -> tuple[int, str, str]:
    code = cli.main(["ik", *arguments])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def printed_angles(out: str) -> list[float]:
    return [float(value) for value in re.findall(r"_joint\s+([-+][0-9.]+) rad", out)]


def test_the_printed_angles_reach_the_target(capsys) -> None:
    target = a1_foot_closed_form("RL", -0.1, 0.9, -1.7)
    code, out, err = run(capsys, "RL", *(repr(float(v)) for v in target))
    assert code == 0 and not err
    assert "status: ok" in out
    angles = printed_angles(out)
    np.testing.assert_allclose(angles, [-0.1, 0.9, -1.7], atol=1e-9)
    np.testing.assert_allclose(a1_foot_closed_form("RL", *angles), target, atol=1e-9)
    assert re.search(r"RL_hip_joint\s+-0.100000000 rad\s+-5.7296 deg", out)
    assert "exact solutions: 4" in out and out.count("inside the limits") == 1


def test_seed_of_three_or_twelve_angles(capsys) -> None:
    target = [repr(float(v)) for v in a1_foot_closed_form("FR", 0.0, 0.8, -1.5)]
    _, three, _ = run(capsys, "FR", *target, "--seed", "0", "0.8", "-1.5")
    _, twelve, _ = run(capsys, "FR", *target, "--seed", *(["0", "0.8", "-1.5"] * 4))
    assert printed_angles(three) == printed_angles(twelve)
    np.testing.assert_allclose(printed_angles(three), [0.0, 0.8, -1.5], atol=1e-9)


def test_a_target_reached_only_outside_the_limits_exits_1_with_the_status(capsys) -> None:
    """Knee at +0.5 rad: the A1's knee range (-2.697..-0.916 rad) excludes every knee >= 0."""
    target = a1_foot_closed_form("FR", 0.0, 0.3, 0.5)
    code, out, err = run(capsys, "FR", *(repr(float(v)) for v in target))
    assert code == 1 and not err
    assert "status: outside_limits" in out
    assert "inside the limits" not in out and "outside the limits" in out


def test_out_of_reach(capsys) -> None:
    code, out, _ = run(capsys, "FL", "0.3", "0.13", "-0.9")
    assert code == 1
    assert "status: unreachable" in out and "exact solutions: 0" in out
    found = re.search(r"residual: ([0-9.e+-]+) m", out)
    assert found is not None, out
    residual = float(found.group(1))
    assert residual > 0.4  # at least 0.9 - 0.4 - (hip height): the leg is 0.4 m long


@pytest.mark.parametrize(
    ("arguments", "culprit"),
    [
        (["FL", "0.3", "0.13", "nan"], "leg FL"),
        (["FL", "0.3", "0.13", "-0.2", "--seed", "1", "2"], "--seed"),
        (["FL", "0.3", "0.13", "-0.2", "--urdf", "/does/not/exist.urdf"], "/does/not/exist.urdf"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, arguments, culprit: str) -> None:
    code, out, err = run(capsys, *arguments)
    assert code == 2 and not out
    assert len(err.strip().splitlines()) == 1 and culprit in err
