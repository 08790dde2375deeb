"""Foot FK speed of a1_leg_fk against two references, measured in one process, in one run.

Run: ``.venv/bin/python bench/fk_speed.py`` (about 20 s). Prints a table:

- one configuration, four feet, median time per call of
  ``Quadruped.fk``, of the four raw generated per-leg functions, of the reference write-up's
  per-leg numpy code (3x3 rotation matrices built with numpy on every call and chained; shown
  with ``np.cos``/``np.sin`` as (a) and with ``math.cos``/``math.sin`` as (a')), and of
  PyBullet (``resetJointState`` x 12 + ``getLinkState`` x 4); targets: <= 5 us per call and
  >= 20x faster than the numpy reference;
- a batch of 10^6 configurations: ``fk_batch`` throughput (target >= 1.3 M configs/s) beside the
  time of ``np.sin`` + ``np.cos`` alone on the same (10^6, 12) array, the floor of any method
  that needs the trigonometry.

Every reference is first checked against ``Quadruped.fk`` on the configuration it is timed on.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from common import REPEATS, SPEED_POSE, machine, median_seconds_per_call, shared, trig_floor

from a1_leg_fk.kinematics.quadruped import Quadruped

BATCH_ROWS = 1_000_000
BATCH_REPEATS = 5


# --- reference (a): the write-up's per-leg numpy code ----------------------------------------


def rx(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rx_math(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry_math(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def numpy_reference(
    quadruped: Quadruped, rot_x=rx, rot_y=ry
) -> Callable[[list[float]], np.ndarray]:
    """Per-leg numpy FK with the URDF numbers read from the model (A1 joint names)."""
    joints = quadruped.model.joints
    legs = []
    for leg in shared.LEGS:
        hip = np.array(joints[f"{leg}_hip_joint"].origin_xyz)  # trunk -> hip roll joint
        thigh = np.array(joints[f"{leg}_upper_joint"].origin_xyz)  # hip link -> hip pitch joint
        knee = np.array(joints[f"{leg}_lower_joint"].origin_xyz)  # thigh link -> knee joint
        foot = np.array(joints[f"{leg}_toe_fixed"].origin_xyz)  # calf link -> toe
        legs.append((hip, thigh, knee, foot))

    def fk(q: list[float]) -> np.ndarray:
        feet = np.empty((4, 3))
        for slot, (hip, thigh, knee, foot) in enumerate(legs):
            q0, q1, q2 = q[3 * slot], q[3 * slot + 1], q[3 * slot + 2]
            hip_rotation = rot_x(q0)
            thigh_rotation = hip_rotation @ rot_y(q1)
            calf_rotation = thigh_rotation @ rot_y(q2)
            feet[slot] = hip + hip_rotation @ thigh + thigh_rotation @ knee + calf_rotation @ foot
        return feet

    return fk


# --- reference (b): PyBullet ------------------------------------------------------------------


class PyBulletFk:
    """The A1 in PyBullet, loaded by the tests' reference (test/pybullet_reference.py: a DIRECT
    client, fixed base at the origin); ``fk(q)`` = resetJointState x 12 + getLinkState x 4."""

    def __init__(self, quadruped: Quadruped) -> None:
        import pybullet
        from pybullet_reference import A1_URDF, PyBulletRobot  # test/ is on the path (common)

        self.p = pybullet
        self.robot = PyBulletRobot(A1_URDF)
        self.body, self.client = self.robot.body, self.robot.client
        self.joints = [self.robot.joint_index[name] for name in quadruped.joint_names]
        self.feet = [self.robot.link_index[foot] for foot in shared.A1_FEET]

    def fk(self, q: list[float]) -> list:
        p, body, client = self.p, self.body, self.client
        for index, angle in zip(self.joints, q):
            p.resetJointState(body, index, angle, physicsClientId=client)
        return [
            p.getLinkState(body, foot, computeForwardKinematics=True, physicsClientId=client)[4]
            for foot in self.feet
        ]

    def close(self) -> None:
        self.robot.close()


# --- the run ------------------------------------------------------------------------------------


def main() -> None:
    print(machine())
    quadruped = Quadruped.from_urdf()
    q = [float(v) for v in SPEED_POSE]
    expected = quadruped.fk(q)

    legs = quadruped.legs
    f0, f1, f2, f3 = (leg.position for leg in legs)
    q0, q1, q2, q3, q4, q5, q6, q7, q8, q9, q10, q11 = q

    def raw() -> tuple:
        return f0(q0, q1, q2), f1(q3, q4, q5), f2(q6, q7, q8), f3(q9, q10, q11)

    reference = numpy_reference(quadruped)
    reference_math = numpy_reference(quadruped, rx_math, ry_math)
    assert np.abs(np.array(raw()) - expected).max() <= 1e-12
    assert np.abs(reference(q) - expected).max() <= 1e-12, "numpy reference disagrees with fk"
    assert np.abs(reference_math(q) - expected).max() <= 1e-12, "numpy reference disagrees with fk"

    pybullet_fk = None
    try:
        pybullet_fk = PyBulletFk(quadruped)
        assert np.abs(np.array(pybullet_fk.fk(q)) - expected).max() <= 1e-7, (
            "PyBullet disagrees with fk"
        )
    except ImportError:
        pass

    functions: dict[str, Callable[[], object]] = {
        "Quadruped.fk(q)  [12 floats -> (4, 3) array]": lambda: quadruped.fk(q),
        "generated per-leg functions x 4  [tuples]": raw,
        "(a) write-up per-leg numpy 3x3 chain, np.cos/sin": lambda: reference(q),
        "(a') the same with math.cos/sin": lambda: reference_math(q),
    }
    if pybullet_fk is not None:
        functions["(b) PyBullet reset x 12 + getLinkState x 4"] = lambda: pybullet_fk.fk(q)
    rows = list(median_seconds_per_call(functions).items())
    if pybullet_fk is not None:
        pybullet_fk.close()

    fk_seconds, numpy_seconds, numpy_math_seconds = rows[0][1], rows[2][1], rows[3][1]
    print(f"\none configuration, four feet (median of {REPEATS} interleaved runs)")
    print(f"  {'method':<52} {'us/call':>9} {'vs Quadruped.fk':>16}")
    for name, seconds in rows:
        print(f"  {name:<52} {seconds * 1e6:9.2f} {seconds / fk_seconds:15.1f}x")
    print(
        f"  Quadruped.fk: {fk_seconds * 1e6:.2f} us/call (target <= 5 us: "
        f"{'met' if fk_seconds <= 5e-6 else 'NOT met'}); {numpy_seconds / fk_seconds:.1f}x "
        "faster than (a) (target >= 20x: "
        f"{'met' if numpy_seconds / fk_seconds >= 20 else 'NOT met'}), "
        f"{numpy_math_seconds / fk_seconds:.1f}x faster than (a')"
    )

    batch = np.random.default_rng(0).uniform(-math.pi, math.pi, size=(BATCH_ROWS, 12))
    sample = slice(0, BATCH_ROWS, 9973)
    np.testing.assert_allclose(
        quadruped.fk_batch(batch[sample]),
        [quadruped.fk(row) for row in batch[sample]],
        rtol=0,
        atol=1e-12,
    )

    batch_runs = median_seconds_per_call(  # interleaved, as above
        {"fk_batch": lambda: quadruped.fk_batch(batch), "trig": trig_floor(batch)},
        repeats=BATCH_REPEATS,
        calibrate=False,
    )
    batch_seconds, trig_seconds = batch_runs["fk_batch"], batch_runs["trig"]
    throughput = BATCH_ROWS / batch_seconds / 1e6
    print(
        f"\nbatch of {BATCH_ROWS:,} configurations, (N, 12) float64 (median of {BATCH_REPEATS} "
        "interleaved runs)"
    )
    print(f"  {'method':<52} {'s':>9} {'M configs/s':>12}")
    print(f"  {'Quadruped.fk_batch':<52} {batch_seconds:9.3f} {throughput:12.2f}")
    print(
        f"  {'np.sin + np.cos alone (the floor)':<52} {trig_seconds:9.3f} "
        f"{BATCH_ROWS / trig_seconds / 1e6:12.2f}"
    )
    print(
        f"  fk_batch / trig floor = {batch_seconds / trig_seconds:.2f}x; "
        f"throughput {throughput:.2f} M/s (target >= 1.3 M/s: "
        f"{'met' if throughput >= 1.3 else 'NOT met'})"
    )


if __name__ == "__main__":
    main()
