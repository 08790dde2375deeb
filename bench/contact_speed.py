"""Per-joint-state cost of the contact pipeline (the node's path, plain floats), against the
quasi-static forces and the FK measured in the same run.

Run: ``.venv/bin/python bench/contact_speed.py`` (about 15 s). One A1 joint state of a trot
(angles, rates, efforts, an IMU with orientation, gyro and accelerometer) stepped again and again,
its stamp advancing 2 ms each call, median of interleaved runs:

- ``ContactEstimator.step``: the dynamic forces (momentum observer) and the contact filter for
  four legs, the whole per-input work (goal <= 40 us);
- its parts: ``MomentumObserver.step_floats`` (the forces), ``ContactFilter.update`` with the
  feet's motion (``LegMotion.foot`` x 4), and inside that update ``FootGround.heights`` (the
  feet's heights against the local ground's slope; two feet standing);
- the model corrections (:mod:`a1_leg_fk.estimation.model_corrections`, online by default):
  ``ContactEstimator.step`` with them off, and their own work in a trot's worst case, two legs
  surely in swing (12 residuals corrected, 6 joints learning); inside the observer, the legs'
  inertia scales' (:mod:`a1_leg_fk.estimation.leg_scales`: 4 legs corrected and kept, 2
  learning);
- the baselines: ``FootForces.estimate_floats`` (the quasi-static forces of the old rule) and
  ``Quadruped.fk`` (one FK of the four legs).
"""

from __future__ import annotations

from common import machine, median_seconds_per_call

from a1_leg_fk.estimation.contact_estimator import ContactEstimator, ImuSample
from a1_leg_fk.estimation.foot_ground import FootGround
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.model_corrections import ModelCorrections
from a1_leg_fk.estimation.momentum_observer import MomentumObserver
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.quadruped import Quadruped

ANGLES = [0.05, 0.8, -1.5, -0.05, 0.95, -1.75, 0.05, 0.9, -1.6, -0.05, 0.75, -1.45]  # rad
RATES = [0.5, -3.0, 4.0, -0.4, 6.0, -9.0, 0.3, 5.0, -8.0, -0.6, -2.5, 3.5]  # rad/s
EFFORTS = [1.1, -2.9, 2.4, -1.0, -0.3, 0.6, -1.9, 0.2, 0.4, 1.7, 2.8, 5.2]  # N m
IMU = ImuSample([0.3, -0.2, -9.79], [0.1, -0.2, 0.3], [-0.3, 0.2, 9.9])
STEP_S = 0.002


def main() -> None:
    print(machine())
    a1 = Quadruped.from_urdf()
    feet, velocities = a1.fk(ANGLES), a1.foot_velocities(ANGLES, RATES)
    legs = [(feet[leg].tolist(), velocities[leg].tolist()) for leg in range(4)]
    estimator, observer, statics = ContactEstimator(a1), MomentumObserver(a1), FootForces(a1)
    without = ContactEstimator(a1, model_corrections="off")
    clock = {"estimator": 0.0, "observer": 0.0, "without": 0.0}

    def estimate() -> None:
        clock["estimator"] += STEP_S
        estimator.step(clock["estimator"], (ANGLES, RATES, EFFORTS), legs, IMU)

    def estimate_without() -> None:
        clock["without"] += STEP_S
        without.step(clock["without"], (ANGLES, RATES, EFFORTS), legs, IMU)

    corrections = ModelCorrections()
    swing = [0.0, 1.0, 1.0, 0.0]  # FR and RL in the air, 0.1 m above the others
    in_air = [FootMotion((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), d) for d in (0.2, 0.3, 0.3, 0.2)]

    def correct_and_learn() -> None:
        for joint in range(12):
            corrections.correct(joint, EFFORTS[joint], RATES[joint])
        corrections.learn(STEP_S, swing, in_air, 0.05)

    scales = ModelCorrections().scales
    residual, model = (0.3, -0.5, 0.8), (1.2, -4.0, 3.1)  # N m
    rates = (0.4, -6.0, 9.0)  # rad/s

    def scale() -> None:
        for leg in range(4):
            scales.keep(leg, scales.correct(leg, residual, model), rates)
        scales.learn(0, STEP_S)
        scales.learn(3, STEP_S)

    def observe() -> None:
        clock["observer"] += STEP_S
        observer.step_floats(
            clock["observer"],
            (ANGLES, RATES, EFFORTS),
            IMU.gravity or (),
            IMU.specific_force,
            IMU.angular_velocity,
        )

    down = (0.0306, -0.0204, -0.9995)
    motion = estimator.motion

    def fuse() -> None:
        motions = [
            motion.foot(leg, ANGLES[3 * leg : 3 * leg + 3], RATES[3 * leg : 3 * leg + 3],
                        *legs[leg], down)
            for leg in range(4)
        ]  # fmt: skip
        estimator.filter.update(
            STEP_S, motions, ([0.1, -0.2, 0.3], None), [20.0, 1.0, 2.0, 30.0], None, down=down
        )

    ground, standing = FootGround(), [True, False, False, True]
    still = [motion.foot(leg, ANGLES[3 * leg : 3 * leg + 3], [0.0] * 3, legs[leg][0], [0.0] * 3,
                         down) for leg in range(4)]  # fmt: skip

    def heights() -> None:
        ground.heights(STEP_S, still, down, (0.1, -0.2, 0.3), standing)

    gravity = list(IMU.gravity or ())
    runs = median_seconds_per_call(
        {
            "ContactEstimator.step": estimate,
            "ContactEstimator.step, corrections off": estimate_without,
            "ModelCorrections: 12 corrected, 6 learning": correct_and_learn,
            "LegScales: 4 legs corrected, 2 learning": scale,
            "MomentumObserver.step_floats": observe,
            "LegMotion.foot x4 + ContactFilter.update": fuse,
            "FootGround.heights (in the filter's update)": heights,
            "FootForces.estimate_floats": lambda: statics.estimate_floats(
                ANGLES, EFFORTS, gravity
            ),
            "Quadruped.fk": lambda: a1.fk(ANGLES),
        }
    )
    whole, fk = runs["ContactEstimator.step"], runs["Quadruped.fk"]
    print(f"\n  {'one joint state, four legs':<44} {'us':>8} {'x fk':>6}")
    for name, seconds in runs.items():
        print(f"  {name:<44} {seconds * 1e6:8.1f} {seconds / fk:6.1f}")
    print(
        f"  dynamic forces + contact filter: {whole * 1e6:.1f} us per joint state (goal <= 40 us: "
        f"{'met' if whole <= 40e-6 else 'NOT met'})"
    )


if __name__ == "__main__":
    main()
