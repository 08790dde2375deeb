"""The contact estimate and the odometry on the mismatched family (test/mismatch_runs.py), scored
against PyBullet's truth: the judge of test/estimation/test_model_corrections.py and of the table
in docs/forces.md ("A robot that is not its URDF").

Each run is scored clean and with the contact family's sensor noise (seed
:data:`NOISE_SEED`); the normal forces' error is a share of the simulated robot's true weight
(payload and leg masses included), not the URDF's.
``python test/mismatch_scoring.py [online|off]`` prints the table.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any

from contact_scoring import FORCE, Score, estimate, score
from mismatch_runs import MismatchRun, mismatch_runs
from mismatch_specs import SPECS_MISMATCH
from odometry_scoring import errors
from odometry_scoring import estimate as odometry
from sensor_noise import with_noise

from a1_leg_fk.kinematics.quadruped import Quadruped

NOISE_SEED = 7
"""The noisy twins' seed (the contact family's)."""


@dataclass(frozen=True)
class Figures:
    """One run's figures: the contacts' :class:`contact_scoring.Score` (forces in % of the true
    weight) and the odometry's share of samples within 3 sigma."""

    contacts: Score
    within_3sigma: float

    def row(self, name: str) -> str:
        """One line of the table."""
        c = self.contacts
        return (
            f"{name:34s} {c.agree_pct:6.2f} {c.swing_as_stance_pct:6.2f} "
            f"{c.stance_as_swing_pct:6.2f} {c.stance_force_pct:6.2f} {self.within_3sigma:6.3f}"
        )


HEADER = f"{'run':34s} {'agree%':>6s} {'sw>st%':>6s} {'st>sw%':>6s} {'Frms%W':>6s} {'in3s':>6s}"


def figures(mismatched: MismatchRun, noisy: bool, **options: Any) -> Figures:
    """The :class:`Figures` of one run (``noisy``: its noisy twin); ``options``: the contact
    estimator's and the odometry feed's keywords."""
    run = with_noise(mismatched.run, NOISE_SEED) if noisy else mismatched.run
    quadruped = Quadruped.from_urdf(run.urdf_path)
    probabilities, normals = estimate(run, quadruped, FORCE, **options)
    contacts = score(run, probabilities, normals, mismatched.true_weight_n)
    result = odometry(run, True, quadruped, **options)
    return Figures(contacts, errors(mismatched.run, result).within_3sigma)


def table(names: tuple[str, ...] = tuple(SPECS_MISMATCH), **options: Any) -> dict[str, Figures]:
    """Every run of ``names``, clean and noisy (``NAME~noise``); the table printed."""
    out = {}
    print(HEADER)
    for name, run in mismatch_runs(names).items():
        for noisy in (False, True):
            key = f"{name}~noise" if noisy else name
            out[key] = figures(run, noisy, **options)
            print(out[key].row(key), flush=True)
    return out


if __name__ == "__main__":
    options: dict[str, Any] = {"model_corrections": sys.argv[1]} if sys.argv[1:] else {}
    table(**options)
