"""The long fuzz of damaged recordings (issue 29; ``make fuzz``): thousands of damaged copies of a
simulated A1 trot (MCAP by rosbags, MCAP with zstd chunks as rosbag2 records it, sqlite3, ROS 1),
each through ``a1-leg-fk bag``, ``bag --forces``, ``gait`` or ``odom`` in this process, every run
checked as test/recording/test_damaged_recordings.py checks its few hundred (the harness is
test/damaged_bags.py): exit 0, 1 or 2; no traceback; one line on stderr; the input untouched; the
output absent or valid (a truncated copy's rows byte-identical to the undamaged output's).

Run: ``.venv/bin/python bench/fuzz_recordings.py [--copies 4000] [--first-seed 100000]``
(about 3 minutes for 4000). Seeds are fixed: copy ``n`` is made from seed ``first + n``, and a
failure prints its seed (``--first-seed SEED --copies 1`` reruns it). A run taking longer than
``--max-seconds`` (default 5) fails too. Exit 1 if any run failed.
"""

from __future__ import annotations

import argparse
import signal
import sys
import tempfile
import time
from pathlib import Path
from types import FrameType

from common import machine
from damaged_bags import FuzzSetup, Outcome, Result, Tally, cases, simulated_trot

HANG_S = 60


class Hang(BaseException):
    """A run exceeded :data:`HANG_S` (a BaseException: nothing under test may catch it)."""


def on_alarm(_signal: int, _frame: FrameType | None) -> None:
    raise Hang


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--copies", type=int, default=4000)
    parser.add_argument("--first-seed", type=int, default=100_000, help="(the CI test: 0 on)")
    parser.add_argument("--max-seconds", type=float, default=5.0)
    options = parser.parse_args()
    print(machine())
    signal.signal(signal.SIGALRM, on_alarm)
    tally = Tally()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="a1_leg_fk_fuzz_") as folder:
        setup = FuzzSetup.make(Path(folder), simulated_trot())
        for case in cases(range(options.first_seed, options.first_seed + options.copies)):
            signal.alarm(HANG_S)
            try:
                result = setup.run(case)
            except Hang:
                hung = Outcome(None, "", "", HANG_S)
                result = Result(case, "?", hung, [f"no end after {HANG_S} s"], 0)
            finally:
                signal.alarm(0)
            if result.outcome.seconds > options.max_seconds and not result.problems:
                result.problems.append(f"took {result.outcome.seconds:.1f} s")
            tally.add(result)
            if result.problems:
                print("FAILED", result.report(), flush=True)
            if tally.runs % 500 == 0:
                print(f"... {tally.runs} copies, {len(tally.failures)} failed", flush=True)
    print("\n".join(tally.lines()))
    print(f"wall time:      {time.perf_counter() - started:.0f} s")
    return 1 if tally.failures else 0


if __name__ == "__main__":
    sys.exit(main())
