"""The momentum observer judged by PyBullet: an A1 thrown spinning into the air, its legs swinging
fast under torque control, touches nothing, so every foot force must be zero; the quasi-static
estimate reads the legs' swing as tens of newtons, and the observer without the IMU's gyro and
accelerometer (an inertial base) reads the fall as load. A standing A1 loaded by a step of force:
the observer follows PyBullet's contact forces through its gain's first-order lag. At rest, the
observer is the statics.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet
import pybullet_data
import pytest
from pybullet_sim import A1_FEET, A1_JOINTS, A1_URDF, STAND, QuadrupedSim, SimRun

from a1_leg_fk.estimation.momentum_observer import MomentumObserver
from a1_leg_fk.kinematics.foot_forces import FootForces
from a1_leg_fk.kinematics.quadruped import Quadruped

A1 = Quadruped.from_urdf()
STEP_S = 1.0 / 500.0
GRAVITY = np.array([0.0, 0.0, -9.81])


def targets(t: float) -> list[float]:
    """Joint targets [rad]: every joint swinging at 2-3 Hz, inside its limits."""
    out = []
    for leg in range(4):
        out += [
            0.3 * math.sin(4 * math.pi * t + leg),
            0.8 + 0.6 * math.sin(6 * math.pi * t + leg),
            -1.6 + 0.5 * math.sin(5 * math.pi * t + 2 * leg),
        ]
    return out


def thrown(seconds: float) -> dict[str, np.ndarray]:
    """The A1 in the air from 3 m, spinning, its joints driven by PD torques: per step the joint
    angles, rates and torques, the root's gyro and specific force (root frame) and gravity in the
    root frame.
    """
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pb = {"physicsClientId": client}
        pybullet.setGravity(*GRAVITY, **pb)
        pybullet.setTimeStep(STEP_S, **pb)
        body = pybullet.loadURDF(
            str(Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"),
            [0, 0, 3],
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
            **pb,
        )
        count = pybullet.getNumJoints(body, **pb)
        index = {pybullet.getJointInfo(body, j, **pb)[1].decode(): j for j in range(count)}
        joints = [index[name] for name in A1.joint_names]
        for link in range(-1, count):
            pybullet.changeDynamics(body, link, linearDamping=0, angularDamping=0, **pb)
        for joint in range(count):
            pybullet.setJointMotorControl2(body, joint, pybullet.VELOCITY_CONTROL, force=0, **pb)
        pybullet.resetBaseVelocity(body, [0.3, 0, 0], [1.5, -2.0, 2.5], **pb)
        com_in_root = pybullet.getDynamicsInfo(body, -1, **pb)[3:5]
        to_root = pybullet.invertTransform(*com_in_root)
        rows: dict[str, list] = {k: [] for k in ("q", "dq", "tau", "gyro", "force", "gravity")}
        previous = None
        for step in range(round(seconds / STEP_S)):
            states = pybullet.getJointStates(body, joints, **pb)
            tau = [
                float(np.clip(40.0 * (goal - s[0]) - 1.0 * s[1], -33.5, 33.5))
                for goal, s in zip(targets(step * STEP_S), states, strict=True)
            ]
            pybullet.setJointMotorControlArray(
                body, joints, pybullet.TORQUE_CONTROL, forces=tau, **pb
            )
            pybullet.stepSimulation(**pb)
            states = pybullet.getJointStates(body, joints, **pb)
            com, orientation = pybullet.getBasePositionAndOrientation(body, **pb)
            root, root_orientation = pybullet.multiplyTransforms(com, orientation, *to_root)
            linear, angular = pybullet.getBaseVelocity(body, **pb)
            rotation = np.array(pybullet.getMatrixFromQuaternion(root_orientation)).reshape(3, 3)
            velocity = np.array(linear) + np.cross(angular, np.subtract(root, com))
            acceleration = np.zeros(3) if previous is None else (velocity - previous) / STEP_S
            previous = velocity
            rows["q"].append([s[0] for s in states])
            rows["dq"].append([s[1] for s in states])
            rows["tau"].append(tau)
            rows["gyro"].append(rotation.T @ np.array(angular))
            rows["force"].append(rotation.T @ (acceleration - GRAVITY))
            rows["gravity"].append(rotation.T @ GRAVITY)
        assert not pybullet.getContactPoints(bodyA=body, **pb)
    finally:
        pybullet.disconnect(client)
    return {key: np.array(value) for key, value in rows.items()}


@pytest.fixture(scope="module")
def flight() -> dict[str, np.ndarray]:
    return thrown(1.5)


def forces(flight: dict[str, np.ndarray], imu: bool) -> np.ndarray:
    """(N, 4, 3) the observer's forces [N], the first 0.1 s (its start) left out."""
    stamps = STEP_S * np.arange(1, len(flight["q"]) + 1)
    estimate = MomentumObserver(A1).step_batch(
        stamps,
        (flight["q"], flight["dq"], flight["tau"]),
        flight["gravity"],
        flight["force"] if imu else None,
        flight["gyro"] if imu else None,
    )
    assert not estimate.missing.any()
    return estimate.forces[50:]


def test_a_leg_in_the_air_feels_no_force(flight: dict[str, np.ndarray]) -> None:
    observed = np.linalg.norm(forces(flight, imu=True), axis=2)
    assert np.sqrt(np.nanmean(observed**2)) < 0.5  # [N]: PyBullet's integration step
    assert np.nanpercentile(observed, 99) < 2.0
    static = FootForces(A1).estimate_batch(flight["q"], flight["tau"], flight["gravity"])
    quasi = np.linalg.norm(static.forces[50:], axis=2)
    assert np.nanpercentile(quasi, 95) > 20.0  # the swing read as load
    assert np.abs(flight["gyro"]).max() > 1.0  # it spins


def test_without_the_imu_the_fall_reads_as_load(flight: dict[str, np.ndarray]) -> None:
    inertial = np.linalg.norm(forces(flight, imu=False), axis=2)
    assert np.nanmedian(inertial) > 3.0  # [N]: the legs' weight, which free fall cancels


def test_at_rest_the_observer_is_the_statics() -> None:
    """A consistency check (any gain gives it: no rates, no change): the observer reduces to the
    statics; PyBullet judges the standing robot's forces in the step-of-load test below."""
    rng = np.random.default_rng(2)
    angles = np.tile([0.05, 0.8, -1.5], 4) + rng.uniform(-0.2, 0.2, 12)
    efforts = rng.uniform(-10.0, 10.0, 12)
    gravity = [0.8, -0.5, -9.7]
    observer = MomentumObserver(A1)
    for step in range(5):
        dynamic, _, _ = observer.step_floats(
            0.002 * step, (angles.tolist(), [0.0] * 12, efforts.tolist()), gravity
        )
    static = FootForces(A1).estimate(angles, efforts, gravity).forces
    assert np.abs(np.array(dynamic) - static).max() < 1e-9


@pytest.mark.parametrize(
    "leg_efforts",  # each sums to a finite value [N m], so the entry check lets them through
    [(1.5e308, -1.5e308, 1.5e308), (-1e308, 1e308, -1e308), (1e308, 0.0, 0.0)],
)
def test_an_absurd_effort_gives_no_force_and_the_next_sample_the_statics(
    leg_efforts: tuple[float, float, float],
) -> None:
    """Issue 38 (found by the node fuzz: a damaged JointState's absurd efforts published a foot
    force of -inf): a leg whose force overflows has none (NaN, counted missing), the other legs
    keep theirs, and the next sane sample at rest is the statics again."""
    angles = np.tile([0.05, 0.8, -1.5], 4)
    efforts = np.tile([0.5, -2.0, 4.0], 4)
    gravity = [0.0, 0.0, -9.81]
    observer = MomentumObserver(A1)
    absurd = efforts.copy()
    absurd[3:6] = leg_efforts  # the second leg
    out, missing, _ = observer.step_floats(
        0.0, (angles.tolist(), [0.0] * 12, absurd.tolist()), gravity
    )
    assert np.isnan(out[1]).all() and missing == [False, True, False, False], (out, missing)
    assert np.isfinite(np.array(out)[[0, 2, 3]]).all()
    for step in range(1, 4):
        out, missing, _ = observer.step_floats(
            0.002 * step, (angles.tolist(), [0.0] * 12, efforts.tolist()), gravity
        )
    static = FootForces(A1).estimate(angles, efforts, gravity).forces
    assert not any(missing) and np.abs(np.array(out) - static).max() < 1e-9


LOAD_GAIN_PER_S = 50.0
"""A gain slow enough to see: the observer's lag 1 / K = 20 ms, ten physics steps."""
LOAD_N = 150.0
"""The step of load pushed down on the base [N]."""


@pytest.fixture(scope="module")
def loaded() -> SimRun:
    """The A1 standing on PyBullet's plane under PD motors, 1 s settled; then a step of
    :data:`LOAD_N` pushed down on its base for 0.4 s."""
    with QuadrupedSim(A1_URDF, A1_JOINTS, A1_FEET, spawn_height_m=0.3,
                      inertia_from_file=True) as sim:  # fmt: skip
        targets = list(STAND) * 4
        sim.place((0.0, 0.0, 0.3), (0.0, 0.0, 0.0, 1.0), targets)
        samples = []
        for step in range(round(1.4 / STEP_S)):
            if step * STEP_S >= 1.0:
                sim.push((0.0, 0.0, -LOAD_N))
            samples.append(sim.step_pd(targets, (80.0, 2.0), 33.5))
    return SimRun.of(A1_JOINTS, samples)


def lagged(values: np.ndarray, gain_per_s: float) -> np.ndarray:
    """``values`` (one per physics step) through a first-order lag of time constant
    ``1 / gain_per_s``, exact for an input held over each step, started at the first value."""
    keep = math.exp(-gain_per_s * STEP_S)
    out = np.empty_like(values)
    out[0] = values[0]
    for k in range(1, len(values)):
        out[k] = keep * out[k - 1] + (1.0 - keep) * values[k]
    return out


def test_a_step_of_load_is_followed_with_the_gains_time_constant(loaded: SimRun) -> None:
    """The observer's total vertical foot force (world) against PyBullet's contact forces: the
    ground's force through a first-order lag of 1 / K (the observer's response; a step reaches
    1 - 1/e at t = 1/K), not the force itself nor a ten times slower lag."""
    run = loaded
    observer = MomentumObserver(A1, gain_per_s=LOAD_GAIN_PER_S)
    rotations = run.rotations
    estimate = observer.step_batch(
        run.stamps_s,
        (run.angles, run.rates, run.torques),
        np.einsum("nji,j->ni", rotations, GRAVITY),
        run.specific_force,
        run.gyro,
    )
    world = np.einsum("nij,nkj->nki", rotations, estimate.forces)
    start = round(0.9 / STEP_S)  # settled, 0.1 s before the load
    standing = np.abs(world - run.contact_forces)[start : start + 50]
    print(f"standing, before the load: each foot's force within {standing.max():.2f} N")
    assert standing.max() <= 0.05 * LOAD_N  # every foot, every axis: the statics at rest
    observed, truth = world[:, :, 2].sum(axis=1), run.contact_forces[:, :, 2].sum(axis=1)
    window = slice(round(1.0 / STEP_S) - start, round(1.15 / STEP_S) - start)
    observed, truth = observed[start:], truth[start:]
    differences = {
        name: float(np.sqrt(np.mean((observed - reference)[window] ** 2)))
        for name, reference in (
            ("lag 1/K", lagged(truth, LOAD_GAIN_PER_S)),
            ("no lag", truth),
            ("lag 10/K", lagged(truth, LOAD_GAIN_PER_S / 10.0)),
        )
    }
    step = float(truth[-50:].mean() - truth[:50].mean())
    print(f"load step {step:.1f} N; observer against the truth, RMS over 0.15 s: " +
          ", ".join(f"{name} {value:.2f} N" for name, value in differences.items()))  # fmt: skip
    assert step > 0.8 * LOAD_N  # the feet carry the load
    assert differences["lag 1/K"] <= 0.05 * step
    assert differences["no lag"] >= 3.0 * differences["lag 1/K"]
    assert differences["lag 10/K"] >= 3.0 * differences["lag 1/K"]
    settled = observed[-50:].mean() - truth[-50:].mean()
    assert abs(settled) <= 0.05 * step
