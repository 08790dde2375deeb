"""Speed of ``a1-leg-fk view`` (the .rrd of a recording) against ``a1-leg-fk bag --csv`` on the
same recording, in one run.

Run: ``.venv/bin/python bench/view_speed.py [--messages N]`` (default 60,000: one minute at
1 kHz; 600,000 is the issue's ten minutes). Generates a 1 kHz bag of 12-joint JointState messages
(positions and velocities, as ``bench/bag_speed.py``), then prints, for ``bag --csv`` and for
``view --no-open`` (the contact pass, the odometry pass and the .rrd), the wall time, the
real-time factor (the recording's duration over the wall time) and view's time as a ratio to
bag's. Goal: view >= 10x real time.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from bag_speed import PERIOD_NS, generate
from common import machine

from a1_leg_fk import cli


def timed(arguments: list[str]) -> float:
    """Wall time [s] of one ``a1-leg-fk`` command (which must succeed)."""
    started = time.perf_counter()
    code = cli.main(arguments)
    elapsed = time.perf_counter() - started
    if code != 0:
        raise SystemExit(f"a1-leg-fk {arguments[0]} exited {code}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=60_000)
    options = parser.parse_args()
    duration_s = options.messages * PERIOD_NS / 1e9
    print(machine())
    with tempfile.TemporaryDirectory() as folder:
        bag = generate(Path(folder) / "bag", options.messages, "mcap", velocities=True)
        bag_s = timed(["bag", str(bag), "--csv", str(Path(folder) / "feet.csv"), "--quiet"])
        rrd = Path(folder) / "run.rrd"
        view_s = timed(["view", str(bag), "--rrd", str(rrd), "--no-open", "--quiet"])
        size_mb = rrd.stat().st_size / 1e6
    print(f"recording: {options.messages} JointState messages, {duration_s:.0f} s at 1 kHz")
    print(f"bag --csv:      {bag_s:7.2f} s  {duration_s / bag_s:7.1f}x real time")
    print(
        f"view --no-open: {view_s:7.2f} s  {duration_s / view_s:7.1f}x real time  "
        f"({view_s / bag_s:.2f}x bag's time; .rrd {size_mb:.1f} MB)"
    )


if __name__ == "__main__":
    main()
