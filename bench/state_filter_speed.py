"""Per-sample cost of the odometry's state filter (plain floats and 15 x 15 numpy), against the
contact estimate and one FK measured in the same run.

Run: ``.venv/bin/python bench/state_filter_speed.py`` (about 15 s). One A1 trot sample (two feet
in stance, the IMU's orientation, gyro and accelerometer) again and again, the stamp advancing
1 ms (with a few µs of jitter, as a node's stamps) each call, median of interleaved runs:

- ``StateFilter step``: one IMU propagation, one update with two stance feet and the IMU's
  orientation, and the output sample: the filter's own work per joint state (goal <= 60 us);
  ``StateFilter step, no give``: the same without the feet's give (``give_s`` 0), the ratio
  printed (the give's cost, goal <= 1.1); ``StateFilter step, impacts fixed``: every landing
  ``touchdown_noise_mps`` (``impact_window_s`` 0, the filter before each landing was measured),
  the ratio printed; ``StateFilter trot step`` and ``..., impacts fixed``: the same on a trot (the
  pairs in turn, 48 samples each, all four feet standing for 2 between), where each touchdown's
  jolt is measured (:mod:`~a1_leg_fk.estimation.foot_jolt`), the ratio printed;
- its parts: ``propagate``, ``update``, ``sample``;
- ``OdometryFeed.step``: the whole per-joint-state work of ``leg_odometry_node`` without ROS (the
  contact estimate with efforts, the feet's motion and Jacobians, the filter);
- ``OdometryFeed.ground_plane``: the local ground the node publishes beside each sample (its slope
  across the base's heading the standing feet's), and ``LocalGround.reported`` without the heading
  (the footholds' plane alone, as before), the ratio printed;
- the baselines: ``ContactEstimator.step`` and ``Quadruped.fk``.
"""

from __future__ import annotations

import itertools

from common import machine, median_seconds_per_call

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.estimation.filter_model import FilterSettings, LegMeasurement
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.odometry import ImuReading
from a1_leg_fk.estimation.odometry_feed import OdometryFeed
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.kinematics.quadruped import Quadruped

ANGLES = [0.05, 0.8, -1.5, -0.05, 0.95, -1.75, 0.05, 0.9, -1.6, -0.05, 0.75, -1.45]  # rad
RATES = [0.5, -3.0, 4.0, -0.4, 6.0, -9.0, 0.3, 5.0, -8.0, -0.6, -2.5, 3.5]  # rad/s
EFFORTS = [1.1, -2.9, 2.4, -1.0, -0.3, 0.6, -1.9, 0.2, 0.4, 1.7, 2.8, 5.2]  # N m
ORIENTATION = (0.0153, -0.0102, 0.0, 0.99983)
GYRO, FORCE = (0.1, -0.2, 0.3), (-0.3, 0.2, 9.9)
STEP_NS = 1_000_000
JITTER_NS = (-7_000, 5_000, 2_000)
"""The stamps' jitter [ns]: a node's messages are never exactly 1 ms apart."""
JJT = (0.05, 0.0, 0.01, 0.0, 0.06, 0.0, 0.01, 0.0, 0.04)  # m^2/rad^2


def main() -> None:
    print(machine())
    a1 = Quadruped.from_urdf()
    feet, velocities = a1.fk(ANGLES), a1.foot_velocities(ANGLES, RATES)
    legs = [(feet[leg].tolist(), velocities[leg].tolist()) for leg in range(4)]
    state, feed, contacts = StateFilter(), OdometryFeed(a1), ContactEstimator(a1)
    rigid = StateFilter(FilterSettings(give_s=0.0))
    fixed = StateFilter(FilterSettings(impact_window_s=0.0))
    trotting, trotting_fixed = StateFilter(), StateFilter(FilterSettings(impact_window_s=0.0))
    clock = {
        "filter": 0,
        "rigid": 0,
        "fixed": 0,
        "trot": 0,
        "trot fixed": 0,
        "propagate": 0,
        "update": 0,
        "feed": 0,
        "contacts": 0,
    }
    stance = [
        LegMeasurement(FootMotion((0.3, 0.0, 0.0), (0.18, -0.13, -0.3), 0.3), 0.99, JJT),
        None,
        None,
        LegMeasurement(FootMotion((0.3, 0.0, 0.0), (-0.18, 0.13, -0.3), 0.3), 0.99, JJT),
    ]
    other = [
        None,
        LegMeasurement(FootMotion((0.3, 0.0, 0.0), (0.18, 0.13, -0.3), 0.3), 0.99, JJT),
        LegMeasurement(FootMotion((0.3, 0.0, 0.0), (-0.18, -0.13, -0.3), 0.3), 0.99, JJT),
        None,
    ]
    four = [stance[0], other[1], other[2], stance[3]]
    gait = [stance] * 48 + [four] * 2 + [other] * 48 + [four] * 2
    gaits = {"trot": itertools.cycle(gait), "trot fixed": itertools.cycle(gait)}
    for each in (state, rigid, fixed, trotting, trotting_fixed):
        each.propagate(0, GYRO, FORCE, ORIENTATION)
    imu = ImuReading(ORIENTATION, GYRO, specific_force=FORCE)
    sample = ImuSample((0.3, -0.2, -9.79), GYRO, FORCE)

    jitter = itertools.cycle(JITTER_NS)

    def tick(name: str) -> int:
        clock[name] += STEP_NS + next(jitter)
        return clock[name]

    def step(state: StateFilter = state, name: str = "filter") -> None:
        stamp = tick(name)
        state.propagate(stamp, GYRO, FORCE)
        state.update(stamp, stance, ORIENTATION)
        state.sample(stamp, (0, 3), (0, 3))

    def trot(state: StateFilter, name: str) -> None:
        stamp = tick(name)
        state.propagate(stamp, GYRO, FORCE)
        used = state.update(stamp, next(gaits[name]), ORIENTATION)
        state.sample(stamp, used, used)

    def fed() -> None:
        stamp = tick("feed")
        feed.add_imu(stamp, imu)
        feed.step(stamp, legs, ANGLES, RATES, efforts=EFFORTS)

    stood = feed.step(tick("feed"), legs, ANGLES, RATES, efforts=EFFORTS)
    for k in range(40):  # a trot's footholds on a 5° slope: the ground has its plane
        pair, ahead = ((0, 3), (1, 2))[k % 2], 0.1 * k
        points = [(leg, (feet[leg][0] + ahead, feet[leg][1], 0.087 * (feet[leg][0] + ahead)))
                  for leg in pair]  # fmt: skip
        for sample_s in range(20):
            feed.ground.update(k * 0.2 + sample_s * 0.01, points)
    assert stood is not None and feed.ground_plane(stood) is not None
    x, y, _ = stood.position

    runs = median_seconds_per_call(
        {
            "StateFilter step": step,
            "StateFilter step, no give": lambda: step(rigid, "rigid"),
            "StateFilter step, impacts fixed": lambda: step(fixed, "fixed"),
            "StateFilter trot step": lambda: trot(trotting, "trot"),
            "StateFilter trot step, impacts fixed": lambda: trot(trotting_fixed, "trot fixed"),
            "StateFilter.propagate": lambda: state.propagate(tick("filter"), GYRO, FORCE),
            "StateFilter.update": lambda: state.update(tick("filter"), stance, ORIENTATION),
            "StateFilter.sample": lambda: state.sample(0, (0, 3), (0, 3)),
            "OdometryFeed.step (with efforts)": fed,
            "OdometryFeed.ground_plane": lambda: feed.ground_plane(stood),
            "LocalGround.reported, no heading": lambda: feed.ground.reported(x, y),
            "ContactEstimator.step": lambda: contacts.step(
                tick("contacts") / 1e9, (ANGLES, RATES, EFFORTS), legs, sample
            ),
            "Quadruped.fk": lambda: a1.fk(ANGLES),
        }
    )
    fk = runs["Quadruped.fk"]
    print(f"\n  {'one sample':<36} {'us':>8} {'x fk':>6}")
    for name, seconds in runs.items():
        print(f"  {name:<36} {seconds * 1e6:8.1f} {seconds / fk:6.1f}")
    ground = runs["OdometryFeed.ground_plane"] / runs["LocalGround.reported, no heading"]
    print(f"\n  the slope across the heading: the ground {ground:.2f}x its cost without it")
    node = (runs["OdometryFeed.step (with efforts)"] + runs["OdometryFeed.ground_plane"]) / (
        runs["OdometryFeed.step (with efforts)"] + runs["LocalGround.reported, no heading"]
    )
    print(f"  the odometry's step and its ground: {node:.3f}x")
    give = runs["StateFilter step"] / runs["StateFilter step, no give"]
    print(f"\n  the feet's give: StateFilter step {give:.3f}x its cost without it")
    impact = runs["StateFilter step"] / runs["StateFilter step, impacts fixed"]
    print(f"  each landing measured: StateFilter step {impact:.3f}x its cost with them fixed")
    jolt = runs["StateFilter trot step"] / runs["StateFilter trot step, impacts fixed"]
    print(f"  on a trot, with each touchdown's jolt: {jolt:.3f}x its cost with them fixed")


if __name__ == "__main__":
    main()
