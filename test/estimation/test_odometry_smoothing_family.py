"""The smoothed trajectory (a1_leg_fk.estimation.odometry_smoother, as ``a1-leg-fk odom`` without
``--causal``) on the state filter's family (test_state_filter_family.py: the long runs, clean and
noisy, with efforts and without; PyBullet's root motion the truth; TUNED and HELD_OUT as there:
the smoother has no setting of its own but its windows, chosen on a TUNED run).

Goals (issue 36), on every estimate: velocity RMSE <= half the causal filter's; final horizontal
error <= 0.5 % of the path, vertical <= 0.3 %; the error within the smoothed 3 sigma on >= 95 %
of the samples, the sigma at most 5x the RMS error. The whole family runs under ``accept``
(minutes); one tuned and one held-out run, their first 8 s, in the normal suite.
"""

from __future__ import annotations

import dataclasses
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import pytest
from conftest import FAMILY_NOISE_SEED, family_folder
from odometry_scoring import CONFIGS, HELD_OUT, TUNED, missed, xfail_params

NOISY_UNMET = (
    "with the noisy sensors the RMSE is not halved: the error left is the sensors' white noise, "
    "of which a smoother removes at most half the mean square (71 % of the RMSE stays); "
    "a1_trot_long, whole: noisy 0.0042/0.0058 m/s with efforts, 0.0043/0.0058 kinematic "
    "(smoothed/causal); clean 0.0008/0.0017 both, met"
)
UNMET: dict[str, str] = dict.fromkeys(TUNED + HELD_OUT, NOISY_UNMET)
"""Runs whose goals are not met, with the measured numbers (strict xfail): every run's noisy
estimates (a1_trot_long measured whole; the others by the same bound, docs/leg_odometry.md)."""
SHORT_S = 8.0
"""[s] The normal suite's runs: their first seconds (the gait starts within the first two)."""


def _score(name: str, seconds: float | None = None) -> list[tuple[str, Any, Any]]:
    """A worker: one run's four estimates, each (label, causal Errors, smoothed Errors)."""
    from contact_runs import ARRAYS, contact_runs, with_noise
    from odometry_scoring import errors, estimate

    from a1_leg_fk.kinematics.quadruped import Quadruped

    run = contact_runs(family_folder(), (name,))[name]
    if seconds is not None:
        rows = run.stamps_s <= seconds
        run = dataclasses.replace(run, **{a: getattr(run, a)[rows] for a in ARRAYS})
    quadruped = Quadruped.from_urdf(run.urdf_path)
    noisy = with_noise(run, FAMILY_NOISE_SEED)
    scored = []
    for sensors, efforts in CONFIGS:
        label = f"{name} {sensors} {'efforts' if efforts else 'kinematic'}"
        result = estimate(run if sensors == "clean" else noisy, efforts, quadruped, smoothed=True)
        assert result.causal is not None
        scored.append((label, errors(run, result.causal), errors(run, result)))
    return scored


def _misses(scored: list[tuple[str, Any, Any]]) -> list[str]:
    """The goals the smoothed estimates miss, in words; the table printed."""
    from odometry_scoring import HEADER

    print("\n" + HEADER)
    misses = []
    for label, causal, smoothed in scored:
        print(causal.row(f"{label} causal"))
        print(smoothed.row(f"{label} smoothed"))
        rmse = f"RMSE {smoothed.rmse:.4f} > {causal.rmse:.4f}/2"
        misses += missed(
            label,
            (
                (smoothed.rmse <= 0.5 * causal.rmse, rmse),
                (smoothed.horizontal_pct <= 0.5, f"horizontal {smoothed.horizontal_pct:.2f} %"),
                (smoothed.vertical_pct <= 0.3, f"vertical {smoothed.vertical_pct:.2f} %"),
                (smoothed.within_3sigma >= 0.95, f"3 sigma {100 * smoothed.within_3sigma:.1f} %"),
                (smoothed.sigma_ratio <= 5.0, f"sigma / error {smoothed.sigma_ratio:.1f}"),
            ),
        )
    return misses


@pytest.fixture(scope="module")
def scores() -> dict[str, list[tuple[str, Any, Any]]]:
    """Every run's scores, one worker per core (the runs simulated first, once per machine)."""
    from contact_runs import simulate_missing

    names = TUNED + HELD_OUT
    workers = min(2, os.cpu_count() or 1)
    simulate_missing(family_folder(), names, workers)
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return dict(zip(names, pool.map(_score, names)))


@pytest.mark.accept
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("name", xfail_params(TUNED + HELD_OUT, UNMET))
def test_every_run_meets_the_goals(name: str, scores) -> None:
    misses = _misses(scores[name])
    assert not misses, "\n".join(misses)


SHORT_UNMET: dict[str, str] = {
    "a1_trot_long": "RMSE not halved over 8 s (the start's transient, which both estimates "
    "share, weighs more): clean 0.0017/0.0029 efforts, 0.0019/0.0029 kinematic; noisy "
    "0.0040/0.0057, 0.0042/0.0058 m/s (smoothed/causal); every other goal met",
    "a1_turn_long": "RMSE not halved over 8 s: clean 0.0028/0.0042 efforts, 0.0030/0.0046 "
    "kinematic; noisy 0.0044/0.0064, 0.0047/0.0068 m/s (smoothed/causal); every other goal met",
}
"""The short runs' goals not met, with the measured numbers (strict xfail)."""


@pytest.mark.accept  # a minute of simulation for two strict xfails: make test has the smoother's
# by-construction tests (test_state_smoother.py) and odom's (test/cli/test_cli_odom.py) instead
@pytest.mark.parametrize("name", xfail_params(("a1_trot_long", "a1_turn_long"), SHORT_UNMET))
def test_a_tuned_and_a_held_out_run_meet_the_goals(name: str) -> None:
    """a1_trot_long (tuned) and a1_turn_long (held out), their first SHORT_S seconds."""
    from contact_runs import simulate_missing

    simulate_missing(family_folder(), (name,), 1)
    misses = _misses(_score(name, SHORT_S))
    assert not misses, "\n".join(misses)
