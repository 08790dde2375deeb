"""``leg_odometry_node``'s stamp-to-receipt latency with each IMU message published before its
joint state, and after it (the joint state then waits for it: ``imu_wait_s``), in one run.

Run: ``.venv/bin/python bench/imu_pairing_latency.py`` (about 40 s; ``--duration S``, ``--rate
HZ``). This process publishes JointState (the demo gait's angles and velocities, the A1's standing
efforts) and sensor_msgs/Imu (level, turning at 0.1 rad/s, feeling gravity: the state filter runs)
at ``--rate`` each, both stamped with the send time (``time.time_ns()``), in one order or the
other, and takes each ``leg_odometry`` message's latency as its receipt time minus its stamp.
Three nodes in turn: IMU first; IMU second; IMU second with ``imu_wait_s:=0`` (no waiting: the
previous IMU sample, as before issue 34's pairing). Each on a ROS domain of its own (``--domain``,
else 1 + pid % 100), LOCALHOST discovery. Prints p50 / p99 [ms] per case and the ratios against
the IMU-first case; exit 0.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine
from odometry_throughput import STANDING_EFFORTS, WARMUP_S

from a1_leg_fk.cli import common

CASES = (("IMU first", True, ()), ("IMU second", False, ()),
         ("IMU second, imu_wait_s 0", False, ("-p", "imu_wait_s:=0.0")))  # fmt: skip


def latencies(imu_first: bool, args: argparse.Namespace) -> np.ndarray:
    """[ms] of every answer over the measured window, the node under test already running."""
    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.qos import QoSProfile
    from sensor_msgs.msg import Imu, JointState

    from a1_leg_fk.gait.demo_gait import Gait, limits_of
    from a1_leg_fk.kinematics.quadruped import Quadruped

    node = rclpy.create_node(f"pairing_bench_{os.getpid()}")
    quadruped = Quadruped.from_urdf()
    gait = Gait(limits_of(quadruped))
    states = [gait.state(2.0 + k / args.rate) for k in range(int(args.rate))]
    joints, imu = JointState(), Imu()
    joints.name, joints.effort = list(quadruped.joint_names), STANDING_EFFORTS
    imu.orientation.w, imu.angular_velocity.z, imu.linear_acceleration.z = 1.0, 0.1, 9.80665
    joint_pub = node.create_publisher(JointState, "joint_states", QoSProfile(depth=100))
    imu_pub = node.create_publisher(Imu, "imu", QoSProfile(depth=100))
    received: list[float] = []

    def answer(msg: Odometry) -> None:
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        received.append((time.time_ns() - stamp) * 1e-6)

    node.create_subscription(Odometry, "leg_odometry", answer, QoSProfile(depth=1000))
    deadline = time.monotonic() + 30.0
    while node.count_publishers("leg_odometry") == 0 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    first, second = (imu_pub, joint_pub) if imu_first else (joint_pub, imu_pub)
    count, start, total = 0, time.perf_counter(), round((WARMUP_S + args.duration) * args.rate)
    while count < total:
        due = start + count / args.rate
        while time.perf_counter() < due:
            rclpy.spin_once(node, timeout_sec=max(0.0, due - time.perf_counter() - 0.0002))
        if count == round(WARMUP_S * args.rate):
            received.clear()
        stamp = time.time_ns()
        joints.position, joints.velocity = states[count % len(states)]
        for message in (imu, joints):
            message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 10**9)
        first.publish(imu if imu_first else joints)
        second.publish(joints if imu_first else imu)
        count += 1
    end = time.monotonic() + 0.5
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    node.destroy_node()
    return np.array(received)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=500.0, help="Hz of each stream (500)")
    parser.add_argument("--duration", type=float, default=8.0, help="measured s per case (8)")
    parser.add_argument("--domain", type=int, default=1 + os.getpid() % 100)
    args = parser.parse_args()
    os.environ.update(ROS_DOMAIN_ID=str(args.domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    import rclpy

    print(machine())
    rclpy.init()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name, imu_first, extra in CASES:
            command = common.child_command("leg_odometry_node", "a1_leg_fk.ros.leg_odometry_node")
            node = common.Child("node", [*command, "--ros-args", *extra], Path(folder) / "n.log")
            try:
                values = latencies(imu_first, args)
            finally:
                node.stop()
            rows.append((name, values))
    rclpy.try_shutdown()
    print(f"{args.rate:g} Hz joint_states + imu, {args.duration:g} s per case; stamp to receipt:")
    base = np.percentile(rows[0][1], [50, 99])
    for name, values in rows:
        p50, p99 = np.percentile(values, [50, 99]) if len(values) else (np.nan, np.nan)
        print(f"  {name:<26} {len(values):5d} answers  p50 {p50:6.2f} ms  p99 {p99:6.2f} ms  "
              f"(x{p50 / base[0]:.2f}, x{p99 / base[1]:.2f})")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
