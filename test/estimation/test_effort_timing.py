"""The efforts' scale and latency a calibration's file gives (estimation/effort_timing.py), by
construction: a smooth torque reported ``k`` times and ``L`` late is put back to within the
first-order prediction's error; a PyBullet trot's efforts scaled by 0.9 and 3 ms late give, with
the file's scale and latency, the forces of the trot as it was (in the typical sample)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from contact_scoring import FORCE, estimate
from mismatch_runs import mismatch_runs

from a1_leg_fk.estimation.correction_file import CorrectionFileError, read_correction_file
from a1_leg_fk.estimation.effort_timing import EffortTiming
from a1_leg_fk.kinematics.quadruped import Quadruped

A1 = Quadruped.from_urdf()
A1_KG = 12.458
"""pybullet_data's a1.urdf: the sum of its links' masses [kg], by hand."""
STEP_S, SCALE, LATENCY_S = 0.002, 0.9, 0.003


def late(stamps: np.ndarray, torques: np.ndarray) -> np.ndarray:
    """``torques`` [N m] (rows at ``stamps`` [s]) as reported: times :data:`SCALE`,
    :data:`LATENCY_S` late (linear interpolation; the first held)."""
    columns = [np.interp(stamps - LATENCY_S, stamps, column) for column in torques.T]
    result: np.ndarray = SCALE * np.stack(columns, axis=1)
    return result


def test_a_smooth_torque_late_and_scaled_is_put_back() -> None:
    """10 N m at 2 Hz, 500 Hz: reported 0.9 x and 3 ms late it is off by up to 1.2 N m; put back,
    within the prediction's error (L^2 w^2 A / 2 + L dt w^2 A / 2 ~ 0.01 N m)."""
    stamps = np.arange(0.0, 1.0, STEP_S)
    torque = 10.0 * np.sin(2.0 * math.pi * 2.0 * stamps)[:, None]
    reported = late(stamps, torque)
    timing = EffortTiming(SCALE, LATENCY_S)
    back = np.array([timing.efforts(t, row.tolist()) for t, row in zip(stamps, reported)])
    assert np.abs(reported - torque)[10:].max() > 1.0
    assert np.abs(back - torque)[10:].max() < 0.03
    assert EffortTiming().identity and not timing.identity


def test_a_gap_or_a_nan_gives_no_rate() -> None:
    timing = EffortTiming(0.5, 0.01)
    first = timing.efforts(0.0, [1.0, math.nan])
    assert first[0] == 2.0 and math.isnan(first[1])
    assert timing.efforts(0.002, [2.0, 1.0]) == [2.0 * (2.0 + 5.0), 2.0]  # NaN before: no rate
    assert timing.efforts(1.0, [3.0, 3.0]) == [6.0, 6.0]  # after a 1 s gap: scale alone


def write(tmp_path: Path, **entries: object) -> Path:
    """A calibration of the A1 without terms, with ``entries``."""
    document = {
        "format": "a1_leg_fk model corrections 1",
        "payload_kg": 0.0,
        "standing_s": 0.5,
        "urdf_mass_kg": A1_KG,
        "joints": {name: {"bias_nm": 0.0, "viscous_nms_per_rad": 0.0, "coulomb_nm": 0.0}
                   for name in A1.joint_names},
        **entries,
    }  # fmt: skip
    path = tmp_path / "timing.yaml"
    path.write_text(json.dumps(document))
    return path


def test_the_file_gives_the_scale_and_latency_within_their_ranges(tmp_path: Path) -> None:
    plain = read_correction_file(write(tmp_path), A1.joint_names, A1_KG)
    assert (plain.effort_scale, plain.effort_latency_s) == (1.0, 0.0)
    given = read_correction_file(
        write(tmp_path, effort_scale=0.9, effort_latency_s=0.003), A1.joint_names, A1_KG
    )
    assert (given.effort_scale, given.effort_latency_s) == (0.9, 0.003)
    for entries, reason in (
        ({"effort_scale": 0.1}, "effort_scale 0.1 is absurd"),
        ({"effort_scale": 3.0}, "effort_scale 3.0 is absurd"),
        ({"effort_latency_s": -0.001}, "effort_latency_s -0.001 is absurd"),
        ({"effort_latency_s": 0.5}, "effort_latency_s 0.5 is absurd"),
    ):
        with pytest.raises(CorrectionFileError, match=reason):
            read_correction_file(write(tmp_path, **entries), A1.joint_names, A1_KG)


def test_the_file_puts_a_late_scaled_trot_back(tmp_path: Path) -> None:
    """The mismatch family's exact fast A1 trot (PyBullet; 8 s of gait; the run make test
    simulates for test_mismatch_family), its efforts 0.9 x and 3 ms late by construction
    (corrections off, so only the efforts differ): the normal forces' median error against the
    trot's own is 2.9 % of the weight; with the file's scale and latency, under a fifteenth of
    that (0.16 %). (Their RMS stays near 6 %: a touchdown's torque step cannot be predicted 3 ms
    ahead by any causal rule, docs/forces.md.)"""
    name = "a1_trot_fast=exact"
    run = mismatch_runs((name,))[name].run
    quadruped = Quadruped.from_urdf(run.urdf_path)
    reported = replace(run, torques=late(run.stamps_s, run.torques))
    path = write(tmp_path, effort_scale=SCALE, effort_latency_s=LATENCY_S)
    truth = estimate(run, quadruped, FORCE, model_corrections="off")[1]
    weight = A1_KG * 9.80665
    error = {
        corrections: float(np.nanmedian(np.abs(normals - truth))) / weight
        for corrections in ("off", str(path))
        for normals in [estimate(reported, quadruped, FORCE, model_corrections=corrections)[1]]
    }
    off, back = error["off"], error[str(path)]
    assert off > 0.02, error
    assert back < off / 15.0, error
