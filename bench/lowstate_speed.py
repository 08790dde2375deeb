"""Speed of reading Unitree LowState recordings against rosbags' own deserializer, in one run.

Run: ``.venv/bin/python bench/lowstate_speed.py [--messages N]`` (about half a minute for the
default 100,000). Writes a 500 Hz MCAP bag of ``unitree_go/msg/LowState`` (motors in a trot-like
motion, 1,180 bytes each) in a temporary folder, then prints messages per second for:

(a) the floor: ``rosbags`` reading the raw messages, no deserialization;
(b) the peer way: ``rosbags`` deserializing every message (given Unitree's definitions) and
    taking the 12 motors' q, dq and tau_est;
(c) the package's reading: the same raw messages through
    :meth:`~a1_leg_fk.recording.lowstate.LowStateInput.blocks` (:mod:`a1_leg_fk.wire.lowstate`);
(d) ``a1-leg-fk bag --csv`` on the bag (reading, FK and CSV),

each as a ratio to (b). Target: (c) >= 2x (b).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from common import machine

from a1_leg_fk import cli
from a1_leg_fk.recording.lowstate import LowStateInput
from a1_leg_fk.recording.reads import RecordingReads
from a1_leg_fk.recording.typestores import open_reader, with_unitree_types
from a1_leg_fk.wire.lowstate import layout_for
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE

T0 = 1_700_000_000_000_000_000
PERIOD_NS = 2_000_000  # 500 Hz
STAND = (0.0, 0.8, -1.5)


def generate(path: Path, messages: int) -> Path:
    """An MCAP bag of ``messages`` LowStates: zero bytes of the published layout with the motors'
    q, dq, tau_est and the IMU's quaternion written in."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = with_unitree_types(get_typestore(Stores.ROS2_JAZZY))
    layout = layout_for(GO_LOW_STATE, None, False)
    template = bytearray(layout.size)
    template[:4] = b"\x00\x01\x00\x00"
    quaternion = layout.field("imu_state.quaternion").offset
    template[quaternion : quaternion + 16] = np.array([1, 0, 0, 0], "<f4").tobytes()
    offsets = [
        [layout.field(f"motor_state[{m}].{name}").offset for m in range(12)]
        for name in ("q", "dq", "tau_est")
    ]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/lowstate", GO_LOW_STATE, typestore=typestore)
        for index in range(messages):
            phase = 2.0 * np.pi * index / 250.0
            angles = np.tile(STAND, 4) + 0.2 * np.sin(phase + np.arange(12))
            for values, fields in zip((angles, np.cos(angles), 3.0 * angles), offsets):
                raw = values.astype("<f4").tobytes()
                for motor, offset in enumerate(fields):
                    template[offset : offset + 4] = raw[4 * motor : 4 * motor + 4]
            writer.write(connection, T0 + index * PERIOD_NS, bytes(template))
    return path


def floor(path: Path) -> int:
    reader, _ = open_reader(path)
    try:
        return sum(1 for _ in reader.messages())
    finally:
        reader.close()


def peer(path: Path) -> int:
    """Messages read: each deserialized, its 12 motors' q, dq, tau_est taken as arrays."""
    reader, _ = open_reader(path)
    count = 0
    try:
        for connection, _, raw in reader.messages():
            message: Any = reader.deserialize(raw, connection.msgtype)
            motors = message.motor_state[:12]
            np.array([(m.q, m.dq, m.tau_est) for m in motors])
            count += 1
    finally:
        reader.close()
    return count


def ours(path: Path) -> int:
    """Messages read by the package's LowState reading (q, dq, tau_est, IMU, foot sensors)."""
    reader, _ = open_reader(path)
    count = 0
    try:
        reads = RecordingReads(reader, path)
        lowstate = LowStateInput.open(reads, reader.connections[0])
        for times, _ in lowstate.blocks(reads):
            count += len(times)
    finally:
        reader.close()
    return count


def timed(function, *arguments) -> float:
    """Seconds of one call (its printing swallowed)."""
    started = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        function(*arguments)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=100_000)
    options = parser.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as folder:
        bag = generate(Path(folder) / "lowstate", options.messages)
        csv = Path(folder) / "feet.csv"
        seconds = {
            "(a) rosbags, raw messages": timed(floor, bag),
            "(b) rosbags deserialize + motors": timed(peer, bag),
            "(c) a1_leg_fk LowState reading": timed(ours, bag),
            "(d) a1-leg-fk bag --csv": timed(cli.main, ["bag", str(bag), "--csv", str(csv)]),
        }
    reference = seconds["(b) rosbags deserialize + motors"]
    for name, value in seconds.items():
        rate = options.messages / value
        print(f"{name:<36} {rate:>12,.0f} msg/s  {reference / value:6.2f}x (b)")


if __name__ == "__main__":
    main()
