"""The state estimate of a simulated run (:class:`contact_runs.ContactRun`) through the odometry
feed, and its errors against the run's truth (the URDF root's motion in PyBullet)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from contact_runs import ContactRun
from pybullet_sim import rotation_matrices

from a1_leg_fk.estimation.ground_plane import GroundPlane
from a1_leg_fk.estimation.odometry import ImuReading, OdometrySample
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.estimation.odometry_smoother import OdometrySmoother
from a1_leg_fk.kinematics.quadruped import Quadruped

WINDOW_S = 0.1
"""The burst test's window [s]."""
TUNED = (
    "a1_trot_long",
    "a1_walk_long",
    "a1_flying_trot_fast",
    "go2_trot_long",
    "go2_trot_slips",
    "a1_flying_trot",
    "a1_trot_slips",
)
"""The state filter's family (test_state_filter_family.py): its settings were tuned on these
(``a1_flying_trot`` and ``a1_trot_slips`` among them: the touchdown, scatter and doubt terms came
from their coverage diagnosis)."""
HELD_OUT = ("a1_trot_fast_long", "a1_turn_long")
"""Long runs at the tuned gaits' other speeds and a turn, scored with the same defaults."""
HELD_OUT_OTHER = ("a1_trot_soft", "go2_walk", "go2_trot_fast")
"""Other conditions and gaits (10.5 s each, test/contact_gaits.py ``SPECS``): never tuned on."""
HELD_OUT_NOISE_SEED = 40
"""The noise seed of the held-out runs' noisy twins (the tuned runs': ``FAMILY_NOISE_SEED``)."""
CONFIGS = (("clean", True), ("clean", False), ("noise", True), ("noise", False))
"""(sensors, efforts) of each run's four estimates."""


def missed(label: str, checks: tuple[tuple[Any, str], ...]) -> list[str]:
    """``label: what`` for each check (ok, what) not ok."""
    return [f"{label}: {what}" for ok, what in checks if not ok]


def xfail_params(names: tuple[str, ...], unmet: dict[str, str]) -> list[Any]:
    """pytest params of ``names``, those in ``unmet`` strict xfails with their reason."""
    import pytest

    return [
        pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=unmet[name]))
        if name in unmet
        else name
        for name in names
    ]


@dataclass(frozen=True)
class Estimate:
    """The feed's output over a run (N samples): body-frame velocity [m/s] and its variances,
    world position [m], the legs used (N, 4) bool, and the feed's counts."""

    velocity: np.ndarray
    velocity_variance: np.ndarray
    position: np.ndarray
    used: np.ndarray
    feed: OdometryFeed | None
    causal: Estimate | None = None
    """With ``smoothed``: the filter's own estimate of the same pass."""


def estimate(
    run: ContactRun,
    efforts: bool,
    quadruped: Quadruped | None = None,
    accelerometer: bool = True,
    smoothed: bool = False,
    **options: Any,
) -> Estimate:
    """Feed every sample of ``run`` to a new feed (``options``: its keywords); ``accelerometer``
    false: the IMU has none (the legs alone); ``smoothed``: the samples smoothed over the run
    (:class:`OdometrySmoother`, as ``a1-leg-fk odom`` without ``--causal``)."""
    quadruped = quadruped or Quadruped.from_urdf(run.urdf_path)
    feed = OdometryFeed(quadruped, contacts="auto" if efforts else "kinematic", **options)
    causal: list[OdometrySample] = []
    samples = feed_samples(
        feed,
        quadruped,
        run,
        run.quaternions,
        efforts=run.torques if efforts else None,
        accelerometer=accelerometer,
        smoother=OdometrySmoother(feed.filter) if smoothed else None,
        causal=causal,
    )
    return _estimate(samples, feed, _estimate(causal, feed) if smoothed else None)


def _estimate(
    samples: list[OdometrySample], feed: OdometryFeed, causal: Estimate | None = None
) -> Estimate:
    used = np.zeros((len(samples), 4), dtype=bool)
    for row, sample in enumerate(samples):
        used[row, list(sample.used)] = True
    return Estimate(
        np.array([sample.linear for sample in samples]),
        np.array([sample.twist_variance[:3] for sample in samples]),
        np.array([sample.position for sample in samples]),
        used,
        feed,
        causal,
    )


def feed_samples(
    feed: OdometryFeed,
    quadruped: Quadruped,
    run: Any,
    quaternions: np.ndarray,
    efforts: np.ndarray | None = None,
    contacts: np.ndarray | None = None,
    accelerometer: bool = True,
    smoother: OdometrySmoother | None = None,
    causal: list[OdometrySample] | None = None,
    planes: list[GroundPlane | None] | None = None,
) -> list[OdometrySample]:
    """Feed every sample of a simulated ``run`` (its ``stamps_s``, ``angles``, ``rates``,
    ``gyro`` and ``specific_force``; the base's ``quaternions`` x, y, z, w) to ``feed``: the
    IMU first, then the joint state with ``efforts`` [N m] and ``contacts`` (N, 4) from
    elsewhere (None: none); ``accelerometer`` false: the IMU has none. The feed's samples (with
    a ``smoother``: its samples, smoothed, the feed's own appended to ``causal``); ``planes``,
    when given, gets the feed's local ground after each (live, as a node has it)."""
    rows = len(run.stamps_s)
    feet = quadruped.fk_batch(run.angles).tolist()
    speeds = quadruped.foot_velocities_batch(run.angles, run.rates).tolist()
    angles, rates = run.angles.tolist(), run.rates.tolist()
    gyro, orientations = run.gyro.tolist(), quaternions.tolist()
    forces = run.specific_force.tolist() if accelerometer else [None] * rows
    torques = efforts.tolist() if efforts is not None else [None] * rows
    standing = contacts.tolist() if contacts is not None else [None] * rows
    samples = []
    for row, seconds in enumerate(run.stamps_s.tolist()):
        stamp = round(seconds * 1e9)
        force = forces[row]
        feed.add_imu(
            stamp,
            ImuReading(
                tuple(orientations[row]),
                tuple(gyro[row]),
                specific_force=None if force is None else tuple(force),
            ),
        )
        sample = feed.step(
            stamp,
            list(zip(feet[row], speeds[row])),
            angles[row],
            rates[row],
            standing[row],
            torques[row],
        )
        assert sample is not None
        if planes is not None:
            planes.append(feed.ground_plane(sample))
        if smoother is None:
            samples.append(sample)
        else:
            samples += smoother.add(sample, feed.samples_filtered)
            if causal is not None:
                causal.append(sample)
    return samples if smoother is None else samples + smoother.finish()


@dataclass(frozen=True)
class Errors:
    """An estimate's errors over the gait: velocity RMSE [m/s] (3D, base frame), the worst 0.1 s
    window's mean error norm [m/s], horizontal and vertical drift [% of the distance], the
    distance [m], the share of samples whose error lies within 3 sigma on every axis, and the
    largest ratio of the reported sigma to the actual RMS error (per axis)."""

    rmse: float
    worst_window: float
    horizontal_pct: float
    vertical_pct: float
    distance_m: float
    within_3sigma: float
    sigma_ratio: float

    def row(self, name: str) -> str:
        return (
            f"{name:<34} {self.rmse:7.4f} {self.worst_window:7.3f} {self.horizontal_pct:6.2f} "
            f"{self.vertical_pct:6.2f} {self.distance_m:6.1f} {self.within_3sigma:6.3f} "
            f"{self.sigma_ratio:6.2f}"
        )


HEADER = (
    f"{'run':<34} {'rmse':>7} {'burst':>7} {'hor%':>6} {'ver%':>6} {'dist':>6} {'in3s':>6} "
    f"{'s/err':>6}"
)


def goals(e: Errors, rmse: float, drift: float = 1.0) -> list[tuple[str, bool, str]]:
    """The odometry goals (issues 27 and 34), each as (goal, met by ``e``, the figure in words):
    velocity RMSE <= ``rmse`` [m/s], no 0.1 s window above 0.2 m/s, horizontal drift <=
    ``drift`` %, vertical <= 0.5 %, >= 95 % of the samples within 3 sigma, sigma <= 5x the RMS
    error."""
    return [
        (f"RMSE <= {rmse}", e.rmse <= rmse, f"RMSE {e.rmse:.4f}"),
        ("burst <= 0.2", e.worst_window <= 0.2, f"burst {e.worst_window:.3f} m/s"),
        (f"horizontal drift <= {drift} %", e.horizontal_pct <= drift,
         f"horizontal drift {e.horizontal_pct:.2f} %"),
        ("vertical drift <= 0.5 %", e.vertical_pct <= 0.5,
         f"vertical drift {e.vertical_pct:.2f} %"),
        ("within 3 sigma >= 95 %", e.within_3sigma >= 0.95,
         f"within 3 sigma {100 * e.within_3sigma:.1f} %"),
        ("sigma / error <= 5", e.sigma_ratio <= 5.0, f"sigma / error {e.sigma_ratio:.2f}"),
    ]  # fmt: skip


def misses(label: str, e: Errors, rmse: float, drift: float = 1.0) -> list[str]:
    """The :func:`goals` ``e`` misses, in words prefixed by ``label``."""
    return [f"{label}: {figure}" for _, met, figure in goals(e, rmse, drift) if not met]


def errors(truth: ContactRun, result: Estimate) -> Errors:
    """``result``'s errors against the clean run ``truth`` (its root motion), over the gait."""
    gait = truth.gait
    rotations = rotation_matrices(truth.quaternions)
    true_body = np.einsum("nji,nj->ni", rotations, truth.base_velocities)
    error = (result.velocity - true_body)[gait]
    rmse = float(np.sqrt((error**2).sum(axis=1).mean()))
    window = max(1, round(WINDOW_S / float(np.median(np.diff(truth.stamps_s)))))
    norms = np.linalg.norm(error, axis=1)
    kernel = np.ones(window) / window
    means = np.convolve(norms, kernel, mode="valid") if len(norms) >= window else norms
    first = int(np.argmax(gait))
    moved = truth.base_positions[-1] - truth.base_positions[first]
    estimated = result.position[-1] - result.position[first]
    path = np.diff(truth.base_positions[gait], axis=0)
    distance = float(np.linalg.norm(path[:, :2], axis=1).sum())
    drift = estimated - moved
    sigma = np.sqrt(result.velocity_variance[gait])
    inside = (np.abs(error) <= 3.0 * sigma).all(axis=1)
    actual = np.sqrt((error**2).mean(axis=0))
    ratio = float((sigma.mean(axis=0) / actual).max())
    return Errors(
        rmse,
        float(means.max()),
        100.0 * float(math.hypot(drift[0], drift[1])) / distance,
        100.0 * abs(float(drift[2])) / distance,
        distance,
        float(inside.mean()),
        ratio,
    )


def stance_slides(run: ContactRun, quadruped: Quadruped) -> np.ndarray:
    """How far [m] each foot's frame moved horizontally over each complete stance of the gait
    (PyBullet's contacts; the feet by the URDF's FK at the true root pose): rolling moves a
    sphere's centre a few millimetres, a slip centimetres."""
    feet = quadruped.fk_batch(run.angles)
    world = run.base_positions[:, None, :] + np.einsum(
        "nij,nfj->nfi", rotation_matrices(run.quaternions), feet
    )
    contacts = run.contacts & run.gait[:, None]
    slides = []
    for foot in range(contacts.shape[1]):
        down = contacts[:, foot]
        starts = np.flatnonzero(~down[:-1] & down[1:]) + 1
        ends = np.flatnonzero(down[:-1] & ~down[1:]) + 1
        for start in starts:
            later = ends[ends > start]
            if len(later):
                moved = world[later[0] - 1, foot, :2] - world[start, foot, :2]
                slides.append(float(np.linalg.norm(moved)))
    return np.array(slides)
