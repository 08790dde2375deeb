"""``a1-leg-fk echo --rerun``: what the nodes publish, streamed to a Rerun viewer with the
entities of ``a1-leg-fk view`` (:mod:`a1_leg_fk.view.live`).

Subscribes (under ``--namespace``) to ``foot_positions/<leg>``, ``foot_forces/<leg>``,
``foot_contacts`` (foot_fk_node), ``leg_odometry`` (leg_odometry_node) and ``joint_states``;
sends the rows every :data:`~a1_leg_fk.view.live.BATCH_S` to a viewer it spawns, or with
``--connect URL`` to a running one (``rerun``, or ``rerun --serve-grpc``); prints
``receiving: TOPIC`` at each topic's first message. Ctrl-C (or ``--duration``) takes in the
messages already received (:func:`_drain`), sends what is left, flushes and disconnects: the
viewer keeps the data; exit 0.
Exit 2: no ``rerun-sdk``, a URDF that does not load, no viewer taking the stream at the start
(within :data:`CONNECT_TIMEOUT_S`), ROS that cannot start; 1: the viewer stopped taking it. Rerun's
own log lines are off unless ``RUST_LOG`` is set.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from a1_leg_fk.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_OK,
    PROG,
    Ros,
    prefixed,
    with_ros,
)
from a1_leg_fk.cli.rerun_sdk import import_rerun, viewer_executable
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:
    from a1_leg_fk.view.live import LiveRows, LiveView

CONNECT_TIMEOUT_S = 5.0
"""How long the description may take to reach the viewer at the start [s]."""
FLUSH_TIMEOUT_S = 10.0
"""How long the last rows may take to reach the viewer [s]."""
SPIN_S = 0.01
DRAIN_QUIET_S = 0.2
"""At the stop, the messages already received are taken in until none has come for this long
[s] (on a loaded machine echo lags the nodes: Ctrl-C would drop the messages still queued) ..."""
DRAIN_TIMEOUT_S = 2.0
"""... or for at most this long [s] (a robot that keeps publishing)."""


def add_arguments(echo: argparse.ArgumentParser) -> None:
    """``echo``'s Rerun options: ``--rerun``, ``--connect URL``, ``--urdf FILE``."""
    echo.add_argument(
        "--rerun",
        action="store_true",
        help="stream feet, contacts, forces, odometry and joint states to a Rerun viewer (the "
        "entities of a1-leg-fk view) instead of printing the table",
    )
    echo.add_argument(
        "--connect",
        metavar="URL",
        help="with --rerun: a running viewer or gRPC server (e.g. "
        "rerun+http://127.0.0.1:9876/proxy) instead of spawning a viewer",
    )
    echo.add_argument(
        "--urdf",
        metavar="FILE",
        help="with --rerun: the robot's description (default: the embedded A1)",
    )


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk echo --rerun``: see the module docstring for exit codes."""
    rr = import_rerun("echo --rerun")
    if rr is None:
        return EXIT_BAD_INPUT
    from a1_leg_fk.kinematics.robot_config import load_robot
    from a1_leg_fk.model.urdf import default_urdf_path
    from a1_leg_fk.view.live import LiveView
    from a1_leg_fk.view.scene import APPLICATION_ID, Scene

    recording = rr.RecordingStream(APPLICATION_ID, send_properties=False)
    try:
        quadruped = load_robot("", options.urdf or "").quadruped
        if options.connect:
            recording.connect_grpc(options.connect)
        else:
            rr.spawn(recording=recording, executable_path=viewer_executable())
        scene = Scene(recording, Path(options.urdf or default_urdf_path()), quadruped)
        _flushed(recording, CONNECT_TIMEOUT_S, options.connect or "the spawned viewer")
    except (LegFkError, OSError, ValueError, RuntimeError) as error:
        recording.disconnect()
        lines = str(error).strip().splitlines() or [repr(error)]  # Rerun's span several
        print(f"{PROG} echo: {lines[0]}", file=sys.stderr)
        return EXIT_BAD_INPUT
    live = LiveView(scene)
    target = options.connect or "a spawned viewer"
    print(f"streaming {options.namespace or '.'}/ to {target} (Ctrl-C to stop)", flush=True)
    if scene.note:
        print(f"view:      {scene.note}", flush=True)
    result = with_ros("echo", argv, lambda ros, stop: _stream(ros, stop, live, options))
    try:
        _flushed(recording, FLUSH_TIMEOUT_S, target)
    except RuntimeError as error:
        print(f"{PROG} echo: {error}", file=sys.stderr)
        return EXIT_FAILED
    finally:
        recording.disconnect()
    if result is None:
        return EXIT_BAD_INPUT
    span = (
        f", stamps {live.first_ns / 1e9:.3f} .. {live.last_ns / 1e9:.3f} s"
        if live.first_ns is not None and live.last_ns is not None
        else ""
    )
    print(f"streamed:  {live.sent} rows{span} to {target}")
    return EXIT_OK


def _flushed(recording: Any, timeout_s: float, target: str) -> None:
    """Everything logged so far delivered to ``target`` within ``timeout_s`` [s], else
    RuntimeError saying so.
    """
    try:
        recording.flush(timeout_sec=timeout_s)
    except RuntimeError as error:
        raise RuntimeError(f"{target} did not take the stream: {error}") from None


def _stream(ros: Ros, stop: threading.Event, live: LiveView, options: argparse.Namespace) -> bool:
    """Subscribe, then spin and send every :data:`~a1_leg_fk.view.live.BATCH_S` until
    ``stop`` or ``--duration``; send the rest. True (ROS ran).
    """
    from a1_leg_fk.view.live import BATCH_S

    subscribe(ros, options.namespace, live.rows)
    start = time.monotonic()
    next_batch = start + BATCH_S
    while not stop.is_set() and ros.context.ok():
        now = time.monotonic()
        if options.duration is not None and now - start >= options.duration:
            break
        if now >= next_batch:
            live.tick(now)
            next_batch = now + BATCH_S
        ros.executor.spin_once(timeout_sec=SPIN_S)
    _drain(ros, live.rows)
    live.tick(time.monotonic(), everything=True)
    return True


def _drain(ros: Ros, rows: LiveRows) -> None:
    """Take in the messages that have come but wait in the subscriptions' queues: spin until
    none has been taken for :data:`DRAIN_QUIET_S`, at most :data:`DRAIN_TIMEOUT_S` [s].
    """
    deadline = time.monotonic() + DRAIN_TIMEOUT_S
    quiet_until = time.monotonic() + DRAIN_QUIET_S
    while ros.context.ok() and time.monotonic() < min(deadline, quiet_until):
        taken = rows.messages
        ros.executor.spin_once(timeout_sec=SPIN_S)
        if rows.messages != taken:
            quiet_until = time.monotonic() + DRAIN_QUIET_S


def subscribe(ros: Ros, namespace: str, rows: LiveRows) -> None:
    """The nodes' topics under ``namespace`` into ``rows`` (best effort: a viewer may miss a
    message, the robot never waits for it); a line ``receiving: TOPIC`` at each topic's first
    message.
    """
    from geometry_msgs.msg import PointStamped, WrenchStamped
    from nav_msgs.msg import Odometry
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
    node = ros.node
    heard: set[str] = set()

    def on(kind: type, topic: str, callback: Any) -> None:
        name = prefixed(namespace, topic)

        def take(message: Any) -> None:
            if name not in heard:  # said once per topic: what the viewer will get
                heard.add(name)
                print(f"receiving: {name}", flush=True)
            callback(message)

        node.create_subscription(kind, name, take, qos)

    for slot, leg in enumerate(LEG_NAMES):
        on(
            PointStamped,
            f"foot_positions/{leg}",
            lambda m, s=slot: rows.foot(s, _ns(m), (m.point.x, m.point.y, m.point.z)),
        )
        on(
            WrenchStamped,
            f"foot_forces/{leg}",
            lambda m, s=slot: rows.force(s, _ns(m), _xyz(m.wrench.force)),
        )
    on(JointState, "foot_contacts", lambda m: rows.contacts(_ns(m), m.name, m.position, m.effort))
    on(JointState, "joint_states", lambda m: rows.angles(_ns(m), m.name, m.position))

    def on_odometry(m: Odometry) -> None:
        pose, twist = m.pose.pose, m.twist
        q = pose.orientation
        variances = (twist.covariance[0], twist.covariance[7], twist.covariance[14])
        rows.odometry(
            _ns(m), _xyz(pose.position), (q.x, q.y, q.z, q.w), _xyz(twist.twist.linear), variances
        )

    on(Odometry, "leg_odometry", on_odometry)


def _ns(message: Any) -> int:
    """A stamped message's header stamp [ns]."""
    stamp = message.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _xyz(vector: Any) -> tuple[float, float, float]:
    return (vector.x, vector.y, vector.z)
