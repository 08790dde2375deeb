"""Leg odometry on retargeted A1 motion clips (AMP_for_hardware's ``datasets/mocap_motions``
format), the clip's own base motion as the truth.

Run: ``.venv/bin/python bench/odometry_mocap.py CLIP.txt...`` (the clips are CC BY-NC: download
them yourself; none is in this repository). A clip is JSON with ``FrameDuration`` [s] and
``Frames``: per frame the base position [m] and quaternion (x, y, z, w) of PyBullet's A1 base (the
trunk's centre of mass), then the 12 joint angles [rad] in the order FR, FL, RR, RL x hip, thigh,
calf (pybullet_data's a1.urdf), then toe positions and velocities (not used: the clips'
velocities disagree with their own angles' differences). Joint rates and the true base velocity
are central differences; the gyro comes from the clip's orientations; the base is converted to
the URDF root's origin. Three modes per clip:

- ``legs + orientation``: the clip's orientation and gyro as the IMU, no accelerometer, so the
  legs-alone averaging estimator;
- ``legs, no IMU``: no IMU at all (planar);
- ``filter (full IMU)``: a synthetic full IMU, the orientation, the gyro and the root origin's
  acceleration as specific force ``Rᵀ(a - g)``, so the state filter. ``a`` at frame k is the mean
  over the step the filter holds the sample for, ``(v_k - v_(k-1)) / dt`` of the true velocity
  (central differences of the root positions).

Prints one table per clip: the body-velocity RMSE [m/s], the final position error as % of the
distance (3-D, and horizontal), and for the filter the share of samples whose velocity error is
within 3 sigma on every axis (``twist_variance[:3]``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pybullet
import pybullet_data
from common import ROOT  # noqa: F401 (makes a1_leg_fk importable from a checkout)

from a1_leg_fk.estimation.odometry import ImuReading
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.kinematics.quadruped import Quadruped


def root_poses(positions: np.ndarray, quaternions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """PyBullet base (CoM) poses -> the URDF root's (positions, quaternions x y z w)."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(
            f"{pybullet_data.getDataPath()}/a1/a1.urdf", physicsClientId=client
        )
        to_root = pybullet.invertTransform(
            *pybullet.getDynamicsInfo(body, -1, physicsClientId=client)[3:5]
        )
    finally:
        pybullet.disconnect(client)
    poses = [pybullet.multiplyTransforms(p, q, *to_root) for p, q in zip(positions, quaternions)]
    return np.array([p for p, _ in poses]), np.array([q for _, q in poses])


def matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations of (N, 4) quaternions x, y, z, w."""
    x, y, z, w = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


GRAVITY = np.array([0.0, 0.0, -9.80665])
"""[m/s²] in the world."""
MODES = ("legs + orientation", "legs, no IMU", "filter (full IMU)")


class Clip(NamedTuple):
    """A clip's joint states and truth, per frame: ``dt`` [s], root ``position`` (world) and
    ``quaternion`` (x, y, z, w), ``angles`` and ``rates``, the true body velocity ``truth``, the
    ``gyro`` and the ``specific_force`` (base frame).
    """

    dt: float
    position: np.ndarray
    quaternion: np.ndarray
    angles: np.ndarray
    rates: np.ndarray
    truth: np.ndarray
    gyro: np.ndarray
    specific_force: np.ndarray


class Result(NamedTuple):
    """One mode's scores: velocity RMSE [m/s], final position error [% of the distance] in 3-D
    and horizontally, and the share of samples within 3 sigma (NaN: no covariance used)."""

    rmse: float
    drift_pct: float
    horizontal_pct: float
    within_3sigma: float


def load(path: Path) -> Clip:
    """The clip's frames, converted to the URDF root, with their central differences."""
    clip = json.loads(path.read_text())
    dt, frames = float(clip["FrameDuration"]), np.array(clip["Frames"], dtype=float)
    position, quaternion = root_poses(frames[:, 0:3], frames[:, 3:7])
    angles = frames[:, 7:19]
    rotation = matrices(quaternion)
    velocity = np.gradient(position, dt, axis=0)
    spin = np.einsum("nji,njk->nik", rotation, np.gradient(rotation, dt, axis=0))
    gyro = np.stack([spin[:, 2, 1] - spin[:, 1, 2], spin[:, 0, 2] - spin[:, 2, 0],
                     spin[:, 1, 0] - spin[:, 0, 1]], 1) / 2  # fmt: skip
    acceleration = np.diff(velocity, axis=0, prepend=velocity[:1]) / dt
    force = np.einsum("nji,nj->ni", rotation, acceleration - GRAVITY)
    truth = np.einsum("nji,nj->ni", rotation, velocity)
    rates = np.gradient(angles, dt, axis=0)
    return Clip(dt, position, quaternion, angles, rates, truth, gyro, force)


def run(clip: Clip, quadruped: Quadruped, mode: str) -> Result:
    """Feed the clip through :class:`OdometryFeed` in one of :data:`MODES`."""
    feed = OdometryFeed(quadruped, use_imu=mode != MODES[1])
    feet = quadruped.fk_batch(clip.angles).tolist()
    foot_velocities = quadruped.foot_velocities_batch(clip.angles, clip.rates).tolist()
    linear, odom, variance = [], [], []
    for row in range(len(clip.angles)):
        stamp = round(row * clip.dt * 1e9)
        force = tuple(clip.specific_force[row]) if mode == MODES[2] else None
        feed.add_imu(stamp, ImuReading(tuple(clip.quaternion[row]), tuple(clip.gyro[row]),
                                       specific_force=force))  # fmt: skip
        sample = feed.step(
            stamp,
            list(zip(feet[row], foot_velocities[row])),
            clip.angles[row].tolist(),
            clip.rates[row].tolist(),
        )
        assert sample is not None
        linear.append(sample.linear)
        odom.append(sample.position)
        variance.append(sample.twist_variance[:3])
    inner = slice(1, -1)  # central differences only
    error = np.array(linear)[inner] - clip.truth[inner]
    rmse = float(np.sqrt(np.mean(np.sum(error**2, axis=1))))
    within = np.all(np.abs(error) <= 3 * np.sqrt(np.array(variance)[inner]), axis=1)
    moved, steps = clip.position[-1] - clip.position[0], np.diff(clip.position, axis=0)
    percents = []
    for axes in (slice(0, 3), slice(0, 2)):
        distance = np.linalg.norm(steps[:, axes], axis=1).sum()
        drift = np.linalg.norm(np.array(odom)[-1, axes] - moved[axes])
        percents.append(float(100 * drift / distance))
    if mode == MODES[1]:
        percents[0] = math.nan  # planar: no height
    share = float(within.mean()) if mode == MODES[2] else math.nan
    return Result(rmse, percents[0], percents[1], share)


def evaluate(path: Path, quadruped: Quadruped) -> None:
    """Print the clip's size and one row per mode."""
    clip = load(path)
    frames = len(clip.angles)
    distance = np.linalg.norm(np.diff(clip.position[:, :2], axis=0), axis=1).sum()
    seconds = (frames - 1) * clip.dt
    print(f"\n{path.name}: {frames} frames at {1 / clip.dt:.1f} Hz, {seconds:.2f} s, "
          f"{distance:.3f} m horizontal")  # fmt: skip
    print(f"  {'mode':<20} {'vel RMSE m/s':>12} {'pos err %':>9} {'horiz %':>8} {'in 3sd':>7}")
    for mode in MODES:
        result = run(clip, quadruped, mode)
        share = "-" if math.isnan(result.within_3sigma) else f"{result.within_3sigma:.1%}"
        drift = "-" if math.isnan(result.drift_pct) else f"{result.drift_pct:.2f}"
        print(f"  {mode:<20} {result.rmse:>12.4f} {drift:>9} "
              f"{result.horizontal_pct:>8.2f} {share:>7}")  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="+", type=Path, metavar="CLIP.txt")
    quadruped = Quadruped.from_urdf()
    for path in parser.parse_args().clips:
        evaluate(path, quadruped)
    return 0


if __name__ == "__main__":
    sys.exit(main())
