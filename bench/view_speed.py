"""Speed of ``a1-leg-fk view`` (the .rrd of a recording) against ``a1-leg-fk bag --csv`` on the
same recording, in one run, with view's time split by stage.

Run: ``.venv/bin/python bench/view_speed.py [--messages N]`` (default 60,000: one minute at
1 kHz; 600,000 is the issue's ten minutes). Generates a 1 kHz bag of 12-joint JointState messages
(positions and velocities, as ``bench/bag_speed.py``), then prints, for ``bag --csv``, for
``view --no-open`` as a whole, and for view's stages run one by one (the contact pass: ``bag``'s
pipeline with contacts; the odometry pass: ``odom``'s; the rerun write: the .rrd from their
arrays), the wall time, the real-time factor (the recording's duration over the wall time) and
the ratio to bag's time. Goal: view >= 10x real time.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bag_speed import PERIOD_NS, generate
from common import machine

from a1_leg_fk import cli
from a1_leg_fk.cli.odom import track_of
from a1_leg_fk.cli.view import feet_pass, robot_options, summary_of
from a1_leg_fk.recording.outputs import checked_targets
from a1_leg_fk.view.recording import write_view


def timed(work: Callable[[], Any]) -> tuple[float, Any]:
    """(wall time [s], result) of ``work()``, its printed summary dropped."""
    started = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        result = work()
    return time.perf_counter() - started, result


def command(arguments: list[str]) -> Callable[[], None]:
    """One ``a1-leg-fk`` command (which must succeed)."""

    def run() -> None:
        if cli.main(arguments) != 0:
            raise SystemExit(f"a1-leg-fk {arguments[0]} failed")

    return run


def stages(bag: Path, rrd: Path) -> dict[str, float]:
    """view's three stages, timed one by one, as the command runs them."""
    options = cli.build_parser().parse_args(["view", str(bag), "--rrd", str(rrd), "--quiet"])
    contact_s, feet = timed(lambda: feet_pass(options))
    odometry_s, track = timed(lambda: track_of(options))
    target = checked_targets(bag, {"--rrd": str(rrd)}, True)["--rrd"]
    summary = summary_of(feet, track)
    write_s, _ = timed(lambda: write_view(target, feet, track, robot_options(options), summary))
    return {"contact pass": contact_s, "odometry pass": odometry_s, "rerun write": write_s}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=60_000)
    options = parser.parse_args()
    duration_s = options.messages * PERIOD_NS / 1e9
    print(machine())
    with tempfile.TemporaryDirectory() as folder:
        bag = generate(Path(folder) / "bag", options.messages, "mcap", velocities=True)
        csv = str(Path(folder) / "feet.csv")
        bag_s, _ = timed(command(["bag", str(bag), "--csv", csv, "--quiet"]))
        rrd = Path(folder) / "run.rrd"
        view_s, _ = timed(command(["view", str(bag), "--rrd", str(rrd), "--no-open", "--quiet"]))
        size_mb = rrd.stat().st_size / 1e6
        split = stages(bag, rrd)
    print(f"recording: {options.messages} JointState messages, {duration_s:.0f} s at 1 kHz")
    rows = [("bag --csv", bag_s), ("view --no-open", view_s), *split.items()]
    for name, seconds in rows:
        print(
            f"{name + ':':<16}{seconds:8.2f} s {duration_s / seconds:7.1f}x real time "
            f"{seconds / bag_s:7.2f}x bag's time"
        )
    print(f"stages summed:  {sum(split.values()):8.2f} s; .rrd {size_mb:.1f} MB")


if __name__ == "__main__":
    main()
