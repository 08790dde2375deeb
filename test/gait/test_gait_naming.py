"""Gait names in Hildebrand's terms, and contacts that hold on motion with the properties of real
animals and robots.

The answers come from the definitions, worked out here by hand: the limb phase is the fraction of
the stride by which a fore foot touches down after the hind foot of its side; a symmetric gait's
left and right feet are half a cycle apart; pace, trot and the lateral- and diagonal-sequence
bands of Hildebrand's plane; an asymmetric gait by its pairs' unison. The end-to-end fixtures
(test_gait_analysis.synthetic) are what real retargeted dog motion looks like: hind feet leading
the fore feet of their side by a tenth of a cycle, diagonal feet 0.05 cycle apart, stance feet
sliding at 0.4 m/s, four-foot flight phases; at 25..1000 Hz with noise and jittered stamps.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import raises_leg_fk_error
from shared import LEGS, known
from synthetic_gaits import PERIOD_S, synthetic

from a1_leg_fk.gait.analysis import ContactThresholds, analyze_gait
from a1_leg_fk.gait.naming import circular_distance, name_gait

# name, region, touchdown phases of FR, FL, RR, RL [cycles], duty factor, limb phase [cycles]
PATTERNS = [
    # A real dog's pace: each hind foot 0.1 cycle before the fore foot of its side.
    ("pace", "pace", (0.0, 0.5, 0.9, 0.4), 0.48, 0.1),
    ("pace", "walking pace", (0.0, 0.5, 0.95, 0.45), 0.6, 0.05),
    ("walk", "lateral-sequence walk", (0.0, 0.5, 0.75, 0.25), 0.75, 0.25),
    ("walk", "diagonal-sequence walk", (0.0, 0.5, 0.25, 0.75), 0.7, 0.75),
    ("amble", "lateral-sequence run", (0.0, 0.5, 0.7, 0.2), 0.4, 0.3),
    # A trot whose hind feet land 0.05 cycle after their diagonal fore feet.
    ("trot", "trot", (0.0, 0.5, 0.55, 0.05), 0.45, 0.45),
    ("trot", "walking trot", (0.0, 0.5, 0.5, 0.0), 0.6, 0.5),
    ("bound", "bound", (0.0, 0.03, 0.55, 0.52), 0.35, None),
    ("half-bound", "half-bound (fore pair split)", (0.0, 0.15, 0.55, 0.55), 0.35, None),
    # Transverse: the second foot of each pair (the lead) is on the same side, here the left.
    ("gallop", "transverse gallop", (0.0, 0.15, 0.5, 0.65), 0.3, None),
    ("gallop", "rotary gallop", (0.0, 0.15, 0.65, 0.5), 0.3, None),
    ("pronk", "pronk", (0.0, 0.02, 0.98, 0.0), 0.35, None),
]


def as_phases(pattern: tuple[float, float, float, float]) -> dict[str, float | None]:
    return {leg: (phase - pattern[0]) % 1.0 for leg, phase in zip(LEGS[1:], pattern[1:])}


@pytest.mark.parametrize(("name", "region", "pattern", "duty", "limb_phase"), PATTERNS)
def test_named_from_phases(name, region, pattern, duty, limb_phase) -> None:
    consistency = dict.fromkeys(("FL", "RR", "RL"), 0.98)
    for shift in (0.0, 0.37):  # the answer does not depend on when FR's stride starts
        shifted = tuple((phase + shift) % 1.0 for phase in pattern)
        gait = name_gait(as_phases(shifted), dict(consistency), duty)
        assert (gait.name, gait.region) == (name, region), gait.reason
        assert 0.5 < gait.fit <= 0.98
        assert gait.symmetric == (limb_phase is not None)
        if limb_phase is not None:
            assert circular_distance(known(gait.limb_phase), limb_phase) < 1e-9
            assert circular_distance(known(gait.limb_phase_left), limb_phase) < 1e-9


def test_patterns_between_regions_and_drifting_phases_are_unknown() -> None:
    # Fore feet alternate, hind feet a quarter cycle apart: neither symmetric nor paired.
    between = name_gait(
        as_phases((0.0, 0.5, 0.3, 0.55)), dict.fromkeys(("FL", "RR", "RL"), 1.0), 0.5
    )
    assert between.name == "unknown" and between.region == "" and "no region" in between.reason
    assert between.symmetric is False and between.fit == 0.0
    drifting = name_gait(as_phases((0.0, 0.5, 0.5, 0.0)), {"FL": 0.9, "RR": 0.4, "RL": 0.9}, 0.5)
    assert drifting.name == "unknown" and "not consistent" in drifting.reason
    missing = name_gait(
        {"FL": 0.5, "RR": None, "RL": 0.0}, {"FL": 1.0, "RR": None, "RL": 1.0}, 0.5
    )
    assert missing.name == "unknown" and "RR" in missing.reason and missing.limb_phase is None


def stance_agreement(contacts, truth) -> float:
    """Share of the samples (away from the ends) whose stance flag matches the true stances."""
    times = contacts.times_s
    inner = (times > 0.2) & (times < times[-1] - 0.2)
    true_stance = np.zeros(contacts.stance.shape, dtype=bool)
    for leg, intervals in enumerate(truth):
        for t_on, t_off in intervals:
            true_stance[(times >= t_on) & (times < t_off), leg] = True
    return float((contacts.stance[inner] == true_stance[inner]).mean())


@pytest.mark.parametrize("rate", [25, 200, 1000])
@pytest.mark.parametrize("slip", [0.0, 0.4])
@pytest.mark.parametrize(("name", "region", "pattern", "duty", "limb_phase"), PATTERNS)
def test_gaits_with_slip_and_noise(rate, slip, name, region, pattern, duty, limb_phase) -> None:
    stamps, feet, truth = synthetic(
        "trot", 0.5, rate, seed=rate + 7, phases=pattern, duty=duty, slip_mps=slip
    )
    contacts, report = analyze_gait(stamps, feet)
    sample = float(np.diff(stamps).max())
    naming = report.naming
    assert naming is not None
    assert (report.gait, naming.region) == (name, region), report.gait_reason
    agreement = stance_agreement(contacts, truth)
    assert agreement > 0.93, agreement
    for leg in LEGS:
        metrics = report.legs[leg]
        assert abs(known(metrics.duty_factor) - duty) <= 0.03 + sample / PERIOD_S
        assert abs(known(metrics.stride_period_s) - PERIOD_S) <= 0.005
    if limb_phase is not None:
        assert circular_distance(known(naming.limb_phase), limb_phase) < 0.03
    if slip:  # each foot's derived speed gate lets the sliding stance in
        assert all(t.speed_on_mps > slip for t in contacts.leg_thresholds)


def test_fixed_thresholds_and_slipping_stances() -> None:
    # Stance feet sliding at 0.2 and 0.4 m/s judged by the fixed 0.15 m/s gate: at 0.2 the gate
    # shrinks stances to their slow ends, and the edges, placed by the heights (a foot standing
    # while it slides), carry them back to the true duty 0.5 (before the edges did: 0.34..0.39);
    # at 0.4 no foot is ever still, so not even the ground is found. The derived gates hold both.
    for slip in (0.2, 0.4):
        stamps, feet, truth = synthetic("trot", 0.5, 200, slip_mps=slip)
        fixed = ContactThresholds(adaptive=False)
        if slip < 0.3:
            contacts, report = analyze_gait(stamps, feet, fixed)
            assert all(abs(known(m.duty_factor) - 0.5) < 0.02 for m in report.legs.values())
        else:
            with raises_leg_fk_error("no foot is ever still"):
                analyze_gait(stamps, feet, fixed)
        contacts, report = analyze_gait(stamps, feet)
        assert stance_agreement(contacts, truth) > 0.95 and report.gait == "trot"


@pytest.mark.parametrize("rate", [25, 1000])
def test_no_stance_in_flight(rate) -> None:
    # A pronk (hops in place, then forward) has all four feet in the air 65 % of the time; at the
    # top of each hop the feet hang still (in place) 7 cm up: never a stance.
    for speed in (0.0, 1.0):
        stamps, feet, truth = synthetic(
            "pronk", speed, rate, seed=3, phases=(0.0, 0.0, 0.0, 0.0), duty=0.35
        )
        contacts, report = analyze_gait(stamps, feet)
        times = contacts.times_s
        flight = np.ones(times.size, dtype=bool)
        margin = 1.0 / rate + 0.01  # an edge may be off by a sample and the hysteresis delay
        for t_on, t_off in truth[0]:
            flight &= (times < t_on - margin) | (times > t_off + margin)
        assert flight.sum() > 0.4 * times.size
        assert not contacts.stance[flight].any()
        assert report.gait == "pronk"


def test_report_gives_limb_phase_region_and_thresholds() -> None:
    stamps, feet, _ = synthetic("walk", 0.3, 100, slip_mps=0.3)
    contacts, report = analyze_gait(stamps, feet)
    document = json.loads(json.dumps(report.to_json(), allow_nan=False))
    assert document["gait"] == "walk" and document["gait_region"] == "lateral-sequence walk"
    assert abs(document["limb_phase"] - 0.25) < 0.03 and document["gait_symmetric"] is True
    assert set(document["thresholds_used"]) == set(LEGS)
    for leg, used in document["thresholds_used"].items():
        bounds = document["thresholds"]
        assert bounds["speed_on_mps"] <= used["speed_on_mps"] <= bounds["speed_on_max_mps"]
        assert bounds["height_on_m"] <= used["height_on_m"] <= bounds["height_on_max_m"]
        assert used["height_off_m"] - used["height_on_m"] == pytest.approx(
            bounds["height_off_m"] - bounds["height_on_m"]
        )
        assert used == {
            key: getattr(contacts.leg_thresholds[LEGS.index(leg)], key) for key in used
        }
