"""Contacts, forces and odometry on robots that are not their URDF (test/mismatch_runs.py: joint
friction, heavier and lighter legs, a payload, an effort scaled and late; the package always given
the nominal description), with the online model corrections and without, judged by PyBullet.

The corrections' settings were tuned on :data:`mismatch_runs.TUNED` (friction and leg masses);
:data:`mismatch_runs.HELD_OUT` (payloads, torque scales, latencies: whole kinds) was never looked
at while tuning. Goals (issue #35): contacts >= 98.5 % agreement, <= 1 % of the samples swing
called stance, the stance normal force's RMS error <= 5 % of the true weight, the odometry's
velocity within 3 sigma for >= 95 % of the samples; with the exact robot, the corrections cost no
more than 0.1 points anywhere. Runs that miss a goal are strict xfails with their measured
numbers (``pytest -s`` prints every figure; the table is in docs/forces.md).
"""

from __future__ import annotations

from typing import Any

import pytest
from mismatch_runs import EXACT, HELD_OUT, TUNED, mismatch_runs
from mismatch_scoring import HEADER, Figures, figures

UNMET = {
    "a1_trot_turn+light_legs": "95.53 % agreement, 4.46 % swing called stance: the lighter "
    "legs' inertia error (not a friction term) reads as +4 N for ~15 ms after each liftoff",
    "a1_trot_turn+light_legs~noise": "95.84 %, 4.14 % swing called stance (as the clean run)",
    "a1_trot_fast+friction~noise": "98.73 %, 1.19 % swing called stance",
    "a1_trot_fast+payload~noise": "98.26 %, 1.48 % swing called stance",
    "a1_trot_slow+scale_latency": "94.93 %, 5.05 % swing called stance, forces 5.29 % of the "
    "weight: 3 ms of effort latency is not a friction term, and the torque scale is not learnt",
    "a1_trot_slow+scale_latency~noise": "94.89 %, 5.07 %, forces 5.78 % of the weight",
    "a1_trot_turn+everything": "97.39 %, 2.47 % swing called stance, forces 7.17 % of the "
    "weight (latency, scale and the payload's 3 kg)",
    "a1_trot_turn+everything~noise": "97.43 %, 2.44 %, forces 6.94 % of the weight",
}
"""Runs (with the corrections online) that miss a goal: their measured figures."""


def _cases(names: tuple[str, ...]) -> list[Any]:
    cases = []
    for name in names:
        for key in (name, f"{name}~noise"):
            marks = [pytest.mark.xfail(strict=True, reason=UNMET[key])] if key in UNMET else []
            cases.append(pytest.param(key, marks=marks, id=key))
    return cases


_FIGURES: dict[tuple[str, str], Figures] = {}


def figures_of(key: str, corrections: str) -> Figures:
    """The figures of run ``key`` (``NAME`` or ``NAME~noise``) with ``corrections``, printed."""
    if (key, corrections) not in _FIGURES:
        name = key.removesuffix("~noise")
        run = mismatch_runs((name,))[name]
        result = figures(run, key.endswith("~noise"), model_corrections=corrections)
        print(f"\n{HEADER}\n{result.row(f'{key} ({corrections})')}")
        _FIGURES[key, corrections] = result
    return _FIGURES[key, corrections]


def assert_goals(result: Figures, key: str) -> None:
    contacts = result.contacts
    assert contacts.agree_pct >= 98.5, key
    assert contacts.swing_as_stance_pct <= 1.0, key
    assert contacts.stance_force_pct <= 5.0, key
    assert result.within_3sigma >= 0.95, key


@pytest.mark.accept
@pytest.mark.parametrize("key", _cases(TUNED))
def test_tuned_mismatches_meet_the_goals_with_online_corrections(key) -> None:
    assert_goals(figures_of(key, "online"), key)


@pytest.mark.accept
@pytest.mark.parametrize("key", _cases(HELD_OUT))
def test_held_out_mismatches_meet_the_goals_with_online_corrections(key) -> None:
    assert_goals(figures_of(key, "online"), key)


@pytest.mark.accept
@pytest.mark.xfail(
    strict=True,
    reason="the corrections learn friction the exact robot does not have and cost it 0.25-1.7 "
    "points on every run (online against off: a1_trot_fast 99.46 -> 99.18 %, +noise 99.08 -> "
    "97.75; a1_trot_slow 99.44 -> 99.24, +noise 99.25 -> 97.68; a1_trot_turn 99.65 -> 99.20, "
    "+noise 99.21 -> 97.54; a1_walk 99.80 -> 98.97, +noise 99.74 -> 98.16; go2_trot 99.25 -> "
    "99.00, +noise 99.11 -> 98.39; go2_walk 99.42 -> 98.94, +noise 99.40 -> 98.34): hence "
    "model_corrections defaults to off",
)
@pytest.mark.parametrize(
    "key", [f"{name}=exact{noise}" for name in EXACT for noise in ("", "~noise")]
)
def test_the_exact_robot_loses_nothing_to_the_corrections(key) -> None:
    off, online = figures_of(key, "off"), figures_of(key, "online")
    assert online.contacts.agree_pct >= off.contacts.agree_pct - 0.1, key


def test_corrections_undo_joint_friction_on_a_fast_trot() -> None:
    """The representative run (make test): the A1's fast trot with 0.1 N m s/rad of viscous and
    0.4 N m of Coulomb friction on every joint (simulated in ~5 s, once per machine). Without
    corrections the friction reads as load in swing (97.4 %, 2.6 % of the samples swing called
    stance); online, the goals hold."""
    key = "a1_trot_fast+friction"
    assert figures_of(key, "off").contacts.swing_as_stance_pct > 1.0
    assert_goals(figures_of(key, "online"), key)
