"""Contacts, forces and odometry on robots that are not their URDF (test/mismatch_runs.py: joint
friction, heavier and lighter legs, a payload, an effort scaled and late; the package always given
the nominal description), with the online model corrections and without, judged by PyBullet.

The corrections' settings were tuned on :data:`mismatch_specs.TUNED` (friction and leg masses,
and the slow trot's torque scale and latency, whose failure was diagnosed);
:data:`mismatch_specs.HELD_OUT` (payloads, torque scales, latencies) was never looked at while
tuning. Goals (issue #35): contacts >= 98.5 % agreement, <= 1 % of the samples swing
called stance, the stance normal force's RMS error <= 5 % of the true weight, the odometry's
velocity within 3 sigma for >= 95 % of the samples; with the exact robot, the corrections cost no
more than 0.1 points anywhere. Runs that miss a goal are strict xfails with their measured
numbers (``pytest -s`` prints every figure; the table is in docs/forces.md).
"""

from __future__ import annotations

from typing import Any

import pytest
from contact_scoring import FORCE, estimate, score
from mismatch_runs import mismatch_runs
from mismatch_scoring import HEADER, NOISE_SEED, Figures, figures
from mismatch_specs import EXACT, HELD_OUT, TUNED
from sensor_noise import with_noise

from a1_leg_fk.kinematics.quadruped import Quadruped

UNMET = {
    "a1_trot_turn+light_legs": "97.96 % agreement, 1.94 % swing called stance (97.58 / 2.36 "
    "before the force's fade held on any ground, docs/forces.md): the lighter "
    "legs' inertia error (not a friction term; 254 of the 329 swing samples called stance in "
    "the last fifth of swing). The legs' inertia scales learnt live reach 99.02 %, 0.92 % but "
    "cost both held-out latency runs (a1_trot_turn+everything 97.84 -> 97.18 %, "
    "go2_walk+payload_scale 99.63 -> 99.52 %: a late effort reads as a scale), so online they "
    "are not learnt; calibrate fits them and its file gives them (docs/forces.md)",
    "a1_trot_turn+light_legs~noise": "98.14 %, 1.60 % swing called stance (97.92 / 1.98 before "
    "the fade everywhere; as the clean run; "
    "98.89 %, 1.01 % with the scales learnt live)",
    "a1_trot_slow+scale_latency": "95.47 %, 4.26 % swing called stance (95.52 / 4.47 before "
    "the fade everywhere), forces 6.37 % of the "
    "weight: the 3 ms latency (undone causally with the true 3 ms and x0.9 given: 98.60 %, "
    "1.05 %, 4.49 %; a latency budget in the filter's force noise costs exact robots 0.6 "
    "points, a scale budget gains 0.66 for 15 us per joint state) and the scale, which a "
    "payload hides; the legs' inertia scales learnt live read the x0.9 as 0.83-0.85 (97.73 %, "
    "2.11 %; docs/forces.md)",
    "a1_trot_slow+scale_latency~noise": "96.24 %, 3.39 %, forces 7.10 % of the weight (96.31, "
    "3.57 before the fade everywhere)",
    "a1_trot_turn+everything": "98.08 %, 1.73 % swing called stance (97.83 / 2.01 before the "
    "fade everywhere), forces 7.09 % of the "
    "weight (latency, scale and the payload's 3 kg)",
    "a1_trot_turn+everything~noise": "98.11 %, 1.64 %, forces 6.87 % of the weight (97.84, 1.96 "
    "before the fade everywhere)",
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
@pytest.mark.parametrize(
    "key", [f"{name}=exact{noise}" for name in EXACT for noise in ("", "~noise")]
)
def test_the_exact_robot_loses_nothing_to_the_corrections(key) -> None:
    """Each term is taken off only once it clears 3 standard deviations: an exact robot's stay
    0 (before that rule the corrections cost these runs 0.25-1.7 points)."""
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


def test_an_exact_noisy_robot_keeps_its_contacts_with_the_corrections() -> None:
    """The representative exact run (make test): the A1's fast trot without any mismatch, with
    sensor noise, where the corrections once cost 1.3 points (99.08 -> 97.75 %): the same
    agreement to 0.1 points, online and off (contacts only)."""
    mismatched = mismatch_runs(("a1_trot_fast=exact",))["a1_trot_fast=exact"]
    run = with_noise(mismatched.run, NOISE_SEED)
    quadruped = Quadruped.from_urdf(run.urdf_path)
    agreement = {}
    for corrections in ("off", "online"):
        probabilities, normals = estimate(run, quadruped, FORCE, model_corrections=corrections)
        result = score(run, probabilities, normals, mismatched.true_weight_n)
        agreement[corrections] = result.agree_pct
    assert agreement["online"] >= agreement["off"] - 0.1, agreement
