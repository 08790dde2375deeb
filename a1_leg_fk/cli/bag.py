"""``a1-leg-fk bag``: a recorded run (ROS bag) -> the feet as CSV, a new bag, a PNG, a summary.

A thin layer over :mod:`a1_leg_fk.recording.trajectories` and :mod:`a1_leg_fk.recording.outputs`.
Exit codes: 0 done; 1 the bag could not be read to its end (what was read is written, the reason
printed); 2 bad usage or input (one line on stderr, nothing written); 130 interrupted (nothing left
under the final output names).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from a1_leg_fk.cli.common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    add_corrections_argument,
    input_error,
    non_negative,
)
from a1_leg_fk.estimation.contact_estimator import (
    CONTACT_RULES,
    DYNAMIC,
    FILTER,
    FORCE_MODELS,
    THRESHOLD,
)
from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS
from a1_leg_fk.estimation.sensor_contacts import DEFAULT_SENSOR_THRESHOLD_COUNTS
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.trajectories import (
    DEFAULT_MAX_POSE_GAP_S,
    FootTrajectories,
    RecordingChoices,
    read_foot_trajectories,
)


def add_recording_arguments(parser: argparse.ArgumentParser) -> None:
    """INPUT and the options that choose what is read from it (shared with ``a1-leg-fk gait``)."""
    add_input_arguments(parser)
    parser.add_argument(
        "--base-pose",
        metavar="TOPIC",
        help="the base's pose (nav_msgs/Odometry, geometry_msgs/PoseStamped, "
        "PoseWithCovarianceStamped, or /tf): adds world-frame feet",
    )
    parser.add_argument(
        "--max-pose-gap",
        type=non_negative,
        default=DEFAULT_MAX_POSE_GAP_S,
        metavar="S",
        help="no world position between two poses further apart than S seconds (default "
        f"{DEFAULT_MAX_POSE_GAP_S:g})",
    )
    parser.add_argument(
        "--imu",
        metavar="TOPIC",
        help="sensor_msgs/msg/Imu aligned with the base, at its origin: gravity's direction from "
        "its orientation (default: the base is level), the base's motion from its gyro and "
        "accelerometer, for the foot forces and contacts (nearest sample in time)",
    )
    parser.add_argument(
        "--force-model",
        choices=FORCE_MODELS,
        default=DYNAMIC,
        help="foot forces from the legs' dynamics (momentum observer; default) or quasi-static",
    )
    parser.add_argument(
        "--contact-rule",
        choices=CONTACT_RULES,
        default=FILTER,
        help="contacts from the fused filter (force, foot heights and speeds; default) or the "
        "normal force between --touchdown-force and --liftoff-force",
    )
    parser.add_argument(
        "--touchdown-force",
        type=non_negative,
        metavar="N",
        help="--contact-rule threshold: a foot touches down at this normal force [N] (default: 8 "
        "%% of the robot's weight)",
    )
    parser.add_argument(
        "--liftoff-force",
        type=non_negative,
        metavar="N",
        help="--contact-rule threshold: a foot lifts off below this normal force [N] (default: 4 "
        "%% of the weight)",
    )
    parser.add_argument(
        "--sensor-threshold",
        type=non_negative,
        default=DEFAULT_SENSOR_THRESHOLD_COUNTS,
        metavar="COUNTS",
        help="a Unitree LowState's foot sensor above this raw count is in contact (default "
        f"{DEFAULT_SENSOR_THRESHOLD_COUNTS:g}, as a controller run on real A1s takes it)",
    )
    add_corrections_argument(parser)
    parser.add_argument(
        "--causal",
        action="store_true",
        help="the contact filter's live answer, each sample from the samples before it, as the "
        "node has it (default: smoothed over the whole recording, forward and backward)",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def add_input_arguments(parser: argparse.ArgumentParser) -> None:
    """INPUT, its JointState topic and the robot model (shared with ``a1-leg-fk odom``)."""
    parser.add_argument(
        "input",
        metavar="INPUT",
        help="a ROS 2 bag directory (sqlite3 or MCAP), a .mcap file or a ROS 1 .bag",
    )
    parser.add_argument(
        "--topic",
        help="the sensor_msgs/msg/JointState topic (needed when the bag has several), or a "
        "Unitree LowState topic (unitree_go/msg/LowState, unitree_legged_msgs/LowState: read "
        "without --topic when the bag has no JointState)",
    )
    parser.add_argument(
        "--urdf",
        metavar="FILE",
        help="robot model (default: the bag's robot_description topic, else the embedded A1)",
    )
    parser.add_argument(
        "--foot-links",
        nargs="*",
        default=[],
        metavar="LEG=link",
        help="as the node's foot_links parameter",
    )
    parser.add_argument(
        "--joint-aliases",
        nargs="*",
        default=[],
        metavar="NAME=joint",
        help="as the node's joint_aliases parameter",
    )


def recording_options(
    options: argparse.Namespace, forces: bool = False, contacts: bool = False
) -> RecordingChoices:
    """The keyword arguments of :func:`~a1_leg_fk.recording.trajectories.open_recording` from
    parsed options; ``forces``: foot forces and contacts from the efforts too; ``contacts``:
    contacts with or without efforts.
    """
    return {
        "topic": options.topic,
        "urdf": options.urdf,
        "foot_links": options.foot_links,
        "joint_aliases": options.joint_aliases,
        "base_pose": options.base_pose,
        "max_pose_gap_s": options.max_pose_gap,
        "forces": forces,
        "estimate_contacts": contacts,
        "imu": options.imu,
        "contact_thresholds": (options.touchdown_force, options.liftoff_force),
        "force_model": options.force_model,
        "contact_rule": options.contact_rule,
        "model_corrections": options.corrections,
        "sensor_threshold": getattr(options, "sensor_threshold", DEFAULT_SENSOR_THRESHOLD_COUNTS),
        "causal": options.causal,
    }


def show_progress(options: argparse.Namespace) -> bool:
    """A progress bar on stderr when it is a terminal, unless ``--quiet``."""
    return not options.quiet and sys.stderr.isatty()


def trajectories_from_options(
    options: argparse.Namespace, forces: bool = False
) -> FootTrajectories:
    """The feet (and with ``forces``, foot forces and contacts) of ``options.input`` as arrays;
    :class:`LegFkError` (one line) for bad input.
    """
    return read_foot_trajectories(
        options.input, progress=show_progress(options), **recording_options(options, forces)
    )


def check_force_options(options: argparse.Namespace, forces: bool, needs: str) -> None:
    """:class:`LegFkError` for force and contact options given without force or contact
    estimation (``needs``: the options that turn it on), or threshold forces without the
    threshold rule.
    """
    chosen = [
        ("--imu", options.imu is not None),
        ("--force-model", options.force_model != DYNAMIC),
        ("--contact-rule", options.contact_rule != FILTER),
        ("--corrections", options.corrections != DEFAULT_MODEL_CORRECTIONS),
        ("--touchdown-force", options.touchdown_force is not None),
        ("--liftoff-force", options.liftoff_force is not None),
        ("--causal", options.causal),
    ]
    for option, given in chosen:
        if given and not forces:
            raise LegFkError(f"{option} needs {needs}")
        if given and option.endswith("-force") and options.contact_rule != THRESHOLD:
            raise LegFkError(f"{option} needs --contact-rule threshold")


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``bag`` with the ``a1-leg-fk`` sub-commands."""
    bag = commands.add_parser(
        "bag",
        help="a recorded run (ROS bag) -> foot trajectories: CSV, a new bag, a PNG",
        description="Compute every foot of a recorded run with the node's model and JointState "
        "rules, and write them as CSV (--csv), a new ROS 2 bag (--output-bag) and/or a plot "
        "(--plot); print a summary. Exit 0 done, 1 the bag could not be read to its end (what "
        "was read is written), 2 bad input.",
    )
    add_recording_arguments(bag)
    bag.add_argument(
        "--csv",
        metavar="FILE",
        help="one row per accepted JointState: stamps, feet [m], velocities [m/s], world feet [m] "
        "(and with --forces, foot forces [N] and contact probabilities)",
    )
    bag.add_argument(
        "--contacts",
        action="store_true",
        help="contact probabilities, with the joint efforts' forces as evidence when the "
        "JointStates carry them and from the feet's heights and speeds alone when not: CSV "
        "columns FR_contact .. RL_contact, /foot_contacts in --output-bag",
    )
    bag.add_argument(
        "--forces",
        action="store_true",
        help="foot forces from the joint efforts (the ground's force on each foot [N], base "
        "frame) and contacts: CSV columns FR_fx .. RL_fz, FR_contact .. RL_contact; "
        "/foot_forces/<leg> and /foot_contacts in --output-bag",
    )
    bag.add_argument(
        "--output-bag",
        metavar="PATH",
        help="a new ROS 2 bag with foot_positions/<leg> (and velocities, world feet)",
    )
    bag.add_argument(
        "--storage",
        choices=("mcap", "sqlite3"),
        default="mcap",
        help="storage of --output-bag (default mcap)",
    )
    bag.add_argument(
        "--copy-input",
        action="store_true",
        help="copy every input topic into --output-bag as well",
    )
    bag.add_argument(
        "--plot", metavar="FILE.png", help="the feet over time (x, y, z per leg), needs matplotlib"
    )
    bag.add_argument("--force", action="store_true", help="replace outputs that exist")
    bag.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk bag``: see the module docstring for exit codes."""
    from a1_leg_fk.plots import pyplot
    from a1_leg_fk.recording.outputs import Outputs, convert

    del argv  # no ROS here
    try:
        if not (options.csv or options.output_bag or options.plot):
            raise LegFkError(
                "nothing to write: give --csv FILE, --output-bag PATH and/or --plot FILE.png"
            )
        if options.copy_input and not options.output_bag:
            raise LegFkError("--copy-input needs --output-bag")
        estimated = options.forces or options.contacts
        check_force_options(options, estimated, "--forces or --contacts")
        if options.plot:
            pyplot()  # before the work: MissingMatplotlib says how to install it
        outputs = Outputs.checked(
            Path(options.input),
            csv=options.csv,
            bag=options.output_bag,
            plot=options.plot,
            storage=options.storage,
            copy_input=options.copy_input,
            force=options.force,
        )
        summary = convert(
            Path(options.input),
            outputs,
            progress=show_progress(options),
            **recording_options(options, options.forces, options.contacts),
        )
    except (LegFkError, OSError) as error:  # OSError: an output folder not writable, a full disk
        return input_error("a1-leg-fk bag", error)
    except KeyboardInterrupt:
        print("a1-leg-fk bag: interrupted; no output written", file=sys.stderr)
        return EXIT_INTERRUPTED
    for line in summary.lines():
        print(line)
    for written in outputs.written():
        print(f"wrote:     {written}")
    if summary.stopped:
        print(f"a1-leg-fk bag: {options.input}: stopped early: {summary.stopped}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK
