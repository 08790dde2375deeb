"""Cost of smoothed contacts on a recording (``a1-leg-fk bag --contacts``, the default) against
the causal filter's (``--causal``), in one run.

Run: ``.venv/bin/python bench/contact_smoothing_speed.py [--seconds S]`` (a few minutes for the
default 60 s). Generates 1 kHz bags of JointStates with positions and velocities (bag_speed.py's
trot-like motion, no efforts: kinematic evidence) of ``S`` and ``S / 3`` seconds, then runs
``bag --contacts --csv`` on each, causal and smoothed, each in its own process, and prints:

- the speed as a multiple of real time (1 kHz recording seconds per wall second);
- the process's peak RSS [MB]. The smoother keeps a block (4096 rows) plus its 0.5 s lag, so
  the peak must not grow with the recording: the long bag's against the short one's is the
  evidence for the one-hour bound (an hour's rows are never held at once).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from bag_speed import generate
from common import machine, measured_cli


def measured(bag: Path, out: Path, causal: bool) -> tuple[float, float]:
    """Wall time [s] and peak RSS [MB] of ``a1-leg-fk bag --contacts`` in a fresh process."""
    arguments = ["bag", str(bag), "--contacts", "--csv", str(out), "--quiet", "--force"]
    wall, _, peak = measured_cli(arguments + (["--causal"] if causal else []))
    return wall, peak


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="the long bag [s] at 1 kHz")
    options = parser.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as folder:
        print(f"{'bag':>8s} {'contacts':>9s} {'wall s':>7s} {'x real time':>12s} {'peak MB':>8s}")
        for seconds in (options.seconds / 3.0, options.seconds):
            bag = generate(Path(folder) / f"bag{seconds:g}", int(seconds * 1000), "mcap", True)
            for causal in (True, False):
                wall, peak = measured(bag, Path(folder) / "out.csv", causal)
                name = "causal" if causal else "smoothed"
                print(f"{seconds:7.0f}s {name:>9s} {wall:7.1f} {seconds / wall:12.1f} {peak:8.0f}")


if __name__ == "__main__":
    main()
