"""Speed of the offline path (``a1-leg-fk bag``) against rosbags itself, in one run.

Run: ``.venv/bin/python bench/bag_speed.py [--messages N] [--storage mcap|sqlite3]`` (about a
minute for the default 300,000 messages). Generates a 1 kHz bag of 12-joint JointState messages
(positions and velocities of a trot-like motion) in a temporary folder, then prints messages per
second for:

(a) the floor: ``rosbags`` reading the raw messages, no deserialization;
(b) the peer way: ``rosbags`` deserialization + ``Quadruped.fk`` per message;
(c) ``a1-leg-fk bag --csv``;
(d) ``a1-leg-fk bag --output-bag`` (MCAP),

each as a ratio to (b). Target: (c) >= 3x (b).

``--long``: instead, a 30-minute 1 kHz bag (1.8 M messages) and a 3-minute one; the peak RSS of
``a1-leg-fk bag --csv`` and ``--output-bag`` over each (separate processes): the long bag must not
need more memory than the short one.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from common import machine

from a1_leg_fk import cli
from a1_leg_fk.kinematics.quadruped import Quadruped

JOINT_STATE = "sensor_msgs/msg/JointState"
T0 = 1_700_000_000_000_000_000
PERIOD_NS = 1_000_000  # 1 kHz


def generate(path: Path, messages: int, storage: str, velocities: bool = False) -> Path:
    """A bag of ``messages`` JointStates at 1 kHz (names and positions, and velocities if asked);
    serialized once, stamps and values patched in."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = typestore.types
    names = list(Quadruped.from_urdf().joint_names)
    header = types["std_msgs/msg/Header"](types["builtin_interfaces/msg/Time"](0, 0), "")
    marks_q, marks_dq = np.arange(1.0, 13.0), np.arange(101.0, 113.0)  # found in the bytes below
    template = bytearray(
        typestore.serialize_cdr(
            types[JOINT_STATE](
                header, names, marks_q, marks_dq if velocities else np.zeros(0), np.zeros(0)
            ),
            JOINT_STATE,
        )
    )
    positions_at = bytes(template).index(marks_q.astype("<f8").tobytes())
    velocities_at = bytes(template).index(marks_dq.astype("<f8").tobytes()) if velocities else 0
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    base = np.array([0.05, 0.8, -1.5] * 4)
    phase = np.array(
        [0.0, 0.0, 0.0, math.pi, math.pi, math.pi, math.pi, math.pi, math.pi, 0.0, 0.0, 0.0]
    )
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection("/joint_states", JOINT_STATE, typestore=typestore)
        for index in range(messages):
            stamp = T0 + index * PERIOD_NS
            angle = 2 * math.pi * 2.0 * index / 1000.0 + phase
            q = base + 0.3 * np.sin(angle)
            dq = 0.3 * 2 * math.pi * 2.0 * np.cos(angle)
            template[4:12] = np.array(divmod(stamp, 1_000_000_000), dtype="<i4").tobytes()
            template[positions_at : positions_at + 96] = q.astype("<f8").tobytes()
            if velocities:
                template[velocities_at : velocities_at + 96] = dq.astype("<f8").tobytes()
            writer.write(connection, stamp, bytes(template))
    return path


def floor(path: Path) -> int:
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return sum(
            1
            for _ in reader.messages(
                connections=[c for c in reader.connections if c.msgtype == JOINT_STATE]
            )
        )


def peer(path: Path) -> int:
    from rosbags.highlevel import AnyReader

    robot = Quadruped.from_urdf()
    count = 0
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.msgtype == JOINT_STATE]
        for connection, _, raw in reader.messages(connections=connections):
            message: Any = reader.deserialize(raw, connection.msgtype)  # a sensor_msgs JointState
            robot.fk(message.position)
            count += 1
    return count


def command(arguments: list[str]) -> int:
    code = cli.main(arguments)
    if code != 0:
        raise SystemExit(f"a1-leg-fk {' '.join(arguments)} exited {code}")
    return 0


def timed(function, *arguments) -> float:
    started = time.perf_counter()
    function(*arguments)
    return time.perf_counter() - started


def speed(options: argparse.Namespace, folder: Path) -> None:
    bag = folder / "bench_bag"
    content = "names, positions and velocities" if options.velocities else "names and positions"
    print(
        f"generating {options.messages:,} JointState messages at 1 kHz ({content}; "
        f"{options.storage}) ...",
        flush=True,
    )
    generation = timed(generate, bag, options.messages, options.storage, options.velocities)
    print(f"  written in {generation:.1f} s ({options.messages / generation:,.0f} messages/s)")
    rows = [
        ("(a) floor: rosbags raw read, no deserialization", timed(floor, bag)),
        ("(b) peer: rosbags deserialize + Quadruped.fk", timed(peer, bag)),
        (
            "(c) a1-leg-fk bag --csv",
            timed(
                command, ["bag", str(bag), "--csv", str(folder / "feet.csv"), "--quiet", "--force"]
            ),
        ),
        (
            "(d) a1-leg-fk bag --output-bag (MCAP)",
            timed(
                command,
                ["bag", str(bag), "--output-bag", str(folder / "feet_bag"), "--quiet", "--force"],
            ),
        ),
    ]
    peer_rate = options.messages / rows[1][1]
    print("\n| | messages/s | time [s] | ratio to (b) |\n| --- | --- | --- | --- |")
    for name, seconds in rows:
        rate = options.messages / seconds
        print(f"| {name} | {rate:,.0f} | {seconds:.2f} | {rate / peer_rate:.2f}x |")


PEAK_RSS_CHILD = (
    "import resource, sys\n"
    "from a1_leg_fk import cli\n"
    "code = cli.main(sys.argv[1:])\n"
    "print('peak_rss_kb', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n"
    "sys.exit(code)\n"
)


def peak_rss_mb(arguments: list[str]) -> float:
    """Peak RSS [MB] of ``a1-leg-fk`` run with ``arguments`` in a process of its own."""
    result = subprocess.run(
        [sys.executable, "-c", PEAK_RSS_CHILD, *arguments],
        check=True,
        capture_output=True,
        text=True,
    )
    return int(result.stdout.split("peak_rss_kb")[-1]) / 1024


def long_run(options: argparse.Namespace, folder: Path) -> None:
    print(
        "| bag | messages | --csv peak RSS [MB] | --output-bag peak RSS [MB] |\n"
        "| --- | --- | --- | --- |"
    )
    for minutes in (3, 30):
        messages = minutes * 60 * 1000
        bag = generate(folder / f"bag_{minutes}min", messages, options.storage)
        csv_rss = peak_rss_mb(
            ["bag", str(bag), "--csv", str(folder / f"{minutes}.csv"), "--quiet"]
        )
        bag_rss = peak_rss_mb(
            ["bag", str(bag), "--output-bag", str(folder / f"{minutes}_out"), "--quiet"]
        )
        print(
            f"| {minutes} min at 1 kHz | {messages:,} | {csv_rss:.0f} | {bag_rss:.0f} |",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=300_000)
    parser.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    parser.add_argument(
        "--velocities",
        action="store_true",
        help="give the joint velocities too (12 more CSV columns)",
    )
    parser.add_argument(
        "--long", action="store_true", help="peak RSS over a 3-minute and a 30-minute bag instead"
    )
    options = parser.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory(prefix="a1_leg_fk_bag_bench_") as folder:
        (long_run if options.long else speed)(options, Path(folder))


if __name__ == "__main__":
    main()
