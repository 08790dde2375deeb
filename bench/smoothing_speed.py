"""Cost of the smoothed trajectory (``a1-leg-fk odom``, the default) against the causal filter's
(``odom --causal``) on a 1 kHz recording, in one run.

Run: ``.venv/bin/python bench/smoothing_speed.py [--seconds S]`` (a few minutes for the default
60 s). Generates bags of JointStates (bag_speed.py's trot-like motion, positions and velocities,
no efforts) and Imu messages (level, turning at 0.1 rad/s, the accelerometer feeling gravity:
the state filter runs), both at 1 kHz, of ``S / 3`` and ``S`` seconds; runs ``odom --csv`` on
each, causal and smoothed, each in its own process; prints

- the speed as a multiple of real time (recording seconds per CPU second of the process: one
  core, not the wall clock a shared machine stretches), and the wall time;
- the process's peak RSS [MB], and per bag the smoothed run's extra over the causal one: the
  smoother's history (one 8 s window and its 2 s overlap, 2.9 kB a step) and its pending
  samples, which must not grow with the recording;
- the peak's growth per recorded minute (both runs: the track of every row, as ``odom`` keeps
  it to write its CSV and plot), extrapolated to one hour.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

from common import machine, measured_cli

from a1_leg_fk.kinematics.quadruped import Quadruped

T0 = 1_700_000_000_000_000_000
PERIOD_NS = 1_000_000


def generate(path: Path, seconds: float) -> Path:
    """A bag of JointStates and Imu messages at 1 kHz for ``seconds``."""
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    t = typestore.types
    names = list(Quadruped.from_urdf().joint_names)
    base = np.array([0.05, 0.8, -1.5] * 4)
    phase = np.array([0.0] * 3 + [math.pi] * 6 + [0.0] * 3)
    joint_type, imu_type = "sensor_msgs/msg/JointState", "sensor_msgs/msg/Imu"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        joints = writer.add_connection("/joint_states", joint_type, typestore=typestore)
        imu = writer.add_connection("/imu", imu_type, typestore=typestore)
        for index in range(round(seconds * 1000)):
            stamp = T0 + index * PERIOD_NS
            time_msg = t["builtin_interfaces/msg/Time"](stamp // 10**9, stamp % 10**9)
            header = t["std_msgs/msg/Header"](time_msg, "base")
            yaw = 0.1 * index / 1000.0
            quaternion = t["geometry_msgs/msg/Quaternion"](
                0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)
            )
            vector = t["geometry_msgs/msg/Vector3"]
            covariance = np.zeros(9)
            message = t[imu_type](
                header, quaternion, covariance, vector(0.0, 0.0, 0.1), covariance,
                vector(0.0, 0.0, 9.80665), covariance,
            )  # fmt: skip
            writer.write(imu, stamp, typestore.serialize_cdr(message, imu_type))
            angle = 2 * math.pi * 2.0 * index / 1000.0 + phase
            positions = base + np.array([0.0, 0.3, 0.4] * 4) * np.sin(angle)
            velocities = np.array([0.0, 0.3, 0.4] * 4) * 2 * math.pi * 2.0 * np.cos(angle)
            message = t[joint_type](header, names, positions, velocities, np.zeros(0))
            writer.write(joints, stamp, typestore.serialize_cdr(message, joint_type))
    return path


def measured(bag: Path, out: Path, causal: bool) -> tuple[float, float, float]:
    """Wall time, CPU time [s] and peak RSS [MB] of ``a1-leg-fk odom --csv``."""
    arguments = ["odom", str(bag), "--csv", str(out), "--quiet", "--force"]
    return measured_cli(arguments + (["--causal"] if causal else []))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="the long bag [s] at 1 kHz")
    options = parser.parse_args()
    print(machine())
    peaks: dict[tuple[float, bool], float] = {}
    with tempfile.TemporaryDirectory() as folder:
        print(
            f"{'bag':>8s} {'odom':>9s} {'wall s':>7s} {'cpu s':>7s} {'x real time (cpu)':>18s} "
            f"{'peak MB':>8s}"
        )
        lengths = (options.seconds / 3.0, options.seconds)
        for seconds in lengths:
            bag = generate(Path(folder) / f"bag{seconds:g}", seconds)
            for causal in (True, False):
                wall, cpu, peak = measured(bag, Path(folder) / "out.csv", causal)
                peaks[seconds, causal] = peak
                name = "causal" if causal else "smoothed"
                print(
                    f"{seconds:7.0f}s {name:>9s} {wall:7.1f} {cpu:7.1f} {seconds / cpu:18.1f} "
                    f"{peak:8.0f}"
                )
    for seconds in lengths:
        extra = peaks[seconds, False] - peaks[seconds, True]
        print(f"{seconds:7.0f}s: smoothing's extra peak {extra:6.1f} MB")
    for causal in (True, False):
        short, long = peaks[lengths[0], causal], peaks[lengths[1], causal]
        per_minute = (long - short) / ((lengths[1] - lengths[0]) / 60.0)
        hour = long + per_minute * (60.0 - lengths[1] / 60.0)
        name = "causal" if causal else "smoothed"
        print(
            f"{name}: peak grows {per_minute:5.1f} MB per recorded minute: ~{hour:.0f} MB for 1 h"
        )


if __name__ == "__main__":
    main()
