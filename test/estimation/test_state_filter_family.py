"""The state filter (a1_leg_fk.estimation.state_filter through the odometry feed) on the long runs
of the simulated family (test/contact_runs.py, ``LONG_SPECS``: >= 60 s and >= 20 m each; trots,
a walk, flying trots, ice patches with sideways pushes, the A1 and the Go2-like robot), clean and
with the contact issue's sensor noise, with efforts (force evidence for the contacts) and without
(kinematic evidence). PyBullet's root motion is the truth.

The filter's settings were tuned on :data:`TUNED` only; :data:`HELD_OUT` are scored with the same
defaults. Goals (issue 27), on every run: velocity RMSE <= 0.03 m/s clean, <= 0.05 m/s noisy; no
0.1 s window with a mean error above 0.2 m/s; horizontal drift <= 1 % of the distance (1.5 % with
slips), vertical <= 0.5 %; the error within the reported 3 sigma on >= 95 % of the samples and the
reported sigma at most 5x the actual RMS error.
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np
import pytest
from conftest import FAMILY_NOISE_SEED, family_folder

pytestmark = pytest.mark.timeout(900)
"""The module's fixture simulates the nine long runs (two at a time) and scores 36 estimates, once
per session: minutes, more than the suite's per-test bound."""
TUNED = (
    "a1_trot_long",
    "a1_walk_long",
    "a1_flying_trot_fast",
    "go2_trot_long",
    "go2_trot_slips",
)
HELD_OUT = ("a1_trot_fast_long", "a1_turn_long", "a1_flying_trot", "a1_trot_slips")
CONFIGS = (("clean", True), ("clean", False), ("noise", True), ("noise", False))
"""(sensors, efforts) of each run's four estimates."""
UNMET: dict[str, str] = {}
"""Runs whose goals are not met yet, with why (strict xfail: a run that meets them must say so)."""


def _score(name: str) -> list[tuple[str, Any]]:
    """A worker: the four estimates of one run, scored (row label, Errors)."""
    from contact_runs import contact_runs, with_noise
    from odometry_scoring import errors, estimate

    from a1_leg_fk.kinematics.quadruped import Quadruped

    run = contact_runs(family_folder(), (name,))[name]
    quadruped = Quadruped.from_urdf(run.urdf_path)
    noisy = with_noise(run, FAMILY_NOISE_SEED)
    scored = []
    for sensors, efforts in CONFIGS:
        fed = run if sensors == "clean" else noisy
        label = f"{name} {sensors} {'efforts' if efforts else 'kinematic'}"
        scored.append((label, errors(run, estimate(fed, efforts, quadruped))))
    return scored


@pytest.fixture(scope="module")
def scores() -> dict[str, list[tuple[str, Any]]]:
    """Every run's four scores, computed in one worker per core (the runs simulated first, once
    per machine)."""
    from contact_runs import simulate_missing
    from odometry_scoring import HEADER

    names = TUNED + HELD_OUT
    workers = min(2, os.cpu_count() or 1)
    simulate_missing(family_folder(), names, workers)
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = dict(zip(names, pool.map(_score, names)))
    print("\n" + HEADER)
    for group, members in (("tuned", TUNED), ("held out", HELD_OUT)):
        print(f"-- {group}")
        for name in members:
            for label, result in results[name]:
                print(result.row(label))
    return results


def _misses(name: str, scored: list[tuple[str, Any]]) -> list[str]:
    """The goals a run's four estimates miss, in words."""
    from odometry_scoring import misses

    drift = 1.5 if "slips" in name else 1.0
    found = []
    for label, e in scored:
        found += misses(label, e, 0.03 if " clean " in label else 0.05, drift)
    return found


def _check(name: str, scores: dict[str, list[tuple[str, Any]]]) -> None:
    misses = _misses(name, scores[name])
    assert not misses, "\n".join(misses)


def _params(names: tuple[str, ...]) -> list[Any]:
    return [
        pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=UNMET[name]))
        if name in UNMET
        else name
        for name in names
    ]


@pytest.mark.parametrize("name", _params(TUNED))
def test_tuned_runs_meet_the_goals(name: str, scores) -> None:
    _check(name, scores)


@pytest.mark.parametrize("name", _params(HELD_OUT))
def test_held_out_runs_meet_the_goals(name: str, scores) -> None:
    _check(name, scores)


def test_the_runs_are_what_the_issue_asks_for() -> None:
    """Every run >= 60 s and >= 20 m; at least three gaits, one with flight phases; turning and
    straight; both robots; slips of 2-5 cm."""
    from contact_gaits import LONG_SPECS
    from contact_runs import contact_runs
    from odometry_scoring import stance_slides

    from a1_leg_fk.kinematics.quadruped import Quadruped

    runs = contact_runs(family_folder(), TUNED + HELD_OUT)
    for name, run in runs.items():
        gait = run.gait
        path = run.base_positions[gait]
        distance = float(np.linalg.norm(np.diff(path[:, :2], axis=0), axis=1).sum())
        seconds = float(run.stamps_s[gait][-1] - run.gait_start_s)
        flight = float((~run.contacts[gait].any(axis=1)).mean())
        print(f"{name:<22} {seconds:5.1f} s {distance:5.1f} m flight {100 * flight:4.1f} %")
        assert seconds >= 60.0 and distance >= 20.0, name
    assert {spec.robot for spec in LONG_SPECS.values()} == {"a1", "go2"}
    assert any(spec.gait.yaw_rate for spec in LONG_SPECS.values())
    assert (~runs["a1_flying_trot"].contacts.any(axis=1)).mean() > 0.05
    slips = runs["a1_trot_slips"]
    slides = stance_slides(slips, Quadruped.from_urdf(slips.urdf_path))
    print(f"a1_trot_slips: {100 * (slides > 0.02).mean():.1f} % of stances slide over 2 cm")
    assert (slides > 0.02).mean() >= 0.05 and slides.max() <= 0.06
