"""Today's estimators on the terrain family (:mod:`terrain_runs`), scored as the contact and
odometry families are (:mod:`contact_scoring`, :mod:`odometry_scoring`): the contacts with efforts
(force evidence) and without (kinematic), the odometry clean and with the family's sensor noise,
with efforts and without, every estimator at its default settings.
"""

from __future__ import annotations

from dataclasses import dataclass

from contact_scoring import FORCE, KINEMATIC, Score, estimate, score
from odometry_scoring import Errors, errors
from odometry_scoring import estimate as odometry
from sensor_noise import with_noise
from terrain_runs import TerrainRun

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
    f"{'run':<18} {'F agree':>7} {'sw>st':>5} {'K agree':>7} {'sw>st':>5} | {'odometry':<15} "
    f"{'rmse':>6} {'burst':>5} {'hor%':>5} {'ver%':>6} {'in3s%':>5} {'s/err':>5}"
)


def rows(name: str, scores: TerrainScores) -> list[str]:
    """The run's table lines: its contacts on the first, one odometry estimate on each."""
    force, kinematic = scores.contacts[FORCE], scores.contacts[KINEMATIC]
    head = (
        f"{name:<18} {force.agree_pct:7.2f} {force.swing_as_stance_pct:5.2f} "
        f"{kinematic.agree_pct:7.2f} {kinematic.swing_as_stance_pct:5.2f}"
    )
    lines: list[str] = []
    for (sensors, efforts), e in scores.odometry.items():
        label = f"{sensors} {'efforts' if efforts else 'kinematic'}"
        lines.append(
            f"{head if not lines else '':<46} | {label:<15} {e.rmse:6.4f} {e.worst_window:5.3f} "
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
        rmse = 0.03 if sensors == "clean" else 0.05
        for ok, what in (
            (e.rmse <= rmse, f"RMSE {e.rmse:.4f} > {rmse}"),
            (e.worst_window <= 0.2, f"burst {e.worst_window:.3f} m/s"),
            (e.horizontal_pct <= 1.0, f"horizontal drift {e.horizontal_pct:.2f} %"),
            (e.vertical_pct <= 0.5, f"vertical drift {e.vertical_pct:.2f} %"),
            (e.within_3sigma >= 0.95, f"within 3 sigma {100 * e.within_3sigma:.1f} %"),
            (e.sigma_ratio <= 5.0, f"sigma / error {e.sigma_ratio:.1f}"),
        ):
            if not ok:
                found.append(f"{label}: {what}")
    return found
