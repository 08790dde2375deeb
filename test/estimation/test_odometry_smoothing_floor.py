"""Why the smoothed odometry barely beats the causal filter on a1_walk_long with clean sensors
(issue 36; docs/leg_odometry.md, "Why the clean runs' smoothed error stays near the causal
one"): the error both keep is the feet's own. Against PyBullet's root velocity (the truth, base
frame), each foot the filter used measures the base's velocity as ``e - w x r`` (the true gyro);
their mean error, over 20 ms, is most of the smoothed error, and the feet the contact estimate
loads lightly carry most of both errors. Under ``accept``: two passes over a 41 s run.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import family_folder

RUN = "a1_walk_long"
LIGHT_N = 30.0
"""[N] A foot loaded under this (the contact estimate's normal force) is lightly loaded: a
quarter of the A1's weight share per foot on three feet is ~40 N."""
MEAN_S = 0.02
"""[s] The feet's error is compared over this running mean (the filter averages the feet)."""


def _run() -> Any:
    from contact_runs import contact_runs, simulate_missing

    simulate_missing(family_folder(), (RUN,), 1)
    return contact_runs(family_folder(), (RUN,))[RUN]


def _true_body_velocity(run: Any) -> np.ndarray:
    from pybullet_sim import rotation_matrices

    return np.einsum("nji,nj->ni", rotation_matrices(run.quaternions), run.base_velocities)


def _running_mean(values: np.ndarray, weights: np.ndarray, samples: int) -> np.ndarray:
    """(N, 3) the running mean of ``values`` over ``samples`` rows, each row weighted (0 or 1)."""
    kernel = np.ones(samples)
    total = np.stack([np.convolve(values[:, k] * weights, kernel, "same") for k in range(3)], 1)
    count = np.convolve(weights, kernel, "same")
    return total / np.maximum(count, 1e-9)[:, None]


@pytest.mark.accept
def test_the_clean_walks_smoothed_error_is_mostly_the_feet_own(monkeypatch) -> None:
    """The smoothed error less the used feet's mean error (20 ms) keeps at most half the
    smoothed error's mean square in x and in y: the rest is an error the feet make, which a
    backward pass over the same measurements shares."""
    from odometry_scoring import estimate

    from a1_leg_fk.estimation import state_filter

    run = _run()
    truth = _true_body_velocity(run)
    stamps = np.round(run.stamps_s * 1e9).astype(np.int64)
    errors = np.zeros((len(stamps), 3))
    used_feet = np.zeros(len(stamps))
    update = state_filter.StateFilter.update

    def recorded(self, stamp_ns, legs, *args, **kwargs):
        used = update(self, stamp_ns, legs, *args, **kwargs)
        row = int(np.searchsorted(stamps, stamp_ns))
        for leg in used:
            e, r, _ = legs[leg].motion
            errors[row] += np.subtract(e, np.cross(run.gyro[row], r)) - truth[row]
        used_feet[row] = len(used)
        return used

    monkeypatch.setattr(state_filter.StateFilter, "update", recorded)
    smoothed = estimate(run, True, smoothed=True)
    gait = run.gait & (used_feet > 0)
    feet = errors / np.maximum(used_feet, 1)[:, None]
    samples = round(MEAN_S / float(np.median(np.diff(run.stamps_s))))
    feet = _running_mean(feet, (used_feet > 0).astype(float), samples)
    error = (smoothed.velocity - truth)[gait]
    left = error - feet[gait]
    shares = (left[:, :2] ** 2).mean(axis=0) / (error[:, :2] ** 2).mean(axis=0)
    print(f"the smoothed error's mean square left beside the feet's own: x, y {shares.round(3)}")
    assert (shares <= 0.5).all()


@pytest.mark.accept
def test_the_lightly_loaded_feet_carry_most_of_both_errors(monkeypatch) -> None:
    """The feet the contact estimate loads under LIGHT_N left out of the filter's updates: the
    causal and the smoothed errors each lose at least half their mean square."""
    from odometry_scoring import errors, estimate

    from a1_leg_fk.estimation import odometry_feed, state_filter

    run = _run()
    default = estimate(run, True, smoothed=True)
    normals: list[list[float] | None] = [None]
    contacts = odometry_feed.OdometryFeed._contacts
    update = state_filter.StateFilter.update

    def kept(self, *args, **kwargs):
        step = contacts(self, *args, **kwargs)
        normals[0] = None if step is None else step.normals
        return step

    def heavy(self, stamp_ns, legs, *args, **kwargs):
        loads = normals[0]
        if loads is not None:
            legs = [
                None if leg is None or load < LIGHT_N else leg for leg, load in zip(legs, loads)
            ]
        return update(self, stamp_ns, legs, *args, **kwargs)

    monkeypatch.setattr(odometry_feed.OdometryFeed, "_contacts", kept)
    monkeypatch.setattr(state_filter.StateFilter, "update", heavy)
    loaded = estimate(run, True, smoothed=True)
    for label, before, after in (
        ("causal", default.causal, loaded.causal),
        ("smoothed", default, loaded),
    ):
        assert before is not None and after is not None
        was, now = errors(run, before).rmse, errors(run, after).rmse
        print(f"{label}: RMSE {was:.5f} -> {now:.5f} m/s without the feet under {LIGHT_N} N")
        assert now**2 <= 0.5 * was**2
