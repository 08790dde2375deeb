"""The node's CPU per input against the raw floor's, side by side: both answer the same JointState
stream at the same time, so whatever else the machine runs weighs on both alike.

Run: ``.venv/bin/python bench/node_cost.py`` (about 2 min; ``--rounds N``, ``--phase S``). On a
shared machine, phases run one after the other (``bench/node_throughput.py``: the node's, then the
floor's) see different loads from other processes, and their CPU ratio wanders by +-20 %. Here one
load generator (``bench/throughput_roles.py generator``, 1 kHz) publishes ``/joint_states`` and two
processes take every message at once: ``foot_fk_node`` (namespace ``/node``) and the raw floor
(``throughput_roles.py baseline``, namespace ``/floor``: the stamp read from the bytes, the same
pre-serialized messages out, no decoding, no rules, no FK). Each has its own receiver
(``throughput_roles.py receiver``) taking all of its outputs, as a reliable reader would
(``--floor-raw``: the floor publishes as the node does, through
``a1_leg_fk.ros.serialized_output.raw_publish``, not ``Publisher.publish``). Each round runs a
phase without efforts (the node publishes the 4 feet, their 4 velocities and ``foot_contacts``; the
floor the same 9 messages) and one with efforts (also the 4 ``foot_forces``; the node runs the
momentum observer and the filter on forces). Per phase: each process's CPU (utime + stime,
/proc/<pid>/stat), the inputs it answered (its ``foot_positions/FR`` messages in the phase's stamp
window, counted by their DDS sequence numbers), and the CPU per answered input; the ratio is the
node's per-input CPU over the floor's. The summary gives, per kind of phase, the ratios of every
round (min, median, max): the spread is the figure, not one run.

Every process runs on one ROS_DOMAIN_ID of its own (``--domain``, else $BENCH_ROS_DOMAIN_ID, else 1
+ pid % 100) with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST; all are stopped at the end, on Ctrl-C
and on SIGTERM.
"""

from __future__ import annotations

import argparse
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine
from node_throughput import (
    DRAIN_S,
    ROLES,
    Child,
    Phase,
    add_process_arguments,
    analyse,
    choose_domain,
    machine_busy_s,
    process_env,
    run_children,
)

RATE_HZ = 1000.0
GOAL_RATIO = 1.2
CLEAN_SHARE = 0.99
KINDS = ("without efforts", "with efforts")


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5, help="rounds of both phases (5)")
    parser.add_argument("--phase", type=float, default=10.0, help="seconds per phase (10)")
    parser.add_argument(
        "--floor-raw",
        action="store_true",
        help="the floor publishes as the node does (raw_publish, without rclpy's per-call "
        "wrapper), not with Publisher.publish",
    )
    add_process_arguments(parser)
    args = parser.parse_args()
    choose_domain(args)
    return args


def in_namespace(namespace: str) -> list[str]:
    """ROS arguments: the process in ``namespace``, its ``joint_states`` the generator's."""
    return ["--ros-args", "-r", f"__ns:=/{namespace}", "-r", "joint_states:=/joint_states"]


def count_answers(records: list[dict], phases: dict[str, list[Phase]], log_dir: Path) -> None:
    """Each record's inputs answered by node and floor: the messages each published on
    ``foot_positions/FR`` in the phase's stamp window, from the DDS sequence numbers its receiver
    saw (an answer the receiver missed still counts), and the share its receiver got.
    """
    for name, named in phases.items():
        analyse(named, np.load(log_dir / f"{name}.npz"))
        for record, phase in zip(records, named, strict=True):
            record[f"{name}_answered"] = phase.result["answered"]
            record[f"{name}_received"] = 1.0 - phase.result["foot_loss"]


def run(args: argparse.Namespace, log_dir: Path, children: list[Child]) -> list[dict]:
    """Start the processes, run the rounds; one record per phase."""
    env = process_env(args)
    python, roles = sys.executable, str(ROLES)

    def start(name: str, command: list[str]) -> Child:
        child = Child(name, command, env, log_dir)
        children.append(child)
        return child

    receivers = {
        name: start(
            f"{name}-receiver",
            [python, roles, "receiver", str(log_dir / f"{name}.npz"), *in_namespace(name)],
        )
        for name in ("node", "floor")
    }
    generator = start("generator", [python, roles, "generator"])
    for child in (*receivers.values(), generator):
        child.wait_event("up", 30)
    time.sleep(0.5)
    floor_options = ["--raw-publish"] if args.floor_raw else []
    under_test = {
        "node": start("node", [python, "-m", "a1_leg_fk.ros.foot_fk_node", *in_namespace("node")]),
        "floor": start(
            "floor",
            [python, roles, "baseline", "node", *floor_options, *in_namespace("floor")],
        ),
    }
    for receiver in receivers.values():
        receiver.wait_event("ready", 60)
    time.sleep(1.0)  # discovery settles; warm-up traffic stops at the first phase
    records: list[dict] = []
    phases: dict[str, list[Phase]] = {name: [] for name in under_test}
    for round_index in range(args.rounds):
        for kind in KINDS:
            efforts = kind == "with efforts"
            under_test["floor"].send(op="phase", efforts=efforts)
            time.sleep(0.3)
            generator.send(op="phase", rate=RATE_HZ, duration=args.phase, efforts=efforts)
            generator.wait_event("phase_start", 10)
            cpu0 = {name: child.cpu_s() for name, child in under_test.items()}
            busy0 = machine_busy_s()
            end = generator.wait_event("phase_end", args.phase * 3 + 15)
            cpu1 = {name: child.cpu_s() for name, child in under_test.items()}
            busy1 = machine_busy_s()
            time.sleep(DRAIN_S)
            record: dict = {"round": round_index + 1, "kind": kind, "sent": end["sent"]}
            for name in under_test:
                record[f"{name}_cpu_s"] = cpu1[name] - cpu0[name]
                phases[name].append(Phase(kind, RATE_HZ, args.phase, result=dict(end)))
            ours = record["node_cpu_s"] + record["floor_cpu_s"]
            record["others_pct"] = 100 * max(0.0, busy1 - busy0 - ours) / end["elapsed_s"]
            record["elapsed_s"] = end["elapsed_s"]
            records.append(record)
            print(f"  round {round_index + 1}, {kind}: done", flush=True)
    generator.send(op="stop")
    for name, receiver in receivers.items():
        under_test[name].stop(signal.SIGINT, timeout_s=3)
        receiver.send(op="stop")
        receiver.wait_event("done", 30)
    count_answers(records, phases, log_dir)
    return records


def per_input_us(record: dict, name: str) -> float:
    """A process's CPU [us] per input it answered in a phase."""
    return 1e6 * record[f"{name}_cpu_s"] / max(record[f"{name}_answered"], 1)


def ratio(record: dict) -> float:
    """The node's CPU per answered input over the floor's."""
    return per_input_us(record, "node") / per_input_us(record, "floor")


def row(record: dict) -> str:
    """One phase as a line of the table."""
    sent = record["sent"]
    return (
        f"{record['round']:>5} {record['kind']:<16} {sent:>6} "
        f"{record['node_answered'] / sent:>8.2%} {record['floor_answered'] / sent:>8.2%} "
        f"{min(record['node_received'], record['floor_received']):>8.2%} "
        f"{100 * record['node_cpu_s'] / record['elapsed_s']:>7.1f} "
        f"{100 * record['floor_cpu_s'] / record['elapsed_s']:>7.1f} "
        f"{per_input_us(record, 'node'):>8.0f} {per_input_us(record, 'floor'):>8.0f} "
        f"{record['others_pct']:>8.0f} {ratio(record):>6.2f}x"
    )


def summary(records: list[dict]) -> None:
    """Per kind of phase: the ratios of every round, their min, median and max; the median CPU
    per input of node and floor; and the rounds in which both answered at least
    :data:`CLEAN_SHARE` of the inputs (a process that drops inputs still received them, so its
    CPU per answered input reads high).
    """
    for kind in KINDS:
        rounds = [r for r in records if r["kind"] == kind]
        if not rounds:
            continue
        ratios = sorted(ratio(r) for r in rounds)
        clean = sorted(
            ratio(r)
            for r in rounds
            if min(r["node_answered"], r["floor_answered"]) >= CLEAN_SHARE * r["sent"]
        )
        node_us = statistics.median(per_input_us(r, "node") for r in rounds)
        floor_us = statistics.median(per_input_us(r, "floor") for r in rounds)
        print(
            f"  {kind}: node/floor {', '.join(f'{x:.2f}' for x in ratios)} -> min "
            f"{ratios[0]:.2f}x, median {statistics.median(ratios):.2f}x, max {ratios[-1]:.2f}x "
            f"({sum(x <= GOAL_RATIO for x in ratios)}/{len(ratios)} rounds <= {GOAL_RATIO}x); "
            f"median CPU per input: node {node_us:.0f} us, floor {floor_us:.0f} us, difference "
            f"{node_us - floor_us:.0f} us; rounds without loss (both >= {CLEAN_SHARE:.0%} "
            f"answered): {', '.join(f'{x:.2f}' for x in clean) or 'none'}"
        )


def main() -> int:
    args = parse_args()
    log_dir = Path(tempfile.mkdtemp(prefix="a1_leg_fk-cost-"))
    children: list[Child] = []

    print(machine())
    print(
        f"node_cost: {args.rounds} rounds of 2 x {args.phase:.0f} s at {RATE_HZ:.0f} Hz on "
        f"ROS_DOMAIN_ID={args.domain}, node and raw floor side by side (the floor publishing "
        f"{'as the node does, raw_publish' if args.floor_raw else 'with Publisher.publish'})"
    )

    def work() -> None:
        records = run(args, log_dir, children)
        print(
            f"{'round':>5} {'phase':<16} {'inputs':>6} {'node ans':>8} {'floor ans':>8} "
            f"{'rx':>8} {'node %':>7} {'floor %':>7} {'node us':>8} {'floor us':>8} "
            f"{'others%':>8} {'ratio':>7}"
        )
        for record in records:
            print(row(record))
        print(
            "(ans: inputs answered, by the outputs' DDS sequence numbers; rx: the share of the\n"
            " outputs the worse receiver got; CPU % of one core; us: CPU per answered input;\n"
            " others: CPU % of processes outside this benchmark; ratio: node us / floor us)"
        )
        summary(records)

    return run_children("node_cost", work, children, log_dir, keep_logs=False)


if __name__ == "__main__":
    sys.exit(main())
