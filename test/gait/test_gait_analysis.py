"""gait_analysis against synthetic gaits whose true stance intervals the test itself knows.

The generator (test/synthetic_gaits.py) is written from the gait definitions, not from the code:
each leg touches down at ``(offset + k) * period``, stays on a fixed foothold for ``duty *
period``, then swings to the next foothold (horizontal cosine blend, vertical ``clearance * sin``)
while the body moves at ``speed``. The ground is a plane inclined a few degrees, not at z = 0, and
the foot frame sits a foot radius above it; stamps jitter; positions get Gaussian noise.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import raises_leg_fk_error
from shared import LEGS, known
from synthetic_gaits import (
    CLEARANCE_M,
    DUTY,
    FOOT_RADIUS_M,
    GROUND_Z0_M,
    NOISE_M,
    PERIOD_S,
    PHASES,
    SLOPE_DEG,
    synthetic,
)

from a1_leg_fk.gait.analysis import ContactThresholds, analyze_gait, detect_contacts

DEFAULTS = ContactThresholds()


def vertical_speed(gait: str) -> float:
    """The feet's vertical speed at touchdown and lift-off [m/s] (derivative of the sine lift)."""
    return CLEARANCE_M * math.pi / ((1.0 - DUTY[gait]) * PERIOD_S)


CASES = [
    (gait, rate, speed) for gait in PHASES for rate in (25, 100, 1000) for speed in (0.0, 0.4, 1.2)
]


@pytest.mark.parametrize(("gait", "rate", "speed"), CASES)
def test_synthetic_gait(gait: str, rate: int, speed: float) -> None:
    stamps, feet, truth = synthetic(gait, speed, rate, seed=rate + round(10 * speed))
    contacts, report = analyze_gait(stamps, feet)
    times = stamps - stamps[0]
    sample = float(np.diff(times).max())
    # Hysteresis delay: how long the true foot spends between the ground and the on/off height.
    v = vertical_speed(gait)
    tolerances = (sample + DEFAULTS.height_on_m / v, sample + DEFAULTS.height_off_m / v)
    worst = [0.0, 0.0]
    for leg in range(4):
        detected = contacts.stances[leg]
        for t_on, t_off in truth[leg]:
            for edge, true_time in enumerate((t_on, t_off)):
                if not 0.1 < true_time < times[-1] - 0.1:
                    continue
                found = [
                    (s.t_on, s.t_off)[edge]
                    for s in detected
                    if (s.touchdown_observed, s.liftoff_observed)[edge]
                ]
                error = min(abs(f - true_time) for f in found)
                worst[edge] = max(worst[edge], error)
                assert error <= tolerances[edge], (leg, edge, true_time, error)
        metrics = report.legs[LEGS[leg]]
        assert metrics.status == "ok"
        assert abs(known(metrics.duty_factor) - DUTY[gait]) <= 0.02
        assert abs(known(metrics.stride_period_s) - PERIOD_S) <= 0.005
        assert abs(known(metrics.step_length_m) - speed * PERIOD_S) <= 0.005
        assert abs(known(metrics.clearance_m) - CLEARANCE_M) <= 0.005
    assert report.gait == gait and report.gait_fit > 0.8
    for name, phase in zip(("FL", "RR", "RL"), PHASES[gait][1:]):
        off = abs(known(report.phase_vs_fr[name]) - phase)
        assert min(off, 1 - off) < 0.03
    # The ground plane: level of the foot frame in stance, and the slope.
    ground = contacts.ground
    a, b = (math.tan(math.radians(d)) for d in SLOPE_DEG)
    x0, y0 = ground.origin_xy
    true_level = GROUND_Z0_M + a * x0 + b * y0 + FOOT_RADIUS_M * math.sqrt(1 + a * a + b * b)
    assert abs(ground.level_m - true_level) < 0.002
    assert abs(ground.slope[0] - a) < 0.003 and abs(ground.slope[1] - b) < 0.003
    print(
        f"{gait} {rate} Hz {speed} m/s: worst touchdown error {worst[0] * 1e3:.1f} ms, lift-off "
        f"{worst[1] * 1e3:.1f} ms, duty "
        f"{[round(known(m.duty_factor), 3) for m in report.legs.values()]} (true {DUTY[gait]})"
    )


def test_a_pause_is_an_irregular_stride() -> None:
    # A pronk frozen mid-stance (all four feet down) for 1 s: the stride around it is no gait
    # cycle.
    pause_at = 3 * PERIOD_S + 0.5 * DUTY["pronk"] * PERIOD_S
    stamps, feet, _ = synthetic("pronk", 0.0, 200, seconds=7.0, pause=(pause_at, 1.0))
    _, report = analyze_gait(stamps, feet)
    assert report.gait == "pronk"
    for metrics in report.legs.values():
        assert metrics.irregular_strides == 1
        assert abs(known(metrics.stride_period_s) - PERIOD_S) <= 0.005
        assert abs(known(metrics.duty_factor) - DUTY["pronk"]) <= 0.02


def test_two_strides_far_from_their_median_are_no_gait() -> None:
    # Two strides, 0.47 s and 1.47 s (a 1 s pause mid-stance): their median, 0.97 s, is more
    # than 50 % from both, so no stride is regular; the legs say so instead of dividing by zero.
    pause_at = PERIOD_S + 0.5 * DUTY["pronk"] * PERIOD_S
    stamps, feet, _ = synthetic(
        "pronk", 0.0, 200, seconds=3 * PERIOD_S + 1.2, pause=(pause_at, 1.0)
    )
    _, report = analyze_gait(stamps, feet)
    assert {metrics.status for metrics in report.legs.values()} == {"irregular strides"}
    assert report.gait == "unknown"
    json.dumps(report.to_json(), allow_nan=False)


def test_json_is_strict_and_complete() -> None:
    stamps, feet, _ = synthetic("trot", 0.5, 200)
    _, report = analyze_gait(stamps, feet)
    document = json.loads(json.dumps(report.to_json(), allow_nan=False))
    assert document["gait"] == "trot"
    assert set(document["legs"]) == set(LEGS)
    for leg in document["legs"].values():
        assert {
            "duty_factor",
            "stride_period_s",
            "step_length_m",
            "clearance_m",
            "stance_s",
        } <= set(leg)
        assert all(a < b for a, b in leg["stance_s"])
    assert set(document["phase_vs_FR"]) == {"FL", "RR", "RL"}
    assert set(document["thresholds"]) >= {
        "height_on_m",
        "height_off_m",
        "speed_on_mps",
        "speed_off_mps",
        "min_phase_s",
    }


def test_unsorted_stamps_are_sorted_or_rejected() -> None:
    stamps, feet, _ = synthetic("trot", 0.5, 100, seconds=4.0)
    order = np.random.default_rng(1).permutation(stamps.size)
    _, reference = analyze_gait(stamps, feet)
    contacts, shuffled = analyze_gait(stamps[order], feet[order])
    assert shuffled.legs == reference.legs
    assert any("sorted" in note for note in contacts.notes)
    with raises_leg_fk_error("not increasing"):
        detect_contacts(stamps[order], feet[order], unsorted="reject")
    repeated = np.concatenate((stamps[:10], stamps[9:]))
    contacts = detect_contacts(repeated, np.concatenate((feet[:10], feet[9:])))
    assert any("repeated a stamp" in note for note in contacts.notes)


def test_too_few_samples_and_bad_shapes() -> None:
    stamps, feet, _ = synthetic("trot", 0.5, 100, seconds=1.0)
    with raises_leg_fk_error("too few samples"):
        detect_contacts(stamps[:4], feet[:4])
    with raises_leg_fk_error("(N, 4, 3)"):
        detect_contacts(stamps, feet[:, :3])
    with raises_leg_fk_error("off >= on"):
        ContactThresholds(height_on_m=0.05, height_off_m=0.03)
    with raises_leg_fk_error("max >= on", "0.15 / 0.1 m/s"):
        ContactThresholds(speed_on_max_mps=0.1)


def test_leg_that_never_touches_down_or_never_lifts() -> None:
    stamps, feet, _ = synthetic("trot", 0.0, 100, seconds=4.0)
    feet[:, 1, 2] += 0.15  # FL held in the air (a lifted leg)
    feet[:, 2] = feet[0, 2] + np.random.default_rng(2).normal(
        0.0, NOISE_M, feet[:, 2].shape
    )  # RR planted
    feet[:, 2, 2] = np.min(feet[:, 0, 2]) + np.random.default_rng(3).normal(
        0.0, NOISE_M, stamps.size
    )
    _, report = analyze_gait(stamps, feet)
    assert (
        report.legs["FL"].status == "never touches down" and report.legs["FL"].duty_factor == 0.0
    )
    assert report.legs["RR"].status == "never lifts" and report.legs["RR"].duty_factor == 1.0
    assert report.legs["FR"].status == "ok"
    assert report.gait == "unknown" and "FL" in report.gait_reason
    document = json.loads(json.dumps(report.to_json(), allow_nan=False))
    assert document["legs"]["FL"]["stride_period_s"] is None and document["legs"]["FL"]["reason"]


def test_nan_gap_splits_phases() -> None:
    stamps, feet, _ = synthetic("trot", 0.5, 200, seconds=6.0)
    times = stamps - stamps[0]
    gap = (times > 2.9) & (times < 3.3)
    feet[gap] = np.nan
    contacts, report = analyze_gait(stamps, feet)
    before, after = int(np.flatnonzero(gap)[0]) - 1, int(np.flatnonzero(gap)[-1]) + 1
    truncated = 0
    for leg in range(4):
        for stance in contacts.stances[leg]:
            assert stance.last <= before or stance.first >= after, "a stance spans the gap"
            if stance.last == before:
                assert not stance.liftoff_observed
                truncated += 1
            if stance.first == after:
                assert not stance.touchdown_observed
                truncated += 1
    assert truncated >= 2  # in a trot two feet are down at any time, so two stances end at the gap
    assert report.gait == "trot"
    assert all(abs(known(m.duty_factor) - DUTY["trot"]) <= 0.02 for m in report.legs.values())
    assert any("a gap" in note for note in contacts.notes)


def test_slope_is_not_fitted_where_the_feet_do_not_spread() -> None:
    # Only FR is known, stepping in place on one spot: no slope can be told from one spot, so
    # (almost) none is fitted.
    stamps, feet, _ = synthetic("trot", 0.0, 100, seconds=4.0)
    feet[:, 1:] = np.nan
    contacts, report = analyze_gait(stamps, feet)
    assert max(map(abs, contacts.ground.slope)) < 1e-3  # fitted to the noise: ~0.1
    assert (
        report.legs["FR"].status == "ok"
        and abs(known(report.legs["FR"].duty_factor) - DUTY["trot"]) <= 0.02
    )
    assert [report.legs[leg].status for leg in ("FL", "RR", "RL")] == ["no data"] * 3
    assert (
        report.gait == "unknown"
        and json.loads(json.dumps(report.to_json(), allow_nan=False))["phase_vs_FR"]["FL"] is None
    )
