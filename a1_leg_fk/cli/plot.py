"""``a1-leg-fk plot``: PNGs of a leg's reach envelope and of the feet over the demo gait (no
ROS).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from a1_leg_fk.cli.common import EXIT_FAILED, EXIT_OK, PROG
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.model.urdf import LegFkError


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``plot`` with the ``a1-leg-fk`` sub-commands."""
    plot = commands.add_parser(
        "plot",
        help="write PNGs: a leg's reach envelope, and the feet over the demo gait (needs "
        "matplotlib)",
        description="Write reach_<leg>.png (where the leg's foot can be, in its hip's sagittal "
        "plane, with the inner/outer reach circles) and demo_gait_feet.png (the four feet over "
        "two cycles of the demo trot, side and top views). No ROS needed.",
    )
    plot.add_argument(
        "--out", default=".", metavar="DIR", help="output folder (default: current folder)"
    )
    plot.add_argument(
        "--leg", default="FR", choices=LEG_NAMES, help="leg of the reach plot (default FR)"
    )
    plot.add_argument(
        "--urdf", metavar="FILE", help="robot description (default: the embedded Unitree A1)"
    )
    plot.set_defaults(handler=run)


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk plot``: write the PNGs; exit 1 (one line on stderr) if they cannot be made."""
    del argv  # no ROS here
    try:
        from a1_leg_fk import plots
        from a1_leg_fk.kinematics.quadruped import Quadruped

        plots.pyplot()  # fail early, with the install hint, when matplotlib is missing
        quadruped = Quadruped.from_urdf(options.urdf)
        out = Path(options.out)
        out.mkdir(parents=True, exist_ok=True)
        written = [
            plots.plot_reach(quadruped, options.leg, out / f"reach_{options.leg}.png"),
            plots.plot_gait_feet(quadruped, out / "demo_gait_feet.png"),
        ]
    except (LegFkError, OSError) as error:
        print(f"{PROG} plot: {error}", file=sys.stderr)
        return EXIT_FAILED
    for path in written:
        print(f"wrote {path} ({path.stat().st_size} bytes)")
    return EXIT_OK
