"""Issue 29: a damaged recording ends every bag command in one line, exit 0, 1 or 2, never a
traceback, with what was read written (a truncated copy: a byte-for-byte prefix of the undamaged
output); our own errors still surface; a length field of terabytes is not allocated.

The CI-sized fuzz (a few hundred damaged copies, every format, command and damage; the long run
is ``make fuzz``) and the cases the fuzz found or the issue reported, each made on purpose.
"""

from __future__ import annotations

import sqlite3
import struct
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from bag_factory import T0, BagSpec, JointStateMsg, write_bag
from damaged_bags import (
    FORMATS,
    Case,
    FuzzSetup,
    Outcome,
    Tally,
    cases,
    headers_match_without_rows,
    output_problems,
    problems,
    run_in_process,
    simulated_trot,
)
from rosbags.rosbag2.storage_mcap import McapReader

from a1_leg_fk import cli
from a1_leg_fk.kinematics.quadruped import Quadruped

NAMES = list(Quadruped.from_urdf().joint_names)
CI_SEEDS = range(400)  # five of each (format, command, damage); the long run: make fuzz
SUBPROCESS_SEEDS = (3, 6, 9, 12, 16, 33, 37, 58, 64, 111, 142, 189)
REJECT_S = 5.0


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> FuzzSetup:
    return FuzzSetup.make(tmp_path_factory.mktemp("fuzz"), simulated_trot())


def test_damaged_copies_end_in_one_line_with_a_valid_output(setup: FuzzSetup) -> None:
    tally = Tally()
    for case in cases(CI_SEEDS):
        tally.add(setup.run(case))
    print("\n".join(tally.lines()))
    assert not tally.failures, "\n".join(result.report() for result in tally.failures[:10])
    assert tally.slowest_s <= REJECT_S, tally.slowest
    # the paths under test were taken: damage read past (exit 1) in every format, and truncated
    # copies whose rows were compared with the undamaged output's
    assert all(tally.codes[kind, 1] >= 5 for kind in FORMATS), tally.codes
    assert tally.prefix_copies >= 20 and tally.prefix_rows >= 2000, tally.lines()


def test_a_sample_as_real_processes_prints_no_traceback(setup: FuzzSetup) -> None:
    results = [
        setup.run(case, subprocess_run=True)
        for case in cases(range(200))
        if case.seed in SUBPROCESS_SEEDS
    ]
    assert {result.case.kind for result in results} == set(FORMATS)
    failed = [result.report() for result in results if result.problems]
    assert not failed, "\n".join(failed)
    assert {result.outcome.code for result in results} >= {1, 2}


# --- the checks themselves can fail ----------------------------------------------------------


def test_the_checks_find_a_traceback_a_second_line_and_a_changed_row() -> None:
    case = Case("mcap", "bag", "truncation", 0)
    reference = b"stamp_ns,FR_x\n1,0.5\n2,0.25\n3,0.125\n"
    assert problems(
        case, Outcome(None, "", "Traceback ...", 0.1), Path("/nonexistent"), reference
    )[0]
    assert problems(case, Outcome(1, "one\ntwo\n", "", 0.1), Path("/nonexistent"), reference)[0]
    assert problems(case, Outcome(3, "", "", 0.1), Path("/nonexistent"), reference)[0]
    assert output_problems(case, b"stamp_ns,FR_x\n1,0.5\n2,0.25\n", reference) == ([], 2)
    found, _ = output_problems(case, b"stamp_ns,FR_x\n1,0.5\n2,0.26\n", reference)
    assert found == ["row 2 of 2 is not the undamaged file's"]
    found, _ = output_problems(case, b"stamp_ns,FR_x\n1,0.5\n2,0.25\n3,0.125\n4,1\n", reference)
    assert found
    bits = Case("mcap", "bag", "bit flips", 0)
    assert output_problems(bits, b"stamp_ns,FR_x\n1,0.5,7\n", reference)[0]
    assert output_problems(bits, b"stamp_ns,FR_y\n1,0.5\n", reference)[0]


# --- damage made on purpose --------------------------------------------------------------------


def joint_states_bag(path: Path, kind: str, count: int = 400) -> Path:
    """``count`` JointStates with positions, velocities and efforts, one per ms."""
    rng = np.random.default_rng(29)
    spec = BagSpec()
    for index in range(count):
        stamp = T0 + index * 1_000_000
        q, rates, efforts = (rng.uniform(-1, 1, 12).tolist() for _ in range(3))
        spec.add_joint_state(
            "/joint_states", stamp, JointStateMsg(stamp, NAMES, q, rates, efforts=efforts)
        )
    return write_bag(path, spec, kind)


def csv_of(arguments: list[str], output: Path) -> tuple[Outcome, list[bytes]]:
    outcome = run_in_process([*arguments, "--csv", str(output), "--quiet"])
    return outcome, output.read_bytes().splitlines() if output.exists() else []


@pytest.mark.parametrize(("fail_at", "forces"), [(250, False), (250, True), (0, True)])
def test_a_reader_failing_mid_read_gives_the_rows_before_it_and_exit_1(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fail_at: int, forces: bool
) -> None:
    """The issue's ROS 1 case (a bare AssertionError inside rosbags), here in its MCAP reader,
    in the conversion and in the --forces pre-check (fail_at 0: the first message)."""
    bag = joint_states_bag(tmp_path / "in", "mcap")
    options = ["bag", str(bag), *(["--forces", "--causal"] if forces else [])]
    _, undamaged = csv_of(options, tmp_path / "undamaged.csv")
    reader_messages = McapReader.messages

    def failing(self: McapReader, *args, **kwargs):
        for index, message in enumerate(reader_messages(self, *args, **kwargs)):
            if index == fail_at:
                raise AssertionError
            yield message

    monkeypatch.setattr(McapReader, "messages", failing)
    outcome, rows = csv_of(options, tmp_path / "damaged.csv")
    where = (
        f"cannot read past message {fail_at} of /joint_states (bag time "
        f"{T0 + (fail_at - 1) * 1_000_000} ns): AssertionError"
        if fail_at
        else "cannot read the first message of /joint_states: AssertionError"
    )
    assert outcome.code == 1 and outcome.stderr.count("\n") == 1, outcome
    assert f"{bag}: stopped early: the recording is damaged: {where}" in outcome.stderr
    assert len(rows) == 1 + fail_at
    if fail_at:
        assert rows == undamaged[: 1 + fail_at]  # byte for byte
    else:  # no row: no velocity columns (they are there when a row has a foot velocity)
        assert headers_match_without_rows(rows[0], undamaged[0])


def test_a_sqlite_data_cell_that_is_an_integer_ends_the_read(tmp_path: Path) -> None:
    """The issue's sqlite3 case: SQLite's dynamic typing gives a damaged data cell back as an
    integer (it was ``len(raw)``: TypeError)."""
    bag = joint_states_bag(tmp_path / "in", "sqlite3")
    _, undamaged = csv_of(["bag", str(bag)], tmp_path / "undamaged.csv")
    with sqlite3.connect(next(bag.glob("*.db3"))) as db:
        db.execute("UPDATE messages SET data = 12345 WHERE id = 201")
    outcome, rows = csv_of(["bag", str(bag)], tmp_path / "damaged.csv")
    assert outcome.code == 1, outcome
    assert "message 201 of /joint_states: its data is int '12345', not bytes" in outcome.stderr
    assert rows == undamaged[:201]


def chunk_index_sizes(data: bytes) -> int:
    """The offset of the first chunk index's ``compressed_size`` in an MCAP file's summary."""
    summary = struct.unpack_from("<Q", data, len(data) - 37 + 9)[0]
    offset = summary
    while data[offset] != 0x08:  # chunk index
        offset += 9 + struct.unpack_from("<Q", data, offset + 1)[0]
    at = offset + 9 + 32
    at += 4 + struct.unpack_from("<I", data, at)[0]  # message index offsets
    at += 8  # message index length
    at += 4 + struct.unpack_from("<I", data, at)[0]  # compression
    return at


@pytest.mark.parametrize("claimed", [2**41, 2**33])
def test_a_length_of_terabytes_is_not_allocated(tmp_path: Path, claimed: int) -> None:
    """A chunk whose compressed size says 2 TB (or 8 GB, which malloc would grant): a short
    read and rosbags' own line with the offset, not a MemoryError or an allocation."""
    bag = joint_states_bag(tmp_path / "in", "mcap")
    mcap = next(bag.glob("*.mcap"))
    data = bytearray(mcap.read_bytes())
    struct.pack_into("<Q", data, chunk_index_sizes(bytes(data)), claimed)
    mcap.write_bytes(bytes(data))
    tracemalloc.start()
    try:
        outcome, rows = csv_of(["bag", str(bag)], tmp_path / "damaged.csv")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert outcome.code == 1 and len(rows) == 1, outcome  # the header: no message readable
    assert f"expected {claimed} bytes, got" in outcome.stderr
    assert "Truncated record at offset" in outcome.stderr
    assert peak < 64e6, peak


# --- our own errors are not the recording's ------------------------------------------------------


def test_an_error_of_our_own_in_the_pass_surfaces(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bag = joint_states_bag(tmp_path / "in", "mcap")

    def broken(*_args, **_kwargs):
        raise ZeroDivisionError("a bug of ours")

    monkeypatch.setattr("a1_leg_fk.recording.blocks._finish", broken)
    with pytest.raises(ZeroDivisionError, match="a bug of ours"):
        cli.main(["bag", str(bag), "--csv", str(tmp_path / "feet.csv"), "--quiet"])
    assert not (tmp_path / "feet.csv").exists()


def test_an_error_of_our_own_in_a_read_ahead_surfaces(
    setup: FuzzSetup, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The base pose (read before the pass) and the JointState decoder: only the calls into the
    reader are guarded."""

    def broken(*_args, **_kwargs):
        raise KeyError("a bug of ours")

    monkeypatch.setattr("a1_leg_fk.recording.base_pose._poses_of", broken)
    recording = setup.recordings["ros1"]
    with pytest.raises(KeyError, match="a bug of ours"):
        cli.main(["gait", str(recording), "--base-pose", "/truth", "--quiet"])
    monkeypatch.undo()
    monkeypatch.setattr("a1_leg_fk.recording.forces.JointStateDecoder.fields", broken)
    with pytest.raises(KeyError, match="a bug of ours"):
        cli.main(["bag", str(recording), "--forces", "--csv", str(tmp_path / "f.csv")])
