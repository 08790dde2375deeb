"""``a1-leg-fk gait``: a recorded run (ROS bag) -> contacts, stride metrics and the gait's name.

The feet come from :func:`a1_leg_fk.cli.bag.trajectories_from_options` (world frame, so
``--base-pose`` is required) and go through :mod:`a1_leg_fk.gait.analysis`. Prints a short report;
``--json``, ``--plot`` and ``--csv-contacts`` write files: checked before the input is read (as
``a1-leg-fk bag`` checks its outputs; an existing file is replaced only with ``--force``), written
under hidden temporary names and renamed when complete. Exit codes: 0 done; 1 the bag could not be
read to its end (the analysis covers what was read) or a plot could not be drawn; 2 bad usage,
input or output (one line on stderr); 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.cli.bag import (
    add_recording_arguments,
    check_force_options,
    trajectories_from_options,
)
from a1_leg_fk.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    input_error,
)
from a1_leg_fk.estimation.sensor_contacts import sensor_contacts
from a1_leg_fk.gait.analysis import (
    Contacts,
    ContactThresholds,
    GaitReport,
    LegMetrics,
    detect_contacts,
    gait_metrics,
)
from a1_leg_fk.gait.contacts_csv import write_contacts_csv
from a1_leg_fk.gait.force_contacts import with_force_stance
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.recording.reads import DamagedRecording

if TYPE_CHECKING:  # imported when the command runs, as a1-leg-fk bag does
    from a1_leg_fk.recording.outputs import OutputTarget
    from a1_leg_fk.recording.trajectories import FootTrajectories

PROG = "a1-leg-fk gait"
NEEDS_BASE_POSE = (
    "needs --base-pose TOPIC (nav_msgs/Odometry, geometry_msgs/PoseStamped or /tf): contacts "
    "are found from each foot's height above the ground and its speed, which only world-frame "
    "feet have; base-frame feet move with the body (a stance foot sweeps backwards, a swing "
    "foot can look still)"
)
FILE_OPTIONS = {"--json": "json", "--csv-contacts": "csv_contacts", "--plot": "plot"}
"""The options that name an output file, and their attribute in the parsed options."""
THRESHOLD_HELP = {
    "height_on_m": "stance starts below this height above the ground level [m]; the floor of "
    "each foot's derived value unless --fixed-thresholds",
    "height_off_m": "stance ends above this height [m] (derived: the same gap above on)",
    "speed_on_mps": "stance starts below this foot speed [m/s]; the floor of each foot's derived "
    "value unless --fixed-thresholds",
    "speed_off_mps": "stance ends above this foot speed [m/s] (derived: the same gap above on)",
    "height_on_max_m": "the ceiling of each foot's derived stance-start height [m]",
    "speed_on_max_mps": "the ceiling of each foot's derived stance-start speed [m/s]",
    "min_phase_s": "shorter stances and swings (blips) are removed, shortest first: a stance "
    "blip dropped, a swing blip bridged [s]",
    "ground_percentile": "the ground level is this percentile of the still feet's heights [%%]",
    "speed_window_s": "speeds are difference quotients over at least this span [s]",
}


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``gait`` with the ``a1-leg-fk`` sub-commands."""
    gait = commands.add_parser(
        "gait",
        help="a recorded run (ROS bag) -> when each foot was down, duty factor, stride, step, "
        "clearance, gait name",
        description="Find each foot's stance phases from its world-frame height and speed "
        "(hysteresis, minimum phase, ground level estimated from the data), then per-leg "
        "metrics and the gait named in Hildebrand's terms (limb phase, duty factor: walk, amble, "
        "trot, pace; bound, half-bound, gallop, pronk; or unknown). Needs --base-pose. "
        "Exit 0 done, 1 bag not read to its end or plot failed, 2 bad input or output.",
    )
    add_recording_arguments(gait)
    gait.add_argument(
        "--json",
        metavar="FILE",
        help="write the report as JSON (no NaN: missing values are null with a reason)",
    )
    gait.add_argument(
        "--plot",
        metavar="FILE.png",
        help="Hildebrand gait diagram above the feet's heights (needs matplotlib)",
    )
    gait.add_argument(
        "--csv-contacts",
        metavar="FILE",
        help="one row per sample: time, stance (0/1), height [m] and speed [m/s] per leg",
    )
    gait.add_argument("--force", action="store_true", help="replace outputs that exist")
    gait.add_argument(
        "--contacts",
        choices=("auto", "force", "kinematic", "sensor"),
        default="auto",
        help="stance from the joint efforts' foot forces (force), from the feet's height and "
        "speed (kinematic), from a Unitree LowState's foot sensors (sensor: count above "
        "--sensor-threshold), or force when every leg has efforts (auto, the default)",
    )
    gait.add_argument(
        "--unsorted",
        choices=("sort", "reject"),
        default="sort",
        help="stamps that go back in time: sort them (default, reported) or reject the input",
    )
    gait.add_argument(
        "--fixed-thresholds",
        action="store_true",
        help="judge every foot by the threshold options as given, instead of deriving each "
        "foot's from its own height and speed distributions (bounded by them)",
    )
    defaults = ContactThresholds()
    for item in fields(ContactThresholds):
        if item.name == "adaptive":
            continue
        gait.add_argument(
            f"--{item.name.replace('_', '-')}",
            dest=item.name,
            type=float,
            metavar="X",
            default=getattr(defaults, item.name),
            help=f"{THRESHOLD_HELP[item.name]} (default {getattr(defaults, item.name):g})",
        )
    gait.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk gait``: see the module docstring for exit codes."""
    from a1_leg_fk.plots import pyplot

    del argv  # no ROS here
    try:
        if not options.base_pose:
            raise LegFkError(NEEDS_BASE_POSE)
        thresholds = ContactThresholds(
            **{
                item.name: getattr(options, item.name)
                for item in fields(ContactThresholds)
                if item.name != "adaptive"
            },
            adaptive=not options.fixed_thresholds,
        )
        estimated = options.contacts in ("auto", "force")
        check_force_options(options, estimated, "--contacts force|auto")
        if options.plot:
            pyplot()  # before the work: MissingMatplotlib says how to install it
        targets = checked_outputs(options)
        trajectories, source = read_with_contacts(options)
        try:
            contacts = analysed(options, trajectories, source, thresholds)
        except LegFkError as error:
            stopped = trajectories.summary.stopped
            if not stopped:
                raise
            raise DamagedRecording(
                f"{options.input}: stopped early: {stopped}; what was read gives no gait: {error}"
            ) from None
        report = gait_metrics(contacts)
    except LegFkError as error:
        return input_error(PROG, error)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    smoothing = " (causal, as the node)" if options.causal else " (smoothed over the recording)"
    print(f"contacts:  {source}{smoothing if source == 'force' else ''}")
    for line in report_lines(report, trajectories.world_frame):
        print(line)
    options.contact_source = source  # for the JSON
    code = write_outputs(options, targets, contacts, report, trajectories.world_frame)
    if trajectories.summary.stopped:
        print(
            f"{PROG}: {options.input}: stopped early: {trajectories.summary.stopped}",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT if code == EXIT_BAD_INPUT else EXIT_FAILED
    return code


def analysed(
    options: argparse.Namespace,
    trajectories: FootTrajectories,
    source: str,
    thresholds: ContactThresholds,
) -> Contacts:
    """The contacts of the recording's world feet (stance from the forces if ``source`` is
    ``"force"``); :class:`LegFkError` if there are no rows or no contacts can be told.
    """
    if trajectories.world_positions is None or trajectories.stamps_ns.size == 0:
        raise LegFkError(f"{options.input}: no JointState rows with feet")
    stamps_s = (trajectories.stamps_ns - trajectories.stamps_ns.min()) * 1e-9
    unsorted = options.unsorted
    contacts = detect_contacts(stamps_s, trajectories.world_positions, thresholds, unsorted)
    if source == "force" and trajectories.contacts is not None:
        contacts = with_force_stance(contacts, stamps_s, trajectories.contacts, unsorted)
    if source == "sensor" and trajectories.sensor is not None:
        threshold = options.sensor_threshold
        stance = sensor_contacts(trajectories.sensor, threshold).astype(float)
        note = f"stance from the foot sensors (count > {threshold:g})"
        contacts = with_force_stance(contacts, stamps_s, stance, unsorted, note)
    return contacts


def read_with_contacts(options: argparse.Namespace) -> tuple[FootTrajectories, str]:
    """The recording's feet (with forces unless ``--contacts kinematic``) and where the stance
    comes from: ``"force"``, ``"kinematic"`` or ``"sensor"`` (a LowState's foot sensors; a
    recording without them is a :class:`LegFkError`). ``--contacts auto`` takes the forces when
    every leg has some; ``--contacts force`` without them is a :class:`LegFkError`.
    """
    from a1_leg_fk.recording.forces import MissingEfforts

    if options.contacts in ("kinematic", "sensor"):
        trajectories = trajectories_from_options(options)
        if options.contacts == "sensor" and trajectories.sensor is None:
            raise LegFkError(
                "--contacts sensor needs a Unitree LowState topic (its foot sensors); "
                f"{trajectories.summary.topic} is {trajectories.summary.input_type}"
            )
        return trajectories, options.contacts
    try:
        trajectories = trajectories_from_options(options, forces=True)
    except MissingEfforts:
        if options.contacts == "force":
            raise
        return trajectories_from_options(options), "kinematic"
    estimated = (
        np.isfinite(trajectories.contacts).any(axis=0)
        if trajectories.contacts is not None and trajectories.contacts.size
        else np.zeros(len(LEG_NAMES), dtype=bool)
    )
    if estimated.all():
        return trajectories, "force"
    if options.contacts == "force":
        missing = [leg for leg, known in zip(LEG_NAMES, estimated) if not known]
        raise LegFkError(f"--contacts force: no foot force for legs {missing} (no efforts)")
    return trajectories, "kinematic"


def checked_outputs(options: argparse.Namespace) -> dict[str, OutputTarget]:
    """The requested output files by option, checked before the input is read.

    :class:`LegFkError` for a path that is a folder, lies inside the input, sits in a folder that
    does not exist, or exists without ``--force``; or for two options naming the same file.
    """
    from a1_leg_fk.recording.outputs import checked_targets

    paths = {option: getattr(options, name) for option, name in FILE_OPTIONS.items()}
    return checked_targets(Path(options.input), paths, options.force)


def _number(value: float | None, form: str) -> str:
    return "-" if value is None else format(value, form)


def _blips(metrics: LegMetrics) -> str:
    """``-D/+B``: the leg's stance blips dropped and swing blips bridged."""
    return f"-{metrics.blips_dropped}/+{metrics.blips_bridged}"


def threshold_summary(report: GaitReport) -> str:
    """The thresholds each leg was judged by, in one line: height on/off [m], speed on/off
    [m/s].
    """
    kind = "derived per foot" if report.thresholds.adaptive else "fixed"
    used = "; ".join(
        f"{leg} {t.height_on_m:.3f}/{t.height_off_m:.3f} m {t.speed_on_mps:.2f}/"
        f"{t.speed_off_mps:.2f} m/s"
        for leg, t in zip(LEG_NAMES, report.leg_thresholds)
    )
    return f"({kind}, on/off) {used}"


def report_lines(report: GaitReport, world_frame: str | None) -> list[str]:
    """The printed report: gait, ground, one row per leg, notes."""
    phases = ", ".join(
        f"{leg} {_number(value, '.2f')}" for leg, value in report.phase_vs_fr.items()
    )
    naming = report.naming
    limb_phase = naming.limb_phase if naming else None
    lines = [
        f"gait:      {report.gait} (fit {report.gait_fit:.2f}; {report.gait_reason})",
        (
            f"phases:    touchdown vs FR: {phases}; limb phase {_number(limb_phase, '.2f')}; "
            f"mean duty factor {_number(report.duty_factor, '.3f')}"
        ),
        f"thresholds: {threshold_summary(report)}",
        (
            f"ground:    level {report.ground.level_m:.4f} m in "
            f"{world_frame or 'the world frame'} (foot frame in stance), slope "
            f"{report.ground.slope_deg:.1f} deg"
        ),
        (
            f"{'leg':<4} {'status':<19} {'stances':>7} {'duty':>6} {'stride[s]':>9} "
            f"{'freq[Hz]':>8} {'step[m]':>8} {'clear[m]':>8} {'blips':>11}"
        ),
    ]
    for leg, metrics in report.legs.items():
        lines.append(
            f"{leg:<4} {metrics.status:<19} {len(metrics.stance_s):>7} "
            f"{_number(metrics.duty_factor, '.3f'):>6} "
            f"{_number(metrics.stride_period_s, '.3f'):>9} "
            f"{_number(metrics.stride_frequency_hz, '.2f'):>8} "
            f"{_number(metrics.step_length_m, '.3f'):>8} {_number(metrics.clearance_m, '.3f'):>8} "
            f"{_blips(metrics):>11}"
        )
    lines.extend(f"note:      {note}" for note in report.notes)
    return lines


def write_outputs(
    options: argparse.Namespace,
    targets: dict[str, OutputTarget],
    contacts: Contacts,
    report: GaitReport,
    world_frame: str | None,
) -> int:
    """Write ``targets`` (from :func:`checked_outputs`) under their temporary names, then rename
    them to their final names; no temporary is left behind. EXIT_FAILED if the plot cannot be
    drawn (the other files are written), EXIT_BAD_INPUT (one line on stderr) if a file cannot be
    written (a folder not writable, a full disk).
    """
    code, drawn = EXIT_OK, []
    try:
        for option, target in targets.items():
            target.prepare()
            try:
                _write_output(option, target.temporary, options, contacts, report, world_frame)
            except LegFkError as error:  # the plot could not be drawn
                print(f"{PROG}: {error}", file=sys.stderr)
                code = EXIT_FAILED
                continue
            drawn.append(target)
        for target in drawn:
            target.commit()
            print(f"wrote:     {target.final}")
    except OSError as error:
        print(
            f"{PROG}: cannot write {target.final}: {error.strerror or error}",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    finally:
        for target in targets.values():
            target.discard()
    return code


def _write_output(
    option: str,
    path: Path,
    options: argparse.Namespace,
    contacts: Contacts,
    report: GaitReport,
    world_frame: str | None,
) -> None:
    """Write the file of ``option`` (one of :data:`FILE_OPTIONS`) to ``path``; :class:`LegFkError`
    if the plot cannot be drawn.
    """
    from a1_leg_fk.plots import plot_gait_diagram

    if option == "--json":
        document = {
            "input": str(options.input),
            "world_frame": world_frame,
            "contacts": getattr(options, "contact_source", "kinematic"),
            **report.to_json(),
        }
        path.write_text(json.dumps(document, indent=2, allow_nan=False) + "\n")
    elif option == "--csv-contacts":
        write_contacts_csv(contacts, path)
    else:
        plot_gait_diagram(contacts, report, path, title=Path(options.input).name)
