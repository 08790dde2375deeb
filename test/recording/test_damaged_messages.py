"""Issue 38, part 3: a recording whose IMU or LowState messages are damaged in their own bytes
(the container intact: cut short, bit flips, a length field of gigabytes, bytes appended) through
``a1-leg-fk bag``, ``bag --forces``, ``gait`` and ``odom``, as the damaged-recordings work decided
for any message the deserializer cannot decode (a1_leg_fk/recording/reads.py): the read ends
before it, the output keeps every row before it, one line on stderr names the message (its number,
topic and bag time) and the reader's reason, exit 1; never a traceback. A message that can still
be read (bit flips that leave it whole, values changed) is used: exit 0.

The bags (MCAP and sqlite3) are made here: a synthetic A1 swaying in place at 500 Hz, as a
JointState + Imu + base-pose recording or as Unitree LowStates of either layout.
"""

from __future__ import annotations

import csv
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from bag_factory import T0, TYPESTORE, BagSpec, JointStateMsg, T, header, pose, write_bag
from damaged_bags import run_in_process
from lowstate_bags import register_unitree_types, zeroed
from shared import PYBULLET_NAMES, STANDING

from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

ROWS, STEP_NS, DAMAGED_ROW = 240, 2_000_000, 120
IMU, LOWSTATE, TRUTH = "/imu", "/lowstate", "/truth"
COMMANDS = {  # the commands that read an --imu topic (plain bag does not)
    "bag --forces": ["bag", "INPUT", "--forces", "--imu", IMU, "--csv", "OUTPUT"],
    "gait": ["gait", "INPUT", "--base-pose", TRUTH, "--imu", IMU, "--json", "OUTPUT"],
    "odom": ["odom", "INPUT", "--csv", "OUTPUT"],
}
LOWSTATE_COMMANDS = {  # a LowState carries its IMU: no --imu
    "bag": ["bag", "INPUT", "--csv", "OUTPUT"],
    **{name: [p for p in argv if p not in ("--imu", IMU)] for name, argv in COMMANDS.items()},
}
UNREADABLE = ("truncated", "absurd length", "extended")
"""Damage the deserializer cannot read past (for a LowState, a fixed-size message without a
length field: cut short or extended)."""


def damage(kind: str, raw: bytes) -> bytes:
    """``raw`` damaged as ``kind`` says (bit flips: seeded, in the message's values)."""
    if kind == "truncated":
        return raw[: len(raw) // 2]
    if kind == "extended":
        return raw + bytes(range(40))
    data = bytearray(raw)
    if kind == "absurd length":  # the Imu's frame_id length, after the stamp
        struct.pack_into("<I", data, 12, 0xFFFFFFF0)
        return bytes(data)
    rng = np.random.default_rng(38)
    for index in rng.integers(len(data) // 2, len(data), 6):
        data[index] ^= 0x10
    return bytes(data)


def angles(row: int) -> list[float]:
    return [a + 0.1 * math.sin(row * 0.05) for a in STANDING]


def add_truth(spec: BagSpec, stamp: int) -> None:
    message = T["geometry_msgs/msg/PoseStamped"](
        header(stamp, "world"), pose([0.0, 0.0, 0.3], [0.0, 0.0, 0.0, 1.0])
    )
    spec.add(TRUTH, "geometry_msgs/msg/PoseStamped", stamp, message)


def imu_bag(path: Path, kind: str, how: str) -> Path:
    """JointStates (with efforts), a level Imu 1 ns before each, the base pose; Imu
    :data:`DAMAGED_ROW` damaged as ``how``."""
    spec, vector = BagSpec(), T["geometry_msgs/msg/Vector3"]
    for row in range(ROWS):
        stamp = T0 + row * STEP_NS
        imu = T["sensor_msgs/msg/Imu"](
            header(stamp - 1, "imu"), T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
            np.zeros(9), vector(0.0, 0.0, 0.0), np.zeros(9), vector(0.0, 0.0, 9.81), np.zeros(9),
        )  # fmt: skip
        raw = bytes(TYPESTORE.serialize_cdr(imu, "sensor_msgs/msg/Imu"))
        spec.add(
            IMU, "sensor_msgs/msg/Imu", stamp - 1, damage(how, raw) if row == DAMAGED_ROW else imu
        )
        names = list(PYBULLET_NAMES)
        spec.add_joint_state(
            "/joint_states",
            stamp,
            JointStateMsg(stamp, names, angles(row), [0.1] * 12, "", [2.0] * 12),
        )
        add_truth(spec, stamp)
    return write_bag(path, spec, kind)


def lowstate_bag(path: Path, kind: str, how: str, msgtype: str) -> Path:
    """LowStates of ``msgtype`` (motors swaying, IMU level, w first), the base pose; LowState
    :data:`DAMAGED_ROW` damaged as ``how``."""
    register_unitree_types()
    spec, go = BagSpec(), msgtype == GO_LOW_STATE
    for row in range(ROWS):
        stamp = T0 + row * STEP_NS
        message = zeroed(msgtype)
        motors = message.motor_state if go else message.motorState
        for index, angle in enumerate(angles(row)):
            motors[index].q = angle
        imu = message.imu_state if go else message.imu
        imu.quaternion[0], imu.accelerometer[2] = 1.0, 9.81
        message.tick = row * 2
        raw = bytes(TYPESTORE.serialize_cdr(message, msgtype))
        spec.add(LOWSTATE, msgtype, stamp, damage(how, raw) if row == DAMAGED_ROW else message)
        add_truth(spec, stamp)
    return write_bag(path, spec, kind)


def check(argv: list[str], bag: Path, out: Path, topic: str, unreadable: bool) -> str:
    """Run one command; its one line (or ""). Exit 1 and the line naming the damaged message
    for unreadable damage, else exit 0 and no line; never a traceback; rows before the damage
    kept."""
    outcome = run_in_process(
        [str(bag) if p == "INPUT" else str(out) if p == "OUTPUT" else p for p in argv]
    )
    assert not outcome.raised, outcome.raised
    lines = outcome.stderr.splitlines()
    if not unreadable:
        assert outcome.code == 0 and not lines, outcome
        return ""
    assert outcome.code == 1 and len(lines) == 1, outcome
    assert f"message {DAMAGED_ROW + 1} of {topic} (bag time " in lines[0], lines[0]
    assert "cannot be decoded" in lines[0] and "Traceback" not in lines[0], lines[0]
    if out.suffix == ".csv":  # the rows before the damage, and none after it
        with out.open() as stream:
            rows = [row for row in csv.reader(stream) if row and not row[0].startswith("#")]
        assert 0 < len(rows) - 1 <= DAMAGED_ROW, len(rows)
    return lines[0]


@pytest.mark.parametrize("kind", ["mcap", "sqlite3"])
@pytest.mark.parametrize("how", [*UNREADABLE, "bit flips"])
def test_a_damaged_imu_message(kind: str, how: str, tmp_path: Path) -> None:
    bag = imu_bag(tmp_path / "imu_bag", kind, how)
    for name, argv in COMMANDS.items():
        out = tmp_path / f"{name.replace(' ', '')}.{'json' if name == 'gait' else 'csv'}"
        line = check(argv, bag, out, IMU, how in UNREADABLE)
        print(f"{kind} {how} {name}: {line or 'exit 0'}")


@pytest.mark.parametrize("kind", ["mcap", "sqlite3"])
@pytest.mark.parametrize("msgtype", [GO_LOW_STATE, LEGGED_LOW_STATE])
@pytest.mark.parametrize("how", ["truncated", "extended", "bit flips"])
def test_a_damaged_lowstate_message(kind: str, msgtype: str, how: str, tmp_path: Path) -> None:
    bag = lowstate_bag(tmp_path / "lowstate_bag", kind, how, msgtype)
    for name, argv in LOWSTATE_COMMANDS.items():
        out = tmp_path / f"{name.replace(' ', '')}.{'json' if name == 'gait' else 'csv'}"
        line = check(argv, bag, out, LOWSTATE, how != "bit flips")
        print(f"{kind} {msgtype} {how} {name}: {line or 'exit 0'}")
