"""Batch foot-force speed of a1_leg_fk, against fk_batch measured in the same run.

Run: ``.venv/bin/python bench/force_speed.py`` (about 20 s). A batch of 2.5 x 10^5
configurations (10^6 legs) with efforts and a per-row gravity direction: the median time of
``Quadruped.foot_forces_batch`` and of ``Quadruped.fk_batch`` on the same angles, interleaved;
prints legs/s (target >= 1 M legs/s) and the ratio of the two times. Then one configuration (the
per-message path): ``Quadruped.foot_forces`` against ``Quadruped.fk``.

The forces are first checked on a sample of rows against the one-configuration path
``Quadruped.foot_forces``.
"""

from __future__ import annotations

import numpy as np
from common import SPEED_POSE, machine, median_seconds_per_call

from a1_leg_fk.kinematics.quadruped import Quadruped

ROWS = 250_000
REPEATS = 5
LEGS_PER_ROW = 4


def main() -> None:
    print(machine())
    quadruped = Quadruped.from_urdf()
    rng = np.random.default_rng(0)
    angles = np.tile([0.0, 0.8, -1.5] * 4, (ROWS, 1)) + rng.uniform(-0.3, 0.3, (ROWS, 12))
    efforts = rng.uniform(-10.0, 10.0, (ROWS, 12))
    tilt = rng.uniform(-0.2, 0.2, (ROWS, 2))
    gravity = np.c_[tilt, -np.ones(ROWS)]
    gravity *= 9.80665 / np.linalg.norm(gravity, axis=1, keepdims=True)

    sample = slice(0, ROWS, 4999)
    np.testing.assert_allclose(
        quadruped.foot_forces_batch(angles[sample], efforts[sample], gravity[sample]),
        [
            quadruped.foot_forces(a, e, g)
            for a, e, g in zip(angles[sample], efforts[sample], gravity[sample])
        ],
        rtol=1e-12,
        atol=1e-9,
    )
    runs = median_seconds_per_call(
        {
            "foot_forces_batch": lambda: quadruped.foot_forces_batch(angles, efforts, gravity),
            "fk_batch": lambda: quadruped.fk_batch(angles),
        },
        repeats=REPEATS,
        calibrate=False,
    )
    forces_s, fk_s = runs["foot_forces_batch"], runs["fk_batch"]
    legs_per_s = ROWS * LEGS_PER_ROW / forces_s
    print(
        f"\nbatch of {ROWS:,} configurations ({ROWS * LEGS_PER_ROW:,} legs), median of "
        f"{REPEATS} interleaved runs"
    )
    print(f"  {'method':<40} {'s':>8} {'M legs/s':>10}")
    print(f"  {'Quadruped.foot_forces_batch':<40} {forces_s:8.3f} {legs_per_s / 1e6:10.2f}")
    print(f"  {'Quadruped.fk_batch (same angles)':<40} {fk_s:8.3f} {ROWS * 4 / fk_s / 1e6:10.2f}")
    print(
        f"  foot_forces_batch / fk_batch = {forces_s / fk_s:.2f}x; "
        f"{legs_per_s / 1e6:.2f} M legs/s (target >= 1 M legs/s: "
        f"{'met' if legs_per_s >= 1e6 else 'NOT met'})"
    )
    q, tau, g = SPEED_POSE, efforts[0].tolist(), gravity[0].tolist()
    single = median_seconds_per_call(
        {"foot_forces": lambda: quadruped.foot_forces(q, tau, g), "fk": lambda: quadruped.fk(q)}
    )
    print(
        f"\none configuration: Quadruped.foot_forces {single['foot_forces'] * 1e6:.1f} us, "
        f"Quadruped.fk {single['fk'] * 1e6:.2f} us: "
        f"{single['foot_forces'] / single['fk']:.1f}x"
    )


if __name__ == "__main__":
    main()
