"""The smoothed trajectory (a1_leg_fk.estimation.odometry_smoother, as ``a1-leg-fk odom`` without
``--causal``) on the state filter's family (test_state_filter_family.py: the long runs, clean and
noisy, with efforts and without; PyBullet's root motion the truth; TUNED and HELD_OUT as there:
the smoother has no setting of its own but its windows, chosen on a TUNED run).

Goals (issue 36), on every estimate: velocity RMSE <= half the causal filter's; final horizontal
error <= 0.5 % of the path, vertical <= 0.3 %; the error within the smoothed 3 sigma on >= 95 %
of the samples, the sigma at most 5x the RMS error. Under ``accept``: the whole family (8
minutes on 2 shared cores, the runs simulated), and a tuned and a held-out run's first 8 s.
"""

from __future__ import annotations

import dataclasses
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import pytest
from conftest import FAMILY_NOISE_SEED, family_folder
from odometry_scoring import CONFIGS, HELD_OUT, TUNED, missed, xfail_params

UNMET: dict[str, str] = {
    "a1_trot_long": "RMSE not halved with the noisy sensors; smoothed/causal m/s (ratio), "
    "efforts, kinematic: clean 0.0008/0.0017 (0.47), 0.0008/0.0017 (0.47); noisy 0.0041/0.0061 "
    "(0.67), 0.0042/0.0063 (0.67); drift horizontal <= 0.12 %, vertical 0.00 %; 3 sigma covers "
    "99.9-100 %, sigma/error 2.30-4.30",
    "a1_walk_long": "RMSE not halved, clean or noisy; noisy 3 sigma covers 92.9-93.2 %; "
    "smoothed/causal m/s (ratio): clean 0.0017/0.0018 (0.94), 0.0017/0.0019 (0.89); noisy "
    "0.0060/0.0072 (0.83), 0.0061/0.0073 (0.84); drift horizontal <= 0.12 %, vertical 0.00 %; "
    "3 sigma 92.9-99.0 %, sigma/error 2.47-3.02; the clean floor is the feet's own error, which "
    "both passes follow (the smoothed error's correlation with the used feet's, 20 ms mean, "
    "0.92 / 0.90 in x / y: lightly loaded feet sliding, 3.9-8.4 mm/s under 25-31 N)",
    "a1_flying_trot_fast": "RMSE not halved noisy; noisy horizontal drift 0.59-0.60 %; clean "
    "sigma/error 6.20-6.28 (the feet's give: the smoothed error halved, not its sigma); "
    "smoothed/causal m/s (ratio): clean 0.0027/0.0060 (0.45), 0.0027/0.0060 (0.45); noisy "
    "0.0064/0.0104 (0.62), 0.0064/0.0105 (0.61); vertical 0.00 %; 3 sigma 97.7-99.6 %, "
    "sigma/error 3.64-6.28",
    "go2_trot_long": "RMSE not halved; smoothed/causal m/s (ratio): clean 0.0008/0.0012 "
    "(0.67), 0.0008/0.0012 (0.67); noisy 0.0041/0.0056 (0.73), 0.0042/0.0059 (0.71); drift "
    "horizontal <= 0.04 %, vertical 0.00 %; 3 sigma 99.9 %, sigma/error 2.61-4.71",
    "go2_trot_slips": "RMSE not halved; smoothed/causal m/s (ratio): clean 0.0036/0.0038 "
    "(0.95), 0.0036/0.0038 (0.95); noisy 0.0085/0.0117 (0.73), 0.0086/0.0118 (0.73); drift "
    "horizontal <= 0.33 %, vertical 0.00 %; 3 sigma 96.8-97.6 %, sigma/error 1.32-2.45; the "
    "clean floor is the slips, which both passes follow (the smoothed error's correlation with "
    "the used feet's, 20 ms mean, 0.88 / 0.92 in x / y)",
    "a1_flying_trot": "RMSE not halved; clean 3 sigma covers 93.4 %; smoothed/causal m/s "
    "(ratio): clean 0.0044/0.0065 (0.68), 0.0044/0.0066 (0.67); noisy 0.0056/0.0090 (0.62), "
    "0.0057/0.0090 (0.63); drift horizontal <= 0.47 %, vertical 0.00 %; 3 sigma 93.4-99.3 %, "
    "sigma/error 2.38-4.23",
    "a1_trot_slips": "RMSE not halved; noisy 3 sigma 94.4-94.7 %; smoothed/causal m/s (ratio): "
    "clean 0.0129/0.0152 (0.85), 0.0129/0.0152 (0.85); noisy 0.0166/0.0212 (0.78), "
    "0.0209/0.0250 (0.84); drift horizontal <= 0.86 %, vertical 0.00 %; 3 sigma 94.4-95.9 %, "
    "sigma/error 1.07-2.47; clean, 78 % of the smoothed mean square lies where the gate rejects "
    "every foot (6.6 % of the gait, the IMU alone across the slips), the rest follows the used "
    "feet's own error (correlation 0.96 / 0.99 in x / y)",
    "a1_trot_fast_long": "RMSE not halved with the noisy sensors; smoothed/causal m/s (ratio): "
    "clean 0.0015/0.0035 (0.43), 0.0016/0.0037 (0.43); noisy 0.0043/0.0070 (0.61), "
    "0.0043/0.0074 (0.58); drift horizontal <= 0.04 %, vertical 0.00 %; 3 sigma 99.9 %, "
    "sigma/error 2.65-4.22",
    "a1_turn_long": "RMSE not halved with the noisy sensors, clean at half (the 4-digit ratio "
    "0.52 with efforts); smoothed/causal m/s (ratio): clean 0.0013/0.0025 (0.52), 0.0013/0.0026 "
    "(0.50); noisy 0.0044/0.0066 (0.67), 0.0046/0.0070 (0.66); drift horizontal <= 0.04 %, "
    "vertical 0.01 %; 3 sigma 99.6-100 %, sigma/error 2.13-2.70",
}
"""Runs whose goals are not met, each with its own measured numbers (strict xfail; make accept
of 2026-11-28 with the feet's give on by default, the printed table's 4 digits; the ratios
from them). Every run misses the RMSE
goal with the noisy sensors: the error left is the sensors' white noise, of which a smoother
removes at most half the mean square (71 % of the RMSE stays: ratios 0.58-0.84 here); on the
clean runs it is halved where the filter's lag and touchdown transients dominate (the steady
trots) and not where the feet's own velocity error does (the walk's lightly loaded feet sliding,
the slips): both passes follow the feet within each stride, and the pass is the exact smoother of
the filter's model (test_state_smoother.py), so that error is shared (docs/leg_odometry.md, "Why
the clean runs' smoothed error stays near the causal one")."""
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
    "share, weighs more); smoothed/causal m/s (ratio): clean 0.0017/0.0029 (0.59) efforts, "
    "0.0019/0.0029 (0.66) kinematic; noisy 0.0040/0.0057 (0.70), 0.0042/0.0059 (0.71); drift "
    "horizontal <= 0.04 %, vertical 0.03 %; 3 sigma 99.7-99.8 %, sigma/error 1.61-3.83",
    "a1_turn_long": "RMSE not halved over 8 s; smoothed/causal m/s (ratio): clean 0.0028/0.0042 "
    "(0.67) efforts, 0.0030/0.0046 (0.65) kinematic; noisy 0.0044/0.0064 (0.69), 0.0047/0.0068 "
    "(0.69); drift horizontal <= 0.13 %, vertical 0.05 %; 3 sigma 99.4 %, sigma/error 1.46-2.22",
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
