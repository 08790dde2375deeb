"""``a1-leg-fk calibrate``: the model corrections (:mod:`a1_leg_fk.estimation.model_corrections`)
fitted over a whole recording, and the payload its standing phase shows; no ROS install.

A pass of the force and contact pipeline (the bag tools' and the node's) with the corrections
learning without forgetting: every joint's bias, viscous and Coulomb terms are the least squares
over every sample in which its foot was surely in the air (each shrunk by three of its standard
deviations, as online, with the variance of the fit's own residual), with the residual's RMS
before and after the fit; each leg's inertia scale as learnt by the end
(:mod:`a1_leg_fk.estimation.leg_scales`). The payload, in a second pass with those terms fixed
(as a node given the file weighs): while all four feet stand (the filter's probability of
stance at least :data:`STANDING_PROBABILITY`) and are still (each foot slower than
:data:`STILL_MPS` in the base frame), the normal forces' sum is the robot's weight; its mean
over the URDF's weight, in kg. A recording that cannot identify
something is refused in one line: no efforts, never a foot surely in the air, never
:data:`MIN_STANDING_S` of standing still.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import NamedTuple, Unpack

import numpy as np

from a1_leg_fk.estimation.correction_file import (
    EFFORT_LATENCIES_S,
    EFFORT_SCALES,
    CorrectionFile,
)
from a1_leg_fk.estimation.effort_timing import EffortTiming
from a1_leg_fk.estimation.model_corrections import ONLINE, CorrectionSettings
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.blocks import iter_foot_blocks
from a1_leg_fk.recording.foot_block import FootBlock
from a1_leg_fk.recording.forces import RecordingForces
from a1_leg_fk.recording.reader import RecordingChoices, close_recording, open_recording

CALIBRATION = CorrectionSettings(forget_s=1e9, learn_scales=True)
"""The corrections' settings over a recording: no forgetting (1e9 s), the legs' inertia scales
learnt (online they are not), the rest the online ones."""
WITHOUT_IMU = replace(CALIBRATION, learn_scales=False)
"""The same without an IMU's gyro and accelerometer: the legs' inertia scales are not fitted (1),
since without the base's motion they read it (an exact A1 trotting: 0.74-0.97 without, 1.000 with
its IMU)."""
STANDING_PROBABILITY = 0.95
STILL_MPS = 0.02
"""[m/s] A foot slower than this relative to the base is still."""
MIN_STANDING_S = 0.2
"""[s] The least standing phase that gives a payload."""
MAX_ROW_GAP_S = 0.05
"""[s] Two standing rows further apart than this do not add their gap to the standing time."""


class _Standing:
    """The standing rows' normal-force sums [N] and their time [s]."""

    def __init__(self) -> None:
        self.sums: list[float] = []
        self.seconds = 0.0
        self._last_ns: int | None = None

    def add(self, block: FootBlock) -> None:
        """The rows of ``block`` in which all four feet stand still."""
        if block.contacts is None or block.normal_forces is None:
            return
        speeds = np.linalg.norm(block.velocities, axis=2)
        with np.errstate(invalid="ignore"):
            standing = (block.contacts >= STANDING_PROBABILITY).all(axis=1)
            standing &= (speeds < STILL_MPS).all(axis=1)
        standing &= np.isfinite(block.normal_forces).all(axis=1)
        for row in np.flatnonzero(standing).tolist():
            stamp = int(block.stamps_ns[row])
            if self._last_ns is not None and 0 < stamp - self._last_ns <= MAX_ROW_GAP_S * 1e9:
                self.seconds += (stamp - self._last_ns) * 1e-9
            self._last_ns = stamp
            self.sums.append(float(block.normal_forces[row].sum()))
        if not standing[-1]:
            self._last_ns = None


class Calibration(NamedTuple):
    """A recording's calibration: its ``file`` and whether the legs' inertia scales were fitted
    (``scales_fitted``: the recording's IMU gave the base's motion).
    """

    file: CorrectionFile
    scales_fitted: bool


def base_motion(forces: RecordingForces) -> bool:
    """Whether the recording's IMU track gives the base's motion: some sample with a finite gyro
    and accelerometer (a LowState's own IMU included).
    """
    imu = forces.imu
    if imu is None:
        return False
    moving = np.isfinite(imu.angular_velocity).all(axis=1)
    moving &= np.isfinite(imu.specific_force).all(axis=1)
    return bool(moving.any())


def calibrate_recording(
    path: str | Path,
    *,
    progress: bool = False,
    timing: tuple[float, float] = (1.0, 0.0),
    **choices: Unpack[RecordingChoices],
) -> Calibration:
    """The calibration of the recording at ``path`` (``choices`` as
    :func:`~a1_leg_fk.recording.reader.open_recording`'s; forces always, the corrections
    learning); ``timing``: the efforts' scale and latency [s] (given, not fitted), undone before
    the fit (:class:`EffortTiming`) and written to the file; the legs' inertia scales fitted only
    with the base's motion (:func:`base_motion`; else 1); :class:`LegFkError` (one line) for bad
    input or a recording that cannot identify the terms or the payload.
    """
    scale, latency_s = timing
    for option, value, (least, most), unit in (
        ("--effort-scale", scale, EFFORT_SCALES, 1.0),
        ("--effort-latency-ms", latency_s, EFFORT_LATENCIES_S, 1e3),
    ):
        if not least <= value <= most:
            raise LegFkError(
                f"{option} {value * unit:g} is outside [{least * unit:g}, {most * unit:g}]"
            )
    choices["forces"], choices["model_corrections"] = True, ONLINE
    recording = open_recording(path, **choices)
    try:
        forces = recording.forces
        if forces is None or forces.estimator.observer is None:
            raise LegFkError(f"{path}: no foot forces to calibrate from")
        estimator = forces.estimator
        scales_fitted = base_motion(forces)
        estimator.correction_settings = CALIBRATION if scales_fitted else WITHOUT_IMU
        estimator.timing = EffortTiming(scale, latency_s)
        for _ in iter_foot_blocks(recording, progress=progress):
            pass
        corrections = estimator.corrections
    finally:
        close_recording(recording)
    if corrections is None or corrections.learnt_samples == 0:
        raise LegFkError(
            f"{path}: never in swing: no foot was surely in the air (the contact filter's "
            "stance below 5 % and the foot above the others), so no friction or inertia scale "
            "can be fitted; "
            "record a few strides"
        )
    corrections.solve()
    residuals = corrections.fit_residuals()
    fitted = CorrectionFile(
        recording.quadruped.joint_names,
        tuple(corrections.terms_at([after * after for _, _, after in residuals])),
        tuple(residuals),
        0.0,
        0.0,
        str(path),
        estimator.statics.total_mass_kg,
        scale,
        latency_s,
        tuple(corrections.scales.scales),
    )
    standing = _weighed(path, fitted, progress, choices)
    if standing.seconds < MIN_STANDING_S:
        raise LegFkError(
            f"{path}: never stood still ({standing.seconds:.2f} s with all four feet down and "
            f"still, {MIN_STANDING_S:g} s needed), so no payload can be weighed; record a "
            "standing phase"
        )
    payload_kg = float(np.mean(standing.sums)) / STANDARD_GRAVITY - fitted.urdf_mass_kg
    file = replace(fitted, payload_kg=payload_kg, standing_s=standing.seconds)
    return Calibration(file, scales_fitted)


def _weighed(
    path: str | Path, fitted: CorrectionFile, progress: bool, choices: RecordingChoices
) -> _Standing:
    """The standing phase of the recording at ``path`` weighed in a second pass with the
    ``fitted`` terms, scales and timing fixed (as a node given the file runs): weighed during
    the fit, it took the terms learnt so far (none at a recording's start), and a calf bias of
    0.5 N m read as 1.28 kg of payload.
    """
    recording = open_recording(path, **choices)
    try:
        if recording.forces is None:  # not after the first pass; a file changed meanwhile
            raise LegFkError(f"{path}: no foot forces to weigh the standing phase with")
        estimator = recording.forces.estimator
        estimator.calibration = fitted
        estimator.timing = EffortTiming(fitted.effort_scale, fitted.effort_latency_s)
        estimator.reset()
        standing = _Standing()
        for block in iter_foot_blocks(recording, progress=progress):
            standing.add(block)
        return standing
    finally:
        close_recording(recording)
