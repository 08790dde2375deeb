"""``a1-leg-fk ik LEG X Y Z``: the joint angles that put one foot at a point, offline (no ROS).

Prints the chosen angles (rad and degrees), the status, the residual, and every exact solution
with whether it is inside the URDF limits. ``--seed`` takes the leg's 3 angles or all 12 [rad].
Exit codes, for scripts: 0 status ok; 1 the target is outside the limits or unreachable (the
status and the nearest angles still printed); 2 bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from a1_leg_fk.cli.common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK
from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES, leg_slot

if TYPE_CHECKING:  # imported when solving: --help needs no kinematics
    from a1_leg_fk.kinematics.quadruped import Quadruped


def add_parser(
    subparsers: argparse._SubParsersAction[argparse.ArgumentParser],
) -> argparse.ArgumentParser:
    """Register ``ik`` on the ``a1-leg-fk`` command parser."""
    parser = subparsers.add_parser(
        "ik",
        help="joint angles that put one foot at X Y Z (base frame, m): status, residual, every "
        "solution",
        description="Inverse kinematics of one leg, offline: the angles nearest the seed "
        "(default: the middle of the joint ranges) that put the foot at X Y Z [m] in the base "
        "frame, the status (ok, outside_limits, unreachable), the distance from the foot at "
        "those angles to the target, and every exact solution.",
    )
    parser.add_argument(
        "leg", choices=LEG_NAMES, metavar="LEG", help=f"one of {', '.join(LEG_NAMES)}"
    )
    for axis in ("x", "y", "z"):
        parser.add_argument(
            axis, type=float, metavar=axis.upper(), help=f"target {axis} [m], base frame"
        )
    parser.add_argument(
        "--seed",
        type=float,
        nargs="+",
        metavar="RAD",
        help=f"seed angles [rad]: the leg's {JOINTS_PER_LEG}, or all "
        f"{JOINT_COUNT} in slot order (FR, FL, RR, RL, root side first)",
    )
    parser.add_argument(
        "--urdf", metavar="FILE", help="robot description (default: the embedded Unitree A1)"
    )
    parser.set_defaults(handler=run)
    return parser


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """Solve and print; exit 0 for status ok, 1 for outside_limits or unreachable, 2 (one line
    on stderr) for bad input.
    """
    del argv  # no ROS here
    from a1_leg_fk.kinematics.ik.four_legs import OK
    from a1_leg_fk.kinematics.quadruped import Quadruped
    from a1_leg_fk.model.urdf import LegFkError

    try:
        quadruped = Quadruped.from_urdf(options.urdf)
        lines, status = report(
            quadruped, options.leg, (options.x, options.y, options.z), options.seed
        )
    except LegFkError as error:
        print(f"a1-leg-fk ik: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print("\n".join(lines))
    return EXIT_OK if status == OK else EXIT_FAILED


def report(
    quadruped: Quadruped, leg: str, point: tuple[float, float, float], seed: Sequence[float] | None
) -> tuple[list[str], int]:
    """The lines ``a1-leg-fk ik`` prints (see the module docstring) and the status code
    (:data:`a1_leg_fk.kinematics.ik.four_legs.OK`, ...).
    """
    from a1_leg_fk.kinematics.ik.four_legs import STATUS_NAMES, checked_point

    target = checked_point(point, leg)
    result = quadruped.ik_leg(leg, target, leg_seed(leg, seed))
    first = leg_slot(leg) * JOINTS_PER_LEG
    names = quadruped.joint_names[first : first + JOINTS_PER_LEG]
    lines = [
        (
            f"leg {leg}, target ({', '.join(f'{v:.6f}' for v in target)}) m in frame "
            f"'{quadruped.base_frame}' of {quadruped.model.source}"
        ),
        f"status: {STATUS_NAMES[result.status]}   residual: {result.residual_m:.3g} m",
        "angles:",
        *(
            f"  {name:<24} {angle:+.9f} rad {math.degrees(angle):+11.4f} deg"
            for name, angle in zip(names, result.angles)
        ),
    ]
    solutions = quadruped.ik_solutions(leg, target)
    lines.append(
        f"exact solutions: {len(solutions)}"
        + ("" if solutions else " (the target is out of reach)")
    )
    for number, solution in enumerate(solutions, 1):
        values = " ".join(f"{a:+.6f}" for a in solution.angles)
        degrees = " ".join(f"{math.degrees(a):+9.3f}" for a in solution.angles)
        where = "inside the limits" if solution.inside_limits else "outside the limits"
        lines.append(f"  {number}. [{values}] rad  [{degrees}] deg  {where}")
    return lines, int(result.status)


def leg_seed(leg: str, seed: Sequence[float] | None) -> list[float] | None:
    """``leg``'s three seed angles [rad] from ``--seed`` (the leg's 3 or all
    :data:`JOINT_COUNT` in slot order), or ``None``; a wrong count or a non-finite value anywhere
    raises :class:`LegFkError` naming ``--seed``.
    """
    from a1_leg_fk.model.urdf import LegFkError

    if seed is None:
        return None
    if len(seed) not in (JOINTS_PER_LEG, JOINT_COUNT):
        raise LegFkError(
            f"--seed takes {JOINTS_PER_LEG} angles (leg {leg}) or {JOINT_COUNT}, got {len(seed)}"
        )
    for index, value in enumerate(seed):
        if not math.isfinite(value):
            raise LegFkError(f"--seed: value {index + 1} of {len(seed)} is {value}")
    if len(seed) == JOINTS_PER_LEG:
        return list(seed)
    first = leg_slot(leg) * JOINTS_PER_LEG
    return list(seed[first : first + JOINTS_PER_LEG])
