"""``a1-leg-fk``: echo | verify | plot | demo | bag | odom | gait | calibrate | ik, for installs
without the ROS 2 command line tools.

One module per command (:mod:`.echo`, :mod:`.verify`, :mod:`.plot`, :mod:`.demo`, :mod:`.bag`,
:mod:`.odom`, :mod:`.gait`, :mod:`.calibrate`, :mod:`.ik`), each with ``add_parser(subparsers)``
and ``run(options, argv)``; the shared plumbing (exit codes, signals, this tool's ROS node, child
processes) is :mod:`.common`.

The ROS arguments (after ``--ros-args``, up to a lone ``--``) are found by rclpy's own
``remove_ros_args``; ``rclpy.init`` gets the whole command line, so ``--ros-args -r
__ns:=/robot1`` moves this tool's own node, and with it every relative name it uses, into
``/robot1``. ``--namespace NS`` instead prefixes the names themselves (``NS/foot_positions/FR``,
``NS/verify_fk``); an absolute ``NS`` (``/robot1``) is then not affected by ``__ns``.

Exit codes: 0 success; 1 failure (verify said no, a demo child died, a plot could not be made);
2 nobody answered in time (or bad usage); 130 interrupted (Ctrl-C or SIGTERM), except ``echo``,
for which Ctrl-C is the normal way to stop (0); 141 stdout closed by its reader (``| head``), with
no traceback.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Sequence

from a1_leg_fk.cli import bag, calibrate, demo, echo, gait, ik, odom, plot, verify, view
from a1_leg_fk.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_OK,
    PROG,
    BadRosArguments,
    our_arguments,
)

EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE
"""The exit code when stdout's reader went away, as a shell reports a process ended by SIGPIPE."""

COMMANDS = (echo, verify, plot, demo, bag, odom, gait, calibrate, ik, view)
"""The sub-command modules, in the order ``--help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The ``a1-leg-fk`` parser: one sub-command per module of :data:`COMMANDS`."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Tools around foot_fk_node (the a1_leg_fk feet forward kinematics) for "
        "installs without the ROS 2 command line. ROS arguments go last: ... --ros-args -r "
        "__ns:=/robot1",
        epilog="exit codes: 0 ok, 1 failed, 2 no answer in time / bad usage, 130 interrupted",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        command.add_parser(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``a1-leg-fk``; ``argv`` excludes the program name. Returns the exit code."""
    arguments = list(sys.argv[1:] if argv is None else argv)
    try:
        ours = our_arguments(arguments)
    except BadRosArguments as error:
        print(f"{PROG}: bad --ros-args: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    options = build_parser().parse_args(ours)
    try:
        code = int(options.handler(options, arguments))
        sys.stdout.flush()  # here, so that a closed pipe is caught below, not at exit
    except KeyboardInterrupt:  # a Ctrl-C that arrived outside the commands' own handling
        return EXIT_OK if options.command == "echo" else EXIT_INTERRUPTED
    except BrokenPipeError:  # stdout closed by its reader (`a1-leg-fk gait ... | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no error at exit either
        return EXIT_BROKEN_PIPE
    return code
