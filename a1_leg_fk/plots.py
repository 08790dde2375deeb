"""PNG plots of the kinematics: one leg's reach envelope, the feet over the demo gait, a gait
diagram, and the feet of a recording.

matplotlib is optional: it is imported only when a plot is drawn (with the non-interactive Agg
backend), and its absence raises :class:`MissingMatplotlib`, whose message says how to install it.
Sampling (:func:`reach_samples`, :func:`gait_feet`) needs numpy only.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from a1_leg_fk.gait.analysis import Contacts, GaitReport
from a1_leg_fk.gait.demo_gait import STAND_POSE, Gait, limits_of
from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINTS_PER_LEG, LEG_NAMES, leg_slot
from a1_leg_fk.model.urdf import Joint, LegFkError

if TYPE_CHECKING:  # matplotlib is imported only when a plot is drawn
    from matplotlib.figure import Figure

    from a1_leg_fk.recording.trajectories import FootTrajectories

INSTALL_HINT = (
    "matplotlib is not installed: pip install matplotlib (or: sudo apt install python3-matplotlib)"
)
REGION_COLOUR = "#c6dbef"
LEG_COLOURS = {leg: f"C{slot}" for slot, leg in enumerate(LEG_NAMES)}


class MissingMatplotlib(LegFkError):
    """matplotlib cannot be imported; the message says how to install it."""


def pyplot() -> ModuleType:
    """``matplotlib.pyplot`` on the Agg backend, or :class:`MissingMatplotlib`."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as error:
        raise MissingMatplotlib(INSTALL_HINT) from error
    return plt


def _limits(
    joint: Joint, fallback: tuple[float, float] = (-math.pi, math.pi)
) -> tuple[float, float]:
    if joint.lower is None or joint.upper is None:
        return fallback
    return joint.lower, joint.upper


def reach_samples(
    quadruped: Quadruped, leg: str, samples: int = 250
) -> tuple[np.ndarray, np.ndarray]:
    """The leg's foot over a ``samples`` x ``samples`` grid of hip pitch x knee within their
    limits.

    Hip roll is 0. Returns ``(points, edge)`` in the hip's sagittal plane, ``[x, z]`` [m] relative
    to the hip-pitch joint: ``points`` (samples**2, 2) fill the reachable region and ``edge`` (M,
    2) traces its outline (the images of the four edges of the angle rectangle, in order).
    """
    slot = leg_slot(leg)
    first = slot * JOINTS_PER_LEG
    pitch_range = _limits(quadruped.joints[first + 1])
    knee_range = _limits(quadruped.joints[first + 2])
    pitch, knee = np.meshgrid(
        np.linspace(*pitch_range, samples), np.linspace(*knee_range, samples), indexing="ij"
    )
    sweep = np.linspace(0.0, 1.0, 4 * samples)
    lo_p, hi_p = pitch_range
    lo_k, hi_k = knee_range
    edge_pitch = np.concatenate(
        [
            lo_p + sweep * (hi_p - lo_p),
            np.full_like(sweep, hi_p),
            hi_p - sweep * (hi_p - lo_p),
            np.full_like(sweep, lo_p),
        ]
    )
    edge_knee = np.concatenate(
        [
            np.full_like(sweep, lo_k),
            lo_k + sweep * (hi_k - lo_k),
            np.full_like(sweep, hi_k),
            hi_k - sweep * (hi_k - lo_k),
        ]
    )
    return _plane_points(quadruped, slot, pitch.ravel(), knee.ravel()), _plane_points(
        quadruped, slot, edge_pitch, edge_knee
    )


def _plane_points(
    quadruped: Quadruped, slot: int, pitch: np.ndarray, knee: np.ndarray
) -> np.ndarray:
    first = slot * JOINTS_PER_LEG
    angles = np.zeros((pitch.size, len(LEG_NAMES) * JOINTS_PER_LEG))
    angles[:, first + 1], angles[:, first + 2] = pitch, knee
    feet = quadruped.fk_batch(angles)[:, slot]
    pitch_origin = quadruped.legs[slot].joint_points((0.0, 0.0, 0.0))[1]
    if np.abs(feet[:, 1] - pitch_origin[1]).max() > 1e-9:
        raise LegFkError(
            f"leg {LEG_NAMES[slot]}: with hip roll 0 the foot leaves the hip's sagittal plane"
        )
    sagittal: np.ndarray = feet[:, [0, 2]] - pitch_origin[[0, 2]]
    return sagittal


def plot_reach(quadruped: Quadruped, leg: str, path: str | Path, samples: int = 250) -> Path:
    """Write ``path`` (PNG): where the leg's foot can be in its hip's sagittal plane (hip roll
    0).
    """
    plt = pyplot()
    slot = leg_slot(leg)
    points, edge = reach_samples(quadruped, leg, samples)
    reach = quadruped.reach(leg)
    first = slot * JOINTS_PER_LEG
    (lo_p, hi_p), (lo_k, hi_k) = (
        _limits(quadruped.joints[first + 1]),
        _limits(quadruped.joints[first + 2]),
    )
    figure, axes = plt.subplots(figsize=(7.5, 7.5))
    from matplotlib.patches import Patch

    # The region: its outline filled with the non-zero winding rule (the map (pitch, knee) -> foot
    # keeps
    # its orientation away from the straight knee, so every covered point winds at least once),
    # and over it a sparse subset of the sampled feet.
    axes.fill(edge[:, 0], edge[:, 1], color=REGION_COLOUR, linewidth=0, zorder=0)
    region = Patch(
        color=REGION_COLOUR,
        label=f"reachable: hip pitch {lo_p:.2f}..{hi_p:.2f} rad x knee {lo_k:.2f}..{hi_k:.2f} rad",
    )
    step = max(1, samples // 25)
    sparse = points.reshape(samples, samples, 2)[::step, ::step].reshape(-1, 2)
    axes.scatter(
        sparse[:, 0],
        sparse[:, 1],
        s=2.0,
        color="#6baed6",
        linewidths=0,
        zorder=1,
        label="sampled feet (hip pitch x knee grid, FK)",
    )
    axes.plot(
        edge[:, 0],
        edge[:, 1],
        color="#3182bd",
        linewidth=1.0,
        label="edge of the reachable region",
    )
    circle = np.linspace(0.0, 2.0 * math.pi, 721)
    for radius, style, colour, text in (
        (
            reach.min_m,
            "-",
            "C3",
            f"inner radius {reach.min_m:.3f} m (knee at {reach.knee_at_min:.2f} rad)",
        ),
        (
            reach.max_m,
            "-",
            "C2",
            f"outer radius {reach.max_m:.3f} m (knee at {reach.knee_at_max:.2f} rad)",
        ),
        (
            reach.max_unlimited_m,
            "--",
            "0.3",
            (
                f"straight knee {reach.max_unlimited_m:.3f} m (knee "
                f"{reach.knee_at_max_unlimited:.2f} rad: outside its limits)"
            ),
        ),
    ):
        axes.plot(
            radius * np.cos(circle),
            radius * np.sin(circle),
            style,
            color=colour,
            linewidth=1.6,
            label=text,
        )
    # The leg in the stand pose, for scale: hip-pitch joint -> knee -> foot.
    stand = quadruped.legs[slot].joint_points(STAND_POSE)
    origin = quadruped.legs[slot].joint_points((0.0, 0.0, 0.0))[1]
    leg_xz = stand[1:, :][:, [0, 2]] - origin[[0, 2]]
    axes.plot(
        leg_xz[:, 0],
        leg_xz[:, 1],
        "-o",
        color="k",
        linewidth=2.5,
        markersize=5,
        label=f"stand pose (pitch {STAND_POSE[1]}, knee {STAND_POSE[2]} rad)",
    )
    axes.plot([0.0], [0.0], "P", color="k", markersize=10)
    axes.annotate("hip-pitch joint", (0.0, 0.0), xytext=(8, 8), textcoords="offset points")
    axes.set_aspect("equal")
    limit = 1.1 * reach.max_unlimited_m
    axes.set_xlim(-limit, limit)
    axes.set_ylim(-limit, limit)
    axes.set_xlabel("x [m] (forward)")
    axes.set_ylabel("z [m] (up)")
    axes.set_title(
        f"{leg} foot reach in the hip's sagittal plane (hip roll 0)\n{quadruped.model.name}, "
        f"relative to the hip-pitch joint"
    )
    axes.grid(True, linewidth=0.4, alpha=0.6)
    handles, _ = axes.get_legend_handles_labels()
    axes.legend(handles=[region, *handles], loc="upper left", fontsize=7.5, framealpha=0.9)
    return _save(figure, plt, path)


def gait_feet(
    quadruped: Quadruped,
    gait: Gait | None = None,
    cycles: float = 2.0,
    samples_per_cycle: int = 200,
) -> tuple[np.ndarray, np.ndarray]:
    """``(times [s], feet (N, 4, 3) [m, base frame])`` over ``cycles`` periodic trot cycles of the
    gait.
    """
    gait = gait or Gait(limits_of(quadruped))
    count = max(2, round(cycles * samples_per_cycle) + 1)
    times = gait.periodic_from_s + np.linspace(0.0, cycles * gait.period_s, count)
    angles = np.array([gait.angles(float(t)) for t in times])
    return times, quadruped.fk_batch(angles)


def plot_gait_feet(
    quadruped: Quadruped, path: str | Path, gait: Gait | None = None, cycles: float = 2.0
) -> Path:
    """Write ``path`` (PNG): the four feet over ``cycles`` cycles of the demo trot, side and top
    views.
    """
    plt = pyplot()
    gait = gait or Gait(limits_of(quadruped))
    times, feet = gait_feet(quadruped, gait, cycles)
    hips = np.array([leg.joint_points((0.0, 0.0, 0.0))[0] for leg in quadruped.legs])
    figure, (side, top) = plt.subplots(1, 2, figsize=(12, 5.5))
    for slot, leg in enumerate(LEG_NAMES):
        colour = LEG_COLOURS[leg]
        side.plot(feet[:, slot, 0], feet[:, slot, 2], color=colour, linewidth=1.8, label=leg)
        top.plot(feet[:, slot, 0], feet[:, slot, 1], color=colour, linewidth=1.8, label=leg)
        for axes, (a, b) in ((side, (0, 2)), (top, (0, 1))):
            axes.plot(feet[0, slot, a], feet[0, slot, b], "o", color=colour, markersize=5)
    top.plot(hips[:, 0], hips[:, 1], "x", color="k", markersize=8, label="hip joints")
    top.plot(hips[[0, 1, 3, 2, 0], 0], hips[[0, 1, 3, 2, 0], 1], ":", color="0.5", linewidth=1.0)
    side.plot(hips[:, 0], hips[:, 2], "x", color="k", markersize=8, label="hip joints")
    frame = quadruped.base_frame
    for axes, vertical, title in (
        (side, "z [m] (up)", "side view (x-z)"),
        (top, "y [m] (left)", "top view (x-y)"),
    ):
        axes.set_aspect("equal", adjustable="datalim")
        axes.set_xlabel(f"x [m] (forward), frame {frame}")
        axes.set_ylabel(vertical)
        axes.set_title(title)
        axes.grid(True, linewidth=0.4, alpha=0.6)
        axes.legend(fontsize=8, loc="best")
    figure.suptitle(
        f"Feet over {cycles:g} cycles of the demo trot ({gait.parameters.trot_hz:g} Hz, diagonal "
        f"pairs FR+RL / FL+RR), t = {times[0]:.2f}..{times[-1]:.2f} s; dots: start"
    )
    return _save(figure, plt, path)


def _save(figure: Figure, plt: ModuleType, path: str | Path) -> Path:
    path = Path(path)
    try:
        figure.tight_layout()
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return path


def plot_gait_diagram(
    contacts: Contacts, report: GaitReport, path: str | Path, title: str = ""
) -> Path:
    """Write ``path`` (PNG): a Hildebrand gait diagram above the feet's heights over time.

    Top: one row per leg (FR, FL, RR, RL from the top), a bar over each stance interval [s from the
    first stamp]. Bottom: each foot's height above the detected ground plane [m] (the plane itself
    at 0, the on/off height thresholds dashed), so a reader sees at a glance whether the stances
    sit where the feet are down.
    """
    plt = pyplot()
    thresholds = contacts.thresholds
    figure, (diagram, heights) = plt.subplots(
        2, 1, figsize=(14, 7), sharex=True, gridspec_kw={"height_ratios": [1, 1.4]}
    )
    for row, leg in enumerate(LEG_NAMES):
        metrics = report.legs[leg]
        bars = [(t_on, t_off - t_on) for t_on, t_off in metrics.stance_s]
        diagram.broken_barh(bars, (len(LEG_NAMES) - 1 - row - 0.35, 0.7), color=LEG_COLOURS[leg])
        duty = "-" if metrics.duty_factor is None else f"{metrics.duty_factor:.2f}"
        heights.plot(
            contacts.times_s,
            contacts.heights_m[:, row],
            color=LEG_COLOURS[leg],
            linewidth=1.0,
            label=f"{leg} (duty {duty}, {metrics.status})",
        )
    diagram.set_yticks(range(len(LEG_NAMES)), list(reversed(LEG_NAMES)))
    diagram.set_ylim(-0.6, len(LEG_NAMES) - 0.4)
    diagram.set_ylabel("leg (bars: stance)")
    diagram.grid(True, axis="x", linewidth=0.4, alpha=0.6)
    phases = ", ".join(
        f"{leg} {value:.2f}" if value is not None else f"{leg} -"
        for leg, value in report.phase_vs_fr.items()
    )
    naming = report.naming
    region = (
        f", {naming.region}" if naming and naming.region and naming.region != report.gait else ""
    )
    limb = (
        f", limb phase {naming.limb_phase:.2f}"
        if naming is not None and naming.limb_phase is not None
        else ""
    )
    diagram.set_title(
        f"{title + ': ' if title else ''}gait {report.gait}{region} (fit {report.gait_fit:.2f}"
        f"{limb}); touchdown phase vs FR: {phases}"
    )
    ground = contacts.ground
    heights.axhline(
        0.0,
        color="k",
        linewidth=1.2,
        label=f"detected ground (height 0): z = {ground.level_m:.3f} m\nat x, y = "
        f"{ground.origin_xy[0]:.2f}, {ground.origin_xy[1]:.2f} m, slope {ground.slope_deg:.1f} "
        "deg",
    )
    used = contacts.leg_thresholds or (thresholds,)
    for values, text in (
        ([t.height_on_m for t in used], "on"),
        ([t.height_off_m for t in used], "off"),
    ):
        value = max(values)  # per foot when derived: the highest drawn, the range written
        span = f"{min(values):.3f}..{value:.3f}" if min(values) < value else f"{value:g}"
        heights.axhline(value, color="0.4", linestyle="--", linewidth=0.8)
        heights.annotate(
            f"height {text} {span} m",
            (contacts.times_s[0], value),
            xytext=(2, 2),
            textcoords="offset points",
            fontsize=7,
            color="0.3",
        )
    heights.set_xlabel("time [s] from the first stamp")
    heights.set_ylabel("foot height above the ground plane [m]")
    heights.grid(True, linewidth=0.4, alpha=0.6)
    heights.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(figure, plt, path)


def plot_trajectories(trajectories: FootTrajectories, path: Path) -> Path:
    """x, y, z [m] of each foot of a recording over time [s from the first stamp], in the world
    frame when the recording has world feet, else the base frame.
    """
    plt = pyplot()
    world_positions = trajectories.world_positions
    world = world_positions is not None and bool(np.isfinite(world_positions).any())
    values = world_positions if world_positions is not None and world else trajectories.positions
    frame = trajectories.world_frame if world else trajectories.base_frame
    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(11, 8))
    stamps = trajectories.stamps_ns
    seconds = (stamps - stamps[0]) / 1e9 if len(stamps) else stamps
    for axis_slot, (axis, name) in enumerate(zip(axes, "xyz")):
        for slot, leg in enumerate(LEG_NAMES):
            axis.plot(
                seconds,
                values[:, slot, axis_slot],
                color=LEG_COLOURS[leg],
                linewidth=0.8,
                label=leg,
            )
        axis.set_ylabel(f"{name} [m]")
        axis.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", ncol=4, fontsize="small")
    axes[-1].set_xlabel("time since the first JointState stamp [s]")
    summary = trajectories.summary
    figure.suptitle(
        f"Feet in frame '{frame}': {Path(summary.path).name}, {summary.topic}, {summary.rows} rows"
    )
    return _save(figure, plt, path)
