"""The state filter (a1_leg_fk.estimation.state_filter through the odometry feed) on the long runs
of the simulated family (test/contact_runs.py, ``LONG_SPECS``: >= 60 s and >= 20 m each; trots,
a walk, flying trots, ice patches with sideways pushes, the A1 and the Go2-like robot) and three
short ones (``SPECS``), clean and with the contact issue's sensor noise, with efforts (force
evidence for the contacts) and without (kinematic evidence). PyBullet's root motion is the
truth.

The filter's settings were tuned on :data:`TUNED` (``a1_flying_trot`` and ``a1_trot_slips`` among
them: the touchdown, scatter and doubt terms came from their coverage diagnosis); :data:`HELD_OUT`
(long runs at the tuned gaits' other speeds and a turn) and :data:`HELD_OUT_OTHER` (short runs of
the contact family no filter setting was ever looked at on: soft ground, the Go2's walk and fast
trot) are scored with the same defaults, their noisy twins with another noise seed
(:data:`HELD_OUT_NOISE_SEED`).
:func:`test_each_goal_names_its_runs` prints the runs each goal is met and missed on.

Goals (issue 27), on every run: velocity RMSE <= 0.03 m/s clean, <= 0.05 m/s noisy; no 0.1 s
window with a mean error above 0.2 m/s; horizontal drift <= 1 % of the distance (1.5 % with
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
from odometry_scoring import (
    CONFIGS,
    HELD_OUT,
    HELD_OUT_NOISE_SEED,
    HELD_OUT_OTHER,
    TUNED,
    xfail_params,
)

pytestmark = pytest.mark.timeout(900)
"""The module's fixture simulates the runs its selected tests name (two at a time) and scores four
estimates of each, once per session: minutes for the whole family (``make accept``), more than
the suite's per-test bound."""
ACCEPT = pytest.mark.accept
REPRESENTATIVE = ("a1_trot_long", "go2_walk")
"""The runs ``make test`` scores, one tuned and one held out of another robot and gait; every
other run is marked ``accept`` (no ``make mutate`` mutation needs them to die)."""
UNMET: dict[str, str] = {
    "go2_trot_fast": "clean, the reported velocity sigma is too large: 9.2x the actual RMS error "
    "(0.0047 m/s; goal <= 5x; 9.4x before each touchdown's sideways jolt was measured), 1.45x "
    "with noise",
}
"""Runs whose goals are not met yet, with why (strict xfail: a run that meets them must say so).
a1_trot_soft meets them with the feet's give (without it, on soft ground, contact stiffness 3e4
N/m, the error was within 3 sigma on 76-81 % of the samples)."""


def _score(name: str) -> list[tuple[str, Any]]:
    """A worker: the four estimates of one run, scored (row label, Errors); a held-out run's
    noisy twin with its own seed, :data:`HELD_OUT_NOISE_SEED`."""
    from contact_runs import contact_runs, with_noise
    from odometry_scoring import errors, estimate

    from a1_leg_fk.kinematics.quadruped import Quadruped

    run = contact_runs(family_folder(), (name,))[name]
    quadruped = Quadruped.from_urdf(run.urdf_path)
    noisy = with_noise(run, FAMILY_NOISE_SEED if name in TUNED else HELD_OUT_NOISE_SEED)
    scored = []
    for sensors, efforts in CONFIGS:
        fed = run if sensors == "clean" else noisy
        label = f"{name} {sensors} {'efforts' if efforts else 'kinematic'}"
        scored.append((label, errors(run, estimate(fed, efforts, quadruped))))
    return scored


@pytest.fixture(scope="module")
def scores(request: pytest.FixtureRequest) -> dict[str, list[tuple[str, Any]]]:
    """The four scores of each run the session's tests of this module name (every run if one of
    them reads them all), computed in one worker per core (the runs simulated first, once per
    machine)."""
    from contact_runs import simulate_missing
    from odometry_scoring import HEADER

    selected = [i for i in request.session.items if getattr(i, "module", None) is request.module]
    wanted = {item.callspec.params["name"] for item in selected if hasattr(item, "callspec")}
    if any(
        "scores" in getattr(item, "fixturenames", ()) and not hasattr(item, "callspec")
        for item in selected
    ):
        wanted = set(ALL)
    names = tuple(name for name in ALL if name in wanted)
    workers = min(2, os.cpu_count() or 1)
    simulate_missing(family_folder(), names, workers)
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = dict(zip(names, pool.map(_score, names)))
    print("\n" + HEADER)
    for group, members in GROUPS:
        print(f"-- {group}")
        for name in members:
            for label, result in results.get(name, []):
                print(result.row(label))
    return results


GROUPS = (("tuned", TUNED), ("held out", HELD_OUT), ("held out, other", HELD_OUT_OTHER))
ALL = TUNED + HELD_OUT + HELD_OUT_OTHER


def _params(names: tuple[str, ...]) -> list[Any]:
    """:func:`xfail_params` of ``names`` (:data:`UNMET`), each but :data:`REPRESENTATIVE` also
    marked ``accept``."""
    params = []
    for name, param in zip(names, xfail_params(names, UNMET)):
        marks = [*getattr(param, "marks", ()), *([] if name in REPRESENTATIVE else [ACCEPT])]
        params.append(pytest.param(name, marks=marks))
    return params


def _goals(name: str, label: str, e: Any) -> list[tuple[str, bool, str]]:
    """Each goal of one estimate (:func:`odometry_scoring.goals`): 1.5 % horizontal drift with
    slips, the RMSE goal of its sensors."""
    from odometry_scoring import goals

    return goals(e, 0.03 if " clean " in label else 0.05, 1.5 if "slips" in name else 1.0)


def _misses(name: str, scored: list[tuple[str, Any]]) -> list[str]:
    """The goals a run's four estimates miss, in words."""
    return [f"{label}: {figure}" for label, e in scored
            for _, met, figure in _goals(name, label, e) if not met]  # fmt: skip


def _check(name: str, scores: dict[str, list[tuple[str, Any]]]) -> None:
    misses = _misses(name, scores[name])
    assert not misses, "\n".join(misses)


@pytest.mark.parametrize("name", _params(TUNED))
def test_tuned_runs_meet_the_goals(name: str, scores) -> None:
    _check(name, scores)


@pytest.mark.parametrize("name", _params(HELD_OUT))
def test_held_out_runs_meet_the_goals(name: str, scores) -> None:
    _check(name, scores)


@pytest.mark.parametrize("name", _params(HELD_OUT_OTHER))
def test_held_out_other_conditions_meet_the_goals(name: str, scores) -> None:
    _check(name, scores)


@ACCEPT
def test_each_goal_names_its_runs(scores) -> None:
    """Per goal, the runs it is met on (every estimate of the run) and missed on, by group; the
    misses are exactly the runs :data:`UNMET` names."""
    verdicts: dict[str, dict[str, bool]] = {}
    for _, members in GROUPS:
        for name in members:
            for label, e in scores[name]:
                for goal, ok, _ in _goals(name, label, e):
                    runs = verdicts.setdefault(goal, {})
                    runs[name] = runs.get(name, True) and ok
    for goal, runs in verdicts.items():
        print(f"{goal}:")
        for group, members in GROUPS:
            for verdict, word in ((True, "met"), (False, "MISSED")):
                names = [name for name in members if runs.get(name) is verdict]
                if names:
                    print(f"  {group} {word}: {', '.join(names)}")
    missed = {name for runs in verdicts.values() for name, ok in runs.items() if not ok}
    assert missed == set(UNMET)


@ACCEPT
def test_the_runs_are_what_the_issue_asks_for() -> None:
    """Every run >= 60 s and >= 20 m; at least three gaits, one with flight phases; turning and
    straight; both robots; slips of 2-5 cm."""
    from contact_gaits import LONG_SPECS
    from contact_runs import contact_runs
    from odometry_scoring import stance_slides

    from a1_leg_fk.kinematics.quadruped import Quadruped

    runs = contact_runs(family_folder(), TUNED + HELD_OUT)  # the long ones
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
