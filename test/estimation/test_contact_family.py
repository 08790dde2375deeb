"""Foot forces and contacts on a family of PyBullet runs as different from each other as real
robots are (test/contact_runs.py: trots at three speeds, a turn, a walk, a pronk with flight
phases, soft toes, the A1 and a Go2-like model, each clean and with sensor noise), judged by
PyBullet's own contacts (normal force > 0) and normal forces.

The estimator's gains and evidence scales were tuned on :data:`TUNED` only; :data:`HELD_OUT` was
never looked at while tuning. Both must meet the goals. The table of every run (with the old rule,
quasi-static forces through fixed thresholds, beside it) is printed (``pytest -s``) and kept in
docs/forces.md.
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_runs import SPECS, ContactRun
from contact_scoring import FORCE, HEADER, KINEMATIC, OLD_RULE, Score, estimate, robot_of, score

from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY

TUNED = ("a1_trot_fast", "a1_pronk", "go2_trot", "a1_walk")
"""The runs (clean and noisy) the defaults were tuned on."""
HELD_OUT = tuple(name for name in SPECS if name not in TUNED)


@pytest.fixture(scope="session")
def scores(family: dict[str, ContactRun]) -> dict[tuple[str, str], Score]:
    """Every run under every evidence; the table printed."""
    out = {}
    lines = [HEADER]
    for name, run in family.items():
        quadruped = robot_of(run)
        weight = FootForces(quadruped).total_mass_kg * STANDARD_GRAVITY
        for evidence in (OLD_RULE, FORCE, KINEMATIC):
            probabilities, normals = estimate(run, quadruped, evidence)
            out[name, evidence] = score(run, probabilities, normals, weight)
            lines.append(out[name, evidence].row(name, evidence))
    print("\n".join(lines))
    return out


def runs_of(names: tuple[str, ...]) -> list[str]:
    return [run for name in names for run in (name, f"{name}+noise")]


@pytest.mark.parametrize("names", [TUNED, HELD_OUT], ids=["tuned", "held_out"])
def test_fused_contacts_agree_with_pybullet(scores, names) -> None:
    for run in runs_of(names):
        fused = scores[run, FORCE]
        assert fused.agree_pct >= 98.5, run
        assert fused.swing_as_stance_pct <= 1.0, run
        assert fused.touchdown_ms <= 10.0 and fused.liftoff_ms <= 10.0, run
        assert fused.stance_force_pct <= 8.0, run
        assert np.abs(fused.duty - fused.true_duty).max() <= 0.03, run


KINEMATIC_GOALS = (97.0, 0.03)
"""The contact issue's goals for kinematic evidence alone: agreement [%], duty error."""
KINEMATIC_TODAY = (89.0, 0.12)
"""What kinematic evidence alone meets today on every run, as a regression guard (94.2-97.2 %
and 0.033-0.082 measured when this was written; 94.75-98.13 % and 0.020-0.066 since the rise
above the foot's own foothold)."""
KINEMATIC_MISS = pytest.mark.xfail(
    strict=True,
    reason="kinematic evidence alone reaches 94.75-97.61 %, duty errors 0.030-0.070, not the "
    "goals (97 %, 0.03): a foot unloads while it still rests on the ground and moves measurably "
    "only ~10 ms later (0.8 mm and 0.19 m/s 2 ms after liftoff on the fast trot); its rise above "
    "its own foothold cut the filter's liftoff lag from 14-18 to 6-10 ms on the trots (94.2-97.2 "
    "%, 0.033-0.082 before), the walks' stay 28-36 ms late; the rigid feet's height rule does "
    "not apply with the noise (the standing feet's rises spread past 0.6 mm): the noisy runs "
    "within 0.05 point of before",
)
KINEMATIC_MET = (
    "a1_trot_slow",
    "a1_walk",
    "a1_trot_soft",
    "a1_trot_soft+noise",
    "go2_trot",
    "go2_trot_fast",
    "go2_walk",
)
"""The runs whose kinematic contacts meet the goals: the soft trot 97.36-97.72 %, duty error
0.021-0.022, go2_walk 98.53 %, 0.0175 (since the rise above the foot's own foothold); since the
rigid feet's height rule (clean runs: the standing feet's rises spread under 0.6 mm) a1_trot_slow
97.96 %, 0.0215, a1_walk 98.60 %, 0.0156, go2_trot 97.62 %, 0.0265, go2_trot_fast 98.01 %,
0.0116 (a1_trot_fast 97.36 % and a1_trot_turn 97.61 % miss on their duty errors, 0.031-0.032)."""


@pytest.mark.parametrize("names", [TUNED, HELD_OUT], ids=["tuned", "held_out"])
def test_kinematic_contacts_regression_guard(scores, names) -> None:
    for run in runs_of(names):
        kinematic = scores[run, KINEMATIC]
        assert kinematic.agree_pct >= KINEMATIC_TODAY[0], run
        assert np.abs(kinematic.duty - kinematic.true_duty).max() <= KINEMATIC_TODAY[1], run


@pytest.mark.parametrize(
    "run",
    [
        run if run in KINEMATIC_MET else pytest.param(run, marks=KINEMATIC_MISS)
        for run in runs_of(TUNED + HELD_OUT)
    ],
)
def test_kinematic_contacts_meet_the_goals(scores, run) -> None:
    """The goal, per run (a strict expected failure on each: a run that meets it must say so)."""
    kinematic = scores[run, KINEMATIC]
    assert kinematic.agree_pct >= KINEMATIC_GOALS[0]
    assert np.abs(kinematic.duty - kinematic.true_duty).max() <= KINEMATIC_GOALS[1]


def test_the_old_rule_fails_where_the_new_one_holds(scores) -> None:
    """The quasi-static threshold rule on the same runs: the reason for all of this. Where it
    misses the goal (98.5 %) the fused estimate meets it, on the same run."""
    runs = runs_of(TUNED + HELD_OUT)
    failed = [run for run in runs if scores[run, OLD_RULE].agree_pct < 98.5]
    print(f"the old rule misses 98.5 % on {len(failed)} of {len(runs)} runs")
    assert min(scores[run, OLD_RULE].agree_pct for run in failed) < 95.0
    for run in failed:
        assert scores[run, FORCE].agree_pct >= 98.5, run
