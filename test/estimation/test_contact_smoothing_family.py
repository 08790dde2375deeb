"""Contacts smoothed over the whole run (``a1-leg-fk bag`` and ``gait`` without ``--causal``)
on the PyBullet contact family, judged by PyBullet's contacts, against the issue's goals:

- without efforts: agreement >= 98 %, swing called stance <= 1 %, median touchdown and liftoff
  within 4 ms, duty factors within 0.02 of PyBullet's;
- with efforts: agreement no worse than the causal filter's, >= 99 % where the causal filter is
  below it, duty factors within 0.02.

The smoother's settings (without efforts its liftoff lead and the heights' edges of
a1_leg_fk/estimation/stance_edges.py; with them, no liftoff before the filter's, then the load's
edges of a1_leg_fk/estimation/load_edges.py) were chosen on test_contact_family.py's
:data:`TUNED` runs only. A representative pair
(one tuned run, one held out, both noisy) runs in the normal suite; the whole family under
``accept``, with every goal a run misses kept as a strict expected failure that names the
measured number.
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_runs import SPECS, ContactRun
from contact_scoring import FORCE, HEADER, KINEMATIC, Score, estimate, robot_of, score

from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY

EVENT_GOAL_MS = 4.0
FAST = ("a1_trot_fast+noise", "go2_trot_fast+noise")
"""A tuned run and a held-out one (test_contact_family.py's TUNED and HELD_OUT), for the normal
suite."""
MISSED = {
    ("a1_trot_turn", KINEMATIC): (
        "98.29 %, swing as stance 1.31 % (0.74 point the front feet's liftoffs, +6 ms: their "
        "height over the lowest foot falls 0.25-0.43 mm over the 14 ms before they leave; 0.57 "
        "point touchdowns one sample early, as on every run; docs/forces.md)"
    ),
    ("a1_pronk", KINEMATIC): "93.47 %, push-offs as swing 6.24 %, liftoff 26 ms, duty 0.082",
    ("a1_pronk+noise", KINEMATIC): "92.00 %, push-offs as swing 7.63 %, liftoff 32 ms, duty 0.080",
    ("go2_walk+noise", KINEMATIC): (
        "liftoff 20 ms (per leg +22/+24/-12/+4: the front feet's posterior ends, 1.4-1.7 mm up "
        "a slow rise, are under LIFT_M and over the level + 0.1 mm, so nothing moves them, clean "
        "too; docs/forces.md)"
    ),
}
"""Where a goal is not met: the measured numbers (docs/forces.md's table)."""


def scored(run: ContactRun, evidence: str) -> tuple[Score, Score]:
    """The causal filter's and the smoother's scores of one run under one evidence."""
    quadruped = robot_of(run)
    weight = FootForces(quadruped).total_mass_kg * STANDARD_GRAVITY
    causal = score(run, *estimate(run, quadruped, evidence), weight)
    smoothed = score(run, *estimate(run, quadruped, evidence, smoothed=True), weight)
    print(f"\n{HEADER}\n{causal.row(run.name, 'causal')}\n{smoothed.row(run.name, 'smoothed')}")
    return causal, smoothed


def assert_goals(causal: Score, smoothed: Score, evidence: str) -> None:
    """The issue's goals for one run under one evidence."""
    duty_error = np.abs(smoothed.duty - smoothed.true_duty).max()
    if evidence == KINEMATIC:
        assert smoothed.agree_pct >= 98.0
        assert smoothed.swing_as_stance_pct <= 1.0
        # events on a 2 ms grid: 4 ms is the goal however the median's float rounds
        assert max(smoothed.touchdown_ms, smoothed.liftoff_ms) <= EVENT_GOAL_MS + 1e-6
    else:
        assert smoothed.agree_pct >= causal.agree_pct
        assert causal.agree_pct >= 99.0 or smoothed.agree_pct >= 99.0
    assert duty_error <= 0.02


def cases(names: tuple[str, ...]) -> list[object]:
    """(run, evidence) parameters, a strict expected failure where :data:`MISSED` says so."""
    out: list[object] = []
    for name in names:
        for evidence in (FORCE, KINEMATIC):
            reason = MISSED.get((name, evidence))
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            out.append(pytest.param(name, evidence, marks=marks, id=f"{name}-{evidence}"))
    return out


@pytest.mark.parametrize(("name", "evidence"), cases(FAST))
def test_smoothed_contacts_on_a_tuned_and_a_held_out_run(family, name, evidence) -> None:
    assert_goals(*scored(family[name], evidence), evidence)


@pytest.mark.accept
@pytest.mark.parametrize(
    ("name", "evidence"),
    cases(tuple(run for name in SPECS for run in (name, f"{name}+noise") if run not in FAST)),
)
def test_smoothed_contacts_on_the_family(family, name, evidence) -> None:
    assert_goals(*scored(family[name], evidence), evidence)
