"""Contacts smoothed over the whole run (``a1-leg-fk bag`` and ``gait`` without ``--causal``)
on the PyBullet contact family, judged by PyBullet's contacts, against the issue's goals:

- without efforts: agreement >= 98 %, swing called stance <= 1 %, median touchdown and liftoff
  within 4 ms, duty factors within 0.02 of PyBullet's;
- with efforts: agreement no worse than the causal filter's, >= 99 % where the causal filter is
  below it, duty factors within 0.02.

The smoother's settings (its liftoff lead without efforts; with them, no liftoff before the
filter's) were chosen on test_contact_family.py's :data:`TUNED` runs only. A representative pair
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

FAST = ("a1_trot_fast+noise", "go2_trot_fast+noise")
"""A tuned run and a held-out one (test_contact_family.py's TUNED and HELD_OUT), for the normal
suite."""
MISSED = {
    ("a1_trot_slow", KINEMATIC): "swing as stance 1.34 %, duty error 0.025",
    ("a1_trot_slow+noise", KINEMATIC): "swing as stance 1.34 %",
    ("a1_trot_fast", KINEMATIC): "swing as stance 1.16 %",
    ("a1_trot_turn", KINEMATIC): "97.72 %, swing as stance 1.89 %, duty error 0.041",
    ("a1_trot_turn+noise", KINEMATIC): "97.63 %, swing as stance 1.96 %, duty error 0.040",
    ("a1_walk", KINEMATIC): "97.83 %, swing as stance 2.15 %, liftoff 25 ms, duty error 0.042",
    ("a1_walk+noise", KINEMATIC): "97.91 %, 2.07 % swing as stance, liftoff 24 ms, duty 0.041",
    ("a1_pronk", KINEMATIC): "93.61 %, push-offs as swing 5.74 %, liftoff 20 ms, duty 0.065",
    ("a1_pronk+noise", KINEMATIC): "91.79 %, push-offs as swing 7.60 %, liftoff 32 ms, duty 0.080",
    ("a1_trot_soft", KINEMATIC): "swing as stance 1.005 %",
    ("go2_trot", KINEMATIC): "swing as stance 1.40 %, duty error 0.025",
    ("go2_trot+noise", KINEMATIC): "swing as stance 1.21 %",
    ("go2_walk", KINEMATIC): "swing as stance 1.88 %, liftoff 24 ms, duty error 0.025",
    ("go2_walk+noise", KINEMATIC): "swing as stance 1.85 %, liftoff 24 ms, duty error 0.025",
    ("a1_pronk+noise", FORCE): "98.83 % against the causal 98.58 %, below 99 %",
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
        assert smoothed.touchdown_ms <= 4.0 and smoothed.liftoff_ms <= 4.0
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
