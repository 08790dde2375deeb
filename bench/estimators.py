"""Three estimators of the base's velocity side by side on the simulated odometry family (the long
runs of ``test/contact_runs.py``, clean and with the contact issue's sensor noise), PyBullet's root
motion the truth:

- ``eskf``: this package's state filter (``a1_leg_fk.estimation.state_filter``, the default of
  ``leg_odometry_node`` and ``a1-leg-fk odom`` with an accelerometer);
- ``average``: the averaging estimate of the stance feet (the legs alone, what the package did
  before the filter; the IMU's orientation and gyro, no accelerometer);
- ``linear_kf``: the linear Kalman filter of Cheetah-Software / legged_control
  (``bench/linear_kf.py``), the feet's trust from the same contact probabilities.

Run: ``.venv/bin/python bench/estimators.py [RUN ...]`` (default: every long run; runs missing
from the cache are simulated first, about a third of their length each). Prints one table: velocity
RMSE [m/s], the worst 0.1 s window's mean error [m/s], horizontal and vertical drift [% of the
distance].
"""

from __future__ import annotations

import sys
import time

import numpy as np
from common import ROOT
from linear_kf import LinearKalmanFilter

sys.path.insert(0, str(ROOT / "test"))

from conftest import FAMILY_NOISE_SEED, family_folder
from contact_gaits import LONG_SPECS
from contact_runs import ContactRun, contact_runs, with_noise
from odometry_scoring import HEADER, Estimate, errors, estimate
from pybullet_sim import rotation_matrices

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY
from a1_leg_fk.kinematics.quadruped import Quadruped


def linear_kf(run: ContactRun, quadruped: Quadruped) -> Estimate:
    """The linear KF over ``run``, its feet trusted as the contact estimate's probabilities."""
    feet = quadruped.fk_batch(run.angles)
    speeds = quadruped.foot_velocities_batch(run.angles, run.rates)
    rotations = rotation_matrices(run.quaternions)
    contacts = ContactEstimator(quadruped)
    kf = LinearKalmanFilter()
    velocity, position = [], []
    previous = 0.0
    for row, seconds in enumerate(run.stamps_s.tolist()):
        gravity = rotations[row].T @ np.array([0.0, 0.0, -STANDARD_GRAVITY])
        imu = ImuSample(gravity.tolist(), run.gyro[row].tolist(), run.specific_force[row].tolist())
        step = contacts.step(
            seconds,
            (run.angles[row].tolist(), run.rates[row].tolist(), run.torques[row].tolist()),
            list(zip(feet[row].tolist(), speeds[row].tolist())),
            imu,
        )
        trust = [min(max(p, 0.0), 1.0) for p in step.probabilities]
        dt = seconds - previous if row else 0.0
        previous = seconds
        imu_row = (rotations[row], run.gyro[row], run.specific_force[row])
        velocity.append(kf.step(dt, *imu_row, feet[row], speeds[row], trust))
        position.append(kf.x[0:3].copy())
    n = len(velocity)
    return Estimate(
        np.array(velocity), np.full((n, 3), np.nan), np.array(position), np.zeros((n, 4)), None
    )


def main(names: list[str]) -> int:
    """Print the table of every run in ``names`` (default: all long runs)."""
    runs = contact_runs(family_folder(), tuple(names or LONG_SPECS))
    print(HEADER.replace("run", "run / estimator", 1))
    for run in runs.values():
        quadruped = Quadruped.from_urdf(run.urdf_path)
        for fed in (run, with_noise(run, FAMILY_NOISE_SEED)):
            started = time.perf_counter()
            results = {
                "eskf": estimate(fed, True, quadruped),
                "average": estimate(fed, True, quadruped, accelerometer=False),
                "linear_kf": linear_kf(fed, quadruped),
            }
            for estimator, result in results.items():
                print(errors(run, result).row(f"{fed.name} {estimator}"), flush=True)
            print(f"  ({time.perf_counter() - started:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
