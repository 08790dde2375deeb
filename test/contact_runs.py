"""A family of PyBullet runs that judge a contact estimator: an A1 and a Go2-like robot trotting,
turning, walking, pronking, on rigid and on soft ground, with every sensor a robot has.

Independent of the code under test (no a1_leg_fk import): this is the judge. Each run settles
for :data:`SETTLE_S`, then walks a gait of :mod:`contact_gaits` for its ``gait_s``, at a 500 Hz
physics step with a sample after every step (:class:`ContactRun`). The dynamics are those the
estimator models: no link or joint damping (the base's too), no joint friction, every link with
an ``<inertial>`` whose inertia tensor PyBullet uses (``URDF_USE_INERTIA_FROM_FILE``), and PD
torque motors (:class:`contact_gaits.Motors`, ``QuadrupedSim.step_pd``: compliant, as a Unitree
robot's) whose torque, applied over the step, is the effort. Truth is the plane's normal force on
each foot; a foot is in contact when it is positive.

:func:`contact_runs` simulates the family once per machine (cached as ``.npz``, named after a hash
of the generators' source) and :func:`with_noise` adds a robot's sensor errors.
``python test/contact_runs.py OUT_DIR`` generates every run and prints a table of them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import hashlib
import math
import os
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pybullet
from contact_gaits import (
    A1_LEGS,
    GO2_FEET,
    GO2_JOINTS,
    GO2_LEGS,
    LONG_SPECS,
    SPECS,
    Legs,
    Pose,
    RunSpec,
    Slips,
    Targets,
    gait_targets,
    go2_urdf,
)
from pybullet_sim import A1_FEET, A1_JOINTS, A1_URDF, GRAVITY, STEP_S, QuadrupedSim
from sensor_noise import with_noise  # noqa: F401 (the family's noise, re-exported)

SETTLE_S = 0.5
"""Standing still before the gait [s]."""
PLANE_FRICTION = 1.0
"""PyBullet's plane.urdf lateral friction (restored after an ice patch)."""
SOFT_TOES = {"contactStiffness": 3.0e4, "contactDamping": 3.0e2}
"""[N/m], [N s/m]: the soft feet of ``a1_trot_soft`` (PyBullet's default contact is rigid)."""
UP = np.array([0.0, 0.0, 1.0])
"""World up."""
BLIP_S = 0.02
"""[s]: a shorter swing is a blip (a foot bouncing for a step or two at touchdown), not a step."""
ALL_SPECS = {**SPECS, **LONG_SPECS}
"""Every run this module makes: the contact family and the odometry's long runs."""
SOURCES = ("contact_runs.py", "contact_gaits.py", "pybullet_sim.py", "exported_urdf.py")
"""The files whose text names the cache (changed code regenerates)."""


@dataclass(frozen=True)
class ContactRun:
    """One simulated run, N samples (one after every physics step). World frame: the plane's, z up.
    The base is the URDF root link's origin (not PyBullet's centre-of-mass frame); its frame is the
    IMU's. Legs and feet in the order FR, FL, RR, RL. At a touchdown a foot may bounce: its contact
    is then false for a step or few (shorter than :data:`BLIP_S`), as its normal force is 0.
    """

    name: str
    robot: str  # "a1" or "go2"
    urdf_text: str  # the description the estimator loads (what PyBullet simulated)
    urdf_path: str  # the same, as a file: pybullet_data's a1/a1.urdf or the Go2-like file written
    joint_names: tuple[str, ...]  # 12: FR, FL, RR, RL × hip, thigh, calf
    foot_links: tuple[str, ...]  # 4
    gait_start_s: float  # when the gait proper begins (the settling before it is not scored)
    duty: float  # the gait's commanded duty factor (fraction of a cycle a foot stands)
    simulate_s: float  # wall time it took to simulate [s]
    stamps_s: np.ndarray  # (N,) simulated time after the step [s]
    angles: np.ndarray  # (N, 12) joint angles [rad]
    rates: np.ndarray  # (N, 12) joint velocities [rad/s]
    torques: np.ndarray  # (N, 12) the PD motors' torques [N m] over the step, as efforts
    quaternions: np.ndarray  # (N, 4) root orientation x, y, z, w: the IMU's orientation
    gyro: np.ndarray  # (N, 3) angular velocity [rad/s], root frame
    specific_force: np.ndarray  # (N, 3) [m/s^2] root frame: Rᵀ (a - g), see simulate_run
    normal_forces: np.ndarray  # (N, 4) the plane's normal force on each foot [N], >= 0
    contacts: np.ndarray  # (N, 4) bool: normal_forces > 0, the truth
    base_positions: np.ndarray  # (N, 3) root origin [m], world
    base_velocities: np.ndarray  # (N, 3) root origin's velocity [m/s], world
    other_contacts: np.ndarray  # (N,) bool: a link other than a foot touches the plane

    @property
    def gait(self) -> np.ndarray:
        """(N,) bool: the samples of the gait proper (scored), after the settling."""
        result: np.ndarray = self.stamps_s >= self.gait_start_s
        return result


ARRAYS = tuple(
    field.name for field in dataclasses.fields(ContactRun) if field.type == "np.ndarray"
)


def targets_and_rates(
    targets: Targets, t: float, pose: Pose | None, h: float = 1e-4
) -> tuple[list[float], list[float]]:
    """The motors' targets at ``t`` [rad] (``targets(t, pose)``, summed) and their rates [rad/s]:
    those of the planned feet's angles (central difference over ±``h`` [s], at a fixed pose; the
    loading offsets are forces, not motion).
    """
    rates = (targets(t + h, pose)[0] - targets(t - h, pose)[0]) / (2.0 * h)
    angles, offsets = targets(t, pose)
    return (angles + offsets).tolist(), rates.tolist()


def simulate_run(name: str, spec: RunSpec, urdf_path: Path) -> ContactRun:
    """Simulate one run of :data:`SPECS` with the description at ``urdf_path``.

    The robot is placed standing (the gait's nominal feet) 2 mm above the plane, at rest. Each
    step, the PD motors get the targets of the step's end and their rates (the gait's legs loaded
    for the robot's weight and the motors' kp); the gait sees the trunk's pose (roll, pitch,
    height, the gyro's roll and pitch rates) after the previous step. The
    specific force is R_kᵀ ((v_k - v_(k-1)) / dt - g_world), g_world = (0, 0, -9.81) m/s^2: the
    backward difference of the root origin's world velocity over the step that ends at sample k
    (v before the first step: 0), rotated into the root frame at sample k.
    """
    legs: Legs = A1_LEGS if spec.robot == "a1" else GO2_LEGS
    joints, feet = (A1_JOINTS, A1_FEET) if spec.robot == "a1" else (GO2_JOINTS, GO2_FEET)
    started = time.perf_counter()
    rows: dict[str, list[np.ndarray]] = {key: [] for key in ARRAYS}
    with QuadrupedSim(urdf_path, joints, feet, STEP_S, inertia_from_file=True) as sim:
        pb = {"physicsClientId": sim.client}
        links = range(-1, pybullet.getNumJoints(sim.body, **pb))
        mass = sum(pybullet.getDynamicsInfo(sim.body, link, **pb)[0] for link in links)
        targets = gait_targets(legs, spec.gait, SETTLE_S, mass * GRAVITY, spec.motors.kp)
        pybullet.changeDynamics(sim.body, -1, linearDamping=0, angularDamping=0, **pb)
        if spec.soft:
            for foot in sim.feet:
                pybullet.changeDynamics(sim.body, foot, **SOFT_TOES, **pb)
        height = spec.gait.height_m + legs.foot_radius_m + 0.002
        sim.place([0.0, 0.0, height], [0.0, 0.0, 0.0, 1.0], targets(0.0, None)[0].tolist())
        velocity = np.zeros(3)
        slot = {link: index for index, link in enumerate(sim.feet)}
        pose: Pose | None = None
        slipping = 0
        for _ in range(round((SETTLE_S + spec.gait_s) / STEP_S)):
            if spec.slips is not None:
                slipping = _slip(sim, spec.slips, slipping, mass * GRAVITY)
            goal, goal_rates = targets_and_rates(targets, sim.time_s + STEP_S, pose)
            motors = spec.motors
            sample = sim.step_pd(goal, (motors.kp, motors.kd), motors.max_torque_nm, goal_rates)
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
                ("torques", sample.torques),
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
    return ContactRun(
        name=name,
        robot=spec.robot,
        urdf_text=Path(urdf_path).read_text(encoding="utf-8"),
        urdf_path=str(urdf_path),
        joint_names=tuple(joints),
        foot_links=tuple(feet),
        gait_start_s=SETTLE_S,
        duty=spec.gait.duty,
        simulate_s=time.perf_counter() - started,
        **{key: np.array(values) for key, values in rows.items()},
    )


def _slip(sim: QuadrupedSim, slips: Slips, was: int, weight_n: float) -> int:
    """Ice and a push for the coming step when ``slips`` says so (friction restored after)."""
    pb = {"physicsClientId": sim.client}
    side = slips.active(sim.time_s - SETTLE_S)
    if side != was:
        friction = slips.friction if side else PLANE_FRICTION
        pybullet.changeDynamics(
            sim.plane, -1, lateralFriction=friction, frictionAnchor=int(not side), **pb
        )
    if side:
        yaw = pybullet.getEulerFromQuaternion(
            pybullet.getBasePositionAndOrientation(sim.body, **pb)[1]
        )[2]
        push = side * slips.push_g * weight_n
        sim.push([-math.sin(yaw) * push, math.cos(yaw) * push, 0.0])
    return side


def source_hash() -> str:
    """16 hex digits of a hash of :data:`SOURCES` and PyBullet's API version."""
    digest = hashlib.sha256(str(pybullet.getAPIVersion()).encode())
    for name in SOURCES:
        digest.update((Path(__file__).parent / name).read_bytes())
    return digest.hexdigest()[:16]


def _save(run: ContactRun, path: Path) -> None:
    """``run`` as ``path`` (.npz, written to a temporary name and renamed: never half-written)."""
    fields = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    fields["joint_names"] = np.array(run.joint_names)
    fields["foot_links"] = np.array(run.foot_links)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with temporary.open("wb") as file:
        np.savez_compressed(file, **fields)
    temporary.replace(path)


def _load(path: Path) -> ContactRun:
    """The run saved as ``path``."""
    with np.load(path, allow_pickle=False) as data:
        values = {key: data[key] for key in data.files}
    return ContactRun(
        name=str(values["name"]),
        robot=str(values["robot"]),
        urdf_text=str(values["urdf_text"]),
        urdf_path=str(values["urdf_path"]),
        joint_names=tuple(str(name) for name in values["joint_names"]),
        foot_links=tuple(str(name) for name in values["foot_links"]),
        gait_start_s=float(values["gait_start_s"]),
        duty=float(values["duty"]),
        simulate_s=float(values["simulate_s"]),
        **{key: values[key] for key in ARRAYS},
    )


_LOADED: dict[tuple[Path, str], dict[str, ContactRun]] = {}


def contact_runs(cache_dir: Path, names: tuple[str, ...] = tuple(SPECS)) -> dict[str, ContactRun]:
    """The clean runs ``names`` (default: all of :data:`SPECS`; any of :data:`ALL_SPECS`), by name.

    Each is read from ``cache_dir/NAME-HASH.npz`` (HASH: :func:`source_hash`), or simulated and
    saved there; the Go2-like description is written there too. A lock file per run in
    ``cache_dir`` keeps concurrent callers (two sessions, the workers of
    :func:`simulate_missing`) from simulating one run twice; within a process the runs are loaded
    once.
    """
    cache_dir = Path(cache_dir).resolve()
    cache_dir.mkdir(parents=True, exist_ok=True)
    digest = source_hash()
    loaded = _LOADED.setdefault((cache_dir, digest), {})
    missing = [name for name in names if name not in loaded]
    if missing:
        go2_path = cache_dir / f"go2_like-{digest}.urdf"
        with _locked(cache_dir / "go2_like.lock"):
            if not go2_path.exists():
                temporary = go2_path.with_name(f".{go2_path.name}.{os.getpid()}.tmp")
                temporary.write_text(go2_urdf(), encoding="utf-8")
                temporary.replace(go2_path)
        for name in missing:
            path = cache_dir / f"{name}-{digest}.npz"
            with _locked(cache_dir / f"{name}.lock"):
                if not path.exists():
                    spec = ALL_SPECS[name]
                    urdf = A1_URDF if spec.robot == "a1" else go2_path
                    _save(simulate_run(name, spec, urdf), path)
            run = _load(path)  # the Go2-like file in this folder, wherever it was written
            loaded[name] = run if run.robot == "a1" else replace(run, urdf_path=str(go2_path))
    return {name: loaded[name] for name in names}


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on the file ``path`` (created if needed)."""
    with path.open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


def _simulate_one(cache_dir: Path, name: str) -> None:
    """A worker of :func:`simulate_missing`: run ``name`` into the cache."""
    contact_runs(cache_dir, (name,))


def simulate_missing(cache_dir: Path, names: tuple[str, ...], workers: int = 2) -> None:
    """Simulate the runs ``names`` missing from ``cache_dir``, ``workers`` at a time (one per core:
    the long runs take minutes each)."""
    digest = source_hash()
    missing = [n for n in names if not (Path(cache_dir) / f"{n}-{digest}.npz").exists()]
    if len(missing) > 1 and workers > 1:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            list(pool.map(_simulate_one, [Path(cache_dir)] * len(missing), missing))


def swing_durations(contacts: np.ndarray, step_s: float = STEP_S) -> np.ndarray:
    """Durations [s] of every complete swing (contact false between two contacts) in (N, F)."""
    durations: list[float] = []
    for foot in np.asarray(contacts, dtype=bool).T:
        lifts = np.flatnonzero(foot[:-1] & ~foot[1:])
        touches = np.flatnonzero(~foot[:-1] & foot[1:])
        ends = [touches[touches > lift] for lift in lifts]
        durations += [(end[0] - lift) * step_s for lift, end in zip(lifts, ends) if end.size]
    return np.array(durations)


def roll_pitch(quaternions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch [rad] (fixed-axis x, y, z convention) of (N, 4) x, y, z, w quaternions."""
    x, y, z, w = np.asarray(quaternions, dtype=float).T
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    return roll, np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))


def summary(run: ContactRun) -> dict[str, float | str]:
    """The gait's figures: duration [s], true duty per foot, median swing [s] (of those of at
    least :data:`BLIP_S`), blips (shorter swings: a foot bouncing at touchdown), peak joint rate
    [rad/s], flight fraction (no foot in contact), max |roll| and |pitch| [rad], mean forward
    speed [m/s] (along the root's x), other-contact fraction, simulation wall time [s].
    """
    gait = run.gait
    contacts = run.contacts[gait]
    roll, pitch = roll_pitch(run.quaternions[gait])
    x, y, z, w = run.quaternions[gait].T
    heading = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)], 1)
    forward = np.einsum("ni,ni->n", heading, run.base_velocities[gait])
    swings = swing_durations(contacts)
    blips = int((swings < BLIP_S).sum())
    swings = swings[swings >= BLIP_S]
    duty = contacts.mean(axis=0)
    return {
        "run": run.name,
        "gait_s": float(run.stamps_s[gait][-1] - run.gait_start_s),
        "duty": " ".join(f"{value:.2f}" for value in duty),
        "swing_s": float(np.median(swings)) if len(swings) else math.nan,
        "rate": float(np.abs(run.rates[gait]).max()),
        "flight": float((~contacts.any(axis=1)).mean()),
        "roll": float(np.abs(roll).max()),
        "pitch": float(np.abs(pitch).max()),
        "speed": float(forward.mean()),
        "blips": blips,
        "other": float(run.other_contacts[gait].mean()),
        "wall_s": run.simulate_s,
    }


def print_table(runs: dict[str, ContactRun]) -> None:
    """One line of :func:`summary` per run."""
    header = (
        f"{'run':<14} {'gait_s':>6} {'duty FR FL RR RL':>19} {'swing_s':>7} {'blips':>5} "
        f"{'rate':>5} {'flight':>6} {'roll':>5} {'pitch':>5} {'speed':>5} {'other':>5} "
        f"{'wall_s':>6}"
    )
    print(header)
    for run in runs.values():
        row = summary(run)
        print(
            f"{row['run']:<14} {row['gait_s']:6.2f} {row['duty']:>19} {row['swing_s']:7.3f} "
            f"{row['blips']:5d} {row['rate']:5.1f} {row['flight']:6.3f} {row['roll']:5.3f} "
            f"{row['pitch']:5.3f} {row['speed']:5.2f} {row['other']:5.3f} {row['wall_s']:6.1f}"
        )


def main(argv: list[str]) -> int:
    """``contact_runs.py OUT_DIR [NAME ...]``: generate (or load) the runs, print the table."""
    if not argv:
        print("usage: contact_runs.py OUT_DIR [NAME ...]", file=sys.stderr)
        return 2
    names = tuple(argv[1:]) or tuple(SPECS)
    started = time.perf_counter()
    runs = contact_runs(Path(argv[0]), names)
    print_table(runs)
    print(f"{len(runs)} runs in {time.perf_counter() - started:.1f} s (wall)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
