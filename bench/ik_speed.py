"""Foot IK speed of a1_leg_fk, with ratios against references measured in the same process, in one
run.

Run: ``.venv/bin/python bench/ik_speed.py`` (about 30 s). Prints:

- four feet, one call: median time of ``Quadruped.ik`` (closed form) beside ``Quadruped.fk`` on
  the configuration the targets came from, and beside the damped-least-squares path
  (``LegSolver(leg, use_closed_form=False)``) on the same targets; target: ``ik`` <= 10 us;
- a batch of 10^6 in-limit configurations' feet: ``ik_batch`` throughput beside ``fk_batch`` and
  the time of ``np.sin`` + ``np.cos`` alone on a (10^6, 12) array (the trigonometry floor, as
  bench/fk_speed.py prints it); target: >= 1 M configurations/s.

Every timed answer is first checked: the angles of ``ik`` reproduce the targets within 1e-9 m.
"""

from __future__ import annotations

import numpy as np
from common import SPEED_POSE, machine, median_seconds_per_call, trig_floor

from a1_leg_fk.kinematics.ik import four_legs
from a1_leg_fk.kinematics.quadruped import Quadruped

BATCH_ROWS = 1_000_000
BATCH_REPEATS = 3


def main() -> None:
    print(machine())
    quadruped = Quadruped.from_urdf()
    feet = quadruped.fk(SPEED_POSE)
    result = quadruped.ik(feet)
    assert (
        result.status == ("ok",) * 4 and np.abs(quadruped.fk(result.angles) - feet).max() <= 1e-9
    )
    searching = [four_legs.LegSolver(leg, use_closed_form=False) for leg in quadruped.legs]
    searched = four_legs.solve_feet(searching, feet.ravel().tolist(), None)
    assert (
        searched.status == ("ok",) * 4
        and np.abs(quadruped.fk(searched.angles) - feet).max() <= 1e-9
    )

    rows = median_seconds_per_call(
        {
            "Quadruped.ik(feet)  [closed form]": lambda: quadruped.ik(feet),
            "Quadruped.fk(q)": lambda: quadruped.fk(SPEED_POSE),
            "damped least squares, same targets": lambda: four_legs.solve_feet(
                searching, feet.ravel().tolist(), None
            ),
        },
        repeats=7,
    )
    ik_seconds = rows["Quadruped.ik(feet)  [closed form]"]
    print("\nfour feet, one call (median of 7 interleaved runs)")
    print(f"  {'method':<40} {'us/call':>9} {'vs ik':>8}")
    for name, per_call_s in rows.items():
        print(f"  {name:<40} {per_call_s * 1e6:9.2f} {per_call_s / ik_seconds:7.2f}x")
    verdict = "met" if ik_seconds <= 10e-6 else "NOT met"
    print(
        f"  Quadruped.ik: {ik_seconds * 1e6:.1f} us/call = "
        f"{ik_seconds / rows['Quadruped.fk(q)']:.2f}x Quadruped.fk (target <= 10 us: {verdict})"
    )

    lower = np.array([joint.lower for joint in quadruped.joints])
    upper = np.array([joint.upper for joint in quadruped.joints])
    angles = np.random.default_rng(0).uniform(lower, upper, size=(BATCH_ROWS, 12))
    targets = quadruped.fk_batch(angles)
    check = quadruped.ik_batch(targets)
    assert (check.status == four_legs.OK).all() and np.abs(
        quadruped.fk_batch(check.angles) - targets
    ).max() <= 1e-9

    seconds = median_seconds_per_call(
        {
            "ik_batch": lambda: quadruped.ik_batch(targets),
            "fk_batch": lambda: quadruped.fk_batch(angles),
            "trig": trig_floor(angles),
        },
        repeats=BATCH_REPEATS,
        calibrate=False,
    )
    throughput = BATCH_ROWS / seconds["ik_batch"] / 1e6
    print(
        f"\nbatch of {BATCH_ROWS:,} in-limit configurations' feet, (N, 4, 3)"
        f" (median of {BATCH_REPEATS} interleaved runs)"
    )
    print(f"  {'method':<40} {'s':>9} {'M configs/s':>12}")
    print(f"  {'Quadruped.ik_batch':<40} {seconds['ik_batch']:9.3f} {throughput:12.2f}")
    for name, key in (
        ("Quadruped.fk_batch (of the angles)", "fk_batch"),
        ("np.sin + np.cos alone (the floor)", "trig"),
    ):
        print(f"  {name:<40} {seconds[key]:9.3f} {BATCH_ROWS / seconds[key] / 1e6:12.2f}")
    print(
        f"  ik_batch / fk_batch = {seconds['ik_batch'] / seconds['fk_batch']:.2f}x,"
        f" / trig floor = {seconds['ik_batch'] / seconds['trig']:.2f}x;"
        f" throughput {throughput:.2f} M/s "
        f"(target >= 1 M/s: {'met' if throughput >= 1.0 else 'NOT met'})"
    )


if __name__ == "__main__":
    main()
