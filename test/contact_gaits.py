"""The contact runs' robots and gaits (:mod:`contact_runs`): the Go2-like description
(:func:`go2_urdf`), feet planned in the root frame, joint targets from a closed-form inverse
kinematics of a Unitree-style leg, and the family's parameters (:data:`SPECS`).

Independent of the code under test (no a1_leg_fk import). Root frame: x forward, y left, z up,
origin at the URDF root; legs in the order FR, FL, RR, RL, joints hip roll (about x), thigh and
calf pitch (about y) per leg. Angles in radians, lengths in metres, times in seconds.

A gait is periodic: each leg swings for the fraction ``1 - duty`` of the cycle from its offset
and stands for the rest. A stance foot moves against the commanded body motion (forward speed,
yaw rate) at constant speed; a swing foot goes back to the front along a smooth arc and lands at
the stance feet's speed. The walk moves the trunk over the support triangle before each swing
(:attr:`Gait.shift`); the pronk's stance legs push harder (:attr:`Gait.thrust`) so that the
robot leaves the ground.

The motors are compliant PD torque motors (:class:`Motors`): a leg sinks under its load. So each
leg's targets carry its planned share of the weight as an offset (what a feedforward torque
would do: :func:`gait_targets`), shared about the centre of mass with a feedback on the trunk's
attitude (:func:`support_forces`), from shortly before its touchdown (a foot landing early stays
down) to its liftoff (:func:`stance_load`). A swing foot is planned relative to the ground,
given the trunk's measured pose, to land when planned; the robot's centre of mass is put over
the feet's centre (:attr:`Gait.feet_offset_m`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from xml.etree import ElementTree

import numpy as np
from exported_urdf import exported_quadruped

END = (1.0, 1.0, -1.0, -1.0)
"""Per leg (FR, FL, RR, RL): +1 front, -1 rear."""
SIDE = (-1.0, 1.0, -1.0, 1.0)
"""Per leg: +1 left, -1 right."""


@dataclass(frozen=True)
class Legs:
    """A Unitree-style leg set [m]: hip roll joints at (±hip_x, ±hip_y, 0) in the root frame, the
    thigh joint ``thigh_y`` outwards of the hip, thigh and calf pointing down at zero angles, the
    foot at the calf's end; its contact sphere, ``foot_radius_m``, centred ``foot_x`` along the
    calf frame's x from it. The feet here are those spheres' centres.
    """

    hip_x: float
    hip_y: float
    thigh_y: float
    thigh_m: float
    calf_m: float
    foot_radius_m: float
    foot_x: float = 0.0

    def hip(self, leg: int) -> np.ndarray:
        """The hip roll joint of ``leg`` [m], root frame."""
        return np.array([END[leg] * self.hip_x, SIDE[leg] * self.hip_y, 0.0])

    def below_thigh(self, leg: int, height_m: float) -> np.ndarray:
        """The foot of ``leg`` [m, root frame] ``height_m`` straight below its thigh joint."""
        return self.hip(leg) + np.array([0.0, SIDE[leg] * self.thigh_y, -height_m])

    def ik(self, leg: int, foot: np.ndarray) -> tuple[float, float, float]:
        """Hip roll, thigh, calf [rad] (knee bent backwards: calf < 0) that put the foot of ``leg``
        at ``foot`` [m, root frame]; out-of-reach feet are clipped to the nearest reachable one.
        """
        x, y, z = foot - self.hip(leg)
        offset = SIDE[leg] * self.thigh_y
        reach = math.sqrt(max(y * y + z * z - offset * offset, 1e-9))
        roll = math.atan2(z, y) - math.atan2(-reach, offset)
        # the sphere's centre: a calf of length hypot(foot_x, calf_m), turned by `bend`
        calf_m, bend = math.hypot(self.foot_x, self.calf_m), math.atan2(self.foot_x, self.calf_m)
        cosine = (x * x + reach * reach - self.thigh_m**2 - calf_m**2) / (
            2.0 * self.thigh_m * calf_m
        )
        calf = -math.acos(min(1.0, max(-1.0, cosine)))
        along = self.thigh_m + calf_m * math.cos(calf)
        across = calf_m * math.sin(calf)
        thigh = math.atan2(-x, reach) - math.atan2(across, along)
        return roll, thigh, calf + bend

    def lift_row(self, leg: int, angles: np.ndarray) -> np.ndarray:
        """d(foot z)/d(angles) of ``leg`` [m/rad, root frame] at ``angles`` (hip roll, thigh,
        calf [rad]): the z row of the Jacobian of the forward kinematics :meth:`ik` inverts.
        """
        roll, thigh, calf = angles
        calf_m = math.hypot(self.foot_x, self.calf_m)
        knee = thigh + calf - math.atan2(self.foot_x, self.calf_m)
        x = -(self.thigh_m * math.sin(thigh) + calf_m * math.sin(knee))
        down = -(self.thigh_m * math.cos(thigh) + calf_m * math.cos(knee))  # z in the roll frame
        cr, sr = math.cos(roll), math.sin(roll)
        # foot z = offset sin(roll) + down cos(roll); d(down)/d(thigh, calf) = (-x, knee's part)
        across = SIDE[leg] * self.thigh_y * cr - down * sr
        return np.array([across, -x * cr, calf_m * math.sin(knee) * cr])


A1_LEGS = Legs(0.183, 0.047, 0.08505, 0.2, 0.2, 0.02)
"""pybullet_data's A1 (a1/a1.urdf)."""
GO2_LEGS = Legs(0.1934, 0.0465, 0.0955, 0.213, 0.213, 0.022, -0.002)
"""The Go2-like description (:func:`go2_urdf`)."""


GO2_JOINTS = tuple(
    f"{leg}_{part}_joint" for leg in ("FR", "FL", "RR", "RL") for part in ("hip", "thigh", "calf")
)
GO2_FEET = ("FR_foot", "FL_foot", "RR_foot", "RL_foot")
"""The Go2-like robot's joints (FR, FL, RR, RL × hip, thigh, calf) and feet."""
GO2_FOOT_SPHERE = ("0.022", "-0.002 0 0")
"""Radius and centre [m, foot frame] of the Go2's foot spheres (as test_foot_forces' go2_like)."""
GO2_BASE_INERTIA = ("0.025", "0.098", "0.107")
"""Ixx, Iyy, Izz [kg m^2] of the Go2-like trunk: the order of the real Go2's."""


def go2_urdf() -> str:
    """The Go2-like description (exported_urdf's, primitives only): the Go2's foot spheres, a
    trunk inertia of the Go2's order (:data:`GO2_BASE_INERTIA`) and the shin links, collision-only
    in the export, given 5 g each (PyBullet gives a link without ``<inertial>`` 1 kg).
    """
    robot = ElementTree.fromstring(exported_quadruped("go2", meshes=False, shin_links=True))
    for link in robot.iter("link"):
        name = link.get("name", "")
        if name.endswith("_foot"):
            origin, sphere = link.find("collision/origin"), link.find("collision/geometry/sphere")
            assert origin is not None and sphere is not None
            origin.set("xyz", GO2_FOOT_SPHERE[1])
            sphere.set("radius", GO2_FOOT_SPHERE[0])
        elif name == "base":
            inertia = link.find("inertial/inertia")
            assert inertia is not None
            for axis, value in zip(("ixx", "iyy", "izz"), GO2_BASE_INERTIA):
                inertia.set(axis, value)
        elif link.find("inertial") is None:
            inertial = ElementTree.SubElement(link, "inertial")
            ElementTree.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
            ElementTree.SubElement(inertial, "mass", value="0.005")
            moments = {"ixx": "1e-6", "iyy": "1e-6", "izz": "1e-6", "ixy": "0", "ixz": "0"}
            ElementTree.SubElement(inertial, "inertia", {**moments, "iyz": "0"})
    return ElementTree.tostring(robot, encoding="unicode")


@dataclass(frozen=True)
class Gait:
    """One periodic gait.

    ``offsets``: per leg, where in the cycle (fraction) its swing begins; ``height_m``: the hips'
    height above the foot centres; ``lift_m``: the swing foot's peak lift; ``speed_mps`` and
    ``yaw_rate``: the commanded forward speed [m/s] and turn rate [rad/s] of the body;
    ``shift``: how far (fractions in x and y of the way to the support triangle's centroid) the
    trunk moves away from the swinging leg, ``shift_lead`` (cycle fraction) how early it starts;
    ``thrust``: the stance legs push 1 + thrust sin² (over the stance) times the weight;
    ``feet_offset_m``: all feet moved (x, y) in the root frame; ``ground_aware``: swing feet
    planned relative to the ground (see :func:`gait_targets`); ``ramp_s``: how long speed, turn
    rate and thrust take to fade in; ``load_ramp`` and ``load_lead``: see :func:`stance_load`;
    ``attitude_gains``: stiffness [N m/rad] and damping [N m s/rad] of the trunk's roll and
    pitch (:func:`support_forces`).
    """

    period_s: float
    duty: float
    offsets: tuple[float, float, float, float]
    height_m: float
    lift_m: float
    speed_mps: float = 0.0
    yaw_rate: float = 0.0
    shift: tuple[float, float] = (0.0, 0.0)
    shift_lead: float = 0.15
    thrust: float = 0.0
    feet_offset_m: tuple[float, float] = (0.0, 0.0)
    ground_aware: bool = True
    ramp_s: float = 0.5
    load_ramp: float = 0.15
    load_lead: float = 0.04
    attitude_gains: tuple[float, float] = (100.0, 5.0)


def _shift_table(gait: Gait, nominal: np.ndarray, size: int = 400) -> np.ndarray:
    """(size, 2) the trunk's planned offset [m, root x and y] over one cycle: from ``shift_lead``
    before a leg's swing to as long after it, the fractions ``shift`` (x, y) of the way to the
    other three feet's centroid (the mean where two such spans overlap); smoothed by a periodic
    Hann window twice ``shift_lead`` wide.
    """
    u = np.arange(size) / size
    total, count = np.zeros((size, 2)), np.zeros((size, 1))
    for leg in range(4):
        goal = np.array(gait.shift) * (nominal[:, :2].mean(axis=0) - nominal[leg, :2]) / 3.0
        span = 1.0 - gait.duty + 2.0 * gait.shift_lead
        inside = (u - gait.offsets[leg] + gait.shift_lead) % 1.0 < span
        total[inside] += goal
        count[inside] += 1
    raw = total / np.maximum(count, 1)
    width = max(3, round(2.0 * gait.shift_lead * size))
    window = np.hanning(width + 2)[1:-1]
    window /= window.sum()
    padded = np.concatenate([raw[-width:], raw, raw[:width]])
    smooth = np.stack([np.convolve(padded[:, k], window, mode="same") for k in range(2)], 1)
    result: np.ndarray = smooth[width:-width]
    return result


def swing_stroke(progress: float, ratio: float) -> float:
    """Where a swing foot is, from -0.5 (lift-off) to 0.5 (touchdown), in units of the stance
    stroke, at ``progress`` (0 to 1) of the swing: a cubic that leaves and lands at the stance
    feet's speed (relative to the body, ``-ratio`` strokes per swing, ``ratio`` = swing / stance
    duration), so that the foot meets the ground at rest.
    """
    s = progress  # a cubic Hermite spline: -0.5 to 0.5, slope -ratio at both ends
    return 0.5 * (6 * s**2 - 4 * s**3 - 1) - ratio * (2 * s**3 - 3 * s**2 + s)


def smoothstep(x: float) -> float:
    """0 below 0, 1 above 1, and a cubic with level ends between."""
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x)


def level_rotation(roll: float, pitch: float) -> np.ndarray:
    """3×3 rotation of the root frame in its heading frame (yaw removed): Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    return np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])


Pose = tuple[float, float, float, float, float]
"""The trunk's roll, pitch [rad], the root's height [m] above the ground's contact level (root
height minus the foot radius) and the roll and pitch rates [rad/s] (the gyro's x and y)."""
Targets = Callable[[float, Pose | None], tuple[np.ndarray, np.ndarray]]
"""(t [s], pose or None) -> the 12 joint angles [rad] of the planned feet, and the 12 offsets
[rad] that load them (the motors' targets are their sum)."""


def stance_load(u: float, gait: Gait) -> float:
    """How loaded (0 to 1) a leg is planned at cycle fraction ``u`` from its swing's start: a
    smoothstep up over the fraction ``load_ramp`` of the stance from ``load_lead`` (cycle
    fraction) before the touchdown, and down over as long before the liftoff; 0 in the swing.
    """
    ramp = gait.load_ramp * gait.duty
    swing = 1.0 - gait.duty
    return smoothstep((u - swing + gait.load_lead) / ramp) * smoothstep((1.0 - u) / ramp)


def support_forces(
    feet: np.ndarray, loads: np.ndarray, weight_n: float, moment: np.ndarray
) -> np.ndarray:
    """(4,) upward forces [N] on feet at ``feet`` ((4, 2) [m], from the centre of mass) that carry
    ``weight_n`` and make the ``moment`` [N m] about x and y about it, times min(1, sum of
    ``loads``): the least-squares ones weighted by ``loads`` (a foot of load 0 carries none),
    regularised where the feet are (nearly) in a line.
    """
    total = float(loads.sum())
    if total <= 0.0:
        return np.zeros(4)
    system = np.vstack([np.ones(4), feet.T])  # force; moments about y (-x F) and x (y F)
    weighted = system * loads
    goal = min(1.0, total) * np.array([weight_n, -moment[1], moment[0]])
    normal = weighted @ system.T + np.diag([0.0, 1.0, 1.0]) * 1e-3 * total
    result: np.ndarray = weighted.T @ np.linalg.solve(normal, goal)
    return result


def gait_targets(
    legs: Legs, gait: Gait, start_s: float, weight_n: float = 0.0, kp: float = 1.0
) -> Targets:
    """Joint targets [rad] (12, FR..RL × hip, thigh, calf) at time t [s]: standing at the gait's
    nominal feet until ``start_s``, then the gait; its speed, turn rate and thrust fade in over
    ``gait.ramp_s``.

    Stance feet are planned in the root frame (they hold the trunk level at ``height_m``). With
    ``gait.ground_aware`` and a pose, a swing foot is planned relative to the ground: its height
    above the ground and its horizontal place are those planned, in the heading frame, whatever
    the trunk's tilt and height, so that it lands when planned. The correction fades in over the
    first half of the swing and out over the first 30 % of the stance, with the pose at
    touchdown (kept: a stance foot that followed the measured pose would let the trunk drift).
    The returned function keeps that state: call it with times in order.

    The motors are PD torque motors of stiffness ``kp`` [N m/rad]: a loaded leg's targets are
    offset by -Jᵀ F / kp, F = (0, 0, f) [N, root frame], f its force of :func:`support_forces`
    (the legs' :func:`stance_load`, ``weight_n`` times 1 + ``thrust`` sin² of the stance, the
    moment of ``attitude_gains`` against the pose's roll, pitch and rates), so that the motors
    push a foot where it is planned with f (as a feedforward torque -Jᵀ F would).
    """
    nominal = np.array([legs.below_thigh(leg, gait.height_m) for leg in range(4)])
    nominal[:, :2] += gait.feet_offset_m
    shifts = _shift_table(gait, nominal)
    shifts = np.vstack([shifts, shifts[:1]])  # closed, to interpolate
    centre = nominal[:, :2].mean(axis=0)  # under the centre of mass
    swing = 1.0 - gait.duty
    stance_s = gait.duty * gait.period_s

    landed: dict[int, Pose] = {}  # per stance leg: the pose at touchdown

    def targets(t: float, pose: Pose | None = None) -> tuple[np.ndarray, np.ndarray]:
        running = t > start_s
        fade = smoothstep((t - start_s) / gait.ramp_s)
        cycle = (t - start_s) / gait.period_s if running else 0.0
        phases = [(cycle - offset) % 1.0 for offset in gait.offsets]
        loads = np.array([1.0 - fade + fade * stance_load(u, gait) for u in phases])
        # the trunk's shift fades in over the ramp before the gait; the table, interpolated (its
        # steps would be spikes in the target rates)
        at = (t - start_s) / gait.period_s % 1.0 * (len(shifts) - 1)
        shift = np.zeros(3)
        shift[:2] = smoothstep((t - start_s) / gait.ramp_s + 1.0) * np.array(
            [np.interp(at, np.arange(len(shifts)), shifts[:, k]) for k in range(2)]
        )
        feet = []
        for leg in range(4):
            p = nominal[leg]
            # a stance foot moves against the body: -(v + w x p) over the stance
            turn = gait.yaw_rate
            stroke = fade * stance_s * np.array([gait.speed_mps - turn * p[1], turn * p[0], 0.0])
            foot = p - shift
            u = phases[leg]
            weight, leg_pose = 0.0, pose
            if running and u < swing:  # from the back (-stroke/2) to the front (+stroke/2), lifted
                progress = u / swing
                foot = foot + stroke * swing_stroke(progress, swing / gait.duty)
                foot[2] += gait.lift_m * 0.5 * (1.0 - math.cos(2.0 * math.pi * progress))
                weight = smoothstep(2.0 * progress)
                landed.pop(leg, None)
            elif running:  # from the front to the back at constant speed
                progress = (u - swing) / gait.duty
                foot = foot + stroke * (0.5 - progress)
                weight = 1.0 - smoothstep(progress / 0.3)
                if pose is not None:
                    leg_pose = landed.setdefault(leg, pose)
            weight *= fade
            if gait.ground_aware and leg_pose is not None and weight > 0.0:
                roll, pitch, height = leg_pose[:3]
                grounded = foot + np.array([0.0, 0.0, gait.height_m - height])
                foot = foot + weight * (level_rotation(roll, pitch).T @ grounded - foot)
            feet.append(foot)
        tilt = np.zeros((2, 2)) if pose is None else np.array([pose[:2], pose[3:]])
        moment = -np.array(gait.attitude_gains) @ tilt  # against the roll and the pitch
        push = [math.sin(math.pi * max(0.0, u - swing) / gait.duty) ** 2 for u in phases]
        boost = 1.0 + fade * gait.thrust * float(loads @ push) / max(float(loads.sum()), 1e-9)
        forces = support_forces(np.array(feet)[:, :2] - centre, loads, boost * weight_n, moment)
        angles = np.array([legs.ik(leg, foot) for leg, foot in enumerate(feet)])
        offsets = [-legs.lift_row(leg, angles[leg]) * forces[leg] / kp for leg in range(4)]
        return angles.ravel(), np.ravel(offsets)

    return targets


@dataclass(frozen=True)
class Motors:
    """PD torque motors (``QuadrupedSim.step_pd``): τ = clip(kp (q* - q) + kd (q̇* - q̇),
    ±max_torque_nm), kp [N m/rad], kd [N m s/rad], max_torque_nm [N m].
    """

    kp: float
    kd: float
    max_torque_nm: float


@dataclass(frozen=True)
class RunSpec:
    """How one run is made: the robot ("a1" or "go2"), its gait and motors; ``soft``: soft toes;
    ``gait_s``: how long the gait lasts [s]; ``slips``: every :data:`SLIP_PERIOD_S` the ground
    turns to ice for :data:`SLIP_S` while the trunk is pushed sideways (:class:`Slips`).
    """

    robot: str
    gait: Gait
    motors: Motors
    soft: bool = False
    gait_s: float = 10.5
    slips: Slips | None = None


@dataclass(frozen=True)
class Slips:
    """Ice patches: from ``first_s`` [s] on, every ``period_s`` for ``duration_s`` the plane's
    friction drops to ``friction`` (friction anchors off) while a sideways force of
    ``push_g`` times the robot's weight, alternating left and right, pushes the trunk.
    """

    first_s: float = 2.0
    period_s: float = 1.9
    duration_s: float = 0.12
    friction: float = 0.05
    push_g: float = 0.35

    def active(self, t: float) -> int:
        """0 outside a patch at ``t`` [s], else the push's side (+1 left, -1 right)."""
        if t < self.first_s:
            return 0
        cycle, phase = divmod(t - self.first_s, self.period_s)
        return (1 if int(cycle) % 2 == 0 else -1) if phase < self.duration_s else 0


TROT = (0.0, 0.5, 0.5, 0.0)
"""Swing offsets (FR, FL, RR, RL) of a trot."""
WALK = (0.65, 0.15, 0.5, 0.0)
"""Swing offsets of a walk: RL, FL, RR, FR, the two legs of a side back to back."""
A1_FEET_OFFSET = (-0.006, 0.0)
"""[m]: the A1's feet under its centre of mass (6 mm behind the root, standing)."""
GO2_FEET_OFFSET = (-0.002, -0.0065)
"""[m]: the Go2-like robot's feet under its centre of mass."""
A1_TROT = Gait(0.4, 0.58, TROT, 0.27, 0.09, 0.3, feet_offset_m=A1_FEET_OFFSET)
GO2_TROT = Gait(0.4, 0.58, TROT, 0.29, 0.09, 0.35, feet_offset_m=GO2_FEET_OFFSET)
A1_WALK = replace(
    A1_TROT, period_s=1.6, duty=0.88, offsets=WALK, lift_m=0.1, speed_mps=0.12, shift=(0.3, 0.5)
)
GO2_WALK = replace(A1_WALK, height_m=0.29, feet_offset_m=GO2_FEET_OFFSET)
A1_PRONK = replace(
    A1_TROT, duty=0.5, offsets=(0.5,) * 4, lift_m=0, speed_mps=0, thrust=3.0, ground_aware=False
)
A1 = Motors(60.0, 1.5, 33.5)
GO2 = Motors(70.0, 1.5, 45.0)
SPECS = {
    "a1_trot_slow": RunSpec("a1", A1_TROT, A1),
    "a1_trot_fast": RunSpec("a1", replace(A1_TROT, period_s=0.3, duty=0.5, speed_mps=0.48), A1),
    "a1_trot_turn": RunSpec(
        "a1", replace(A1_TROT, period_s=0.35, duty=0.55, speed_mps=0.25, yaw_rate=0.6), A1
    ),
    "a1_walk": RunSpec("a1", A1_WALK, A1),
    "a1_pronk": RunSpec("a1", A1_PRONK, A1),
    "a1_trot_soft": RunSpec("a1", A1_TROT, A1, soft=True),
    "go2_trot": RunSpec("go2", GO2_TROT, GO2),
    "go2_trot_fast": RunSpec(
        "go2", replace(GO2_TROT, period_s=0.3, duty=0.5, speed_mps=0.45), GO2
    ),
    "go2_walk": RunSpec("go2", GO2_WALK, GO2),
}
"""The family, by name: trots (slow, fast, turning, soft toes), walks and a pronk; the duty is
the commanded one (the true one: ``python test/contact_runs.py OUT_DIR``)."""
A1_FLYING_TROT = replace(A1_TROT, period_s=0.35, duty=0.4, speed_mps=0.4, thrust=0.5)
"""A trot whose diagonal pairs both leave the ground between strides (~10 % of the time)."""
A1_LONG_WALK = replace(A1_WALK, period_s=1.2, speed_mps=0.25)
LONG_SPECS = {
    "a1_trot_long": RunSpec("a1", A1_TROT, A1, gait_s=66.0),
    "a1_trot_fast_long": RunSpec("a1", SPECS["a1_trot_fast"].gait, A1, gait_s=60.0),
    "a1_turn_long": RunSpec("a1", SPECS["a1_trot_turn"].gait, A1, gait_s=86.0),
    "a1_walk_long": RunSpec("a1", A1_LONG_WALK, A1, gait_s=82.0),
    "a1_flying_trot": RunSpec("a1", A1_FLYING_TROT, A1, gait_s=62.0),
    "a1_flying_trot_fast": RunSpec(
        "a1",
        replace(A1_TROT, period_s=0.3, duty=0.42, speed_mps=0.45, thrust=0.4),
        A1,
        gait_s=60.0,
    ),
    "a1_trot_slips": RunSpec("a1", A1_TROT, A1, gait_s=66.0, slips=Slips()),
    "go2_trot_long": RunSpec("go2", GO2_TROT, GO2, gait_s=64.0),
    "go2_trot_slips": RunSpec(
        "go2", GO2_TROT, GO2, gait_s=62.0, slips=Slips(1.5, 2.3, 0.1, 0.08, 0.4)
    ),
}
"""The odometry's family: runs of at least 60 s and 20 m (trots straight, fast and turning, a
walk, a flying trot, trots across ice patches with sideways pushes, the Go2-like robot)."""
