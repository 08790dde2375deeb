"""CPU of ``leg_odometry_node`` against ``foot_fk_node`` alone, at the same load, in one run.

Run: ``.venv/bin/python bench/odometry_throughput.py`` (about 40 s; ``--duration S``, ``--rate
HZ``). A load generator publishes JointState (12 joints, the demo gait's angles and velocities, and
the efforts of the A1 standing in PyBullet, docs/forces.md, unless ``--no-efforts``: so
leg_odometry_node estimates the foot forces and takes its contacts from them; stamp = send time)
and sensor_msgs/Imu (level, turning at 0.1 rad/s, its accelerometer feeling gravity: the state
filter runs; same stamps) at ``--rate``
each, paced on perf_counter, for ``--duration`` seconds after a 2 s warm-up; it counts what the
node under test answers (``foot_positions/FR`` or ``leg_odometry``). The node's CPU is
(utime + stime) from /proc over the measured window. Each node runs twice, alternately
(foot_fk_node, leg_odometry_node, foot_fk_node, leg_odometry_node), on a ROS domain of its own
(``--domain``, else 1 + pid % 100), LOCALHOST discovery. The goal (issue 27): leg_odometry_node's
CPU <= 1.5 x foot_fk_node's (with efforts: both estimate the foot forces and contacts). Exit 0
after the table, whether or not the goal is met.

``--role generator`` is the generator itself (started by this script).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

from common import machine, shared

from a1_leg_fk.cli import common

GOAL_RATIO = 1.5
WARMUP_S = 2.0
STANDING_EFFORTS = [1.08, -2.88, 2.42, -1.0, -3.08, 2.26, -1.86, 2.71, 5.02, 1.71, 2.8, 5.22]
"""[N m]: the A1 standing in PyBullet (docs/forces.md): ~30 N on each foot."""


def generator(
    rate: float, duration: float, answer_topic: str, answer_type: str, efforts: bool
) -> None:
    """Publish joint states and IMU samples; print JSON lines "start", then "end" with counts."""
    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.qos import QoSProfile
    from sensor_msgs.msg import Imu, JointState

    from a1_leg_fk.gait.demo_gait import Gait, limits_of
    from a1_leg_fk.kinematics.quadruped import Quadruped

    rclpy.init()
    node = rclpy.create_node(f"odometry_bench_{os.getpid()}")
    quadruped = Quadruped.from_urdf()
    gait = Gait(limits_of(quadruped))
    states = [gait.state(2.0 + k / rate) for k in range(int(rate))]  # one second, cycled
    joints, imu = JointState(), Imu()
    joints.name = list(quadruped.joint_names)
    joints.effort = STANDING_EFFORTS if efforts else []
    imu.orientation.w, imu.angular_velocity.z = 1.0, 0.1
    imu.linear_acceleration.z = 9.80665  # an accelerometer: the state filter runs
    joint_pub = node.create_publisher(JointState, "joint_states", QoSProfile(depth=100))
    imu_pub = node.create_publisher(Imu, "imu", QoSProfile(depth=100))
    answers = [0]
    kind = (
        Odometry
        if answer_type == "odometry"
        else __import__("geometry_msgs.msg", fromlist=["PointStamped"]).PointStamped
    )
    node.create_subscription(
        kind,
        answer_topic,
        lambda _msg: answers.__setitem__(0, answers[0] + 1),
        QoSProfile(depth=1000),
    )
    deadline = time.monotonic() + 30.0
    while joint_pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)

    def publish(seconds: float) -> int:
        count, start = 0, time.perf_counter()
        total = round(seconds * rate)
        while count < total:
            due = start + count / rate
            while time.perf_counter() < due:
                rclpy.spin_once(node, timeout_sec=max(0.0, due - time.perf_counter() - 0.0002))
            stamp = time.time_ns()
            angles, velocities = states[count % len(states)]
            for message in (imu, joints):
                message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 10**9)
            imu_pub.publish(imu)
            joints.position, joints.velocity = angles, velocities
            joint_pub.publish(joints)
            count += 1
        return count

    publish(WARMUP_S)
    answers[0] = 0
    print(json.dumps({"event": "start"}), flush=True)
    sent = publish(duration)
    print(json.dumps({"event": "end", "sent": sent}), flush=True)
    end = time.monotonic() + 0.5
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    print(json.dumps({"event": "answers", "answers": answers[0]}), flush=True)
    node.destroy_node()
    rclpy.try_shutdown()


def measure(name: str, script: str, module: str, args: argparse.Namespace, logs: Path) -> dict:
    """One node under the generator's load: its CPU [% of a core] and answers over the window."""
    env = {
        **os.environ,
        "ROS_DOMAIN_ID": str(args.domain),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    }
    node = common.Child(name, common.child_command(script, module), logs / f"{name}.log", env=env)
    answer = ("leg_odometry", "odometry") if "odometry" in name else ("foot_positions/FR", "point")
    command = [
        sys.executable,
        __file__,
        "--role",
        "generator",
        "--rate",
        str(args.rate),
        "--duration",
        str(args.duration),
        "--answer-topic",
        answer[0],
        "--answer-type",
        answer[1],
        *(["--no-efforts"] if args.no_efforts else []),
    ]
    load = common.Child("generator", command, logs / "generator.log", env=env, pipes=True)
    result: dict = {"node": name}
    try:
        for line in load.process.stdout:  # type: ignore[union-attr]
            event = json.loads(line)
            if event["event"] == "start":
                cpu, started = shared.cpu_seconds(node.process.pid), time.monotonic()
            elif event["event"] == "end":
                result["cpu_pct"] = (
                    100
                    * (shared.cpu_seconds(node.process.pid) - cpu)
                    / (time.monotonic() - started)
                )
                result["sent"] = event["sent"]
            elif event["event"] == "answers":
                result["answers"] = event["answers"]
                break
    finally:
        load.stop()
        node.stop()
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--role", choices=("generator",))
    parser.add_argument(
        "--rate", type=float, default=1000.0, help="Hz of each stream (default 1000)"
    )
    parser.add_argument(
        "--duration", type=float, default=8.0, help="measured seconds per run (default 8)"
    )
    parser.add_argument("--domain", type=int, default=1 + os.getpid() % 100)
    parser.add_argument("--answer-topic", default="")
    parser.add_argument("--answer-type", default="")
    parser.add_argument(
        "--no-efforts",
        action="store_true",
        help="joint states without efforts (leg_odometry_node: kinematic stance)",
    )
    args = parser.parse_args()
    if args.role == "generator":
        generator(
            args.rate, args.duration, args.answer_topic, args.answer_type, not args.no_efforts
        )
        return 0
    print(machine())
    nodes = [
        ("foot_fk_node", "foot_fk_node", "a1_leg_fk.ros.foot_fk_node"),
        ("leg_odometry_node", "leg_odometry_node", "a1_leg_fk.ros.leg_odometry_node"),
    ]
    results: dict[str, list[dict]] = {name: [] for name, _, _ in nodes}
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(2):
            for name, script, module in nodes:
                results[name].append(measure(name, script, module, args, Path(folder)))
    print(
        f"{args.rate:g} Hz joint_states ({'without' if args.no_efforts else 'with'} efforts) + "
        f"{args.rate:g} Hz imu, {args.duration:g} s per run:"
    )
    for name, runs in results.items():
        for r in runs:
            print(
                f"  {name:<18} CPU {r.get('cpu_pct', float('nan')):6.1f} %  answered "
                f"{r.get('answers', 0)} of {r.get('sent', 0)}"
            )
    mean = {
        name: sum(r.get("cpu_pct", float("nan")) for r in runs) / len(runs)
        for name, runs in results.items()
    }
    ratio = mean["leg_odometry_node"] / mean["foot_fk_node"]
    verdict = "met" if ratio <= GOAL_RATIO else "NOT met"
    print(
        f"ratio leg_odometry_node / foot_fk_node CPU: {ratio:.2f}x "
        f"(goal <= {GOAL_RATIO}x: {verdict})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
