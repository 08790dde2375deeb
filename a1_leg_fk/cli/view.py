"""``a1-leg-fk view``: a recorded run -> a Rerun recording (``.rrd``): the robot posed by its joint
states and placed by the odometry, the feet (P(stance), forces, trails) and the time series of
``bag --forces`` and ``odom`` on one timeline; opened in the Rerun viewer unless ``--no-open``.

The same inputs and pipelines as ``bag`` and ``odom`` (:mod:`a1_leg_fk.view` writes what they
compute). Exit codes: 0 done; 1 the bag could not be read to its end (what was read is written);
2 bad usage or input, or no ``rerun-sdk`` (one line on stderr, no ``.rrd`` left); 130
interrupted (no ``.rrd`` left).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from a1_leg_fk.cli.bag import add_recording_arguments, recording_options, show_progress
from a1_leg_fk.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    input_error,
)
from a1_leg_fk.cli.rerun_sdk import import_rerun, viewer_executable
from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:  # the bag side is imported when the command runs
    from a1_leg_fk.recording.odometry import OdometryTrack
    from a1_leg_fk.recording.trajectories import FootTrajectories


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``view`` with the ``a1-leg-fk`` sub-commands."""
    view = commands.add_parser(
        "view",
        help="a recorded run (ROS bag) -> a Rerun recording (.rrd): robot, feet, forces, "
        "contacts, path and time series; opened in the Rerun viewer",
        description="Run the bag (--forces --contacts) and odom pipelines over a recording and "
        "write what they compute as a Rerun recording on the recording's stamps; open it in the "
        "Rerun viewer unless --no-open. Needs rerun-sdk (pip install 'a1_leg_fk[view]'). Exit 0 "
        "done, 1 the bag could not be read to its end, 2 bad input.",
    )
    add_recording_arguments(view)
    view.add_argument(
        "--truth",
        metavar="TOPIC",
        help="the base's true pose (as odom --truth): its path and velocity beside the estimate",
    )
    view.add_argument("--no-imu", action="store_true", help="the odometry from the legs alone")
    view.add_argument("--rrd", metavar="FILE", help="the output (default: INPUT.rrd)")
    view.add_argument("--no-open", action="store_true", help="write the .rrd only")
    view.add_argument("--force", action="store_true", help="replace an existing .rrd")
    view.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk view``: see the module docstring for exit codes."""
    del argv  # no ROS here
    if import_rerun("view") is None:
        return EXIT_BAD_INPUT
    from a1_leg_fk.cli.odom import track_of
    from a1_leg_fk.recording.outputs import checked_targets
    from a1_leg_fk.view.recording import write_view

    source = Path(options.input)
    try:
        rrd = options.rrd or str(source.with_name(source.name.rstrip("/") + ".rrd"))
        target = checked_targets(source, {"--rrd": rrd}, options.force)["--rrd"]
        feet = feet_pass(options)
        track = track_of(options) if feet.velocities is not None else None
        summary = summary_of(feet, track)
        note = write_view(target, feet, track, robot_options(options), summary)
    except (LegFkError, OSError) as error:
        return input_error("a1-leg-fk view", error)
    except KeyboardInterrupt:
        print("a1-leg-fk view: interrupted; no output written", file=sys.stderr)
        return EXIT_INTERRUPTED
    for line in summary:
        print(line)
    if note:
        print(f"view:      {note}")
    print(f"wrote:     {target.final}")
    if not options.no_open:
        _open_viewer(target.final)
    if feet.summary.stopped:
        print(f"a1-leg-fk view: {source}: stopped early: {feet.summary.stopped}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def feet_pass(options: argparse.Namespace) -> FootTrajectories:
    """``bag``'s pipeline over ``options.input`` as ``view`` runs it: contacts, and the foot
    forces where the joint states have efforts. :class:`LegFkError` without joint states.
    """
    from a1_leg_fk.recording.trajectories import read_foot_trajectories

    choices = recording_options(options, contacts=True)  # forces too where efforts are
    feet = read_foot_trajectories(options.input, progress=show_progress(options), **choices)
    if not len(feet.stamps_ns):
        raise LegFkError(f"{options.input}: no joint states to draw")
    return feet


def summary_of(feet: FootTrajectories, track: OdometryTrack | None) -> list[str]:
    """What ``bag`` prints, then ``odom``'s lines after its recording's (the same as feet's)."""
    from a1_leg_fk.cli.odom import summary_lines
    from a1_leg_fk.recording.odometry_kept import KeptRows

    summary = feet.summary.lines()
    if track is not None:
        kept = KeptRows(truth=track.truth is not None, plot=False)
        kept.add(track)
        summary += summary_lines(track, kept)[len(track.summary.lines()) :]
    return summary


def robot_options(options: argparse.Namespace) -> tuple[str | None, list[str], list[str]]:
    """``--urdf``, ``--foot-links`` and ``--joint-aliases``: the description to draw."""
    return (options.urdf, options.foot_links, options.joint_aliases)


def _open_viewer(path: Path) -> None:
    """The Rerun viewer on ``path``, in its own session (it outlives this command)."""
    viewer = viewer_executable()
    subprocess.Popen(
        [viewer, str(path)] if viewer else [sys.executable, "-m", "rerun", str(path)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
