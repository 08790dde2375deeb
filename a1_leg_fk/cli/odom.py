"""``a1-leg-fk odom``: a recorded run (ROS bag) -> the base's leg odometry: CSV, a PNG, a summary,
and with ``--truth`` its error against a recorded base pose.

The same pipeline as ``leg_odometry_node`` (:mod:`a1_leg_fk.estimation.odometry_feed`), fed the
bag's JointState and Imu messages in bag order. Exit codes as ``a1-leg-fk bag``: 0 done; 1 the
bag could not be read to its end (what was read is written); 2 bad usage or input (one line on
stderr, nothing written); 130 interrupted (nothing left under the final output names).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.cli.bag import add_input_arguments, show_progress
from a1_leg_fk.cli.common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    add_corrections_argument,
    input_error,
    non_negative,
)
from a1_leg_fk.estimation.filter_model import DEFAULT_GROUND, GROUND_MODELS
from a1_leg_fk.estimation.ground_outputs import GROUND_COLUMNS
from a1_leg_fk.estimation.imu_pairing import DEFAULT_IMU_WAIT_S
from a1_leg_fk.estimation.odometry_feed import CONTACT_SOURCES
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:  # the bag side is imported when the command runs
    from a1_leg_fk.recording.odometry import (
        OdometryOptions,
        OdometryStream,
        OdometryTrack,
        TrackInfo,
    )
    from a1_leg_fk.recording.odometry_kept import KeptRows
    from a1_leg_fk.recording.odometry_rows import TrackRows
    from a1_leg_fk.recording.outputs import OutputTarget

CSV_HEADER = (
    "stamp_ns,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz,cov_vx,cov_vy,cov_vz,"
    + ",".join(GROUND_COLUMNS)
    + "\n"
)


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``odom`` with the ``a1-leg-fk`` sub-commands."""
    odom = commands.add_parser(
        "odom",
        help="a recorded run (ROS bag) -> the base's leg odometry: CSV, a PNG, errors vs a truth",
        description="Estimate the base's velocity and path from the legs (and an IMU) of a "
        "recorded run, as leg_odometry_node does live; print a summary, write CSV (--csv) and/or "
        "a plot (--plot), and compare with a recorded base pose (--truth). Exit 0 done, 1 the "
        "bag could not be read to its end (what was read is written), 2 bad input.",
    )
    add_input_arguments(odom)
    add_corrections_argument(odom)
    odom.add_argument(
        "--imu", metavar="TOPIC", help="the sensor_msgs/msg/Imu topic (default: the only one)"
    )
    odom.add_argument("--no-imu", action="store_true", help="ignore the IMU: legs alone")
    odom.add_argument(
        "--imu-wait",
        type=non_negative,
        default=DEFAULT_IMU_WAIT_S,
        metavar="S",
        help="a joint state stamped after the newest IMU sample waits for one stamped at or after "
        "it until a joint state this much later [s] (default %(default)g; 0: never waits, the "
        "latest IMU sample at or before it as it arrived)",
    )
    odom.add_argument(
        "--contacts",
        choices=CONTACT_SOURCES,
        default="auto",
        help="the contacts' evidence: the joint efforts' foot forces with the feet's heights and "
        "speeds where a joint state has efforts (auto, the default), the same with no foot "
        "standing without efforts (force), or the feet's heights and speeds alone (kinematic)",
    )
    odom.add_argument(
        "--ground",
        choices=GROUND_MODELS,
        default=DEFAULT_GROUND,
        help="footholds (default): each stance foot's height is held to its foothold's, anchored "
        "where it agrees with the ground predicted from the earlier footholds and their slope "
        "(flat floors, slopes, stairs, rough ground); flat: to the first feet's height (a known "
        "flat floor); none: not held",
    )
    odom.add_argument(
        "--causal",
        action="store_true",
        help="the state filter's own estimate, each row from the rows before it, as "
        "leg_odometry_node has it (default: smoothed over the whole recording, a "
        "Rauch-Tung-Striebel pass backward over the filter's steps)",
    )
    odom.add_argument(
        "--truth",
        metavar="TOPIC",
        help="the base's true pose to compare with (nav_msgs/Odometry, geometry_msgs/PoseStamped, "
        "PoseWithCovarianceStamped, or /tf by the base frame's child transforms)",
    )
    odom.add_argument(
        "--foot-radius",
        type=non_negative,
        metavar="M",
        help="the feet's rolling radius [m] (default: the foot links' collision spheres)",
    )
    odom.add_argument(
        "--csv",
        metavar="FILE",
        help=f"one row per joint state with velocities: {CSV_HEADER.strip()}",
    )
    odom.add_argument(
        "--plot", metavar="FILE.png", help="the path from above and the velocities over time"
    )
    odom.add_argument("--force", action="store_true", help="replace outputs that exist")
    odom.add_argument("--quiet", action="store_true", help="no progress bar")
    odom.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk odom``: see the module docstring for exit codes."""
    from a1_leg_fk.plots import pyplot
    from a1_leg_fk.recording.odometry import odometry_stream
    from a1_leg_fk.recording.outputs import checked_targets

    del argv  # no ROS here
    try:
        odometry, choices = odometry_inputs(
            options,
            radius_m=options.foot_radius,
            contacts=options.contacts,
            ground=options.ground,
            imu_wait_s=options.imu_wait,
        )
        if options.plot:
            pyplot()  # before the work: MissingMatplotlib says how to install it
        targets = checked_targets(
            Path(options.input), {"--csv": options.csv, "--plot": options.plot}, options.force
        )
        stream = odometry_stream(options.input, odometry, **choices)
        info, kept = _write(stream, targets, truth=options.truth is not None)
    except (LegFkError, OSError) as error:
        return input_error("a1-leg-fk odom", error)
    except KeyboardInterrupt:
        print("a1-leg-fk odom: interrupted; no output written", file=sys.stderr)
        return EXIT_INTERRUPTED
    for line in summary_lines(info, kept):
        print(line)
    for path in targets.values():
        print(f"wrote:     {path.final}")
    if info.summary.stopped:
        print(
            f"a1-leg-fk odom: {options.input}: stopped early: {info.summary.stopped}",
            file=sys.stderr,
        )
        return EXIT_FAILED
    return EXIT_OK


def _write(
    stream: OdometryStream, targets: dict[str, OutputTarget], truth: bool
) -> tuple[TrackInfo, KeptRows]:
    """Run ``stream``: its rows written to the CSV as they come, what the summary and the plot
    need of them kept (``truth``: the comparison's columns); the outputs written under
    temporary names, then moved into place.
    """
    from a1_leg_fk.odometry_plot import plot_odometry
    from a1_leg_fk.recording.odometry import OdometryTrack
    from a1_leg_fk.recording.odometry_kept import KeptRows

    kept = KeptRows(truth, plot="--plot" in targets)
    csv = None
    try:
        for target in targets.values():
            target.prepare()
        if "--csv" in targets:
            csv = open(targets["--csv"].temporary, "wb")  # noqa: SIM115 (closed below)
            csv.write(CSV_HEADER.encode())
        for rows in stream:
            if csv is not None:
                csv.write(_csv_rows(rows))
            kept.add(rows)
        if csv is not None:
            csv.close()
        info = stream.info
        assert info is not None  # the stream was run to its end
        if "--plot" in targets:
            plot_odometry(OdometryTrack.of_rows(kept.plotted(), info), targets["--plot"].temporary)
        for target in targets.values():
            target.commit()
    except BaseException:
        if csv is not None:
            csv.close()
        for target in targets.values():
            target.discard()
        raise
    return info, kept


def _csv_rows(rows: TrackRows) -> bytes:
    """The CSV lines of ``rows`` (:data:`CSV_HEADER`'s columns)."""
    from a1_leg_fk.recording.csv_text import format_rows

    floats = np.hstack(
        [rows.positions, rows.orientations, rows.linear, rows.angular, rows.twist_variances[:, :3],
         rows.grounds]
    )  # fmt: skip
    return format_rows(rows.stamps_ns[:, None], floats)


def odometry_inputs(
    options: argparse.Namespace, **settings: Any
) -> tuple[OdometryOptions, dict[str, Any]]:
    """The odometry's options and the recording's choices that ``odom`` and ``view`` share
    (``--imu``, ``--no-imu``, ``--causal``: else smoothed, ``--quiet``; ``--truth``, ``--topic``,
    ``--urdf``, ``--foot-links``, ``--joint-aliases``, ``--corrections``); ``settings``: more of
    :class:`~a1_leg_fk.recording.odometry.OdometryOptions` (``odom``'s ``radius_m``,
    ``contacts``, ``ground``, ``imu_wait_s``). :class:`LegFkError` for contradicting options.
    """
    from a1_leg_fk.recording.odometry import OdometryOptions

    if options.no_imu and options.imu:
        raise LegFkError("--imu and --no-imu contradict each other")
    odometry = OdometryOptions(
        imu_topic=options.imu,
        use_imu=not options.no_imu,
        smoothed=not options.causal,
        progress=show_progress(options),
        **settings,
    )
    choices = {
        "base_pose": options.truth,
        "topic": options.topic,
        "urdf": options.urdf,
        "foot_links": options.foot_links,
        "joint_aliases": options.joint_aliases,
        "model_corrections": options.corrections,
    }
    return odometry, choices


def track_of(options: argparse.Namespace) -> OdometryTrack:
    """The whole odometry track over ``options.input`` (:func:`odometry_inputs`), for ``view``."""
    from a1_leg_fk.recording.odometry import odometry_track

    odometry, choices = odometry_inputs(options)
    return odometry_track(options.input, odometry, **choices)


def summary_lines(info: TrackInfo, kept: KeptRows) -> list[str]:
    """The human summary of an odometry run (``kept``: what it kept of its rows), one fact per
    line.
    """
    summary, counts = info.summary, info.counts
    lines = summary.lines()
    imu = (
        f"{info.imu_topic} ({info.imu_samples} samples; {info.rows_with_imu} of "
        f"{kept.rows} rows had one)"
        if info.imu_topic
        else "none (legs alone: planar pose, yaw from the feet)"
    )
    final = (
        f"; final position {np.round(kept.last, 3).tolist()} m in odom"
        if kept.last is not None
        else ""
    )
    contacts = f"{info.contacts} ({info.contact_counts.line()})" + (
        f" (no foot forces for this robot: {info.contacts_note})" if info.contacts_note else ""
    )
    radii = sorted(set(info.radii))
    lines += [f"imu:       {imu}", f"contacts:  {contacts}"]
    if info.filtered:
        lines.append(_filter_line(info))
    if counts.samples:
        slips = ", ".join(f"{leg} {n}" for leg, n in zip(LEG_NAMES, counts.slips))
        lines.append(
            f"legs alone: {counts.samples} rows (no accelerometer); samples without a stance "
            f"foot {counts.no_stance}; feet dropped as slipping: {slips}"
        )
    lines += [
        f"feet:      rolling radius {', '.join(f'{r:g}' for r in radii)} m",
        f"distance:  {kept.distance_m:.3f} m travelled{final}",
    ]
    if info.truth is not None:
        comparison = kept.comparison(info.planar, info.truth)
        lines.append(
            f"truth:     {info.truth_topic}: "
            + (comparison.line() if comparison else "fewer than two rows with a pose")
        )
    return lines


def _filter_line(track: TrackInfo) -> str:
    """The state filter's line of the summary: rows, the gate's feet, NIS, biases."""
    counts = track.filter_counts
    used = ", ".join(f"{leg} {n}" for leg, n in zip(LEG_NAMES, counts.used))
    rejected = ", ".join(f"{leg} {n}" for leg, n in zip(LEG_NAMES, counts.rejected))
    gyro, accel = (" ".join(f"{value:+.4f}" for value in bias) for bias in track.biases)
    which = "smoothed over the recording (RTS)" if track.smoothed else "causal, as the node has it"
    return (
        f"filter:    {track.filtered} rows (IMU-propagated ESKF, {which}); feet used {used}; "
        f"rejected by "
        f"the gate {rejected}; gate resets {counts.gate_resets}; mean NIS "
        f"{counts.mean_nis:.2f}; gyro bias {gyro} rad/s; accelerometer bias {accel} m/s^2; "
        f"feet noise scales {track.noise_scales[0]:.3f} horizontal, {track.noise_scales[1]:.3f} "
        "vertical"
    )
