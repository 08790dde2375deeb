"""Cost of the smoothed trajectory (``a1-leg-fk odom``, the default) against the causal filter's
(``odom --causal``) on a 1 kHz recording, in one run.

Run: ``.venv/bin/python bench/smoothing_speed.py [--seconds S [S ...]]`` (a few minutes for the
default 60 s). Generates bags of JointStates and Imu messages at 1 kHz (test/synthetic_odometry.py,
shared with the memory test), of ``S / 3`` and ``S`` seconds (or of each length given, e.g.
``--seconds 60 120 300 600``); runs ``odom --csv`` on each, causal and smoothed, each in its own
process; prints

- the speed as a multiple of real time (recording seconds per CPU second of the process: one
  core, not the wall clock a shared machine stretches), and the wall time;
- the process's peak RSS [MB], and per bag the smoothed run's extra over the causal one: the
  smoother's history (one 8 s window and its 2 s overlap, 2.9 kB a step) and its pending
  samples, which must not grow with the recording;
- the peak's growth per recorded minute from the shortest bag to the longest (``odom`` streams:
  its IMU read in the joint states' pass, its rows written as they become final; it must not
  grow), extrapolated to one hour along that straight line.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from common import machine, measured_cli
from synthetic_odometry import write_turning_trot


def measured(bag: Path, out: Path, causal: bool) -> tuple[float, float, float]:
    """Wall time, CPU time [s] and peak RSS [MB] of ``a1-leg-fk odom --csv``."""
    arguments = ["odom", str(bag), "--csv", str(out), "--quiet", "--force"]
    return measured_cli(arguments + (["--causal"] if causal else []))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, nargs="+", default=[60.0], help="the bags [s] at 1 kHz"
    )
    options = parser.parse_args()
    print(machine())
    peaks: dict[tuple[float, bool], float] = {}
    with tempfile.TemporaryDirectory() as folder:
        print(
            f"{'bag':>8s} {'odom':>9s} {'wall s':>7s} {'cpu s':>7s} {'x real time (cpu)':>18s} "
            f"{'peak MB':>8s}"
        )
        lengths = sorted(options.seconds)
        if len(lengths) == 1:
            lengths.insert(0, lengths[0] / 3.0)
        for seconds in lengths:
            bag = write_turning_trot(Path(folder) / f"bag{seconds:g}", seconds)
            for causal in (True, False):
                wall, cpu, peak = measured(bag, Path(folder) / "out.csv", causal)
                peaks[seconds, causal] = peak
                name = "causal" if causal else "smoothed"
                print(
                    f"{seconds:7.0f}s {name:>9s} {wall:7.1f} {cpu:7.1f} {seconds / cpu:18.1f} "
                    f"{peak:8.0f}"
                )
    for seconds in lengths:
        extra = peaks[seconds, False] - peaks[seconds, True]
        print(f"{seconds:7.0f}s: smoothing's extra peak {extra:6.1f} MB")
    for causal in (True, False):
        short, long = peaks[lengths[0], causal], peaks[lengths[-1], causal]
        per_minute = (long - short) / ((lengths[-1] - lengths[0]) / 60.0)
        hour = long + per_minute * (60.0 - lengths[-1] / 60.0)
        name = "causal" if causal else "smoothed"
        print(
            f"{name}: peak grows {per_minute:5.1f} MB per recorded minute: ~{hour:.0f} MB for 1 h"
        )


if __name__ == "__main__":
    main()
