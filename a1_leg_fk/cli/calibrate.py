"""``a1-leg-fk calibrate RECORDING -o FILE``: the model corrections (the joints' bias, viscous and
Coulomb friction, the legs' inertia scales) and the payload fitted over a recorded run
(:mod:`a1_leg_fk.recording.calibration`), written as the file ``bag | gait | odom --corrections
FILE`` read.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from a1_leg_fk.cli.bag import add_input_arguments, show_progress
from a1_leg_fk.cli.common import EXIT_INTERRUPTED, EXIT_OK, input_error
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError

PROG = "a1-leg-fk calibrate"


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``calibrate`` with the ``a1-leg-fk`` sub-commands."""
    calibrate = commands.add_parser(
        "calibrate",
        help="a recorded run (ROS bag) -> the model corrections' file (joint friction, leg "
        "inertia scales, payload)",
        description="Fit the joints' torque bias, viscous and Coulomb friction over the samples "
        "in which a foot was surely in the air with each leg's inertia scale (its links' mass and "
        "inertia over the URDF's), and the payload over a standing phase (all four "
        "feet down and still), from a recording with joint efforts, a few strides and a standing "
        "phase; write them with the fit's residuals to FILE, which bag, gait and odom read with "
        "--corrections FILE. Exit 0 written, 2 bad input or a recording that cannot identify "
        "them.",
    )
    add_input_arguments(calibrate)
    calibrate.add_argument(
        "--imu",
        metavar="TOPIC",
        help="sensor_msgs/msg/Imu aligned with the base: gravity's direction, the base's motion "
        "(as bag --imu); without its gyro and accelerometer the legs' inertia scales are not "
        "fitted (1)",
    )
    calibrate.add_argument(
        "--effort-scale",
        type=float,
        default=1.0,
        metavar="K",
        help="the efforts read K times the motors' torques (a torque constant off; from the "
        "maker or a bench test: a recording cannot tell it from a payload), in [0.5, 2]; "
        "undone before the fit and written to FILE (default 1)",
    )
    calibrate.add_argument(
        "--effort-latency-ms",
        type=float,
        default=0.0,
        metavar="MS",
        help="the efforts arrive MS late against the joint positions (a recording does not "
        "single it out), in [0, 20]; undone (predicted ahead) before the fit and written to "
        "FILE (default 0)",
    )
    calibrate.add_argument("-o", "--output", required=True, metavar="FILE", help="the file")
    calibrate.add_argument("--force", action="store_true", help="replace FILE if it exists")
    calibrate.add_argument("--quiet", action="store_true", help="no progress bar")
    calibrate.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """Calibrate, write FILE, print what was fitted."""
    from a1_leg_fk.recording.calibration import calibrate_recording

    del argv  # no ROS here
    target = Path(options.output)
    try:
        if target.exists() and not options.force:
            raise LegFkError(f"-o {target}: exists already (use --force to replace it)")
        calibration, scales_fitted = calibrate_recording(
            options.input,
            progress=show_progress(options),
            topic=options.topic,
            urdf=options.urdf,
            foot_links=options.foot_links,
            joint_aliases=options.joint_aliases,
            imu=options.imu,
            timing=(options.effort_scale, options.effort_latency_ms * 1e-3),
        )
        target.write_text(calibration.text(), encoding="utf-8")
    except (LegFkError, OSError) as error:
        return input_error(PROG, error)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    print("per joint (hip/thigh/calf): bias [N m], viscous [N m s/rad], Coulomb [N m]; the swing")
    print("residual's RMS [N m] before -> after the fit")
    for leg, name in enumerate(LEG_NAMES):
        joints = range(leg * JOINTS_PER_LEG, (leg + 1) * JOINTS_PER_LEG)
        terms = " / ".join(
            "{:+.2f} {:.2f} {:.2f}".format(*(value + 0.0 for value in calibration.terms[j]))
            for j in joints
        )
        fits = " / ".join(
            f"{calibration.residuals[j][1]:.2f}->{calibration.residuals[j][2]:.2f}" for j in joints
        )
        print(f"{name}: {terms}   ({fits})")
    scales = " ".join(f"{n} {v:.3f}" for n, v in zip(LEG_NAMES, calibration.inertia_scales))
    if scales_fitted:
        print(f"legs:      inertia scales (mass and inertia over the URDF's) {scales}")
    else:
        print("legs:      inertia scales 1, not fitted: no IMU gyro and accelerometer (--imu);")
        print("           without the base's motion the legs' scales would read it")
    print(
        f"payload:   {calibration.payload_kg:+.2f} kg over the URDF's mass, from "
        f"{calibration.standing_s:.2f} s of standing"
    )
    print(
        f"efforts:   scale {calibration.effort_scale:g}, latency "
        f"{calibration.effort_latency_s * 1e3:g} ms (undone before the fit; as given)"
    )
    print(f"wrote:     {target}")
    return EXIT_OK
