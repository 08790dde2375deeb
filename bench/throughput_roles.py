"""The processes of ``bench/node_throughput.py``: load generator, receiver, echo baseline, verify
caller.

Run as ``python bench/throughput_roles.py ROLE [options]`` on the ROS_DOMAIN_ID the orchestrator
chose. Control is by JSON lines: commands on stdin, events on stdout (one object per line), so
the orchestrator itself needs no ROS. Every role exits cleanly on SIGINT/SIGTERM or
``{"op": "stop"}``.

Roles
- ``generator``: JointState (12 joints, positions and velocities; with ``"efforts": true`` in
  a phase command, efforts too) on ``joint_states``. Until the
  first phase it publishes 100 Hz "warm-up" messages (so a node that starts later answers at
  once); ``{"op": "phase", "rate": Hz, "duration": s}`` then publishes exactly ``rate * duration``
  messages, paced by ``time.perf_counter`` (sleep until just before the next one is due, then
  send every message that is due: the average rate is exact, jitter is a few hundred us). Each
  message's stamp is ``time.time_ns()`` when it is sent (strictly increasing), and its
  ``header.frame_id`` is its sequence number. Reports ``phase_start`` and ``phase_end`` (sent,
  first and last stamp, achieved duration).
- ``receiver``: raw (serialized) subscriptions to the eight output topics, drained from its own
  wait set without an executor; per message it keeps the JointState stamp parsed from the CDR
  bytes, the DDS reception time and the publisher's sequence number (``received_timestamp``,
  ``publication_sequence_number`` of the message info), so neither its own speed nor its Python
  wake-up delay enters the latency. ``{"op": "count", "first": ns, "last": ns}`` answers the
  number of inputs answered on ``foot_positions/FR`` in a stamp window (for the ramp's early stop);
  on stop it writes every record to the ``.npz`` given as argument. It also takes (and drops)
  ``foot_forces/<leg>`` and ``foot_contacts``, so that the node publishes them to a reader.
- ``baseline``: the raw floor: same QoS and executor as the node; per JointState (subscribed raw)
  it reads the stamp from the bytes and publishes the node's nine outputs as pre-serialized
  messages (the node's own writers, fixed values: the feet, their velocities and
  ``foot_contacts``, which the node publishes for every JointState); no decoding, no rules, no
  FK. After ``{"op": "phase", "efforts": true}`` it also publishes what the node adds for
  efforts, ``foot_forces/<leg>``, until a phase command without efforts.
- ``verifier``: calls ``verify_fk`` 20 times a second between ``{"op": "go"}`` and
  ``{"op": "stop"}``.
"""

from __future__ import annotations

import json
import math
import os
import queue
import signal
import struct
import sys
import threading
import time
from collections.abc import Callable

import rclpy
from common import shared
from geometry_msgs.msg import PointStamped, Vector3Stamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState

OUTPUT_TOPICS = [f"foot_positions/{leg}" for leg in shared.LEGS] + [
    f"foot_velocities/{leg}" for leg in shared.LEGS
]
WARMUP_RATE_HZ = 100.0
POSES = 250  # distinct pre-built messages the generator cycles through
STANDING_EFFORTS = [1.08, -2.88, 2.42, -1.0, -3.08, 2.26, -1.86, 2.71, 5.02, 1.71, 2.8, 5.22]
"""[N m]: the A1 standing in PyBullet (docs/forces.md)."""
FORCE_TOPICS = [f"foot_forces/{leg}" for leg in shared.LEGS] + ["foot_contacts"]


def emit(**event: object) -> None:
    """One event line to the orchestrator."""
    sys.stdout.write(json.dumps(event) + "\n")
    sys.stdout.flush()


class Control:
    """stdin commands (a reader thread) and SIGINT/SIGTERM, for a process that owns its main
    loop."""

    def __init__(self) -> None:
        self.commands: queue.Queue[dict] = queue.Queue()
        self.stopping = False
        signal.signal(signal.SIGINT, self._on_signal)
        signal.signal(signal.SIGTERM, self._on_signal)
        threading.Thread(target=self._read, daemon=True).start()

    def _on_signal(self, _signum: int, _frame: object) -> None:
        self.stopping = True

    def _read(self) -> None:
        for line in sys.stdin:
            line = line.strip()
            if line:
                command = json.loads(line)
                if command.get("op") == "stop":
                    self.stopping = True
                self.commands.put(command)
        self.stopping = True  # the orchestrator is gone

    def poll(self) -> dict | None:
        try:
            return self.commands.get_nowait()
        except queue.Empty:
            return None


def _init() -> None:
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)


# --- generator ---------------------------------------------------------------------------------


def _poses(efforts: bool = False) -> list[JointState]:
    """Pre-built messages: a small trot-like motion around the standing pose, with its rates and,
    if ``efforts``, joint efforts around those of the A1 standing [N m]."""
    messages = []
    for i in range(POSES):
        phase = 2 * math.pi * i / POSES
        positions = [a + 0.2 * math.sin(phase + k) for k, a in enumerate(shared.STANDING)]
        velocities = [0.2 * 2 * math.pi * math.cos(phase + k) for k in range(len(shared.STANDING))]
        torques = [t * (1.0 + 0.5 * math.sin(phase + k)) for k, t in enumerate(STANDING_EFFORTS)]
        messages.append(
            JointState(
                name=list(shared.PYBULLET_NAMES),
                position=positions,
                velocity=velocities,
                effort=torques if efforts else [],
            )
        )
    return messages


def generator() -> None:
    _init()
    control = Control()
    node = Node("bench_load_generator")
    publisher = node.create_publisher(JointState, "joint_states", QoSProfile(depth=10))
    plain, with_efforts = _poses(), _poses(efforts=True)
    messages = plain
    seq = 0
    last_stamp = 0

    def send() -> int:
        nonlocal seq, last_stamp
        msg = messages[seq % POSES]
        stamp_ns = time.time_ns()
        if stamp_ns <= last_stamp:
            stamp_ns = last_stamp + 1
        last_stamp = stamp_ns
        stamp = msg.header.stamp
        stamp.sec, stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
        msg.header.frame_id = str(seq)
        publisher.publish(msg)
        seq += 1
        return stamp_ns

    emit(event="up", pid=os.getpid())
    warming = True
    next_warmup = time.perf_counter()
    while not control.stopping:
        command = control.poll()
        if command is None:
            if warming and time.perf_counter() >= next_warmup:
                send()
                next_warmup += 1.0 / WARMUP_RATE_HZ
            time.sleep(0.002)
            continue
        if command["op"] != "phase":
            continue
        warming = False
        messages = with_efforts if command.get("efforts") else plain
        rate, duration = float(command["rate"]), float(command["duration"])
        total = max(1, round(rate * duration))
        emit(event="phase_start", name=command.get("name", ""))
        first_stamp = last = 0
        sent = 0
        worst_behind = 0
        t0 = time.perf_counter()
        deadline = t0 + duration * 3 + 5  # a starved generator still ends (and reports it)
        while sent < total and not control.stopping:
            now = time.perf_counter()
            if now > deadline:
                break
            due = min(total, int((now - t0) * rate) + 1)
            worst_behind = max(worst_behind, due - sent - 1)
            while sent < due:
                last = send()
                if not sent:
                    first_stamp = last
                sent += 1
            wait = t0 + sent / rate - time.perf_counter()
            if wait > 0.00015:
                time.sleep(wait - 0.0001)
        elapsed = time.perf_counter() - t0
        emit(
            event="phase_end",
            name=command.get("name", ""),
            sent=sent,
            first_stamp=first_stamp,
            last_stamp=last,
            elapsed_s=elapsed,
            rate_hz=sent / elapsed if elapsed > 0 else 0.0,
            worst_burst=worst_behind + 1,
        )
    node.destroy_node()
    rclpy.try_shutdown()


# --- receiver ----------------------------------------------------------------------------------


def receiver(output: str, force_reader: bool = True) -> None:
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

    _init()
    control = Control()
    node = Node("bench_receiver")
    qos = QoSProfile(depth=1000)  # reliable, as the node publishes; deep enough for any burst
    subscriptions = [
        node.create_subscription(
            PointStamped if "positions" in topic else Vector3Stamped,
            topic,
            lambda _: None,
            qos,
            raw=True,
        )
        for topic in OUTPUT_TOPICS
    ]
    handles = [s.handle for s in subscriptions]
    types = [s.msg_type for s in subscriptions]
    # forces and contacts (with efforts): taken and dropped, so the node publishes to a reader
    drains = [
        node.create_subscription(
            JointState if topic == "foot_contacts" else WrenchStamped,
            topic,
            lambda _: None,
            qos,
            raw=True,
        ).handle
        for topic in (FORCE_TOPICS if force_reader else [])
    ]
    records: list[tuple[list[int], list[int], list[int], list[int]]] = [
        ([], [], [], []) for _ in subscriptions
    ]
    context = rclpy.get_default_context()
    wait_set = _rclpy.WaitSet(len(handles) + len(drains), 0, 0, 0, 0, 0, context.handle)
    unpack = struct.Struct("<iI").unpack_from
    first_seen = [False] * len(handles)
    emit(event="up", pid=os.getpid())
    ready = False
    while not control.stopping:
        wait_set.clear_entities()
        for handle in handles + drains:
            wait_set.add_subscription(handle)
        wait_set.wait(100_000_000)
        for drain, kind in zip(drains, [WrenchStamped] * 4 + [JointState], strict=False):
            while drain.take_message(kind, True) is not None:
                pass
        for index, handle in enumerate(handles):
            stamps, received, sources, sequence = records[index]
            msg_type = types[index]
            while True:
                taken = handle.take_message(msg_type, True)
                if taken is None:
                    break
                data, info = taken
                sec, nanosec = unpack(data, 4)
                stamps.append(sec * 1_000_000_000 + nanosec)
                received.append(info["received_timestamp"])
                sources.append(info["source_timestamp"])
                sequence.append(info["publication_sequence_number"])
            if stamps and not first_seen[index]:
                first_seen[index] = True
                emit(
                    event="first",
                    topic=OUTPUT_TOPICS[index],
                    stamp=stamps[0],
                    received=received[0],
                    source=sources[0],
                )
        if not ready and all(first_seen):
            ready = True
            emit(event="ready")
        command = control.poll()
        if command is not None and command["op"] == "count":
            first, last = command["first"], command["last"]
            answered = len({s for s in records[0][0] if first <= s <= last})
            emit(event="count", answered=answered)
    import numpy as np

    arrays: dict[str, np.ndarray] = {}
    for index, topic in enumerate(OUTPUT_TOPICS):
        key = topic.replace("/", "_")
        for name, values in zip(("stamp", "received", "source", "seq"), records[index]):
            arrays[f"{key}_{name}"] = np.asarray(values, dtype=np.int64)
    np.savez(output, **arrays)  # type: ignore[arg-type]  # numpy's stub matches **kwds to allow_pickle
    emit(event="done", messages=sum(len(r[0]) for r in records))
    node.destroy_node()
    rclpy.try_shutdown()


# --- bare echo baseline ------------------------------------------------------------------------


def floor_callback(
    node: Node, forces: list[bool], raw: bool = False, prefix: str = ""
) -> Callable[[bytes], None]:
    """The raw floor's JointState callback on publishers of ``node`` (topics under ``prefix``):
    the stamp read from the bytes, nine pre-serialized messages out (the node's own output
    writer: the feet, their velocities, foot_contacts), and while ``forces[0]`` the four
    foot_forces too; no decoding, no rules, no FK. Published with ``Publisher.publish``, or
    (``raw``) as the node publishes them, ``a1_leg_fk.ros.serialized_output.raw_publish``."""
    from a1_leg_fk.ros.glue import OUTPUT_QOS
    from a1_leg_fk.ros.serialized_output import SerializedStamped
    from a1_leg_fk.wire.output import (
        contacts_bytes,
        contacts_layout,
        frame_bytes,
        wrench_bytes,
    )

    writer = SerializedStamped("trunk")
    publishers = [
        node.create_publisher(kind, f"{prefix}{topic}/{leg}", OUTPUT_QOS)
        for kind, topic in ((PointStamped, "foot_positions"), (Vector3Stamped, "foot_velocities"))
        for leg in shared.LEGS
    ]
    force_publishers = [
        node.create_publisher(WrenchStamped, f"{prefix}foot_forces/{leg}", OUTPUT_QOS)
        for leg in shared.LEGS
    ]
    contacts_publisher = node.create_publisher(JointState, f"{prefix}foot_contacts", OUTPUT_QOS)
    head, layout = frame_bytes("trunk"), contacts_layout("trunk")
    stamp = struct.Struct("<iI").unpack_from
    values, force = (0.1, 0.2, 0.3), (1.0, 2.0, 30.0)
    probabilities, normal = (1.0, 0.0, 0.0, 1.0), (30.0, 0.0, 0.0, 30.0)
    if raw:
        from a1_leg_fk.ros.serialized_output import raw_publish

        sends = [raw_publish(publisher) for publisher in publishers]
        force_sends = [raw_publish(publisher) for publisher in force_publishers]
        contacts_send = raw_publish(contacts_publisher)
    else:
        sends = [publisher.publish for publisher in publishers]
        force_sends = [publisher.publish for publisher in force_publishers]
        contacts_send = contacts_publisher.publish

    def on_joint_state(data: bytes) -> None:
        sec, nanosec = stamp(data, 4)
        serialized = writer.serialized
        for send in sends:
            send(serialized(sec, nanosec, values))
        if forces[0]:
            for send in force_sends:
                send(wrench_bytes(head, sec, nanosec, force))
        contacts_send(contacts_bytes(layout, sec, nanosec, probabilities, normal))

    return on_joint_state


def baseline(executor_name: str, raw: bool = False) -> None:
    """The floor (:func:`floor_callback`; ``raw``: ``--raw-publish``) on ``joint_states``, with
    the node's QoS and executor; a phase command says whether the inputs carry efforts."""
    from a1_leg_fk.ros.glue import JOINT_STATES_QOS

    _init()
    control = Control()
    node = Node("bench_raw_floor")
    forces = [False]  # set per phase: the inputs carry efforts
    node.create_subscription(
        JointState, "joint_states", floor_callback(node, forces, raw), JOINT_STATES_QOS, raw=True
    )
    executor = make_executor(executor_name)
    executor.add_node(node)
    try:
        while rclpy.ok() and not control.stopping:
            executor.spin_once(timeout_sec=0.1)
            command = control.poll()
            if command is not None and command.get("op") == "phase":
                forces[0] = bool(command.get("efforts"))
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def make_executor(name: str) -> rclpy.executors.Executor:
    """``node``: whatever ``a1_leg_fk.ros.foot_fk_node`` uses; else ``events``, ``single`` or
    ``multi``."""
    if name == "node":
        from a1_leg_fk.ros.glue import make_executor as node_executor

        return node_executor()
    if name == "events":
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    if name == "single":
        return rclpy.executors.SingleThreadedExecutor()
    if name == "multi":
        return rclpy.executors.MultiThreadedExecutor(num_threads=2)
    raise SystemExit(f"unknown executor {name}")


def node_with_executor(executor_name: str, ros_args: list[str]) -> int:
    """``a1_leg_fk.ros.foot_fk_node.main`` with another executor (for comparing executors)."""
    import a1_leg_fk.ros.foot_fk_node as node_module
    import a1_leg_fk.ros.glue as glue_module

    if executor_name != "node":
        glue_module.make_executor = lambda: make_executor(executor_name)
    return node_module.main(["node", *ros_args])


# --- verify_fk caller --------------------------------------------------------------------------


def verifier(rate_hz: float) -> None:
    from std_srvs.srv import Trigger

    _init()
    control = Control()
    node = Node("bench_verify_caller")
    client = node.create_client(Trigger, "verify_fk")
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    emit(event="up", pid=os.getpid())
    while not control.stopping and not client.wait_for_service(timeout_sec=0.2):
        pass
    emit(event="service")
    calling = False
    sent = answered = passed = 0
    latencies: list[float] = []
    next_call = time.perf_counter()

    def done(future, started: float) -> None:
        nonlocal answered, passed
        answered += 1
        latencies.append(time.perf_counter() - started)
        passed += bool(future.result() and future.result().success)

    while not control.stopping:
        command = control.poll()
        if command is not None and command["op"] == "go":
            calling, next_call = True, time.perf_counter()
        now = time.perf_counter()
        if calling and now >= next_call:
            future = client.call_async(Trigger.Request())
            future.add_done_callback(lambda f, started=now: done(f, started))
            sent += 1
            next_call += 1.0 / rate_hz
        executor.spin_once(
            timeout_sec=max(0.0, min(0.01, next_call - time.perf_counter())) if calling else 0.05
        )
    latencies.sort()
    emit(
        event="verify_done",
        sent=sent,
        answered=answered,
        passed=passed,
        p50_ms=1e3 * latencies[len(latencies) // 2] if latencies else math.nan,
        max_ms=1e3 * latencies[-1] if latencies else math.nan,
    )
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    role, arguments = sys.argv[1], sys.argv[2:]
    if role == "generator":
        generator()
    elif role == "receiver":
        receiver(arguments[0], "--no-force-reader" not in arguments)
    elif role == "baseline":
        baseline(arguments[0] if arguments else "node", "--raw-publish" in arguments)
    elif role == "verifier":
        verifier(float(arguments[0]) if arguments else 20.0)
    elif role == "node":
        sys.exit(node_with_executor(arguments[0], arguments[1:]))
    else:
        raise SystemExit(f"unknown role {role}")
