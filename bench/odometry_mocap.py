"""Leg odometry on retargeted A1 motion clips (AMP_for_hardware's ``datasets/mocap_motions``
format), the clip's own base motion as the truth.

Run: ``.venv/bin/python bench/odometry_mocap.py CLIP.txt...`` (the clips are CC BY-NC: download
them yourself; none is in this repository). A clip is JSON with ``FrameDuration`` [s] and
``Frames``: per frame the base position [m] and quaternion (x, y, z, w) of PyBullet's A1 base (the
trunk's centre of mass), then the 12 joint angles [rad] in the order FR, FL, RR, RL x hip, thigh,
calf (pybullet_data's a1.urdf), then toe positions and velocities (not used: the clips'
velocities disagree with their own angles' differences). Joint rates and the true base velocity
are central differences; the gyro comes from the clip's orientations; the base is converted to
the URDF root's origin. Prints, per clip, with the clip's orientation as the IMU and without an
IMU: the body-velocity RMSE [m/s] and the final position error as % of the distance.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

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


def evaluate(path: Path, quadruped: Quadruped) -> None:
    clip = json.loads(path.read_text())
    dt, frames = float(clip["FrameDuration"]), np.array(clip["Frames"], dtype=float)
    position, quaternion = root_poses(frames[:, 0:3], frames[:, 3:7])
    angles = frames[:, 7:19]
    rates = np.gradient(angles, dt, axis=0)
    rotation = matrices(quaternion)
    truth = np.einsum("nji,nj->ni", rotation, np.gradient(position, dt, axis=0))
    spin = np.einsum("nji,njk->nik", rotation, np.gradient(rotation, dt, axis=0))
    gyro = (
        np.stack(
            [
                spin[:, 2, 1] - spin[:, 1, 2],
                spin[:, 0, 2] - spin[:, 2, 0],
                spin[:, 1, 0] - spin[:, 0, 1],
            ],
            1,
        )
        / 2
    )
    feet = quadruped.fk_batch(angles).tolist()
    foot_velocities = quadruped.foot_velocities_batch(angles, rates).tolist()
    for use_imu in (True, False):
        feed = OdometryFeed(quadruped, use_imu=use_imu)
        linear, odom = [], []
        for row in range(len(frames)):
            stamp = round(row * dt * 1e9)
            feed.add_imu(stamp, ImuReading(tuple(quaternion[row]), tuple(gyro[row])))
            sample = feed.step(
                stamp,
                list(zip(feet[row], foot_velocities[row])),
                angles[row].tolist(),
                rates[row].tolist(),
            )
            assert sample is not None
            linear.append(sample.linear)
            odom.append(sample.position)
        inner = slice(1, -1)  # central differences only
        error = np.array(linear)[inner] - truth[inner]
        rmse = float(np.sqrt(np.mean(np.sum(error**2, axis=1))))
        axes = slice(0, 3) if use_imu else slice(0, 2)
        moved = position[-1] - position[0]
        distance = np.linalg.norm(np.diff(position[:, axes], axis=0), axis=1).sum()
        drift = float(np.linalg.norm(np.array(odom)[-1, axes] - moved[axes]))
        print(
            f"{path.name}: {len(frames)} frames ({(len(frames) - 1) * dt:.2f} s), "
            f"{'IMU (the clip orientation)' if use_imu else 'no IMU (planar)':<26} velocity RMSE "
            f"{rmse:.4f} m/s, final position error {drift * 1e3:.1f} mm = "
            f"{100 * drift / distance:.2f} % of {distance:.3f} m"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="+", type=Path, metavar="CLIP.txt")
    quadruped = Quadruped.from_urdf()
    for path in parser.parse_args().clips:
        evaluate(path, quadruped)
    return 0


if __name__ == "__main__":
    sys.exit(main())
