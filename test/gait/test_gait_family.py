"""The gait command's phases on the contact family (test/gait_family.py), per run and evidence,
against PyBullet and against the contact estimate the report names (issue #39): per-leg duty
factors within 0.02 of PyBullet's and within 0.005 of the estimate's, touchdown and lift-off
medians within 4 ms, one stance per stride on the clean runs.

The phase rule was designed on the clean A1 runs (:data:`TUNED`); the Go2-like robot and every
noisy run are held out (:data:`HELD_OUT`). Evidence: ``force`` (the estimate with the joints'
efforts: ``gait --contacts auto`` on a recording with them), ``kinematic`` (the estimate without
efforts) and ``feet`` (the gait's own kinematic contacts: ``gait`` without efforts). A goal the
phase rule cannot meet because the stance it is given is already off is a strict xfail with the
measured number (:data:`UNMET`). ``pytest -s`` prints the table (docs/gait.md).
"""

from __future__ import annotations

import numpy as np
import pytest
from contact_runs import SPECS
from gait_family import FEET, HEADER, GaitScore, score_gait

FORCE, KINEMATIC = "force", "kinematic"
EVIDENCES = (FORCE, KINEMATIC, FEET)
TUNED = ("a1_trot_slow", "a1_trot_fast", "a1_trot_turn", "a1_walk", "a1_pronk", "a1_trot_soft")
"""Clean A1 runs: what the rule was designed on. Held out: the Go2-like robot, every noisy run."""
HELD_OUT = tuple(
    [name for name in SPECS if name not in TUNED] + [f"{name}+noise" for name in SPECS]
)
DUTY, SAME, EVENTS, STANCES = "duty vs PyBullet", "duty vs estimate", "events", "stances"
DUTY_GOAL, SAME_GOAL, EVENT_GOAL_MS = 0.02, 0.005, 4.0
LATE = (
    "without efforts the contact estimate itself is late at lift-off (and its short dips just "
    "before lift-off are bridged, as false swings)"
)
UNLOADS = "the gait's kinematic contacts (heights, speeds): a foot unloads before it moves"
FORCE_LATE = "the force estimate's own lift-off is 6 ms late here"
WALK_START = (
    "the estimate's own false swing of 38-66 ms (longer than the minimum phase) in the walk's "
    "first stride splits that stride; the report leaves the irregular half out"
)
CAUSE = {KINEMATIC: LATE, FEET: UNLOADS}
UNMET = {
    ("a1_trot_slow", "kinematic", DUTY): "0.055 from PyBullet",
    ("a1_trot_slow", "kinematic", EVENTS): "touchdown 0 ms, lift-off 22 ms",
    ("a1_trot_slow", "feet", DUTY): "0.035 from PyBullet",
    ("a1_trot_slow", "feet", EVENTS): "touchdown 4 ms, lift-off 12 ms",
    ("a1_trot_fast", "kinematic", DUTY): "0.059 from PyBullet",
    ("a1_trot_fast", "kinematic", EVENTS): "touchdown 0 ms, lift-off 18 ms",
    ("a1_trot_fast", "feet", DUTY): "0.046 from PyBullet",
    ("a1_trot_fast", "feet", EVENTS): "touchdown 4 ms, lift-off 10 ms",
    ("a1_trot_turn", "kinematic", DUTY): "0.083 from PyBullet",
    ("a1_trot_turn", "kinematic", EVENTS): "touchdown 8 ms, lift-off 22 ms",
    ("a1_trot_turn", "feet", DUTY): "0.044 from PyBullet",
    ("a1_trot_turn", "feet", EVENTS): "touchdown 6 ms, lift-off 12 ms",
    ("a1_walk", "kinematic", DUTY): "0.042 from PyBullet",
    ("a1_walk", "kinematic", EVENTS): "touchdown 0 ms, lift-off 68 ms",
    ("a1_walk", "feet", DUTY): "0.026 from PyBullet",
    ("a1_walk", "feet", EVENTS): "touchdown 4 ms, lift-off 36 ms",
    ("a1_pronk", "kinematic", DUTY): "0.044 from PyBullet",
    ("a1_pronk", "kinematic", EVENTS): "touchdown 4 ms, lift-off 18 ms",
    ("a1_pronk", "feet", DUTY): "0.077 from PyBullet",
    ("a1_pronk", "feet", EVENTS): "touchdown 4 ms, lift-off 34 ms",
    ("a1_trot_soft", "kinematic", DUTY): "0.039 from PyBullet",
    ("a1_trot_soft", "kinematic", EVENTS): "touchdown 0 ms, lift-off 16 ms",
    ("go2_trot", "force", EVENTS): "touchdown 2 ms, lift-off 6 ms",
    ("go2_trot", "kinematic", DUTY): "0.058 from PyBullet",
    ("go2_trot", "kinematic", EVENTS): "touchdown 0 ms, lift-off 24 ms",
    ("go2_trot", "feet", DUTY): "0.032 from PyBullet",
    ("go2_trot", "feet", EVENTS): "touchdown 4 ms, lift-off 12 ms",
    ("go2_trot_fast", "kinematic", DUTY): "0.052 from PyBullet",
    ("go2_trot_fast", "kinematic", EVENTS): "touchdown 2 ms, lift-off 16 ms",
    ("go2_trot_fast", "feet", DUTY): "0.039 from PyBullet",
    ("go2_trot_fast", "feet", EVENTS): "touchdown 4 ms, lift-off 8 ms",
    ("go2_walk", "force", SAME): "0.013 from the estimate",
    ("go2_walk", "force", STANCES): "1.045 stances per stride",
    ("go2_walk", "kinematic", DUTY): "0.034 from PyBullet",
    ("go2_walk", "kinematic", EVENTS): "touchdown 2 ms, lift-off 56 ms",
    ("go2_walk", "feet", EVENTS): "touchdown 4 ms, lift-off 22 ms",
    ("a1_trot_slow+noise", "kinematic", DUTY): "0.051 from PyBullet",
    ("a1_trot_slow+noise", "kinematic", SAME): "0.011 from the estimate",
    ("a1_trot_slow+noise", "kinematic", EVENTS): "touchdown 0 ms, lift-off 20 ms",
    ("a1_trot_slow+noise", "feet", DUTY): "0.046 from PyBullet",
    ("a1_trot_slow+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 16 ms",
    ("a1_trot_fast+noise", "kinematic", DUTY): "0.059 from PyBullet",
    ("a1_trot_fast+noise", "kinematic", SAME): "0.026 from the estimate",
    ("a1_trot_fast+noise", "kinematic", EVENTS): "touchdown 0 ms, lift-off 18 ms",
    ("a1_trot_fast+noise", "feet", DUTY): "0.059 from PyBullet",
    ("a1_trot_fast+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 14 ms",
    ("a1_trot_turn+noise", "kinematic", DUTY): "0.070 from PyBullet",
    ("a1_trot_turn+noise", "kinematic", SAME): "0.010 from the estimate",
    ("a1_trot_turn+noise", "kinematic", EVENTS): "touchdown 4 ms, lift-off 22 ms",
    ("a1_trot_turn+noise", "feet", DUTY): "0.057 from PyBullet",
    ("a1_trot_turn+noise", "feet", EVENTS): "touchdown 6 ms, lift-off 16 ms",
    ("a1_walk+noise", "kinematic", DUTY): "0.043 from PyBullet",
    ("a1_walk+noise", "kinematic", EVENTS): "touchdown 0 ms, lift-off 70 ms",
    ("a1_walk+noise", "feet", DUTY): "0.028 from PyBullet",
    ("a1_walk+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 39 ms",
    ("a1_pronk+noise", "force", EVENTS): "touchdown 2 ms, lift-off 6 ms",
    ("a1_pronk+noise", "kinematic", DUTY): "0.069 from PyBullet",
    ("a1_pronk+noise", "kinematic", EVENTS): "touchdown 6 ms, lift-off 22 ms",
    ("a1_pronk+noise", "feet", DUTY): "0.079 from PyBullet",
    ("a1_pronk+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 34 ms",
    ("a1_trot_soft+noise", "kinematic", DUTY): "0.036 from PyBullet",
    ("a1_trot_soft+noise", "kinematic", SAME): "0.011 from the estimate",
    ("a1_trot_soft+noise", "kinematic", EVENTS): "touchdown 0 ms, lift-off 14 ms",
    ("a1_trot_soft+noise", "feet", DUTY): "0.029 from PyBullet",
    ("a1_trot_soft+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 8 ms",
    ("go2_trot+noise", "force", EVENTS): "touchdown 2 ms, lift-off 6 ms",
    ("go2_trot+noise", "kinematic", DUTY): "0.053 from PyBullet",
    ("go2_trot+noise", "kinematic", SAME): "0.011 from the estimate",
    ("go2_trot+noise", "kinematic", EVENTS): "touchdown 2 ms, lift-off 22 ms",
    ("go2_trot+noise", "feet", DUTY): "0.046 from PyBullet",
    ("go2_trot+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 16 ms",
    ("go2_trot_fast+noise", "kinematic", DUTY): "0.046 from PyBullet",
    ("go2_trot_fast+noise", "kinematic", SAME): "0.017 from the estimate",
    ("go2_trot_fast+noise", "kinematic", EVENTS): "touchdown 2 ms, lift-off 16 ms",
    ("go2_trot_fast+noise", "feet", DUTY): "0.047 from PyBullet",
    ("go2_trot_fast+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 12 ms",
    ("go2_walk+noise", "force", SAME): "0.013 from the estimate",
    ("go2_walk+noise", "kinematic", DUTY): "0.035 from PyBullet",
    ("go2_walk+noise", "kinematic", EVENTS): "touchdown 2 ms, lift-off 56 ms",
    ("go2_walk+noise", "feet", DUTY): "0.024 from PyBullet",
    ("go2_walk+noise", "feet", EVENTS): "touchdown 4 ms, lift-off 34 ms",
}
"""Goals not met, by (run, evidence, goal): the measured number (max over legs)."""


@pytest.fixture(scope="session")
def scored(family):
    """``scored(name, evidence)``: the run's :class:`GaitScore`, computed once per session."""
    cache: dict[tuple[str, str], GaitScore] = {}

    def get(name: str, evidence: str) -> GaitScore:
        if (name, evidence) not in cache:
            cache[name, evidence] = score_gait(family[name], evidence)
        return cache[name, evidence]

    return get


def cause_of(evidence: str, goal: str) -> str:
    """Why ``goal`` is unmet under ``evidence``: with efforts, the walk's start splits a stride
    (duty vs the estimate, stances) or the estimate lifts off late (events); without, the
    evidence's own cause (:data:`CAUSE`)."""
    if evidence == FORCE:
        return WALK_START if goal in (SAME, STANCES) else FORCE_LATE
    return CAUSE[evidence]


def cases(goal: str, evidences: tuple[str, ...], clean_only: bool = False) -> list:
    """One parameter per (run, evidence), tuned then held out; a strict xfail where unmet."""
    out = []
    for held, names in (("tuned", TUNED), ("held_out", HELD_OUT)):
        for name in names:
            if clean_only and name.endswith("+noise"):
                continue
            for evidence in evidences:
                measured = UNMET.get((name, evidence, goal))
                cause = cause_of(evidence, goal)
                marks = (
                    [pytest.mark.xfail(strict=True, reason=f"{cause}: {measured}")]
                    if measured
                    else []
                )
                out.append(
                    pytest.param(name, evidence, marks=marks, id=f"{held}-{name}-{evidence}")
                )
    return out


@pytest.mark.accept
@pytest.mark.parametrize(("name", "evidence"), cases(DUTY, EVIDENCES))
def test_duty_factors_meet_pybullet(scored, name, evidence) -> None:
    score = scored(name, evidence)
    print(f"{HEADER}\n{score.row(name, evidence)}")
    assert np.abs(score.duty - score.true_duty).max() <= DUTY_GOAL


@pytest.mark.accept
@pytest.mark.parametrize(("name", "evidence"), cases(SAME, (FORCE, KINEMATIC)))
def test_duty_factors_are_the_estimates(scored, name, evidence) -> None:
    """The report's duty is that of the estimate it names (fails on the old merge: a1_walk+noise
    0.014, a1_pronk+noise 0.010 with efforts)."""
    score = scored(name, evidence)
    assert score.estimate_duty is not None
    assert np.abs(score.duty - score.estimate_duty).max() <= SAME_GOAL


@pytest.mark.accept
@pytest.mark.parametrize(("name", "evidence"), cases(EVENTS, EVIDENCES))
def test_touchdowns_and_liftoffs_on_time(scored, name, evidence) -> None:
    score = scored(name, evidence)
    assert score.touchdown_ms <= EVENT_GOAL_MS + 1e-6
    assert score.liftoff_ms <= EVENT_GOAL_MS + 1e-6


@pytest.mark.accept
@pytest.mark.parametrize(("name", "evidence"), cases(STANCES, EVIDENCES, clean_only=True))
def test_one_stance_per_stride(scored, name, evidence) -> None:
    assert scored(name, evidence).stances_per_stride == pytest.approx(1.0, abs=1e-9)
