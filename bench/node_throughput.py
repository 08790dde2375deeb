"""Throughput, loss, latency and CPU of ``foot_fk_node`` beside the raw floor, in one run.

Run: ``.venv/bin/python bench/node_throughput.py`` (about 3.5 min; ``--quick``: about 30 s;
``--duration S`` sets the main 1 kHz run). Every process runs on one ROS_DOMAIN_ID of its own
(``--domain``, else $BENCH_ROS_DOMAIN_ID, else 1 + pid % 100) with
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST; all are stopped at the end, on Ctrl-C and on SIGTERM.
Exit status 0 after the table, whether or not the goals are met (they are printed).

Processes (bench/throughput_roles.py): a load generator (JointState, 12 joints with positions and
velocities, stamp = send time, header.frame_id = sequence number, paced on perf_counter), the
node under test (``python -m a1_leg_fk.ros.foot_fk_node``, or the raw-floor baseline: raw
JointState in, nine pre-serialized messages out (those of the node: the feet, their velocities,
foot_contacts), no FK), a receiver of the eight
output topics (raw CDR, its own wait set; latency uses the DDS reception time, so the receiver's
Python speed does not enter it) and, in one phase, a ``verify_fk`` caller at 20 Hz.

Scenarios
1. node, startup: the generator already publishes (100 Hz) when the node process is started;
   startup = the first received foot's source (publish) time - the node's process start.
2. node at 1 kHz for ``--duration``; then the same with joint efforts in every JointState (the
   node also publishes foot_forces/<leg> and foot_contacts, which the receiver takes too; the
   CPU ratio to the run without efforts is printed); then at 1 kHz with verify_fk called 20
   times a second.
3. node ramp: 5 s steps of rising rate, until two steps in a row lose >= 0.1 % of the inputs.
4. baseline (the raw floor, same executor and QoS) at 1 kHz; at 1 kHz with efforts (the floor
   then also publishes the four force messages, pre-serialized: what delivering them costs any
   node; the split of the node's extra cost between that and its own work is printed); the
   same ramp.

Definitions (per phase; inputs are matched to outputs by their stamp)
- in Hz: messages the generator sent / the phase's duration (what it achieved, not the target);
- input loss: 1 - inputs the node answered / inputs sent. "answered" = the number of messages the
  node published on foot_positions/FR in the phase, from the publisher's DDS sequence numbers
  (so an output that the receiver missed still counts as answered);
- foot loss: 1 - outputs received / outputs published (all eight topics, by sequence numbers):
  what got lost between node and receiver, i.e. the receiver's own loss;
- out Hz: answered inputs / duration; latency: DDS reception time of each PointStamped - the
  JointState's stamp (positions topics only);
- CPU: (utime + stime) from /proc/<pid>/stat over the phase, % of one core.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import queue
import re
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from common import ROOT, machine, shared

from a1_leg_fk.cli import common

HERE = Path(__file__).resolve().parent
ROLES = HERE / "throughput_roles.py"
LOSS_LIMIT = 0.001  # a ramp step passes below 0.1 % input and foot loss
RATE_KEPT = 0.97  # ... and when the generator achieved 97 % of the step's rate
DRAIN_S = 0.4  # after a phase, for the last outputs to arrive
GOALS = {
    "p50_ms": 1.0,
    "p99_ms": 5.0,
    "cpu_pct": 40.0,
    "cpu_ratio": 1.2,
    "forces_cpu_ratio": 1.25,
    "ratio": 0.90,
    "max_rate_hz": 2000.0,
    "startup_s": 2.0,
}


@dataclass
class Phase:
    name: str
    rate: float
    duration: float
    verify: bool = False
    ramp: bool = False
    efforts: bool = False  # the JointStates carry efforts: the node publishes forces, contacts
    result: dict = field(default_factory=dict)


def machine_busy_s() -> float:
    """CPU seconds the whole machine has been busy (all cores; /proc/stat, idle and iowait
    excluded)."""
    fields = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:9]]
    return (sum(fields) - fields[3] - fields[4]) / shared.CLOCK_TICKS


class Child(common.Child):
    """A role process (its own session; SIGKILL should the orchestrator die) with JSON-lines events
    on stdout, collected by a thread, and its stderr in ``<log_dir>/<name>.log``."""

    def __init__(self, name: str, command: list[str], env: dict[str, str], log_dir: Path) -> None:
        self.events: queue.Queue[dict] = queue.Queue()
        self.started_ns = time.time_ns()
        super().__init__(
            name,
            command,
            log_dir / f"{name}.log",
            env=env,
            cwd=env["PYTHONPATH"].split(os.pathsep)[0],
            pipes=True,
            death_signal=signal.SIGKILL,
        )
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None  # started with pipes=True
        for line in self.process.stdout:
            try:
                self.events.put(json.loads(line))
            except json.JSONDecodeError:
                with self.log.open("a") as log:
                    log.write(line)

    def send(self, **command: object) -> None:
        assert self.process.stdin is not None  # started with pipes=True
        try:
            self.process.stdin.write(json.dumps(command) + "\n")
            self.process.stdin.flush()
        except (BrokenPipeError, OSError):
            pass

    def wait_event(self, kind: str, timeout: float) -> dict:
        deadline = time.monotonic() + timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(
                    f"{self.name}: no '{kind}' within {timeout:.0f} s (log: {self.log})"
                )
            if self.process.poll() is not None and self.events.empty():
                raise RuntimeError(
                    f"{self.name} exited with {self.process.returncode} (log: {self.log})"
                )
            try:
                event = self.events.get(timeout=min(remaining, 0.2))
            except queue.Empty:
                continue
            if event.get("event") == kind:
                return event

    def cpu_s(self) -> float:
        try:
            return shared.cpu_seconds(self.process.pid)
        except OSError:
            return float("nan")

    def timed_stop(self, sig: int = signal.SIGINT) -> tuple[int | None, float]:
        """Stop it; (exit code, None if it had to be killed; seconds from the signal to the
        exit)."""
        code = self.stop(sig)
        return (None if self.killed else code), self.stop_s


class Scenario:
    """receiver + generator + (node or baseline) [+ verify caller] on one domain, phases in
    order."""

    def __init__(
        self,
        target: str,
        args: argparse.Namespace,
        env: dict[str, str],
        log_dir: Path,
        children: list[Child],
    ) -> None:
        self.target, self.args, self.env, self.log_dir, self.children = (
            target,
            args,
            env,
            log_dir,
            children,
        )
        self.npz = log_dir / f"{target}.npz"
        self.startup_s = float("nan")
        # process start -> the node's "feet of ..." log line (its init done)
        self.ready_s = float("nan")
        self.exit: tuple[int | None, float] = (None, float("nan"))
        self.verify_summary: dict = {}
        self.cpu: dict[str, float] = {}

    def _start(self, name: str, command: list[str]) -> Child:
        child = Child(f"{self.target}-{name}", command, self.env, self.log_dir)
        self.children.append(child)
        return child

    def _ready_s(self) -> float:
        """Process start -> the node's start-up log line, from its log (NaN for the baseline)."""
        found = re.search(
            r"\[INFO\] \[(\d+)\.(\d+)\] \[[^]]*\]: feet of", self.under_test.log.read_text()
        )
        if not found:
            return float("nan")
        return (
            int(found[1]) + int(found[2]) / 10 ** len(found[2]) - self.under_test.started_ns / 1e9
        )

    def run(self, phases: list[Phase]) -> None:
        python = sys.executable
        receiver = [python, str(ROLES), "receiver", str(self.npz)]
        if self.args.no_force_reader:
            receiver.append("--no-force-reader")
        self.receiver = self._start("receiver", receiver)
        self.generator = self._start("generator", [python, str(ROLES), "generator"])
        self.receiver.wait_event("up", 30)
        self.generator.wait_event("up", 30)
        time.sleep(0.5)
        if self.target == "node":
            if self.args.executor == "node":
                command = [python, "-m", "a1_leg_fk.ros.foot_fk_node"]
            else:
                command = [python, str(ROLES), "node", self.args.executor]
        else:
            command = [python, str(ROLES), "baseline", self.args.executor]
        self.under_test = self._start("process", command)
        first = self.receiver.wait_event("first", 30)
        self.startup_s = (first["source"] - self.under_test.started_ns) / 1e9
        self.ready_s = self._ready_s()
        self.receiver.wait_event("ready", 30)
        verifier = None
        if any(p.verify for p in phases):
            verifier = self._start("verifier", [python, str(ROLES), "verifier", "20"])
            verifier.wait_event("service", 30)
        time.sleep(1.0)  # discovery settles; warm-up traffic stops at the first phase
        failures = 0
        for phase in phases:
            if phase.ramp and failures >= 2:
                break
            if phase.verify and verifier is not None:
                verifier.send(op="go")
            if self.target == "baseline":  # the floor publishes the force messages, or not
                self.under_test.send(op="phase", efforts=phase.efforts)
                time.sleep(0.3)
            self.generator.send(
                op="phase",
                rate=phase.rate,
                duration=phase.duration,
                name=phase.name,
                efforts=phase.efforts,
            )
            self.generator.wait_event("phase_start", 10)
            ours = {
                "under_test": self.under_test,
                "receiver": self.receiver,
                "generator": self.generator,
            }
            if phase.verify and verifier is not None:
                ours["verifier"] = verifier
            cpu0 = {name: child.cpu_s() for name, child in ours.items()}
            cpu0["machine"] = machine_busy_s()
            end = self.generator.wait_event("phase_end", phase.duration * 3 + 15)
            cpu1 = {name: child.cpu_s() for name, child in ours.items()}
            cpu1["machine"] = machine_busy_s()
            if phase.verify and verifier is not None:
                verifier.send(op="stop")
                self.verify_summary = verifier.wait_event("verify_done", 10)
                verifier.stop()
            time.sleep(DRAIN_S)
            phase.result = dict(end)
            for key, start in cpu0.items():
                phase.result[f"cpu_{key}"] = 100 * (cpu1[key] - start) / end["elapsed_s"]
            ours_cpu = sum(phase.result[f"cpu_{name}"] for name in ours)
            phase.result["cpu_others"] = max(0.0, phase.result["cpu_machine"] - ours_cpu)
            if phase.ramp:
                self.receiver.send(op="count", first=end["first_stamp"], last=end["last_stamp"])
                answered = self.receiver.wait_event("count", 10)["answered"]
                ok = (
                    answered >= end["sent"] * (1 - LOSS_LIMIT)
                    and end["rate_hz"] >= phase.rate * RATE_KEPT
                )
                failures = 0 if ok else failures + 1
        self.generator.send(op="stop")
        self.generator.stop(signal.SIGTERM)
        self.exit = self.under_test.timed_stop(signal.SIGINT)
        self.receiver.send(op="stop")
        self.receiver.wait_event("done", 30)
        self.receiver.stop(signal.SIGTERM)
        analyse(phases, np.load(self.npz))


def analyse(phases: list[Phase], data: np.lib.npyio.NpzFile) -> None:
    """Fill each finished phase's loss, latency and rate figures from the receiver's records."""
    topics = sorted({k.rsplit("_", 1)[0] for k in data.files})
    for phase in phases:
        r = phase.result
        if not r:
            continue
        first, last, sent, elapsed = r["first_stamp"], r["last_stamp"], r["sent"], r["elapsed_s"]
        published = received = 0
        answered_fr = 0
        latencies = []
        for topic in topics:
            stamps, seq = data[f"{topic}_stamp"], data[f"{topic}_seq"]
            inside = (stamps >= first) & (stamps <= last)
            n = int(inside.sum())
            if not n:
                continue
            in_seq = seq[inside]
            count = (
                int(in_seq.max() - in_seq.min() + 1)
                if in_seq.min() > 0
                else len(np.unique(stamps[inside]))
            )
            published += count
            received += n
            if topic == "foot_positions_FR":
                answered_fr = count
            if topic.startswith("foot_positions"):
                latencies.append((data[f"{topic}_received"][inside] - stamps[inside]) / 1e6)
        lat = np.concatenate(latencies) if latencies else np.array([np.nan])
        r.update(
            answered=answered_fr,
            input_loss=1 - answered_fr / sent if sent else float("nan"),
            foot_loss=1 - received / published if published else float("nan"),
            out_hz=answered_fr / elapsed,
            p50=float(np.percentile(lat, 50)),
            p95=float(np.percentile(lat, 95)),
            p99=float(np.percentile(lat, 99)),
            max=float(np.max(lat)),
        )


def max_sustained(phases: list[Phase]) -> tuple[float, bool]:
    """The highest passing ramp step below the first two failures in a row; (rate, topped out)."""
    best, failures, ran = 0.0, 0, [p for p in phases if p.ramp and p.result]
    for phase in ran:
        r = phase.result
        ok = (
            r["input_loss"] < LOSS_LIMIT
            and r["foot_loss"] < LOSS_LIMIT
            and r["rate_hz"] >= phase.rate * RATE_KEPT
        )
        if ok and failures < 2:
            best = max(best, phase.rate)
        failures = 0 if ok else failures + 1
        if failures >= 2:
            break
    topped_out = bool(ran) and failures == 0 and ran[-1].rate == best
    return best, topped_out


def fmt(value: float, spec: str) -> str:
    return "-" if math.isnan(value) else format(value, spec)


OUTPUTS_PER_INPUT = 8  # per input without efforts: foot_positions/<leg>, foot_velocities/<leg>
OUTPUTS_WITH_FORCES = OUTPUTS_PER_INPUT + 5  # and foot_forces/<leg>, foot_contacts


def per_input_us(result: dict) -> float:
    """The CPU [us] per input of a phase."""
    return 1e4 * result["cpu_under_test"] / result["rate_hz"]


def per_message(result: dict, messages: int) -> float:
    """The node's CPU [us] per output message of a phase."""
    return per_input_us(result) / messages


def print_report(
    node: Scenario,
    base: Scenario | None,
    node_phases: list[Phase],
    base_phases: list[Phase],
    args: argparse.Namespace,
) -> None:
    print()
    print(machine())
    print(f"ROS_DOMAIN_ID {args.domain}, executor '{args.executor}'")
    header = (
        f"{'scenario':<30} {'in Hz':>7} {'out Hz':>7} {'in loss':>8} {'foot loss':>9} "
        f"{'p50 ms':>7} {'p95 ms':>7} {'p99 ms':>7} {'max ms':>7} {'CPU %':>6} {'us/in':>6} "
        f"{'rx CPU%':>7} {'others%':>7} {'ratio':>6}"
    )
    print(header)
    print("-" * len(header))
    base_1k = next((p.result for p in base_phases if not (p.ramp or p.efforts) and p.result), {})
    base_forces_1k = next((p.result for p in base_phases if p.efforts and p.result), {})

    def row(label: str, r: dict, ratio: str = "") -> None:
        print(
            f"{label:<30} {r['rate_hz']:>7.0f} {r['out_hz']:>7.0f} {r['input_loss']:>8.2%} "
            f"{r['foot_loss']:>9.2%} {r['p50']:>7.2f} {r['p95']:>7.2f} {r['p99']:>7.2f} "
            f"{r['max']:>7.1f} {r['cpu_under_test']:>6.1f} "
            f"{per_input_us(r):>6.0f} {r['cpu_receiver']:>7.1f} "
            f"{r['cpu_others']:>7.0f} {ratio:>6}"
        )

    for phase in node_phases:
        if phase.result and not phase.ramp:
            ratio = ""
            floor = base_forces_1k if phase.efforts else base_1k
            if floor and not phase.verify:
                ratio = f"{phase.result['cpu_under_test'] / floor['cpu_under_test']:.2f}x"
            row(f"node {phase.name}", phase.result, ratio)
    for phase in base_phases:
        if phase.result and not phase.ramp:
            row(f"baseline {phase.name}", phase.result)
    for label, phases in (("node", node_phases), ("baseline", base_phases)):
        for phase in phases:
            if phase.result and phase.ramp:
                row(f"{label} ramp {phase.rate:.0f} Hz", phase.result)
    print(
        "(CPU % of one core; us/in: CPU us per input; rx: the receiver; others: CPU % used by "
        "processes outside this benchmark (the machine's total from /proc/stat minus ours), a "
        "sign of a noisy measurement; ratio on a 1 kHz row: node CPU / the raw floor's CPU)"
    )
    print()
    node_max, node_top = max_sustained(node_phases)
    base_max, base_top = max_sustained(base_phases)
    rate_ratio = node_max / base_max if base_max else float("nan")
    print(
        f"max sustained input rate (< {LOSS_LIMIT:.1%} loss): node "
        f"{'>=' if node_top else ''}{node_max:.0f} Hz, baseline "
        f"{'>=' if base_top else ''}{base_max:.0f} Hz, ratio node/baseline "
        f"{fmt(rate_ratio, '.2f')}"
    )
    print(
        f"startup (process start -> first published foot): node {node.startup_s:.2f} s"
        + (f", baseline {base.startup_s:.2f} s" if base else "")
        + "; the node's own start-up (process start -> its start-up log line) "
        f"{fmt(node.ready_s, '.2f')} s, the rest is DDS discovery of the already running "
        "publisher"
    )
    if node.verify_summary:
        v = node.verify_summary
        print(
            f"verify_fk: {v['sent']} calls, {v['answered']} answered, {v['passed']} passed, "
            f"latency p50 {fmt(v['p50_ms'], '.1f')} ms, max {fmt(v['max_ms'], '.1f')} ms"
        )
    code, seconds = node.exit
    print(f"node exit on SIGINT: code {code} after {seconds:.2f} s")
    print()
    main_1k = next(
        (p.result for p in node_phases if not (p.ramp or p.verify or p.efforts) and p.result),
        None,
    )
    forces_1k = next((p.result for p in node_phases if p.efforts and p.result), None)
    verify_1k = next((p.result for p in node_phases if p.verify and p.result), None)
    goals = []
    if main_1k:
        goals += [
            (
                "1 kHz: no input loss (< 0.1 %)",
                main_1k["input_loss"] < LOSS_LIMIT,
                f"{main_1k['input_loss']:.3%}",
            ),
            (
                "1 kHz: no foot loss (< 0.1 %)",
                main_1k["foot_loss"] < LOSS_LIMIT,
                f"{main_1k['foot_loss']:.3%}",
            ),
            (
                "1 kHz: latency p50 <= 1 ms",
                main_1k["p50"] <= GOALS["p50_ms"],
                f"{main_1k['p50']:.2f} ms",
            ),
            (
                "1 kHz: latency p99 <= 5 ms",
                main_1k["p99"] <= GOALS["p99_ms"],
                f"{main_1k['p99']:.2f} ms",
            ),
            (
                "1 kHz: node CPU <= 40 % of a core",
                main_1k["cpu_under_test"] <= GOALS["cpu_pct"],
                f"{main_1k['cpu_under_test']:.1f} %",
            ),
        ]
    if main_1k and base_1k:
        cpu_ratio = main_1k["cpu_under_test"] / base_1k["cpu_under_test"]
        goals.append(
            (
                "1 kHz: node CPU <= 1.2x the raw floor's",
                cpu_ratio <= GOALS["cpu_ratio"],
                (
                    f"{cpu_ratio:.2f}x ({main_1k['cpu_under_test']:.1f} % / "
                    f"{base_1k['cpu_under_test']:.1f} %)"
                ),
            )
        )
    if main_1k and forces_1k:
        forces_ratio = forces_1k["cpu_under_test"] / main_1k["cpu_under_test"]
        goals.append(
            (
                "1 kHz with efforts: node CPU <= 1.25x the node's without efforts",
                forces_ratio <= GOALS["forces_cpu_ratio"],
                (
                    f"{forces_ratio:.2f}x ({forces_1k['cpu_under_test']:.1f} % / "
                    f"{main_1k['cpu_under_test']:.1f} %); per output message "
                    f"{per_message(forces_1k, OUTPUTS_WITH_FORCES):.0f} vs "
                    f"{per_message(main_1k, OUTPUTS_PER_INPUT):.0f} us ({OUTPUTS_WITH_FORCES} vs "
                    f"{OUTPUTS_PER_INPUT} messages per input)"
                ),
            )
        )
    if main_1k and forces_1k and base_1k and base_forces_1k and args.baseline_duration >= 5:
        delivery, total = (
            per_input_us(base_forces_1k) - per_input_us(base_1k),
            per_input_us(forces_1k) - per_input_us(main_1k),
        )
        print(
            f"  efforts and forces cost {total:.0f} us per input: {delivery:.0f} us publishing "
            f"the {OUTPUTS_WITH_FORCES - OUTPUTS_PER_INPUT} more messages (the raw floor's "
            f"own difference, {per_input_us(base_forces_1k) / per_input_us(base_1k):.2f}x: the "
            f"least any node publishing them can cost), {total - delivery:.0f} us the rest"
        )  # not from --quick's 2 s floor phases: too short to split a few tens of us
    if base_phases and any(p.ramp and p.result for p in node_phases):
        goals += [
            ("ramp: node/baseline >= 90 %", rate_ratio >= GOALS["ratio"], fmt(rate_ratio, ".2f")),
            ("ramp: node >= 2 kHz", node_max >= GOALS["max_rate_hz"], f"{node_max:.0f} Hz"),
        ]
    if verify_1k:
        ok = verify_1k["input_loss"] < LOSS_LIMIT and node.verify_summary.get("answered", 0) > 0
        goals.append(
            (
                "verify_fk at 20 Hz during 1 kHz: no input loss",
                ok,
                f"{verify_1k['input_loss']:.3%}",
            )
        )
    goals.append(
        ("startup <= 2 s", node.startup_s <= GOALS["startup_s"], f"{node.startup_s:.2f} s")
    )
    goals.append(
        (
            "node exits 0 within 2 s of SIGINT",
            code == 0 and seconds <= 2.0,
            f"code {code}, {seconds:.2f} s",
        )
    )
    for label, ok, value in goals:
        print(f"  [{'met' if ok else 'MISSED'}] {label}: {value}")
    print(f"goals met: {sum(ok for _, ok, _ in goals)}/{len(goals)}")


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--duration", type=float, default=60.0, help="main 1 kHz run [s] (default 60)"
    )
    parser.add_argument(
        "--verify-duration",
        type=float,
        default=None,
        help="1 kHz + verify_fk run [s] (default duration/3)",
    )
    parser.add_argument(
        "--baseline-duration",
        type=float,
        default=None,
        help="baseline 1 kHz run [s] (default duration/3)",
    )
    parser.add_argument(
        "--ramp", default="500,1000,1500,2000,2500,3000,4000,5000,6000", help="ramp rates [Hz]"
    )
    parser.add_argument("--step", type=float, default=5.0, help="ramp step [s]")
    parser.add_argument("--quick", action="store_true", help="smoke test, about 30 s")
    parser.add_argument(
        "--executor",
        default="node",
        choices=("node", "events", "single", "multi"),
        help="node: the node's own choice; else force one for node and baseline alike",
    )
    parser.add_argument("--no-baseline", action="store_true", help="skip the baseline (no ratio)")
    parser.add_argument("--no-ramp", action="store_true", help="skip both ramps")
    parser.add_argument(
        "--no-force-reader",
        action="store_true",
        help="the receiver does not subscribe to foot_forces/<leg> and foot_contacts (what the "
        "forces cost without their DDS delivery)",
    )
    add_process_arguments(parser)
    parser.add_argument(
        "--discovery-range",
        default="LOCALHOST",
        choices=("LOCALHOST", "SUBNET", "SYSTEM_DEFAULT"),
        help="ROS_AUTOMATIC_DISCOVERY_RANGE of every process (default LOCALHOST)",
    )
    parser.add_argument(
        "--keep-logs", action="store_true", help="keep the processes' logs and records"
    )
    args = parser.parse_args()
    if args.quick:
        args.duration, args.step, args.ramp = 6.0, 2.0, "1000,2000,3000"
        args.verify_duration = args.verify_duration or 3.0
        args.baseline_duration = args.baseline_duration or 2.0
    args.verify_duration = args.verify_duration or max(2.0, args.duration / 3)
    args.baseline_duration = args.baseline_duration or max(2.0, args.duration / 3)
    choose_domain(args)
    return args


def add_process_arguments(parser: argparse.ArgumentParser) -> None:
    """``--domain`` and ``--package-root``, the processes' ROS domain and code."""
    parser.add_argument("--domain", type=int, default=None, help="ROS_DOMAIN_ID (0-101)")
    parser.add_argument(
        "--package-root",
        type=Path,
        default=ROOT,
        help="directory holding the a1_leg_fk to run (e.g. a saved copy, for before/after)",
    )


def choose_domain(args: argparse.Namespace) -> None:
    """``args.domain``, unless given: $BENCH_ROS_DOMAIN_ID, else 1 + pid % 100."""
    if args.domain is None:
        args.domain = int(os.environ.get("BENCH_ROS_DOMAIN_ID", 1 + os.getpid() % 100))


def process_env(args: argparse.Namespace, discovery_range: str = "LOCALHOST") -> dict[str, str]:
    """The environment of every process: the domain, the discovery range, the package root."""
    return dict(
        os.environ,
        ROS_DOMAIN_ID=str(args.domain),
        ROS_AUTOMATIC_DISCOVERY_RANGE=discovery_range,
        PYTHONUNBUFFERED="1",
        PYTHONPATH=os.pathsep.join(
            filter(None, [str(args.package_root), os.environ.get("PYTHONPATH")])
        ),
    )


def main() -> int:
    args = parse_args()
    rates = [float(r) for r in args.ramp.split(",") if r] if not args.no_ramp else []
    node_phases = [
        Phase("1 kHz", 1000, args.duration),
        Phase("1 kHz with efforts and forces", 1000, args.duration, efforts=True),
        Phase("1 kHz + verify_fk 20 Hz", 1000, args.verify_duration, verify=True),
    ]
    node_phases += [Phase(f"{r:.0f} Hz", r, args.step, ramp=True) for r in rates]
    base_phases = (
        []
        if args.no_baseline
        else [
            Phase("1 kHz", 1000, args.baseline_duration),
            Phase("1 kHz with efforts and forces", 1000, args.baseline_duration, efforts=True),
        ]
    )
    base_phases += (
        [Phase(f"{r:.0f} Hz", r, args.step, ramp=True) for r in rates] if base_phases else []
    )
    env = process_env(args, args.discovery_range)
    args.log_dir = Path(tempfile.mkdtemp(prefix="a1_leg_fk-bench-"))
    children: list[Child] = []
    total = sum(p.duration for p in node_phases + base_phases)
    print(
        f"node_throughput: about {total + 15 + 1.4 * len(rates) * 2:.0f} s on "
        f"ROS_DOMAIN_ID={args.domain}",
        flush=True,
    )

    def work() -> None:
        node = Scenario("node", args, env, args.log_dir, children)
        node.run(node_phases)
        base = None
        if base_phases:
            base = Scenario("baseline", args, env, args.log_dir, children)
            base.run(base_phases)
        print_report(node, base, node_phases, base_phases, args)

    return run_children("node_throughput", work, children, args.log_dir, args.keep_logs)


def run_children(
    name: str, work: Callable[[], None], children: list[Child], log_dir: Path, keep_logs: bool
) -> int:
    """Run ``work`` (which starts ``children``); Ctrl-C, SIGTERM or a child that fails end it
    with a line; every child is stopped in the end, and ``log_dir`` removed unless it failed or
    ``keep_logs``. Exit status 0, or 1 when it failed.
    """

    def on_term(_signum: int, _frame: object) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)
    failed = False
    try:
        work()
    except KeyboardInterrupt:
        print(f"\n{name}: interrupted; stopping every process", file=sys.stderr)
        failed = True
    except (TimeoutError, RuntimeError) as error:
        print(f"{name}: {error}", file=sys.stderr)
        failed = True
    finally:
        for child in reversed(children):
            child.stop(signal.SIGINT, timeout_s=3)
        if failed or keep_logs:
            print(f"logs and records: {log_dir}")
        else:
            shutil.rmtree(log_dir, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
