"""A family of PyBullet runs of robots that are not their URDF: joint friction, heavier or
lighter legs, a payload on the trunk, an effort scaled and late. The estimator is always given the
NOMINAL description; PyBullet simulates the mismatched one.

Independent of the code under test (no a1_leg_fk import): this is the judge. The gaits, motors
and robots are the contact family's (:mod:`contact_gaits`, :data:`contact_gaits.SPECS`), walked
for :attr:`MismatchSpec.gait_s` after :data:`contact_runs.SETTLE_S` of standing, 500 Hz, one
sample per physics step, in :class:`contact_runs.ContactRun`'s format (truth: the plane's normal
forces). What a :class:`Mismatch` changes:

- **viscous joint friction** ``damping`` [N m s/rad]: a torque -b q̇ added to the PD motor's over
  each step (explicit, from the joint rate before the step; stable at 500 Hz for b ≤ 0.2);
- **Coulomb joint friction** ``coulomb`` [N m]: PyBullet's velocity motor on every joint, target
  rate 0, maximum force μ. It is a constraint solved with the step (stick-slip, implicit), so it
  holds a joint at rest against torques below μ and opposes motion with μ otherwise; PyBullet keeps
  it beside the torque control (checked: a hanging leg with μ = 0.6 N m holds its thigh and calf
  against gravity, without it they fall). An explicit -μ tanh(q̇/ε) would need ε ≳ 0.5 rad/s to
  stay stable on the A1's light calf at this step;
- **link masses** ``thigh_mass``, ``calf_mass``: fractions added to each thigh's and calf's mass,
  its inertia tensor scaled alike (the same shape, denser: cables, rubber, rotors);
- **payload** ``payload_kg`` at ``payload_at`` [m, root frame]: a link fixed to the root, a
  0.1 m cube's inertia, no collision;
- **the efforts reported**: the motor torque times ``torque_scale`` (a torque constant off), and
  late by ``latency_s`` (linear interpolation between samples; the first held before the start).
  The friction is not in the effort: the motor's current measures the motor's torque.

Ranges (what Unitree publishes): unitree_ros' A1 description gives every joint ``<dynamics
damping="0.01" friction="0.2"/>``, 33.5 N m limits and a 6.0 kg trunk where pybullet_data's A1
has 4.713 kg (1.3 kg that the simulated nominal does not carry); unitree_mujoco's go2.xml gives
damping 0.1 N m s/rad, frictionloss 0.2 N m, armature 0.01 kg m² (a rotor's reflected inertia,
which PyBullet cannot add to a joint: the calves' +25 % stands for part of it), motor limits
23.7 and 45.43 N m. The family spans damping 0-0.2 N m s/rad, Coulomb 0-0.6 N m, masses
-10 %..+25 %, payloads 0-3 kg off-centre, torque scales 0.9-1.1 and latencies 0-3 ms.

``python test/mismatch_runs.py OUT_DIR [NAME ...]`` simulates (or loads) and prints a table.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pybullet
from contact_gaits import GO2_FEET, GO2_JOINTS, SPECS, RunSpec, gait_targets, go2_urdf
from contact_runs import (
    A1_LEGS,
    ARRAYS,
    GO2_LEGS,
    SETTLE_S,
    UP,
    ContactRun,
    Pose,
    _load,
    _locked,
    print_table,
    targets_and_rates,
)
from mismatch_specs import SPECS_MISMATCH, Mismatch, MismatchSpec
from pybullet_sim import A1_FEET, A1_JOINTS, A1_URDF, GRAVITY, STEP_S, QuadrupedSim

CACHE = Path("/tmp/a1_leg_fk-mismatch-runs")
"""Where the family is kept between sessions (its own: the contact family's cache is not
touched)."""
SOURCES = ("mismatch_runs.py", "contact_runs.py", "contact_gaits.py", "pybullet_sim.py")
"""The files whose text names the cache (with each run's own :class:`MismatchSpec`: the
family's table, test/mismatch_specs.py, is not one of them)."""
PAYLOAD_SIDE_M = 0.1
"""[m] The payload's inertia is a cube's of this side."""


@dataclass(frozen=True)
class MismatchRun:
    """A simulated run (``run``: the nominal description as its URDF) with what the estimator
    does not know: the spec, the true total mass [kg] and the motor torques [N m] before the
    scale and latency of the report (N, 12)."""

    run: ContactRun
    spec: MismatchSpec
    true_mass_kg: float
    motor_torques: np.ndarray

    @property
    def true_weight_n(self) -> float:
        """The simulated robot's weight [N]."""
        return self.true_mass_kg * GRAVITY


def mismatched_urdf(text: str, joints: tuple[str, ...], mismatch: Mismatch) -> str:
    """``text`` (a URDF) as the robot of ``mismatch`` is: the thighs' and calves' (children of
    ``joints`` 1 and 2 of each leg) masses and inertias scaled, a payload link fixed to the root;
    without visuals (their meshes lie beside the original).
    """
    robot = ElementTree.fromstring(text)
    children = {joint.get("name"): joint.find("child") for joint in robot.findall("joint")}
    scale = {}
    for index, name in enumerate(joints):
        child = children[name]
        assert child is not None, name
        part = index % 3
        scale[child.get("link")] = (1.0, 1.0 + mismatch.thigh_mass, 1.0 + mismatch.calf_mass)[part]
    for link in robot.findall("link"):
        for visual in link.findall("visual"):  # meshes: relative to the original's folder
            link.remove(visual)
        factor = scale.get(link.get("name"), 1.0)
        inertial = link.find("inertial")
        if factor == 1.0 or inertial is None:
            continue
        mass, inertia = inertial.find("mass"), inertial.find("inertia")
        assert mass is not None and inertia is not None
        mass.set("value", repr(float(mass.get("value", "0")) * factor))
        for key, value in list(inertia.attrib.items()):
            inertia.set(key, repr(float(value) * factor))
    if mismatch.payload_kg > 0.0:
        child_links = {child.get("link") for child in children.values() if child is not None}
        root = next(
            link.get("name") for link in robot.iter("link") if link.get("name") not in child_links
        )
        moment = repr(mismatch.payload_kg * PAYLOAD_SIDE_M**2 / 6.0)
        joint = ElementTree.SubElement(robot, "joint", name="payload_joint", type="fixed")
        ElementTree.SubElement(joint, "parent", link=str(root))
        ElementTree.SubElement(joint, "child", link="payload")
        ElementTree.SubElement(
            joint, "origin", xyz=" ".join(map(repr, mismatch.payload_at)), rpy="0 0 0"
        )
        link = ElementTree.SubElement(robot, "link", name="payload")
        inertial = ElementTree.SubElement(link, "inertial")
        ElementTree.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
        ElementTree.SubElement(inertial, "mass", value=repr(mismatch.payload_kg))
        moments = {"ixx": moment, "iyy": moment, "izz": moment, "ixy": "0", "ixz": "0", "iyz": "0"}
        ElementTree.SubElement(inertial, "inertia", moments)
    return ElementTree.tostring(robot, encoding="unicode")


def reported_efforts(
    stamps_s: np.ndarray, torques: np.ndarray, scale: float, latency_s: float
) -> np.ndarray:
    """(N, J) the efforts a robot reports: ``torques`` [N m] at ``stamps_s`` [s] times ``scale``,
    as they were ``latency_s`` [s] earlier (linear interpolation; the first before the start)."""
    late = np.stack(
        [np.interp(stamps_s - latency_s, stamps_s, column) for column in torques.T], axis=1
    )
    result: np.ndarray = scale * late
    return result


def simulate_mismatch(
    name: str, spec: MismatchSpec, nominal: Path, simulated: Path
) -> MismatchRun:
    """Simulate ``spec`` with the mismatched description at ``simulated``; the run names the
    ``nominal`` one. As :func:`contact_runs.simulate_run` (placement, targets, the gait's view of
    the trunk, the specific force), plus the friction, the effort's scale and latency."""
    base: RunSpec = SPECS[spec.base]
    mismatch = spec.mismatch
    legs = A1_LEGS if base.robot == "a1" else GO2_LEGS
    joints, feet = (A1_JOINTS, A1_FEET) if base.robot == "a1" else (GO2_JOINTS, GO2_FEET)
    started = time.perf_counter()
    rows: dict[str, list[np.ndarray]] = {key: [] for key in ARRAYS}
    with QuadrupedSim(simulated, joints, feet, STEP_S, inertia_from_file=True) as sim:
        pb = {"physicsClientId": sim.client}
        links = range(-1, pybullet.getNumJoints(sim.body, **pb))
        mass = sum(pybullet.getDynamicsInfo(sim.body, link, **pb)[0] for link in links)
        targets = gait_targets(legs, base.gait, SETTLE_S, mass * GRAVITY, base.motors.kp)
        pybullet.changeDynamics(sim.body, -1, linearDamping=0, angularDamping=0, **pb)
        pybullet.setJointMotorControlArray(
            sim.body,
            sim.joints,
            pybullet.VELOCITY_CONTROL,
            targetVelocities=[0.0] * len(sim.joints),
            forces=[mismatch.coulomb] * len(sim.joints),
            **pb,
        )
        height = base.gait.height_m + legs.foot_radius_m + 0.002
        sim.place([0.0, 0.0, height], [0.0, 0.0, 0.0, 1.0], targets(0.0, None)[0].tolist())
        velocity, rates = np.zeros(3), np.zeros(len(sim.joints))
        slot = {link: index for index, link in enumerate(sim.feet)}
        pose: Pose | None = None
        motors = base.motors
        for _ in range(round((SETTLE_S + spec.gait_s) / STEP_S)):
            goal, goal_rates = targets_and_rates(targets, sim.time_s + STEP_S, pose)
            # the viscous friction: the PD torque's rate term with -b, applied with the motor's
            drag = (np.asarray(goal_rates) * motors.kd - mismatch.damping * rates) / motors.kd
            sample = sim.step_pd(goal, (motors.kp, motors.kd), motors.max_torque_nm, drag.tolist())
            rows.setdefault("motor", []).append(
                sample.torques + mismatch.damping * rates
            )  # what the motor gave: the step's torque without the friction folded into it
            rates = sample.rates
            normal = np.zeros(4)
            for point in pybullet.getContactPoints(sim.body, sim.plane, **pb):
                if point[3] in slot:
                    normal[slot[point[3]]] += point[9]
            to_world = np.array(pybullet.getMatrixFromQuaternion(sample.root_orientation))
            acceleration = (sample.linear_velocity - velocity) / STEP_S
            velocity = sample.linear_velocity
            roll, pitch, _ = pybullet.getEulerFromQuaternion(sample.root_orientation)
            above = float(sample.root_position[2]) - legs.foot_radius_m
            pose = (roll, pitch, above, float(sample.gyro[0]), float(sample.gyro[1]))
            for key, value in (
                ("stamps_s", np.array(sample.stamp_s)),
                ("angles", sample.angles),
                ("rates", sample.rates),
                ("quaternions", sample.root_orientation),
                ("gyro", sample.gyro),
                ("specific_force", to_world.reshape(3, 3).T @ (acceleration + UP * GRAVITY)),
                ("normal_forces", normal),
                ("contacts", normal > 0.0),
                ("base_positions", sample.root_position),
                ("base_velocities", sample.linear_velocity),
                ("other_contacts", np.array(sample.other_contact)),
            ):
                rows[key].append(value)
    arrays = {key: np.array(values) for key, values in rows.items()}
    motor = arrays.pop("motor")
    run = ContactRun(
        name=name,
        robot=base.robot,
        urdf_text=nominal.read_text(encoding="utf-8"),
        urdf_path=str(nominal),
        joint_names=tuple(joints),
        foot_links=tuple(feet),
        gait_start_s=SETTLE_S,
        duty=base.gait.duty,
        simulate_s=time.perf_counter() - started,
        **{
            **arrays,
            "torques": reported_efforts(
                arrays["stamps_s"], motor, mismatch.torque_scale, mismatch.latency_s
            ),
        },
    )
    return MismatchRun(run, spec, mass, motor)


def source_hash(spec: MismatchSpec | None = None) -> str:
    """16 hex digits of a hash of :data:`SOURCES`, PyBullet's API version and ``spec`` (its
    repr: None for what all runs share)."""
    digest = hashlib.sha256(str(pybullet.getAPIVersion()).encode())
    for name in SOURCES:
        digest.update((Path(__file__).parent / name).read_bytes())
    if spec is not None:
        digest.update(repr(spec).encode())
    return digest.hexdigest()[:16]


def _save(run: MismatchRun, path: Path) -> None:
    """``run`` as ``path`` (.npz, written to a temporary name and renamed)."""
    fields = {field.name: getattr(run.run, field.name) for field in dataclasses.fields(run.run)}
    fields["joint_names"] = np.array(run.run.joint_names)
    fields["foot_links"] = np.array(run.run.foot_links)
    fields["true_mass_kg"] = np.array(run.true_mass_kg)
    fields["motor_torques"] = run.motor_torques
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with temporary.open("wb") as file:
        np.savez_compressed(file, **fields)
    temporary.replace(path)


def _write(path: Path, text: str) -> None:
    """``text`` as ``path`` unless it exists (written to a temporary name and renamed)."""
    with _locked(path.with_suffix(".lock")):
        if not path.exists():
            temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            temporary.write_text(text, encoding="utf-8")
            temporary.replace(path)


_LOADED: dict[tuple[Path, str, str], MismatchRun] = {}


def mismatch_runs(
    names: tuple[str, ...] = tuple(SPECS_MISMATCH), cache_dir: Path = CACHE
) -> dict[str, MismatchRun]:
    """The clean runs ``names`` of :data:`SPECS_MISMATCH`, by name: read from
    ``cache_dir/NAME-HASH.npz`` (HASH: :func:`source_hash` of its spec) or simulated and saved
    there (with the nominal and mismatched descriptions), one lock per run; loaded once per
    process."""
    cache_dir = Path(cache_dir).resolve()
    cache_dir.mkdir(parents=True, exist_ok=True)
    digest = source_hash()
    go2_path = cache_dir / f"go2_like-{digest}.urdf"
    _write(go2_path, go2_urdf())
    out = {}
    for name in names:
        spec = SPECS_MISMATCH[name]
        key = (cache_dir, source_hash(spec), name)
        if key not in _LOADED:
            nominal = A1_URDF if SPECS[spec.base].robot == "a1" else go2_path
            path = cache_dir / f"{name}-{key[1]}.npz"
            with _locked(cache_dir / f"{name}.lock"):
                if not path.exists():
                    joints = A1_JOINTS if SPECS[spec.base].robot == "a1" else GO2_JOINTS
                    text = nominal.read_text(encoding="utf-8")
                    simulated = cache_dir / f"{name}-{key[1]}.urdf"
                    _write(simulated, mismatched_urdf(text, joints, spec.mismatch))
                    _save(simulate_mismatch(name, spec, nominal, simulated), path)
            run = replace(_load(path), urdf_path=str(nominal))
            with np.load(path, allow_pickle=False) as data:
                mass, motor = float(data["true_mass_kg"]), data["motor_torques"]
            _LOADED[key] = MismatchRun(run, spec, mass, motor)
        out[name] = _LOADED[key]
    return out


def main(argv: list[str]) -> int:
    """``mismatch_runs.py [OUT_DIR [NAME ...]]``: simulate (or load) the runs, print a table."""
    cache = Path(argv[0]) if argv else CACHE
    names = tuple(argv[1:]) or tuple(SPECS_MISMATCH)
    started = time.perf_counter()
    runs = mismatch_runs(names, cache)
    print_table({name: run.run for name, run in runs.items()})
    print(f"{len(runs)} runs in {time.perf_counter() - started:.1f} s (wall)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
