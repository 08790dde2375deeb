"""A robot's sensor errors on a simulated run (:func:`with_noise`): the noise model of the contact
and odometry issues, fixed by a seed."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from contact_runs import ContactRun


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 4) Hamilton products a ⊗ b of (x, y, z, w) quaternions."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def with_noise(run: ContactRun, seed: int) -> ContactRun:
    """``run`` as a robot's sensors would give it (name suffixed ``+noise``); truth unchanged.

    Gaussian errors of standard deviation 5e-4 rad on the encoders, 0.05 rad/s on the joint rates,
    0.3 N m on the efforts (after a scale error per motor, uniform in ±3 %), 0.005 rad/s on the
    gyro plus a 0.01 rad/s bias of random sign per axis, 0.05 m/s^2 on the accelerometer plus a
    0.05 m/s^2 bias of random sign per axis; the orientation tilted by a fixed 0.3° about a
    random horizontal axis of the root frame (q ⊗ tilt: a mounting
    error; gyro and accelerometer keep the root frame). Every error is fixed by ``seed``.
    """
    rng = np.random.default_rng(seed)
    n = len(run.stamps_s)

    def signs(count: int) -> np.ndarray:
        return rng.choice([-1.0, 1.0], count)

    heading = rng.uniform(0.0, 2.0 * math.pi)
    half = math.radians(0.3) / 2.0
    tilt = [math.cos(heading) * math.sin(half), math.sin(heading) * math.sin(half), 0, 1]
    tilt[3] = math.cos(half)
    scale = 1.0 + rng.uniform(-0.03, 0.03, 12)
    return replace(
        run,
        name=f"{run.name}+noise",
        angles=run.angles + rng.normal(0.0, 5e-4, (n, 12)),
        rates=run.rates + rng.normal(0.0, 0.05, (n, 12)),
        torques=run.torques * scale + rng.normal(0.0, 0.3, (n, 12)),
        gyro=run.gyro + 0.01 * signs(3) + rng.normal(0.0, 0.005, (n, 3)),
        specific_force=run.specific_force + 0.05 * signs(3) + rng.normal(0.0, 0.05, (n, 3)),
        quaternions=quaternion_product(run.quaternions, np.array(tilt)),
    )
