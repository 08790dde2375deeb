"""Damaged copies of a small recording and the checks a command's run on one must pass (issue 29):
the harness of the CI-sized fuzz test (test/recording/test_damaged_recordings.py) and of the long
run (bench/fuzz_recordings.py, ``make fuzz``).

The recording: a simulated A1 trot (PyBullet) with joint efforts, an IMU and the true base pose,
in four formats: a rosbag2 MCAP bag (rosbags' writer, one uncompressed chunk), an MCAP file as
rosbag2's MCAP plugin records (the format's reference library, many zstd chunks), a rosbag2
sqlite3 bag and a ROS 1 bag. Damage (:data:`DAMAGES`): bit flips, zeroed runs, truncation,
duplicated blocks, applied to the storage file with a seeded generator.

Every run is checked: exit 0, 1 or 2; no traceback (in-process: no exception out of ``main``);
at most one line on stderr; the input untouched; the output absent or valid: for a truncated
copy, its rows a byte-for-byte prefix of the undamaged file's output, for other damage a
well-formed file of the same columns.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import shutil
import subprocess
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from odometry_bags import TRUTH_TOPIC, write_sim_bag
from pybullet_sim import SimRun, simulate, walking_targets

from a1_leg_fk import cli

FORMATS = ("mcap", "mcap-zstd", "sqlite3", "ros1")
COMMANDS: dict[str, tuple[str, ...]] = {  # INPUT and OUTPUT are replaced by the paths
    "bag": ("bag", "INPUT", "--csv", "OUTPUT", "--quiet"),
    "bag --forces --causal": (
        "bag",
        "INPUT",
        "--forces",
        "--causal",
        "--csv",
        "OUTPUT",
        "--quiet",
    ),
    "gait": ("gait", "INPUT", "--base-pose", TRUTH_TOPIC, "--json", "OUTPUT", "--quiet"),
    "odom": ("odom", "INPUT", "--csv", "OUTPUT", "--quiet"),
    "odom --causal": ("odom", "INPUT", "--causal", "--csv", "OUTPUT", "--quiet"),
}
PREFIX_COMMANDS = ("bag", "bag --forces --causal", "odom --causal")
"""Commands whose CSV rows of a truncated recording must be a prefix of the undamaged ones: the
live answers (``--causal``), each row from the rows before it; a smoothed row also reads the rows
after it, which a truncated recording does not have."""
SIM_S = 1.2  # 600 samples at 500 Hz of each topic


def simulated_trot() -> SimRun:
    """The A1 standing for 0.2 s, then trotting (PyBullet, about a second to compute)."""
    return simulate(walking_targets(start_s=0.2), SIM_S)


def write_recording(folder: Path, kind: str, run: SimRun) -> Path:
    """The run as a recording of ``kind`` (one of :data:`FORMATS`) in ``folder``."""
    name = "trot.bag" if kind == "ros1" else f"trot_{kind}"
    return write_sim_bag(folder / name, run, efforts=True, kind=kind)


def storage_file(recording: Path) -> Path:
    """The file damage is applied to: the ROS 1 bag, or the bag directory's storage file."""
    if recording.is_file():
        return recording
    return next(p for p in sorted(recording.iterdir()) if p.suffix in (".mcap", ".db3"))


# --- damage --------------------------------------------------------------------------------------


def flip_bits(data: bytearray, rng: np.random.Generator) -> str:
    """1 to 8 random bits flipped."""
    count = int(rng.integers(1, 9))
    for _ in range(count):
        at = int(rng.integers(len(data)))
        data[at] ^= 1 << int(rng.integers(8))
    return f"{count} bit flips"


def zero_run(data: bytearray, rng: np.random.Generator) -> str:
    """A run of 1 to 4096 bytes set to zero."""
    length = int(rng.integers(1, 4097))
    start = int(rng.integers(len(data)))
    data[start : start + length] = bytes(len(data[start : start + length]))
    return f"{length} bytes zeroed at {start}"


def truncate(data: bytearray, rng: np.random.Generator) -> str:
    """The file cut short (as a recorder killed or a copy interrupted leaves it)."""
    keep = int(rng.integers(len(data)))
    del data[keep:]
    return f"truncated to {keep} bytes"


def duplicate_block(data: bytearray, rng: np.random.Generator) -> str:
    """A block of 16 to 4096 bytes written twice (inserted again right after itself)."""
    length = int(rng.integers(16, 4097))
    start = int(rng.integers(len(data)))
    data[start:start] = data[start : start + length]
    return f"{length} bytes at {start} duplicated"


DAMAGES: dict[str, Callable[[bytearray, np.random.Generator], str]] = {
    "bit flips": flip_bits,
    "zeroed run": zero_run,
    "truncation": truncate,
    "duplicated block": duplicate_block,
}


@dataclass(frozen=True)
class Case:
    """One damaged copy: its format, command and damage, made from ``seed``."""

    kind: str
    command: str
    damage: str
    seed: int

    def label(self) -> str:
        """How a failure names the case (enough to rerun it)."""
        return f"seed {self.seed}: {self.kind}, {self.damage}, {self.command}"


def cases(seeds: range) -> list[Case]:
    """One case per seed, cycling through formats, commands and damages (every combination
    once per 64 consecutive seeds)."""
    out = []
    for seed in seeds:
        kind = FORMATS[seed % len(FORMATS)]
        command = list(COMMANDS)[seed // len(FORMATS) % len(COMMANDS)]
        damage = list(DAMAGES)[seed // (len(FORMATS) * len(COMMANDS)) % len(DAMAGES)]
        out.append(Case(kind, command, damage, seed))
    return out


def damaged_copy(original: Path, target: Path, case: Case) -> str:
    """Copy ``original`` to ``target`` and damage its storage file as ``case`` says; returns
    what was done."""
    if original.is_dir():
        shutil.copytree(original, target)
    else:
        shutil.copyfile(original, target)
    damaged = storage_file(target)
    data = bytearray(damaged.read_bytes())
    what = DAMAGES[case.damage](data, np.random.default_rng(case.seed))
    damaged.write_bytes(bytes(data))
    return what


# --- running and checking ------------------------------------------------------------------------


@dataclass
class Outcome:
    """A command's run: exit code (None if ``main`` raised), stderr, the traceback of what it
    raised, wall time [s]."""

    code: int | None
    stderr: str
    raised: str
    seconds: float


def arguments(command: str, recording: Path, output: Path) -> list[str]:
    """The command line of ``command`` on ``recording`` writing ``output``."""
    paths = {"INPUT": str(recording), "OUTPUT": str(output)}
    return [paths.get(part, part) for part in COMMANDS[command]]


def run_in_process(argv: list[str]) -> Outcome:
    """``a1-leg-fk argv`` through ``cli.main`` in this process, stdout and stderr captured."""
    out, err = io.StringIO(), io.StringIO()
    raised = ""
    started = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code: int | None = cli.main(argv)
        except Exception:  # noqa: BLE001 (what the fuzz looks for: anything out of main)
            code, raised = None, traceback.format_exc()
    return Outcome(code, err.getvalue(), raised, time.perf_counter() - started)


def run_subprocess(argv: list[str], timeout_s: float = 60.0) -> Outcome:
    """``a1-leg-fk argv`` as a real process (the installed console script)."""
    script = Path(sys.executable).with_name("a1-leg-fk")
    started = time.perf_counter()
    result = subprocess.run(
        [str(script), *argv], capture_output=True, text=True, timeout=timeout_s, check=False
    )
    return Outcome(result.returncode, result.stderr, "", time.perf_counter() - started)


def digest(path: Path) -> str:
    """A hash of a file or of every file under a folder (names and contents)."""
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    sha = hashlib.sha256()
    for file in files:
        sha.update(str(file.relative_to(path.parent)).encode())
        sha.update(file.read_bytes())
    return sha.hexdigest()


def problems(
    case: Case, outcome: Outcome, output: Path, reference: bytes
) -> tuple[list[str], int]:
    """What is wrong with a run on a damaged copy (empty: nothing), and how many rows of its
    output were compared byte for byte with the undamaged output's (a truncated copy's).
    ``reference``: the command's output of the undamaged recording."""
    found = []
    if outcome.raised or "Traceback" in outcome.stderr:
        found.append("traceback: " + (outcome.raised or outcome.stderr).strip()[-2000:])
    if outcome.code not in (0, 1, 2):
        found.append(f"exit code {outcome.code}")
    lines = outcome.stderr.strip().splitlines()
    if len(lines) > 1:
        found.append(f"{len(lines)} lines on stderr: {outcome.stderr.strip()[:600]}")
    compared = 0
    if output.exists():
        output_found, compared = output_problems(case, output.read_bytes(), reference)
        found += output_found
    return found, compared


def output_problems(case: Case, data: bytes, reference: bytes) -> tuple[list[str], int]:
    """What is wrong with an output left by a run on a damaged copy, and how many of its rows
    were compared with the undamaged output's (those of a truncated copy: a prefix)."""
    if case.command == "gait":
        try:
            json.loads(data)
        except ValueError as error:
            return [f"the JSON does not parse: {error}"], 0
        return [], 0
    header, *rows = data.split(b"\n")
    reference_header, *reference_rows = reference.split(b"\n")
    if rows and rows[-1] == b"":
        rows.pop()
    if reference_rows and reference_rows[-1] == b"":
        reference_rows.pop()
    if header != reference_header and (rows or not headers_match_without_rows(header, reference)):
        return [f"CSV header {header[:80]!r} differs from the undamaged one"], 0
    if case.damage == "truncation" and case.command in PREFIX_COMMANDS:
        if rows != reference_rows[: len(rows)]:
            first = next(
                (i for i, (a, b) in enumerate(zip(rows, reference_rows)) if a != b),
                len(reference_rows),
            )
            return [f"row {first + 1} of {len(rows)} is not the undamaged file's"], len(rows)
        return [], len(rows)
    width = header.count(b",")
    for number, row in enumerate(rows, 1):
        cells = row.split(b",")
        if len(cells) != width + 1:
            return [f"row {number} has {len(cells)} cells, the header {width + 1}"], 0
        try:
            [float(cell) for cell in cells if cell]
        except ValueError:
            return [f"row {number} has a cell that is not a number: {row[:120]!r}"], 0
    return [], 0


def headers_match_without_rows(header: bytes, reference: bytes) -> bool:
    """A header-only CSV (no row read) may lack the velocity columns: they are there when a row
    has a foot velocity."""
    reference_header = reference.split(b"\n", 1)[0]
    without_velocities = b",".join(
        cell for cell in reference_header.split(b",") if b"_v" not in cell
    )
    return header in (reference_header, without_velocities)


@dataclass
class FuzzSetup:
    """The undamaged recordings of every format and every command's output of them."""

    folder: Path
    recordings: dict[str, Path]
    references: dict[tuple[str, str], bytes]

    @classmethod
    def make(cls, folder: Path, run: SimRun) -> FuzzSetup:
        """Write the recordings under ``folder`` and run every command on each (all must exit
        0)."""
        recordings = {kind: write_recording(folder, kind, run) for kind in FORMATS}
        references = {}
        for kind, recording in recordings.items():
            for command in COMMANDS:
                output = folder / f"reference_{kind}_{command.replace(' ', '')}.out"
                outcome = run_in_process(arguments(command, recording, output))
                assert outcome.code == 0, (kind, command, outcome)
                references[kind, command] = output.read_bytes()
        return cls(folder, recordings, references)

    def run(self, case: Case, subprocess_run: bool = False) -> Result:
        """Damage a copy as ``case`` says, run its command on it and check the run; the copy is
        removed afterwards."""
        work = self.folder / f"case_{case.seed}"
        work.mkdir()
        try:
            original = self.recordings[case.kind]
            copy = work / original.name
            what = damaged_copy(original, copy, case)
            before = digest(copy)
            output = work / "out"
            argv = arguments(case.command, copy, output)
            outcome = run_subprocess(argv) if subprocess_run else run_in_process(argv)
            reference = self.references[case.kind, case.command]
            found, compared = problems(case, outcome, output, reference)
            if digest(copy) != before:
                found.append("the input was modified")
            return Result(case, what, outcome, found, compared)
        finally:
            shutil.rmtree(work, ignore_errors=True)


@dataclass
class Result:
    """A checked run: the case, what its damage was, the run, the problems found (none: the run
    passed) and the rows compared byte for byte with the undamaged output."""

    case: Case
    damage: str
    outcome: Outcome
    problems: list[str]
    prefix_rows: int

    def report(self) -> str:
        """The failure as one paragraph: the case (its seed reproduces it) and its problems."""
        return f"{self.case.label()} ({self.damage}): " + "; ".join(self.problems)


@dataclass
class Tally:
    """What a fuzz run found: runs, failures, exit codes by format, the slowest run, and the
    truncated copies whose rows were compared with the undamaged output."""

    runs: int = 0
    failures: list[Result] = field(default_factory=list)
    codes: Counter[tuple[str, int | None]] = field(default_factory=Counter)
    slowest_s: float = 0.0
    slowest: str = ""
    prefix_copies: int = 0  # truncated copies with at least one row compared
    prefix_rows: int = 0

    def add(self, result: Result) -> None:
        """Count one checked run."""
        self.runs += 1
        if result.problems:
            self.failures.append(result)
        self.codes[result.case.kind, result.outcome.code] += 1
        if result.outcome.seconds > self.slowest_s:
            self.slowest_s, self.slowest = result.outcome.seconds, result.case.label()
        if result.prefix_rows:
            self.prefix_copies += 1
            self.prefix_rows += result.prefix_rows

    def lines(self) -> list[str]:
        """The summary, one fact per line."""
        codes = "; ".join(
            f"{kind} " + ", ".join(f"exit {code}: {self.codes[kind, code]}" for code in (0, 1, 2))
            for kind in FORMATS
        )
        return [
            f"damaged copies: {self.runs} ({codes})",
            (
                f"failures:       {len(self.failures)} (tracebacks, other exit codes, several "
                "stderr lines, a changed input, a bad output)"
            ),
            f"slowest run:    {self.slowest_s:.3f} s ({self.slowest})",
            (
                f"prefix checked: {self.prefix_copies} truncated copies, {self.prefix_rows} rows "
                "byte-identical to the undamaged output's"
            ),
        ]
