"""Soak test of foot_fk_node: a 1 kHz joint-state stream with ~5 % bad or partial messages and a
verify_fk call every second, for ``--duration`` seconds (default 600; ``make soak``).

Three processes besides this one's: the node, and a foot collector (its own process, so that
counting 4000 feet/s does not compete with the publisher for this interpreter). Every second the
node's RSS (/proc/<pid>/status VmRSS) and CPU (/proc/<pid>/stat utime+stime) are sampled.

Exit 1 when
- the node's RSS at the end is more than ``--max-rss-growth`` (5 %) above its RSS at the end of
  the warm-up (the first 10 % of the run);
- a good message the node received was not published ("lost"). The node's input is best effort,
  so a message can also vanish before the node sees it; those are counted separately from the
  node's own /diagnostics (messages_received) and reported, not failed, unless they exceed
  ``--max-input-loss`` (default 1 %). A good message counts as lost by the node when more good
  messages came back without feet than the node's input loss can explain, or when only some of
  its four feet arrived, or when feet the node published never reached the collector;
- any verify_fk call fails or is not answered within 5 s;
- the node dies.

Run:  python bench/soak.py --duration 60        (ROS_DOMAIN_ID: the caller's, else a free one)
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import IO

from common import shared

from a1_leg_fk.cli.common import Child

VERIFY_TIMEOUT_S = 5.0


# --- the collector (a child process: `soak.py --collect OUT STOP`) -----------------------------


def collect(out: str, stop: str) -> int:
    """Record the stamp of every foot position until the file ``stop`` exists; dump to ``out``."""
    import rclpy
    from geometry_msgs.msg import PointStamped
    from rclpy.qos import QoSProfile

    try:
        from rclpy.experimental import EventsExecutor as Executor
    except ImportError:  # pragma: no cover (older rclpy)
        from rclpy.executors import SingleThreadedExecutor as Executor
    rclpy.init()
    node = rclpy.create_node("soak_foot_collector")
    stamps: dict[str, list[int]] = {}

    def recorder(leg: str):
        received = stamps[leg] = []
        return lambda msg: received.append(
            msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        )

    topics = [f"foot_positions/{leg}" for leg in shared.LEGS]
    for leg, topic in zip(shared.LEGS, topics):
        node.create_subscription(PointStamped, topic, recorder(leg), QoSProfile(depth=10000))
    executor = Executor()
    executor.add_node(node)
    while not all(node.count_publishers(node.resolve_topic_name(t)) for t in topics):
        executor.spin_once(timeout_sec=0.05)
    print("ready", flush=True)
    while not os.path.exists(stop):
        executor.spin_once(timeout_sec=0.05)
    deadline = time.monotonic() + 1.0
    while time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    Path(out).write_text(json.dumps(stamps))
    node.destroy_node()
    rclpy.shutdown()
    return 0


# --- helpers -----------------------------------------------------------------------------------


def use_a_free_domain() -> IO[str] | None:
    """Use the caller's ROS_DOMAIN_ID, else claim a free one (the test suite's lock) and set it.

    Returns the lock file to hold until exit (None for the caller's domain).
    """
    if os.environ.get("ROS_DOMAIN_ID"):
        return None
    try:
        domain_id, lock = shared.claim_domain_id()
    except RuntimeError as error:
        raise SystemExit(f"soak: {error}") from None
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    return lock


class Stream:
    """The message mix: good full messages, and ~bad_fraction of partial or bad ones."""

    def __init__(self, bad_fraction: float, seed: int) -> None:
        self.rng = random.Random(seed)
        self.bad_fraction = bad_fraction
        self.kinds: dict[str, int] = {}

    def next(self) -> tuple[bool, list[str], list[float], list[float]]:
        """(good, names, positions, velocities)."""
        rng = self.rng
        angles = [rng.uniform(-0.8, 0.8), rng.uniform(-0.5, 2.0), rng.uniform(-2.6, -0.9)] * 4
        rates = [rng.uniform(-5.0, 5.0) for _ in range(12)]
        if rng.random() >= self.bad_fraction:
            return True, shared.PYBULLET_NAMES, angles, rates
        kind = rng.choice(
            [
                "partial",
                "position_length",
                "velocity_length",
                "duplicate",
                "nan",
                "one_nan",
                "unknown",
                "empty",
            ]
        )
        self.kinds[kind] = self.kinds.get(kind, 0) + 1
        names = list(rng.choice([shared.PYBULLET_NAMES, shared.UNITREE_NAMES]))
        if kind == "partial":
            keep = sorted(rng.sample(range(12), rng.randint(1, 11)))
            return (
                False,
                [names[i] for i in keep],
                [angles[i] for i in keep],
                [rates[i] for i in keep],
            )
        if kind == "position_length":
            return False, names, angles[: rng.randint(0, 11)], rates
        if kind == "velocity_length":
            return False, names, angles, rates[:5]
        if kind == "duplicate":
            return False, [*names, names[0]], [*angles, 0.1], []
        if kind == "nan":
            return False, names, [math.nan] * 12, rates
        if kind == "one_nan":
            angles[rng.randrange(12)] = rng.choice([math.nan, math.inf, -math.inf])
            return False, names, angles, rates
        if kind == "unknown":
            return False, ["arm_joint_1", "gripper", "ünknown"], [0.1, 0.2, 0.3], []
        return False, [], [], []


# --- the soak ----------------------------------------------------------------------------------


def soak(args: argparse.Namespace) -> int:
    domain_lock = use_a_free_domain()  # noqa: F841 (held until exit)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from node_harness import joint_state_message
    from rclpy.qos import QoSProfile
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger

    folder = args.logs or Path(tempfile.mkdtemp(prefix="a1_leg_fk_soak_"))
    node_log = folder / "node.log"
    stop, feet_file = folder / "stop", folder / "feet.json"
    children: list[Child] = []

    def start(name: str, command: list[str], log: Path) -> subprocess.Popen:
        children.append(Child(name, command, log))
        return children[-1].process

    print(
        f"soak: {args.duration:g} s at {args.rate:g} Hz, ~{100 * args.bad_fraction:g} % "
        f"bad/partial, verify every {args.verify_period:g} s; "
        f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']}; logs in {folder}",
        flush=True,
    )
    node_process = start("foot_fk_node", shared.node_command(), node_log)
    collector = start(
        "collector",
        [sys.executable, __file__, "--collect", str(feet_file), str(stop)],
        folder / "collector.log",
    )

    rclpy.init()
    node = rclpy.create_node("soak_driver")
    publisher = node.create_publisher(JointState, "joint_states", QoSProfile(depth=10000))
    # Deep response history: every client's reader receives every reply (see troubleshooting).
    verify = node.create_client(Trigger, "verify_fk", qos_profile=QoSProfile(depth=1000))
    diagnostics: list[dict[str, str]] = []

    def on_diagnostics(msg: DiagnosticArray) -> None:
        diagnostics.extend(
            {kv.key: kv.value for kv in status.values}
            for status in msg.status
            if status.name.endswith("foot kinematics")
        )

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, QoSProfile(depth=10))

    def spin_until(condition, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while not condition():
            if time.monotonic() > deadline or node_process.poll() is not None:
                return False
            rclpy.spin_once(node, timeout_sec=0.02)
        return True

    def fresh_diagnostics() -> dict[str, str]:
        seen = len(diagnostics)
        if not spin_until(lambda: len(diagnostics) > seen, 5.0):
            raise RuntimeError("no /diagnostics from the node")
        return diagnostics[-1]

    failures: list[str] = []
    try:
        if not verify.wait_for_service(timeout_sec=30.0) or not spin_until(
            lambda: publisher.get_subscription_count() > 0, 30.0
        ):
            raise RuntimeError("the node did not come up")
        if not spin_until(lambda: "ready" in (folder / "collector.log").read_text(), 60.0):
            raise RuntimeError("the foot collector did not come up")
        now_ns = node.get_clock().now().nanoseconds
        publisher.publish(
            joint_state_message(
                shared.PYBULLET_NAMES, shared.STANDING, [0.0] * 12, stamp_ns=now_ns
            )
        )
        spin_until(lambda: False, 0.5)
        before = fresh_diagnostics()

        stream = Stream(args.bad_fraction, args.seed)
        good_stamps: list[int] = []
        all_stamps: set[int] = set()
        sent = 0
        samples: list[tuple[float, float, float]] = []  # (t, rss MB, cpu s)
        verify_calls = verify_failed = 0
        pending = None  # (future, sent at)
        period = 1.0 / args.rate
        start_time = time.monotonic()
        next_due, next_sample, next_verify = (
            start_time,
            start_time,
            start_time + args.verify_period,
        )
        end_time = start_time + args.duration
        last_stamp = 0
        while next_due < end_time:
            now = time.monotonic()
            behind = 0
            while next_due <= now and behind < 50:  # publish what is due (catch up a little)
                good, names, positions, velocities = stream.next()
                # Unique stamps (they identify messages): now, or just after the last one.
                stamp = max(node.get_clock().now().nanoseconds, last_stamp + 1)
                last_stamp = stamp
                publisher.publish(
                    joint_state_message(names, positions, velocities, stamp_ns=stamp)
                )
                sent += 1
                all_stamps.add(stamp)
                if good:
                    good_stamps.append(stamp)
                next_due += period
                behind += 1
            if next_due <= now - 0.1:  # more than 100 ms behind: skip ahead rather than burst
                next_due = now
            if now >= next_sample:
                if node_process.poll() is not None:
                    raise RuntimeError(f"the node exited with {node_process.returncode}")
                samples.append(
                    (
                        now - start_time,
                        shared.rss_mb(node_process.pid),
                        shared.cpu_seconds(node_process.pid),
                    )
                )
                next_sample += 1.0
            if pending is not None:
                future, asked = pending
                if future.done():
                    response = future.result()
                    if not response.success:
                        verify_failed += 1
                        failures.append(f"verify_fk failed: {response.message}")
                    pending = None
                elif now - asked > VERIFY_TIMEOUT_S:
                    verify.remove_pending_request(future)
                    verify_failed += 1
                    failures.append("verify_fk not answered within 5 s")
                    pending = None
            if pending is None and now >= next_verify:
                pending = (verify.call_async(Trigger.Request()), now)
                verify_calls += 1
                next_verify += args.verify_period
            rclpy.spin_once(node, timeout_sec=max(0.0, min(next_due - time.monotonic(), 0.001)))
        elapsed = time.monotonic() - start_time
        if pending is not None and not spin_until(pending[0].done, VERIFY_TIMEOUT_S):
            verify_failed += 1
            failures.append("verify_fk not answered within 5 s")
        spin_until(lambda: False, 1.0)
        after = fresh_diagnostics()
        stop.touch()
        collector.wait(30)
        received = json.loads(feet_file.read_text())
    except Exception as error:  # noqa: BLE001 (reported as the soak's failure)
        print(f"soak: FAILED: {error}", file=sys.stderr)
        print(node_log.read_text()[-3000:], file=sys.stderr)
        return 1
    finally:
        stop.touch()
        for child in children:
            child.stop(signal.SIGINT, timeout_s=10)
        node.destroy_node()
        rclpy.try_shutdown()

    # --- accounting ---------------------------------------------------------------------------
    feet = {leg: set(received.get(leg, ())) for leg in shared.LEGS}
    feet_received = sum(len(stamps & all_stamps) for stamps in feet.values())
    complete = partial = missing = 0
    for stamp in good_stamps:
        legs = sum(stamp in feet[leg] for leg in shared.LEGS)
        complete += legs == 4
        partial += 0 < legs < 4
        missing += legs == 0
    node_received = int(after["messages_received"]) - int(before["messages_received"])
    node_published = int(after["feet_published"]) - int(before["feet_published"])
    input_lost = sent - node_received
    output_lost = node_published - feet_received
    lost_by_node = (
        max(0, missing - input_lost) + partial
    )  # good messages received but not (fully) published
    warm = [s for s in samples if s[0] >= args.warmup_fraction * elapsed]
    rss_warm = warm[0][1] if warm else math.nan
    rss_end = samples[-1][1] if samples else math.nan
    rss_max = max((s[1] for s in warm), default=math.nan)
    cpu_per_s = [
        (b[2] - a[2]) / (b[0] - a[0]) for a, b in itertools.pairwise(samples) if b[0] > a[0]
    ]
    summary = {
        "duration_s": round(elapsed, 1),
        "rate_hz": args.rate,
        "messages_sent": sent,
        "good_messages": len(good_stamps),
        "bad_or_partial": dict(sorted(stream.kinds.items())),
        "node_received": node_received,
        "input_lost_before_node": input_lost,
        "node_feet_published": node_published,
        "feet_received": feet_received,
        "output_lost_after_node": output_lost,
        "good_with_4_feet": complete,
        "good_with_some_feet": partial,
        "good_without_feet": missing,
        "lost_by_node": lost_by_node,
        "rss_start_mb": round(samples[0][1], 1) if samples else None,
        "rss_after_warmup_mb": round(rss_warm, 1),
        "rss_end_mb": round(rss_end, 1),
        "rss_max_after_warmup_mb": round(rss_max, 1),
        "cpu_mean_percent": round(100 * sum(cpu_per_s) / len(cpu_per_s), 1) if cpu_per_s else None,
        "cpu_max_percent": round(100 * max(cpu_per_s), 1) if cpu_per_s else None,
        "verify_calls": verify_calls,
        "verify_failed": verify_failed,
        "stamp_jumps_back": after.get("stamp_jumps_back"),
    }
    print(
        "soak summary:\n" + "\n".join(f"  {key}: {value}" for key, value in summary.items()),
        flush=True,
    )
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1))
    if rss_end > rss_warm * (1.0 + args.max_rss_growth):
        failures.append(
            f"RSS grew {rss_warm:.1f} -> {rss_end:.1f} MB after warm-up (> "
            f"{100 * args.max_rss_growth:g} %)"
        )
    if lost_by_node or output_lost:
        failures.append(
            f"feet lost: {lost_by_node} good messages by the node, {output_lost} feet after it"
        )
    if input_lost > args.max_input_loss * sent:
        failures.append(
            f"the node's best-effort input lost {input_lost} of {sent} messages (> "
            f"{100 * args.max_input_loss:g} %)"
        )
    elif input_lost:
        print(
            f"soak: note: {input_lost} of {sent} messages ({100 * input_lost / sent:.2f} %) "
            "never reached the node (best-effort input under load; not counted as lost by the "
            "node)"
        )
    for failure in failures[:10]:
        print(f"soak: FAIL: {failure}", file=sys.stderr)
    print("soak: " + ("FAILED" if failures else "passed"), flush=True)
    return 1 if failures else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--duration", type=float, default=600.0, help="seconds of streaming (default 600)"
    )
    parser.add_argument(
        "--rate", type=float, default=1000.0, help="joint states per second (default 1000)"
    )
    parser.add_argument(
        "--bad-fraction", type=float, default=0.05, help="share of bad/partial messages (0.05)"
    )
    parser.add_argument(
        "--verify-period", type=float, default=1.0, help="seconds between verify_fk calls (1)"
    )
    parser.add_argument(
        "--warmup-fraction", type=float, default=0.1, help="share of the run before RSS is judged"
    )
    parser.add_argument(
        "--max-rss-growth",
        type=float,
        default=0.05,
        help="allowed RSS growth after warm-up (0.05)",
    )
    parser.add_argument(
        "--max-input-loss", type=float, default=0.01, help="allowed best-effort input loss (0.01)"
    )
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", help="also write the summary to this file")
    parser.add_argument(
        "--logs",
        type=Path,
        help="the folder for the node's and the collector's logs (default: a new temporary one)",
    )
    parser.add_argument("--collect", nargs=2, metavar=("OUT", "STOP"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.collect:
        return collect(*args.collect)
    if args.logs is not None:
        try:
            args.logs.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            parser.error(f"--logs {args.logs}: {error.strerror or error}")
    return soak(args)


if __name__ == "__main__":
    sys.exit(main())
