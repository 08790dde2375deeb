"""``a1-leg-fk echo``: a live table of the four feet (foot_positions/<leg>) and each topic's rate;
with ``--rerun``, everything the nodes publish streamed to a Rerun viewer (:mod:`.echo_rerun`).

The table, its writer and the spin loop are shared with ``a1-leg-fk demo``.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, TextIO

from a1_leg_fk.cli import echo_rerun
from a1_leg_fk.cli.common import (
    EXIT_NO_ANSWER,
    EXIT_OK,
    PROG,
    Ros,
    namespace_parent,
    positive,
    prefixed,
    with_ros,
)
from a1_leg_fk.model.legs import LEG_NAMES

if TYPE_CHECKING:  # imported by subscribe_feet, once ROS is up
    from geometry_msgs.msg import PointStamped

RATE_WINDOW_S = 2.0
TTY_INTERVAL_S = 0.2
PIPE_INTERVAL_S = 1.1
"""Default refresh periods [s]: on a terminal, and otherwise. Neither divides the demo trot's 0.5 s
cycle, so successive tables show different phases instead of seemingly frozen feet."""


def add_interval_argument(parser: argparse.ArgumentParser) -> None:
    """``--interval S``: the table's refresh period (echo, demo)."""
    parser.add_argument(
        "--interval",
        type=positive,
        metavar="S",
        help=f"refresh period [s] (default {TTY_INTERVAL_S:g} on a terminal, "
        f"else {PIPE_INTERVAL_S:g})",
    )


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``echo`` with the ``a1-leg-fk`` sub-commands."""
    echo = commands.add_parser(
        "echo",
        parents=[namespace_parent()],
        help="live table of the four feet (foot_positions/<leg>): x/y/z in mm and each topic's "
        "rate",
        description="Subscribe to foot_positions/FR|FL|RR|RL and show x, y, z [mm] per foot and "
        "the rate of each topic [Hz], refreshed in place (a new table per refresh when the "
        "output is not a terminal). Ctrl-C stops (exit 0).",
    )
    echo.add_argument(
        "--once",
        action="store_true",
        help="print the first complete table (all four feet) and exit",
    )
    echo.add_argument(
        "--duration",
        type=positive,
        metavar="S",
        help="stop after S seconds (default: run until Ctrl-C)",
    )
    add_interval_argument(echo)
    echo_rerun.add_arguments(echo)
    echo.add_argument(
        "--timeout",
        type=positive,
        default=10.0,
        metavar="S",
        help="with --once: give up (exit 2) when no complete table arrives within S s (default "
        "10)",
    )
    echo.set_defaults(handler=run)


class FootTable:
    """The latest position of each foot and each topic's message rate, rendered as text lines."""

    def __init__(self, topics: Sequence[str]) -> None:
        self.topics = list(topics)
        self.latest: dict[str, tuple[float, float, float, str] | None] = dict.fromkeys(LEG_NAMES)
        # (arrival time [s, monotonic], publication sequence number or None) within RATE_WINDOW_S
        self._arrivals: dict[str, deque[tuple[float, int | None]]] = {
            leg: deque() for leg in LEG_NAMES
        }

    def callback(self, leg: str) -> Callable[[PointStamped, dict[str, int]], None]:
        """The subscription callback of ``leg``'s foot topic: stores the point, counts the rate."""

        def on_message(message: PointStamped, info: dict[str, int]) -> None:
            point = message.point
            self.latest[leg] = (point.x, point.y, point.z, message.header.frame_id)
            arrivals = self._arrivals[leg]
            sequence = info.get("publication_sequence_number") if isinstance(info, dict) else None
            if (
                arrivals
                and sequence is not None
                and arrivals[-1][1] is not None
                and sequence <= arrivals[-1][1]
            ):
                arrivals.clear()  # a restarted or second publisher: start measuring again
            arrivals.append((time.monotonic(), sequence))

        return on_message

    @property
    def complete(self) -> bool:
        """Whether every foot has been received at least once."""
        return all(value is not None for value in self.latest.values())

    def rate_hz(self, leg: str, now: float) -> float | None:
        """Messages per second the publisher sent over the last RATE_WINDOW_S (None: too few to
        tell).

        Counted from the publication sequence numbers where the middleware reports them, so that
        messages this tool could not keep up with still count; else from the arrivals.
        """
        arrivals = self._arrivals[leg]
        while arrivals and arrivals[0][0] < now - RATE_WINDOW_S:
            arrivals.popleft()
        if len(arrivals) < 2 or arrivals[-1][0] <= arrivals[0][0]:
            return None
        (first_time, first_seq), (last_time, last_seq) = arrivals[0], arrivals[-1]
        sent = (
            last_seq - first_seq
            if first_seq is not None and last_seq is not None
            else len(arrivals) - 1
        )
        return sent / (last_time - first_time)

    def lines(self, heading: str) -> list[str]:
        """The table: a heading, a column header, one row per leg."""
        now = time.monotonic()
        frames = sorted(
            {value[3] for value in self.latest.values() if value is not None and value[3]}
        )
        rows = [
            heading + (f", frame {'/'.join(frames)}" if frames else ""),
            f"{'leg':<4}{'x [mm]':>9}{'y [mm]':>9}{'z [mm]':>9}{'rate [Hz]':>11}",
        ]
        for leg in LEG_NAMES:
            value = self.latest[leg]
            rate = self.rate_hz(leg, now)
            rate_text = f"{rate:11.1f}" if rate is not None else f"{'-':>11}"
            if value is None:
                rows.append(f"{leg:<4}{'-':>9}{'-':>9}{'-':>9}{rate_text}   no message yet")
            else:
                x, y, z, _ = value
                rows.append(f"{leg:<4}{millimetres(x)}{millimetres(y)}{millimetres(z)}{rate_text}")
        return rows


def millimetres(metres: float) -> str:
    """A coordinate [m] as a 9-character column [mm]: 0.1 mm steps, or for an absurd value (a
    damaged message's 1e300) powers of ten, so the table keeps its columns.
    """
    value = 1000 * metres
    return f"{value:9.1f}" if abs(value) < 1e6 else f"{value:9.2g}"


class TableWriter:
    """Prints tables: over the previous one (ANSI cursor-up) on a terminal, one after another
    otherwise.
    """

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.in_place = stream.isatty() and os.environ.get("TERM") != "dumb"
        self._height = 0

    def write(self, lines: list[str]) -> None:
        """Print ``lines`` (over the previous table on a terminal)."""
        if self.in_place:
            up = f"\x1b[{self._height}F" if self._height else ""
            self.stream.write(up + "".join(f"{line}\x1b[K\n" for line in lines))
        else:
            self.stream.write("\n".join(lines) + "\n\n")
        self.stream.flush()
        self._height = len(lines)


def subscribe_feet(ros: Ros, namespace: str) -> FootTable:
    """Subscribe to the four foot topics under ``namespace``; the table their callbacks fill."""
    from geometry_msgs.msg import PointStamped
    from rclpy.qos import qos_profile_sensor_data

    names = [prefixed(namespace, f"foot_positions/{leg}") for leg in LEG_NAMES]
    table = FootTable(names)
    # Best effort and volatile: matches reliable and best-effort, volatile and transient-local
    # publishers.
    subscriptions = [
        # rclpy passes the MessageInfo dict to a two-argument callback; its annotation names only
        # the one-argument form.
        ros.node.create_subscription(
            PointStamped,
            name,
            table.callback(leg),  # type: ignore[arg-type]
            qos_profile_sensor_data,
        )
        for leg, name in zip(LEG_NAMES, names)
    ]
    table.topics = [subscription.topic_name for subscription in subscriptions]
    return table


def topics_heading(table: FootTable) -> str:
    """The table's heading: the topics as ``<prefix>/<FR|FL|RR|RL>`` when they share a prefix."""
    # Character-wise on purpose: the common prefix is used only when it ends in "/".
    common = os.path.commonprefix(table.topics)  # noqa: RUF071
    return (
        f"feet from {common}<{'|'.join(LEG_NAMES)}>"
        if common.endswith("/")
        else "feet from " + ", ".join(table.topics)
    )


def echo_loop(
    ros: Ros,
    table: FootTable,
    stop: threading.Event,
    heading: str,
    interval_s: float | None,
    duration_s: float | None = None,
    once: bool = False,
    data_timeout_s: float | None = None,
    duration_after_data: bool = False,
    healthy: Callable[[], bool] = lambda: True,
) -> str:
    """Spin and print tables; returns why it ended.

    'once' (``once`` and all four feet arrived: that table printed), 'duration' (``duration_s``
    passed, counted from the first complete table when ``duration_after_data``), 'no_data' (not all
    four feet within ``data_timeout_s``), 'stop' (a signal), 'unhealthy' (``healthy()`` turned
    false). Without ``once`` a table is printed every ``interval_s``, and a last one at the end.
    """
    writer = TableWriter(sys.stdout)
    if interval_s is None:
        interval_s = TTY_INTERVAL_S if writer.in_place else PIPE_INTERVAL_S
    start = time.monotonic()
    complete_at: float | None = None
    next_refresh = start + (interval_s if once else 0.0)
    while True:
        if stop.is_set() or not ros.context.ok():
            return "stop"
        now = time.monotonic()
        if complete_at is None and table.complete:
            complete_at = now
            if once:
                writer.write(table.lines(heading))
                return "once"
        if complete_at is None and data_timeout_s is not None and now - start >= data_timeout_s:
            return "no_data"
        duration_start = complete_at if duration_after_data else start
        if (
            duration_s is not None
            and duration_start is not None
            and now - duration_start >= duration_s
        ):
            writer.write(table.lines(heading))
            return "duration"
        if not healthy():
            return "unhealthy"
        if not once and now >= next_refresh:
            writer.write(table.lines(heading))
            next_refresh += interval_s * (int((now - next_refresh) / interval_s) + 1)
        ros.executor.spin_once(timeout_sec=0.02)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk echo``; ``argv``: the whole command line, for ``rclpy.init``."""
    if options.rerun:
        return echo_rerun.run(options, argv)

    def watch(ros: Ros, stop: threading.Event) -> tuple[str, FootTable]:
        table = subscribe_feet(ros, options.namespace)
        heading = topics_heading(table) + ("" if options.once else " (Ctrl-C to stop)")
        ended = echo_loop(
            ros,
            table,
            stop,
            heading,
            options.interval,
            duration_s=options.duration,
            once=options.once,
            data_timeout_s=options.timeout if options.once else None,
        )
        return ended, table

    result = with_ros("echo", argv, watch)
    if result is None:
        return EXIT_NO_ANSWER
    ended, table = result
    if ended == "no_data":
        print(
            f"{PROG} echo: no message from all of {', '.join(table.topics)} within "
            f"{options.timeout:g} s (is foot_fk_node running, in this namespace and ROS domain, "
            "and receiving joint_states?)",
            file=sys.stderr,
        )
        return EXIT_NO_ANSWER
    return EXIT_OK
