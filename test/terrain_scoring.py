"""Today's estimators on the terrain family (:mod:`terrain_runs`), scored as the contact and
odometry families are (:mod:`contact_scoring`, :mod:`odometry_scoring`): the contacts with efforts
(force evidence) and without (kinematic), the odometry clean and with the family's sensor noise,
with efforts and without, every estimator at its default settings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from contact_scoring import FORCE, KINEMATIC, Score, estimate, score
from gait_family import world_feet
from odometry_scoring import Errors, errors, feed_samples
from odometry_scoring import estimate as odometry
from odometry_scoring import misses as odometry_misses
from sensor_noise import with_noise
from terrain_runs import GRID, TerrainRun
from terrain_specs import Terrain

from a1_leg_fk.estimation.ground_plane import GroundPlane
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped

NOISE_SEED = 7
"""The family's sensor noise (conftest.FAMILY_NOISE_SEED)."""
ODOMETRY = (("clean", True), ("clean", False), ("noise", True), ("noise", False))
"""(sensors, efforts) of each run's four odometry estimates."""


@dataclass(frozen=True)
class TerrainScores:
    """One run's contact scores by evidence and odometry errors by (sensors, efforts)."""

    contacts: dict[str, Score]
    odometry: dict[tuple[str, bool], Errors]


def score_run(terrain: TerrainRun) -> TerrainScores:
    """Every estimate of one run, scored against its truth."""
    run = terrain.run
    quadruped = Quadruped.from_urdf(run.urdf_path)
    weight = FootForces(quadruped).total_mass_kg * STANDARD_GRAVITY
    contacts = {}
    for evidence in (FORCE, KINEMATIC):
        probabilities, normals = estimate(run, quadruped, evidence)
        contacts[evidence] = score(run, probabilities, normals, weight)
    noisy = with_noise(run, NOISE_SEED)
    scored = {
        (sensors, efforts): errors(
            run, odometry(run if sensors == "clean" else noisy, efforts, quadruped)
        )
        for sensors, efforts in ODOMETRY
    }
    return TerrainScores(contacts, scored)


HEADER = (
    f"{'run':<23} {'F agree':>7} {'sw>st':>5} {'K agree':>7} {'sw>st':>5} | {'odometry':<15} "
    f"{'rmse':>6} {'burst':>5} {'hor%':>5} {'ver%':>6} {'in3s%':>5} {'s/err':>5}"
)


def rows(name: str, scores: TerrainScores) -> list[str]:
    """The run's table lines: its contacts on the first, one odometry estimate on each."""
    force, kinematic = scores.contacts[FORCE], scores.contacts[KINEMATIC]
    head = (
        f"{name:<23} {force.agree_pct:7.2f} {force.swing_as_stance_pct:5.2f} "
        f"{kinematic.agree_pct:7.2f} {kinematic.swing_as_stance_pct:5.2f}"
    )
    lines: list[str] = []
    for (sensors, efforts), e in scores.odometry.items():
        label = f"{sensors} {'efforts' if efforts else 'kinematic'}"
        lines.append(
            f"{head if not lines else '':<51} | {label:<15} {e.rmse:6.4f} {e.worst_window:5.3f} "
            f"{e.horizontal_pct:5.2f} {e.vertical_pct:6.2f} {100 * e.within_3sigma:5.1f} "
            f"{e.sigma_ratio:5.2f}"
        )
    return lines


def misses(scores: TerrainScores) -> list[str]:
    """The issue's goals a run misses, in words (vertical drift is judged on every run: the
    family's runs are slopes, stairs and bumps, or flat)."""
    found = []
    force, kinematic = scores.contacts[FORCE], scores.contacts[KINEMATIC]
    for ok, what in (
        (force.agree_pct >= 98.5, f"contacts with efforts {force.agree_pct:.2f} %"),
        (
            force.swing_as_stance_pct <= 1.0,
            f"swing called stance {force.swing_as_stance_pct:.2f} %",
        ),
        (kinematic.agree_pct >= 95.0, f"contacts without efforts {kinematic.agree_pct:.2f} %"),
    ):
        if not ok:
            found.append(what)
    for (sensors, efforts), e in scores.odometry.items():
        label = f"{sensors} {'efforts' if efforts else 'kinematic'}"
        found += odometry_misses(label, e, 0.03 if sensors == "clean" else 0.05)
    return found


FIRST_EDGE_M = 0.45
"""[m, world x] a staircase's first edge (:func:`terrain_runs.build_terrain`)."""


def stair_profile(terrain: Terrain, x: np.ndarray, tread_mean: bool = False) -> np.ndarray:
    """A staircase's height [m] at world ``x`` [m] (any shape): its treads' (the rays'), or with
    ``tread_mean`` averaged over one tread's depth about ``x`` (a ramp through the treads'
    middles, level on the landings, bending over one tread at either end)."""
    edges = FIRST_EDGE_M + terrain.run_m * np.arange(terrain.steps)
    offsets = (np.asarray(x, dtype=float)[..., None] - edges) / terrain.run_m
    climbed = np.clip(offsets + 0.5, 0.0, 1.0) if tread_mean else (offsets >= 0.0).astype(float)
    result: np.ndarray = max(0.0, -terrain.rise_m * terrain.steps) + terrain.rise_m * climbed.sum(
        axis=-1
    )
    return result


def stair_ground(terrain: Terrain, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ground a controller plans on over a staircase, below roots at world ``x`` (N,) [m]:
    the rays' plane (least squares at :data:`terrain_runs.GRID`'s offsets about the root) through
    the staircase averaged over one tread (:func:`stair_profile`), not through its treads. Its
    height [m] at the root (N,) and gradient (N, 2): the staircase's mean slope, rise over run,
    wherever the grid spans treads alone, and level on the landings. The rays' own plane through
    the treads swings about it as the root passes the edges: its height by 0.3, 0.15 and 0.2
    rises on 0.3, 0.4 and 0.5 m treads, its slope 0.8-1.33 and 0.67-1.33 times this one's on
    0.4 and 0.5 m treads (on 0.3 m ones, the rays half a tread apart, it is this one's)."""
    along = np.array(sorted({dx for dx, _ in GRID}))  # the plane is level across the stairs
    heights = stair_profile(terrain, np.asarray(x, dtype=float)[:, None] + along, True)
    centred = along - along.mean()
    slope = heights @ centred / float(centred @ centred)
    height = heights.mean(axis=1) - slope * along.mean()
    return height, np.column_stack([slope, np.zeros_like(slope)])


FOOTHOLDS_S = 0.8
"""[s] the stances :func:`foothold_ground` spans: the reported plane's eight footholds, two
strides of the families' 0.4 s trots."""
SPAN_SAMPLES = 41
"""The points over a span that :func:`span_slope`'s fit takes (1.5-2 cm apart on 0.6-0.8 m)."""


def span_slope(terrain: Terrain, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The slope (N,) of the staircase averaged over one tread (:func:`stair_profile`) fitted by
    least squares over world x from ``low`` to ``high`` (N,) [m]: rise over run where the span
    lies on the flight, level where it lies on a landing (and where it is empty)."""
    x = low[:, None] + (high - low)[:, None] * np.linspace(0.0, 1.0, SPAN_SAMPLES)
    heights = stair_profile(terrain, x, True)
    centred = x - x.mean(axis=1, keepdims=True)
    spread = (centred * centred).sum(axis=1)
    slope: np.ndarray = np.where(
        spread > 1e-12, (heights * centred).sum(axis=1) / np.maximum(spread, 1e-12), 0.0
    )
    return slope


def foothold_ground(terrain: TerrainRun, window_s: float = FOOTHOLDS_S) -> np.ndarray:
    """The truth a causal estimate from footholds can know (N,): :func:`span_slope` over the span
    of world x where the feet stood (PyBullet's contacts, our FK placed by the true base pose)
    over the last ``window_s`` [s]; the staircase ahead of the front feet, which the rays' truth
    (:func:`stair_ground`) sees, left out."""
    run = terrain.run
    feet = world_feet(run)[:, :, 0]
    rows = max(1, round(window_s / float(np.median(np.diff(run.stamps_s)))))
    windows = np.lib.stride_tricks.sliding_window_view
    pad = np.full(rows - 1, np.inf)
    low = windows(np.concatenate([pad, np.where(run.contacts, feet, np.inf).min(axis=1)]), rows)
    high = windows(np.concatenate([-pad, np.where(run.contacts, feet, -np.inf).max(axis=1)]), rows)
    low, high = low.min(axis=1), high.max(axis=1)
    stood = np.isfinite(low)
    low, high = np.where(stood, low, 0.0), np.where(stood, high, 0.0)
    return span_slope(terrain.terrain, low, high)


@dataclass(frozen=True)
class GroundErrors:
    """The live local ground against the truth's (``TerrainRun``: the plane through rays about
    the root; on a staircase :func:`stair_ground`'s), after the first stride: the worst and the
    95th-percentile angle between the normals [deg], and of the error of the base's height above
    the ground [m]; the share of samples with a plane; the worst angle [deg] where the truth's
    slope has not changed over the last stride (a staircase's flight or landing, not its ends
    passing under the robot: footholds cannot see a step the feet have not reached); on a
    staircase the worst and 95th-percentile angle [deg] against :func:`foothold_ground`, the
    staircase where the feet stood (on a slope the same as against the rays')."""

    worst_deg: float
    p95_deg: float
    worst_height_m: float
    p95_height_m: float
    coverage: float
    steady_worst_deg: float
    span_worst_deg: float
    span_p95_deg: float

    def row(self, name: str) -> str:
        return (
            f"{name:<23} {self.worst_deg:6.2f} {self.p95_deg:6.2f} "
            f"{100 * self.worst_height_m:7.2f} {100 * self.p95_height_m:7.2f} "
            f"{100 * self.coverage:6.1f} {self.steady_worst_deg:7.2f} "
            f"{self.span_worst_deg:6.2f} {self.span_p95_deg:6.2f}"
        )


GROUND_HEADER = (
    f"{'run':<23} {'worst°':>6} {'p95°':>6} {'worstcm':>7} {'p95cm':>7} {'have%':>6} "
    f"{'steady°':>7} {'span°':>6} {'sp95°':>6}"
)
STEADY_RAD = 1e-4
"""A truth's gradient that moved less than this over the last stride is steady."""


def ground_errors(
    terrain: TerrainRun, after_s: float, stride_s: float = 0.4, **options: Any
) -> GroundErrors:
    """The odometry feed's local ground (efforts, clean sensors; ``options``: the feed's) on a run,
    from ``after_s`` [s] after the gait's start on, against the rays' plane (on a staircase
    :func:`stair_ground`'s); steady where the truth held over the last ``stride_s`` [s]."""
    run = terrain.run
    quadruped = Quadruped.from_urdf(run.urdf_path)
    feed = OdometryFeed(quadruped, **options)
    planes: list[GroundPlane | None] = []
    samples = feed_samples(feed, quadruped, run, run.quaternions, run.torques, planes=planes)
    scored = run.stamps_s >= run.gait_start_s + after_s
    angles, heights, steady = [], [], []
    lag = max(1, round(stride_s / float(np.median(np.diff(run.stamps_s)))))
    true_heights, true_gradients = terrain.plane_heights, terrain.plane_gradients
    span_gradients = true_gradients
    if terrain.terrain.kind == "stairs":
        true_heights, true_gradients = stair_ground(terrain.terrain, run.base_positions[:, 0])
        span = foothold_ground(terrain)
        span_gradients = np.column_stack([span, np.zeros_like(span)])
    true_normals, span_normals = _normals(true_gradients), _normals(span_gradients)
    spans = []
    true_above = run.base_positions[:, 2] - true_heights
    for row in np.flatnonzero(scored):
        plane = planes[row]
        if plane is None:
            continue
        angles.append(_angle_deg(plane.normal, true_normals[row]))
        spans.append(_angle_deg(plane.normal, span_normals[row]))
        held = true_gradients[max(0, row - lag) : row + 1]
        steady.append(float(np.ptp(held, axis=0).max()) < STEADY_RAD)
        heights.append(abs(samples[row].position[2] - plane.height_m - true_above[row]))
    return GroundErrors(
        max(angles),
        float(np.percentile(angles, 95)),
        max(heights),
        float(np.percentile(heights, 95)),
        len(angles) / int(scored.sum()),
        max((a for a, kept in zip(angles, steady) if kept), default=math.nan),
        max(spans),
        float(np.percentile(spans, 95)),
    )


def _normals(gradients: np.ndarray) -> np.ndarray:
    """The unit normals (N, 3) of planes of ``gradients`` (N, 2) (dz/dx, dz/dy)."""
    normals = np.column_stack([-gradients, np.ones(len(gradients))])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return normals


def _angle_deg(normal: tuple[float, float, float], other: np.ndarray) -> float:
    """The angle [deg] between two unit normals."""
    return math.degrees(math.acos(float(np.clip(np.dot(normal, other), -1.0, 1.0))))
