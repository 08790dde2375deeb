"""``a1-leg-fk demo``: the process supervisor behind ``make demo``.

Starts foot_fk_node and joint_state_demo as children, shows the live echo table, calls
verify_fk, then stops both (SIGINT, as Ctrl-C) and reports how each ended.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import tempfile
from collections.abc import Sequence
from pathlib import Path

from a1_leg_fk.cli.common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    Child,
    Ros,
    child_command,
    namespace_parent,
    positive,
    ros_section,
    say,
    start_ros,
)
from a1_leg_fk.cli.echo import add_interval_argument, echo_loop, subscribe_feet, topics_heading
from a1_leg_fk.cli.verify import call_verify
from a1_leg_fk.stop_signals import StopSignals

DEMO_START_TIMEOUT_S = 20.0


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``demo`` with the ``a1-leg-fk`` sub-commands."""
    demo = commands.add_parser(
        "demo",
        parents=[namespace_parent()],
        help="start foot_fk_node and joint_state_demo, show the feet live, verify, stop "
        "everything",
        description="The whole pipeline in one command: starts foot_fk_node and "
        "joint_state_demo (a simulated A1 that stands up, then trots in place), shows the live "
        "echo table for --duration seconds, calls verify_fk, then stops both. Uses "
        "ROS_DOMAIN_ID if set, else picks one for itself.",
    )
    demo.add_argument(
        "--duration",
        type=positive,
        default=10.0,
        metavar="S",
        help="seconds of live view (default 10)",
    )
    add_interval_argument(demo)
    demo.add_argument(
        "--log-dir",
        metavar="DIR",
        help="where the children's output goes (default: a new temp folder)",
    )
    demo.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk demo``; ``argv``: the whole command line, for ``rclpy.init`` and the nodes."""
    with StopSignals() as signals:
        demo = Demo(options, argv, signals)
        code = EXIT_FAILED  # if run() raises
        try:
            code = demo.run()
        finally:
            if signals.stop.is_set():
                say(f"\n{signals.signal_name or 'interrupted'}: stopping")
            code = demo.cleanup(code)
    return EXIT_INTERRUPTED if signals.stop.is_set() else code


class Demo:
    """``a1-leg-fk demo``: the two nodes as children, the live table, verify, then a clean stop."""

    def __init__(
        self, options: argparse.Namespace, argv: Sequence[str], signals: StopSignals
    ) -> None:
        self.options = options
        self.argv = list(argv)
        self.signals = signals
        self.children: list[Child] = []
        self.temporary_log_dir: Path | None = None  # made by us: removed after a clean run
        self.ros: Ros | None = None

    def run(self) -> int:
        """Start the demo's processes, show the feet, verify, stop everything; the exit code."""
        options, stop = self.options, self.signals.stop
        say("== a1-leg-fk demo: joint_state_demo -> foot_fk_node -> feet ==")
        if not os.environ.get("ROS_DOMAIN_ID"):
            domain = 1 + os.getpid() % 100
            os.environ["ROS_DOMAIN_ID"] = str(domain)
            os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
            say(
                f"ROS_DOMAIN_ID was unset: using {domain} for this demo and its nodes "
                f"(discovery range {os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE']}); to watch from "
                f"another terminal: export ROS_DOMAIN_ID={domain}"
            )
        else:
            say(f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} (from the environment)")
        if options.log_dir:
            log_dir = Path(options.log_dir)
            log_dir.mkdir(parents=True, exist_ok=True)
        else:
            log_dir = self.temporary_log_dir = Path(tempfile.mkdtemp(prefix="a1_leg_fk_demo_"))
        child_ros_args = ros_section(self.argv)
        if options.namespace:
            namespace = (
                options.namespace if options.namespace.startswith("/") else "/" + options.namespace
            )
            child_ros_args = ["--ros-args", "-r", f"__ns:={namespace}", *child_ros_args]
        os.environ["PYTHONUNBUFFERED"] = "1"

        kept = "kept only if something fails" if self.temporary_log_dir else "kept"
        say(f"\n[1/4] starting the two nodes (their output goes to {log_dir}/, {kept})")
        for name, module in (
            ("foot_fk_node", "a1_leg_fk.ros.foot_fk_node"),
            ("joint_state_demo", "a1_leg_fk.ros.joint_state_demo"),
        ):
            if stop.is_set():
                return EXIT_INTERRUPTED
            command = child_command(name, module) + child_ros_args
            self.children.append(Child(name, command, log_dir / f"{name}.log"))
            say(f"  {name:<17} pid {self.children[-1].process.pid}: {' '.join(command)}")
        say(
            "  joint_state_demo: publishes joint_states at 500 Hz: the A1 stands up from a "
            "crouch (2 s), then trots in place"
        )
        say(
            "  foot_fk_node:     joint_states -> forward kinematics -> foot_positions/<leg>; "
            "offers verify_fk"
        )

        self.ros = start_ros("demo", self.argv)
        if self.ros is None:
            return EXIT_FAILED
        table = subscribe_feet(self.ros, options.namespace)
        say(
            f"\n[2/4] the feet, live for {options.duration:g} s: x forward, y left, z up, in mm "
            "from the trunk origin; rate = messages per second on each topic   (Ctrl-C stops "
            "everything)"
        )
        ended = echo_loop(
            self.ros,
            table,
            stop,
            topics_heading(table),
            options.interval,
            duration_s=options.duration,
            data_timeout_s=DEMO_START_TIMEOUT_S,
            duration_after_data=True,
            healthy=lambda: all(child.alive() for child in self.children),
        )
        if ended == "stop":
            return EXIT_INTERRUPTED
        if ended == "unhealthy":
            return EXIT_FAILED  # which child died, and its output, is reported when stopping
        code = EXIT_OK
        if ended == "no_data":
            say(
                f"  no feet from all of {', '.join(table.topics)} within "
                f"{DEMO_START_TIMEOUT_S:g} s"
            )
            code = EXIT_FAILED

        say(
            "\n[3/4] verify_fk: the node recomputes the latest feet with PyBullet and compares "
            "(distance per foot, m)"
        )
        verify_code, text = call_verify(self.ros, options.namespace, 5.0, stop)
        say("  " + text.replace("\n", "\n  "))
        if verify_code == EXIT_INTERRUPTED:
            return EXIT_INTERRUPTED
        return code if verify_code == EXIT_OK else EXIT_FAILED

    def cleanup(self, code: int) -> int:
        """Close our node, stop the children; the exit code, made 1 if a child misbehaved."""
        if self.ros is not None:
            self.ros.close()
            self.ros = None
        code = _stop_children(self.children, code)
        if self.temporary_log_dir is not None and code in (EXIT_OK, EXIT_INTERRUPTED):
            shutil.rmtree(self.temporary_log_dir, ignore_errors=True)
        return code


def _stop_children(children: list[Child], code: int) -> int:
    """Stop every child; report each; EXIT_FAILED if one died early or exited badly."""
    if not children:
        return code
    say("\n[4/4] stopping the nodes (SIGINT, as Ctrl-C)")
    died = [child for child in children if not child.alive()]
    for child in children:
        returncode = child.stop()
        if child not in died and returncode == -signal.SIGINT:
            # Our SIGINT arrived before the child's Python had installed rclpy's handlers (it was
            # still importing): the default action ended it. Stopped as asked, nothing to report.
            say(f"  {child.name} stopped (by SIGINT while still starting)")
        elif child in died or returncode != 0:
            how = "had already exited" if child in died else "exited"
            say(
                f"  {child.name} {how} with code {returncode}; its last output "
                f"({child.log}):\n{child.tail()}"
            )
            code = EXIT_FAILED
        else:
            say(f"  {child.name} stopped (exit code 0)")
    if code == EXIT_OK:
        say("demo finished: OK")
    elif code == EXIT_INTERRUPTED:
        say("demo interrupted: everything stopped")
    else:
        say(f"demo finished: FAILED (exit {code})")
    return code
