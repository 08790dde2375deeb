"""``a1-leg-fk gait`` on real recordings made by others, with the package of this checkout and with
another one (``--before``: a checkout of an older version), side by side: duty factors, stances per
stride and the blips the minimum-phase rule removed, per leg.

Run: ``.venv/bin/python bench/gait_real_clips.py [--before /path/to/older/checkout] [--keep
DIR]``. The inputs are read from pybullet_data at run time (none is in this repository):

- ``laikago/data1.txt``: a real Laikago's recorded joint angles (frame, time [ms], 12 angles; rows
  2-3 ms apart), mapped onto ``laikago/laikago_toes.urdf`` as pybullet_robots/laikago/laikago.py
  maps them (joint directions and offsets below, the URDF's joint order FR, FL, RR, RL, which its
  joint names and hip positions confirm). The file holds no base pose, so the angles are replayed
  as that script replays them (a plane, 500 Hz steps, position control, free base) and the
  replayed trunk's pose is the base pose; PyBullet's toe contacts in that replay are the
  reference (its spans without contact are printed). A second bag adds the replay's joint rates and
  torques and an IMU (the replayed trunk's), so ``gait`` takes the contact estimate's stance.
- ``data/motions/laikago_walk.txt``: a retargeted dog walk (DeepMimic's layout: per frame its
  duration [s], the base position [m] and quaternion (x, y, z, w: the other order puts the feet
  0.2-0.6 m above the ground), then the 12 angles as in data1.txt), looped with its own position
  offset per cycle. Three bags: the frames at their own 16 Hz; the frames interpolated to 500 Hz
  as pybullet's DeepMimic player does (linear, the orientation slerped); and the 500 Hz angles
  alone (the base held at the clip's first pose).

A clip's base pose is PyBullet's base, the trunk's centre of mass; the bag gets the URDF root's
pose. Each input becomes an MCAP bag (``/joint_states``, ``/base_pose`` PoseStamped in
``world``), and ``python -m a1_leg_fk.cli gait`` runs on it with ``PYTHONPATH`` set to each
checkout, default settings, ``--json``. Stances per stride is each leg's count of touchdowns over
the strides its span holds: the span (first to last observed touchdown) over the clip's stride,
its cycle over the dominant harmonic of its upper-leg angles (the clip's rhythm, not the gait
analysis's). ``--keep`` names a new folder for the bags and reports.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet
import pybullet_data
from common import ROOT  # first: it puts test/ (bag_factory) on the path

from a1_leg_fk.model.legs import LEG_NAMES

DATA = Path(pybullet_data.getDataPath())
LAIKAGO = DATA / "laikago" / "laikago_toes.urdf"
WALK = DATA / "data" / "motions" / "laikago_walk.txt"
DIRECTIONS = np.array([-1, 1, 1, 1, 1, 1, -1, 1, 1, 1, 1, 1], dtype=float)
"""laikago.py's joint directions: the recorded angle times this, plus the offset, is the URDF's."""
OFFSETS = np.tile([0.0, -0.7, 0.7], 4)
"""laikago.py's joint offsets [rad] per leg (hip, upper leg, lower leg)."""
REPLAY_FORCE_NM = 100.0
"""The replay's position-control torque bound [N m]: laikago.py's slider starts at 20, under which
the 25 kg replay sags and lags its angles; the angles are what the bag records."""
RATE_HZ = 500.0
SETTLE_S = 1.0
"""The replay holds the first row this long [s] before recording, to settle on the plane."""
LOOPS = 8


@dataclass
class Clip:
    """One input: stamps [s], the URDF's angles (N, 12) [rad], the root's poses (N, 3) [m] and
    (N, 4) quaternions x, y, z, w, and its stride period [s] (None: no gait cycle: standing)."""

    name: str
    urdf: Path
    stamps: np.ndarray
    angles: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    stride_s: float | None
    reference: str = ""
    efforts: np.ndarray | None = None  # (N, 12) [N m] with (N, 12) ``rates`` [rad/s]
    rates: np.ndarray | None = None
    imu: np.ndarray | None = None  # (N, 6): gyro [rad/s], specific force [m/s²], base frame


def body(urdf: Path, client: int) -> int:
    """The robot of ``urdf`` in ``client``, as the clips' players load it."""
    flags = pybullet.URDF_USE_SELF_COLLISION
    return pybullet.loadURDF(str(urdf), [0, 0, 0.5], [0, 0.5, 0.5, 0], flags=flags,
                             physicsClientId=client)  # fmt: skip


def to_root(
    urdf: Path, positions: np.ndarray, quaternions: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """PyBullet base (centre of mass) poses -> the URDF root's (positions, quaternions)."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        inertial = pybullet.getDynamicsInfo(body(urdf, client), -1, physicsClientId=client)[3:5]
        shift = pybullet.invertTransform(*inertial)
    finally:
        pybullet.disconnect(client)
    poses = [pybullet.multiplyTransforms(p, q, *shift) for p, q in zip(positions, quaternions)]
    return np.array([p for p, _ in poses]), np.array([q for _, q in poses])


def revolute(robot: int, client: int) -> list[int]:
    """The robot's revolute joints in URDF order."""
    count = pybullet.getNumJoints(robot, physicsClientId=client)
    info = [pybullet.getJointInfo(robot, j, physicsClientId=client) for j in range(count)]
    return [j for j in range(count) if info[j][2] == pybullet.JOINT_REVOLUTE]


def laikago_data1() -> list[Clip]:
    """The real Laikago's angles, replayed in PyBullet for a base pose (see the module doc): the
    angles alone, and with the replay's joint rates, torques and an IMU."""
    rows = np.loadtxt(DATA / "laikago" / "data1.txt", delimiter=",")
    stamps, angles = (rows[:, 1] - rows[0, 1]) * 1e-3, rows[:, 2:14] * DIRECTIONS + OFFSETS
    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.setAdditionalSearchPath(str(DATA), physicsClientId=client)
        pybullet.loadURDF("plane.urdf", physicsClientId=client)
        pybullet.setGravity(0, 0, -9.8, physicsClientId=client)
        pybullet.setTimeStep(1.0 / RATE_HZ, physicsClientId=client)
        robot = body(LAIKAGO, client)
        joints = revolute(robot, client)
        toes = [j + 1 for j in joints[2::3]]  # each lower leg's fixed toe

        def step(row: np.ndarray) -> None:
            pybullet.setJointMotorControlArray(robot, joints, pybullet.POSITION_CONTROL, row,
                                               forces=[REPLAY_FORCE_NM] * 12,
                                               physicsClientId=client)  # fmt: skip
            pybullet.stepSimulation(physicsClientId=client)

        for _ in range(round(SETTLE_S * RATE_HZ)):  # dropped from the spawn pose onto the plane
            step(angles[0])
        positions, quaternions, contact, states, spins = [], [], [], [], []
        for row in angles:
            step(row)
            states.append(pybullet.getJointStates(robot, joints, physicsClientId=client))
            spins.append(pybullet.getBaseVelocity(robot, physicsClientId=client)[1])
            where, turned = pybullet.getBasePositionAndOrientation(robot, physicsClientId=client)
            positions.append(where)
            quaternions.append(turned)
            contact.append([bool(pybullet.getContactPoints(robot, -1, toe, -1,
                                                           physicsClientId=client))
                            for toe in toes])  # fmt: skip
    finally:
        pybullet.disconnect(client)
    root, turned = to_root(LAIKAGO, np.array(positions), np.array(quaternions))
    reference = "replay's toe swings: " + "; ".join(
        f"{leg} {swings(stamps, np.array(contact)[:, slot])}" for slot, leg in enumerate(LEG_NAMES)
    )
    standing = Clip("laikago data1 (replayed base)", LAIKAGO, stamps, angles, root, turned, None,
                    reference)  # fmt: skip
    rates = np.array([[state[1] for state in row] for row in states])
    efforts = np.array([[state[3] for state in row] for row in states])
    with_efforts = Clip(f"{standing.name} + replay's efforts and IMU", LAIKAGO, stamps, angles,
                        root, turned, None, reference, efforts, rates,
                        imu_of(stamps, root, turned, np.array(spins)))  # fmt: skip
    return [standing, with_efforts]


def swings(stamps: np.ndarray, contact: np.ndarray) -> str:
    """The spans [s] without contact in (N,) ``contact``, e.g. ``4.110-4.164``."""
    edges = np.flatnonzero(np.diff(np.concatenate(([1], contact.astype(np.int8), [1]))))
    spans = [f"{stamps[a]:.3f}-{stamps[b - 1]:.3f}" for a, b in zip(edges[::2], edges[1::2])]
    return ", ".join(spans) or "none"


def imu_of(
    stamps: np.ndarray, root: np.ndarray, turned: np.ndarray, spin: np.ndarray
) -> np.ndarray:
    """(N, 6) an IMU at the root, base frame: the gyro (``spin`` (N, 3) [rad/s], world) and the
    specific force R^T (a - g), ``a`` the root's acceleration by central differences [m/s²]."""
    rotations = np.array([pybullet.getMatrixFromQuaternion(q) for q in turned]).reshape(-1, 3, 3)
    velocity = np.gradient(root, stamps, axis=0)
    acceleration = np.gradient(velocity, stamps, axis=0) - np.array([0.0, 0.0, -9.8])
    gyro = np.einsum("nji,nj->ni", rotations, spin)
    return np.hstack([gyro, np.einsum("nji,nj->ni", rotations, acceleration)])


def looped(frames: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """``LOOPS`` cycles of a wrapping clip (its last frame is the next cycle's first): stamps [s],
    positions (shifted by the clip's offset each cycle), quaternions, angles (as in the file)."""
    cycle = frames[:-1]
    offset = frames[-1, 0:3] - frames[0, 0:3]
    offset[2] = 0.0
    positions = np.concatenate([cycle[:, 0:3] + k * offset for k in range(LOOPS)])
    quaternions = np.tile(cycle[:, 3:7], (LOOPS, 1))
    angles = np.tile(cycle[:, 7:19], (LOOPS, 1))
    return np.arange(len(positions)) * dt, positions, quaternions, angles


def slerp(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(N, 4) quaternions between rows ``a`` and ``b`` at fractions ``f`` (N,)."""
    dot = np.sum(a * b, axis=1)
    b = np.where(dot[:, None] < 0, -b, b)
    angle = np.arccos(np.clip(np.abs(dot), -1.0, 1.0))[:, None]
    small = angle < 1e-9
    sin = np.where(small, 1.0, np.sin(angle))
    wa = np.where(small, 1 - f[:, None], np.sin((1 - f[:, None]) * angle) / sin)
    wb = np.where(small, f[:, None], np.sin(f[:, None] * angle) / sin)
    return wa * a + wb * b


def resampled(stamps: np.ndarray, *series: np.ndarray) -> tuple[np.ndarray, ...]:
    """``series`` (positions, quaternions, angles) at ``RATE_HZ``: linear, quaternions slerped."""
    fine = np.arange(0.0, stamps[-1], 1.0 / RATE_HZ)
    k = np.minimum(np.searchsorted(stamps, fine, side="right") - 1, stamps.size - 2)
    f = (fine - stamps[k]) / (stamps[k + 1] - stamps[k])
    positions, quaternions, angles = series
    return (
        fine,
        positions[k] + f[:, None] * (positions[k + 1] - positions[k]),
        slerp(quaternions[k], quaternions[k + 1], f),
        angles[k] + f[:, None] * (angles[k + 1] - angles[k]),
    )


def strides_per_cycle(angles: np.ndarray) -> int:
    """The strides in one cycle of a looping clip's (n, 12) angles: the dominant harmonic of the
    upper legs' angles (the clip's own rhythm, not the gait analysis's)."""
    thighs = angles[:, 1::3] - angles[:, 1::3].mean(axis=0)
    return int(np.argmax(np.abs(np.fft.rfft(thighs, axis=0)).sum(axis=1)[1:])) + 1


def laikago_walk() -> list[Clip]:
    """The looping walk: at its own rate, at ``RATE_HZ``, and the angles alone."""
    raw = np.array(json.loads(WALK.read_text())["Frames"], dtype=float)
    dt, frames = float(raw[0, 0]), raw[:, 1:20]  # DeepMimic: each frame starts with its duration
    stamps, positions, quaternions, angles = looped(frames, dt)
    angles = angles * DIRECTIONS + OFFSETS
    stride = dt * (len(frames) - 1) / strides_per_cycle(frames[:-1, 7:19])
    name, urdf = "laikago_walk", LAIKAGO
    out = [Clip(f"{name} {1 / dt:.0f} Hz", urdf, stamps, angles,
                *to_root(urdf, positions, quaternions), stride)]  # fmt: skip
    fine = resampled(stamps, positions, quaternions, angles)
    root = to_root(urdf, fine[1], fine[2])
    out.append(Clip(f"{name} {RATE_HZ:.0f} Hz", urdf, fine[0], fine[3], *root, stride))
    held = (np.repeat(root[0][:1], fine[0].size, 0), np.repeat(root[1][:1], fine[0].size, 0))
    out.append(Clip(f"{name} {RATE_HZ:.0f} Hz, angles alone", urdf, fine[0], fine[3], *held,
                    stride))  # fmt: skip
    return out


def joint_names(urdf: Path) -> list[str]:
    """The revolute joints' names in URDF order (FR, FL, RR, RL x 3 in laikago_toes)."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        robot = pybullet.loadURDF(str(urdf), physicsClientId=client)
        return [pybullet.getJointInfo(robot, j, physicsClientId=client)[1].decode()
                for j in revolute(robot, client)]  # fmt: skip
    finally:
        pybullet.disconnect(client)


def write(clip: Clip, path: Path) -> Path:
    """The clip as an MCAP bag: ``/joint_states`` and ``/base_pose`` at every stamp."""
    from bag_factory import BagSpec, JointStateMsg, write_bag

    spec, names, t0 = BagSpec(), joint_names(clip.urdf), 1_700_000_000_000_000_000
    poses = zip(clip.stamps, clip.angles, clip.positions, clip.quaternions)
    for row, (stamp, angles, where, turned) in enumerate(poses):
        ns = t0 + round(stamp * 1e9)
        message = JointStateMsg(ns, names, angles.tolist())
        if clip.efforts is not None and clip.rates is not None:
            message.velocities = clip.rates[row].tolist()
            message.efforts = clip.efforts[row].tolist()
        spec.add_joint_state("/joint_states", ns, message)
        if clip.imu is not None:
            spec.add("/imu", "sensor_msgs/msg/Imu", ns, imu_message(ns, turned, clip.imu[row]))
        base = spec_pose(ns, where, turned)
        spec.add("/base_pose", "geometry_msgs/msg/PoseStamped", ns, base)
    return write_bag(path, spec)


def spec_pose(stamp_ns: int, where: np.ndarray, turned: np.ndarray) -> object:
    """A PoseStamped in ``world``."""
    from bag_factory import T, header, pose

    return T["geometry_msgs/msg/PoseStamped"](
        header(stamp_ns, "world"), pose(where.tolist(), turned.tolist())
    )


def imu_message(stamp_ns: int, turned: np.ndarray, imu: np.ndarray) -> object:
    """A sensor_msgs/Imu in ``base``: orientation (x, y, z, w), gyro, specific force."""
    from bag_factory import T, header

    vector, covariance = T["geometry_msgs/msg/Vector3"], np.zeros(9)
    return T["sensor_msgs/msg/Imu"](header(stamp_ns, "base"),
                                    T["geometry_msgs/msg/Quaternion"](*turned), covariance,
                                    vector(*imu[:3]), covariance, vector(*imu[3:]),
                                    covariance)  # fmt: skip


def gait(bag: Path, clip: Clip, checkout: Path, out: Path) -> dict:
    """``a1-leg-fk gait``'s JSON report on ``bag`` with the package of ``checkout``."""
    feet = [f"{leg}=toe{leg}" for leg in LEG_NAMES]
    command = [sys.executable, "-m", "a1_leg_fk.cli", "gait", str(bag), "--urdf", str(clip.urdf),
               "--base-pose", "/base_pose", "--json", str(out), "--quiet", "--force",
               "--foot-links", *feet,
               *(["--imu", "/imu"] if clip.imu is not None else [])]  # fmt: skip
    environment = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run(  # cwd: not this checkout, which python -m would put first on the path
        command, env=environment, cwd=out.parent, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise SystemExit(f"{checkout}: gait failed on {clip.name}: {done.stderr.strip()}")
    return json.loads(out.read_text())


def leg_cells(report: dict, clip: Clip) -> list[str]:
    """Per leg: duty, stances per stride (when the clip has a cycle), blips -dropped/+bridged."""
    cells = []
    for leg in LEG_NAMES:
        metrics = report["legs"][leg]
        duty = metrics["duty_factor"]
        text = "-" if duty is None else f"{duty:.3f}"
        ons = [a for a, _ in metrics["stance_s"]][1:]  # the first may be cut by the start
        if clip.stride_s and len(ons) > 1:
            text += f" {(len(ons) - 1) / ((ons[-1] - ons[0]) / clip.stride_s):.2f}/str"
        if "blips_dropped" in metrics:
            text += f" -{metrics['blips_dropped']}/+{metrics['blips_bridged']}"
        if metrics["status"] != "ok":
            text += f" ({metrics['status']})"
        cells.append(text)
    return cells


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, help="an older checkout to compare with")
    parser.add_argument("--keep", type=Path, help="write the bags and reports here")
    options = parser.parse_args()
    if options.keep is not None and options.keep.exists():
        parser.error(f"--keep {options.keep}: exists already")
    clips = [*laikago_data1(), *laikago_walk()]
    checkouts = {"after": ROOT, **({"before": options.before} if options.before else {})}
    with tempfile.TemporaryDirectory() as scratch:
        folder = options.keep or Path(scratch)
        folder.mkdir(exist_ok=folder == Path(scratch))
        for number, clip in enumerate(clips):
            bag = write(clip, folder / f"clip{number}")
            stride = f", stride {clip.stride_s:.3f} s" if clip.stride_s else ""
            print(f"{clip.name}: {clip.stamps.size} rows, {clip.stamps[-1]:.2f} s{stride}"
                  + (f"; {clip.reference}" if clip.reference else ""))  # fmt: skip
            for label, checkout in checkouts.items():
                report = gait(bag, clip, checkout, folder / f"clip{number}-{label}.json")
                cells = "  ".join(
                    f"{leg} {cell}" for leg, cell in zip(LEG_NAMES, leg_cells(report, clip))
                )
                print(f"  {label:6s} {report['gait']:8s} {cells}")


if __name__ == "__main__":
    main()
