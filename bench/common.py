"""What the bench/ scripts share: the import path, the names and poses, the machine line, timing.

Import it first (``from common import ...``; a script's own folder is on ``sys.path``): it makes
``a1_leg_fk`` importable from a source checkout that was not installed, and hands on the module
the tests use for the names, the ROS-domain lock and the process helpers (``common.shared``, i.e.
test/shared.py), so the bench and the tests keep one definition of each.
"""

from __future__ import annotations

import importlib.util
import os
import platform
import statistics
import sys
import timeit
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if (
    importlib.util.find_spec("a1_leg_fk") is None
):  # a source checkout without the package installed
    sys.path.insert(0, str(ROOT))
sys.path.append(str(ROOT / "test"))  # appended: nothing in test/ may shadow an installed module

import shared  # noqa: E402 (needs the path above)

__all__ = [
    "REPEATS",
    "ROOT",
    "SPEED_POSE",
    "machine",
    "measured_cli",
    "median_seconds_per_call",
    "shared",
    "trig_floor",
]

SPEED_POSE = [0.05, 0.8, -1.5, -0.05, 0.8, -1.5, 0.05, 0.9, -1.6, -0.05, 0.9, -1.6]
"""The configuration the speed benchmarks time [rad]: standing, with hip roll and unequal legs."""

REPEATS = 15
"""Interleaved runs per function in :func:`median_seconds_per_call`."""


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "absent"


def machine() -> str:
    """Two lines on what a result was measured on: CPUs, model, load; Python and the libraries."""
    model = next(
        (
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text().splitlines()
            if line.startswith("model name")
        ),
        platform.processor() or platform.machine(),
    )
    load = " ".join(f"{average:.2f}" for average in os.getloadavg())
    rmw = os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp (default)")
    libraries = ", ".join(f"{name} {_version(name)}" for name in ("numpy", "pybullet", "rclpy"))
    return (
        f"machine: nproc={len(os.sched_getaffinity(0))} (cpu_count={os.cpu_count()}), {model}, "
        f"{platform.platform()}, load avg {load}\npython {platform.python_version()}, "
        f"{libraries}, {rmw}"
    )


def median_seconds_per_call(
    functions: dict[str, Callable[[], object]],
    repeats: int = REPEATS,
    target_s: float = 0.05,
    *,
    calibrate: bool = True,
) -> dict[str, float]:
    """Median time per call [s] of each function over ``repeats`` runs of about ``target_s`` each.

    The runs are interleaved (one run of every function per round), so a slow spell of the
    machine hits all of them alike and the ratios stay fair. ``calibrate=False``: one call per
    run, no calibration, for calls known to take longer than ``target_s`` (a batch of 10^6).
    """
    timers = {name: timeit.Timer(function) for name, function in functions.items()}
    numbers = dict.fromkeys(timers, 1)
    if calibrate:
        for name, timer in timers.items():
            number, elapsed = timer.autorange()
            numbers[name] = max(1, int(number * target_s / max(elapsed, 1e-9)))
    runs: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(repeats):
        for name, timer in timers.items():
            runs[name].append(timer.timeit(numbers[name]) / numbers[name])
    return {name: statistics.median(times) for name, times in runs.items()}


def trig_floor(angles: np.ndarray) -> Callable[[], None]:
    """A call of ``np.sin`` and ``np.cos`` on ``angles`` [rad] alone: the floor under the time of
    any method that needs their trigonometry."""

    def sin_and_cos() -> None:
        np.sin(angles)
        np.cos(angles)

    return sin_and_cos


CLI_RUN = """
import resource, sys
from a1_leg_fk import cli
code = cli.main(sys.argv[1:])
usage = resource.getrusage(resource.RUSAGE_SELF)
print(usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0)
sys.exit(code)
"""


def measured_cli(arguments: list[str]) -> tuple[float, float, float]:
    """Wall time, CPU time [s] and peak RSS [MB] of ``a1-leg-fk ARGUMENTS`` in a fresh
    process."""
    import subprocess
    import time

    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", CLI_RUN, *arguments], capture_output=True, text=True, check=True
    )
    cpu, peak = done.stdout.strip().splitlines()[-1].split()
    return time.perf_counter() - started, float(cpu), float(peak)
