"""The terrain family's runs (issue 34), as data: the robots (:data:`ROBOTS`), the terrains
(:class:`Terrain`), the runs (:data:`SPECS`) and which of them one may tune on (:data:`TUNED`).

Independent of the code under test (no a1_leg_fk import). Kept apart from the simulator
(:mod:`terrain_runs`): a run's cache key is a hash of the simulator's sources and of that run's
own spec and robot (their reprs: frozen dataclasses, deterministic), so that adding, changing or
relabelling a run here simulates that run only. Units: m, rad unless named otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from contact_gaits import (
    A1,
    A1_LEGS,
    A1_TROT,
    GO2,
    GO2_FEET,
    GO2_JOINTS,
    GO2_LEGS,
    GO2_TROT,
    TROT,
    Gait,
    Legs,
    Motors,
)
from pybullet_sim import A1_FEET, A1_JOINTS


@dataclass(frozen=True)
class Robot:
    """A simulated robot: its legs (the gait's inverse kinematics), the URDF's joints (FR, FL,
    RR, RL × hip, thigh, calf) and foot links, the description (``urdf``: a path inside
    pybullet_data, read there at run time; "" for the Go2-like one this repository exports) and
    the POSITION_CONTROL motors' force limit ``position_torque_nm`` [N m]."""

    legs: Legs
    joints: tuple[str, ...]
    feet: tuple[str, ...]
    urdf: str
    position_torque_nm: float


ALIENGO_LEGS = Legs(0.2399, 0.051, 0.083, 0.25, 0.25, 0.0265)
"""Unitree's Aliengo as pybullet_data publishes it (aliengo/aliengo.urdf): hips at (±0.2399,
±0.051) m, thighs 0.083 m outwards, thigh and calf 0.25 m, the toes' collision spheres 0.0265 m."""
ALIENGO_JOINTS = tuple(
    f"{leg}_{part}_joint" for leg in ("FR", "FL", "RR", "RL") for part in ("hip", "upper", "lower")
)
ALIENGO_FEET = ("FR_toe", "FL_toe", "RR_toe", "RL_toe")
ROBOTS = {
    "a1": Robot(A1_LEGS, A1_JOINTS, A1_FEET, "a1/a1.urdf", 33.5),
    "go2": Robot(GO2_LEGS, GO2_JOINTS, GO2_FEET, "", 45.0),
    "aliengo": Robot(ALIENGO_LEGS, ALIENGO_JOINTS, ALIENGO_FEET, "aliengo/aliengo.urdf", 44.4),
}
"""The family's robots by name: pybullet_data's A1, the Go2-like export, Unitree's Aliengo (its
URDF's 44.4 N m effort limit; 20.6 kg)."""
ALIENGO = Motors(150.0, 3.0, 44.4)
"""The Aliengo's PD torque motors (kp [N m/rad], kd [N m s/rad], the URDF's effort limit)."""
ALIENGO_TROT = Gait(0.45, 0.58, TROT, 0.36, 0.09, 0.35, feet_offset_m=(-0.004, 0.002))
"""The Aliengo's trot: hips 0.36 m above the toes, its feet under its centre of mass (4 mm behind
and 2 mm left of the root, standing)."""


@dataclass(frozen=True)
class Terrain:
    """The ground of a run. ``kind``: "flat" (PyBullet's plane), "slope" (a box tilted about y:
    the ground rises ``slope_deg`` along +x, falls if negative), "stairs" (the plane, then steps of
    ``rise_m`` up every ``run_m`` from x = 0.45 m, ``steps`` of them; with ``rise_m`` < 0, down
    from a landing that high), "rough" (a seeded random
    heightfield, smooth bumps of at most ``amplitude_m``), "heightmap" (the held-out real
    heightfield's centre, heights times ``amplitude_m``). ``toes``: contactStiffness [N/m] and
    contactDamping [N s/m] of the feet (None: PyBullet's rigid default).
    """

    kind: str = "flat"
    slope_deg: float = 0.0
    rise_m: float = 0.0
    run_m: float = 0.3
    steps: int = 8
    amplitude_m: float = 0.0
    seed: int = 0
    toes: tuple[float, float] | None = None


@dataclass(frozen=True)
class TerrainSpec:
    """One run: robot (a key of :data:`ROBOTS`), gait, motors (None: PyBullet's
    POSITION_CONTROL with ``position_gain``), terrain, gait duration [s]."""

    robot: str
    gait: Gait
    motors: Motors | None
    terrain: Terrain
    gait_s: float = 10.0
    position_gain: float = 0.3


MAT = (5.0e3, 1.2e2)
"""[N/m], [N s/m]: mat-soft toes, a sixth of the contact family's soft toes' stiffness (3e4; a
tenth, 3e3, sank the A1 onto its calves 75 % of the time)."""
RIGID = (3.0e5, 1.0e3)
"""A decade stiffer than the contact family's soft toes."""
SPECS = {
    "a1_slope_up_5": TerrainSpec("a1", A1_TROT, A1, Terrain("slope", slope_deg=5.0)),
    "a1_slope_down_5": TerrainSpec("a1", A1_TROT, A1, Terrain("slope", slope_deg=-5.0)),
    "a1_rough_2cm": TerrainSpec("a1", A1_TROT, A1, Terrain("rough", amplitude_m=0.02, seed=1)),
    "a1_mat_toes": TerrainSpec("a1", A1_TROT, A1, Terrain(toes=MAT)),
    "go2_slope_up_5": TerrainSpec("go2", GO2_TROT, GO2, Terrain("slope", slope_deg=5.0)),
    "go2_rough_1cm": TerrainSpec("go2", GO2_TROT, GO2, Terrain("rough", amplitude_m=0.01, seed=2)),
    "a1_slope_down_10": TerrainSpec("a1", A1_TROT, A1, Terrain("slope", slope_deg=-10.0)),
    "go2_slope_down_8": TerrainSpec("go2", GO2_TROT, GO2, Terrain("slope", slope_deg=-8.0)),
    "a1_stairs_up_3cm": TerrainSpec(
        "a1", replace(A1_TROT, lift_m=0.14), A1, Terrain("stairs", rise_m=0.03, run_m=0.5)
    ),
    "a1_stairs_down_4cm": TerrainSpec(
        "a1", replace(A1_TROT, lift_m=0.12), A1, Terrain("stairs", rise_m=-0.04)
    ),
    "go2_stairs_down_6cm": TerrainSpec(
        "go2", replace(GO2_TROT, lift_m=0.12), GO2, Terrain("stairs", rise_m=-0.06)
    ),
    "go2_stairs_up_4cm": TerrainSpec(
        "go2", replace(GO2_TROT, lift_m=0.14), GO2, Terrain("stairs", rise_m=0.04, run_m=0.4)
    ),
    "a1_stairs_down_3cm": TerrainSpec(
        "a1", replace(A1_TROT, lift_m=0.14), A1, Terrain("stairs", rise_m=-0.03, run_m=0.4)
    ),
    "go2_stairs_down_5cm": TerrainSpec(
        "go2", replace(GO2_TROT, lift_m=0.12), GO2, Terrain("stairs", rise_m=-0.05, run_m=0.3)
    ),
    "a1_heightmap": TerrainSpec("a1", A1_TROT, A1, Terrain("heightmap", amplitude_m=0.01)),
    "a1_rigid_toes": TerrainSpec("a1", A1_TROT, A1, Terrain(toes=RIGID)),
    "a1_position_flat": TerrainSpec(
        "a1", replace(A1_TROT, attitude_gains=(0, 0)), None, Terrain()
    ),
    "go2_position_flat": TerrainSpec(
        "go2", replace(GO2_TROT, attitude_gains=(0, 0)), None, Terrain(), position_gain=0.5
    ),
    "aliengo_flat": TerrainSpec("aliengo", ALIENGO_TROT, ALIENGO, Terrain()),
    "aliengo_stairs_down_4cm": TerrainSpec(
        "aliengo", replace(ALIENGO_TROT, lift_m=0.12), ALIENGO, Terrain("stairs", rise_m=-0.04)
    ),
    "aliengo_stairs_down_3cm": TerrainSpec(
        "aliengo", replace(ALIENGO_TROT, lift_m=0.12), ALIENGO, Terrain("stairs", rise_m=-0.03)
    ),
    "aliengo_slope_up_5": TerrainSpec(
        "aliengo", ALIENGO_TROT, ALIENGO, Terrain("slope", slope_deg=5.0)
    ),
    "aliengo_position_flat": TerrainSpec(
        "aliengo",
        replace(ALIENGO_TROT, attitude_gains=(0, 0)),
        None,
        Terrain(),
        position_gain=0.5,
    ),
}
"""The family. The open-loop trot climbs 5° (at 7-10° it slides back and turns) and 3 cm steps
0.5 m deep with a 14 cm swing (4 cm steps 0.3 m deep stub its rear toes on the first riser; the
Go2 climbs 4 cm steps 0.4 m deep); it walks down 10° and down 4-6 cm steps (8 cm: the Go2's
calves touch the treads on 8 % of the samples, more than the family allows; down 3 cm steps 0.4
m deep the A1's front calves touch the steps on 5.4 % with a 12 cm swing, 4.5 % with 14 cm;
down 5 cm steps its calves touch on 5.0-19 % with 0.3-0.5 m treads, the Go2's on 2.0 % with 0.3
m). The Aliengo walks its four on its feet alone (no other link touches): with kp 120 N m/rad it
yawed off the 5° slope and rolled over, with :data:`ALIENGO`'s 150 it climbs it."""
TUNED = (
    "a1_slope_up_5",
    "a1_slope_down_5",
    "a1_rough_2cm",
    "a1_mat_toes",
    "go2_slope_up_5",
    "go2_rough_1cm",
    "go2_stairs_down_6cm",
    "a1_position_flat",
    "go2_position_flat",
    "a1_stairs_down_4cm",
    "aliengo_stairs_down_4cm",
)
"""Conditions one may tune on: gentle slopes, seeded rough ground, mat-soft toes,
go2_stairs_down_6cm (held out until the feet's give was tuned on it: a stance counts toward the
give once it has lasted 0.1 s; go2_stairs_up_4cm took its place) and both POSITION_CONTROL runs
(held out until their contacts with efforts were diagnosed and fixed, stop 46: a forced foot
whose force says swing gets no low-and-still stance; Unitree's Aliengo took their place) and
a1_stairs_down_4cm (held out until its noisy kinematic vertical drift was diagnosed and fixed,
stop 47: a touchdown's noise is its own height's; go2_stairs_down_5cm took its place) and
aliengo_stairs_down_4cm (held out until its noisy vertical drift with efforts was diagnosed and
fixed, stop 48: a staircase's touchdowns judged against its treads; aliengo_stairs_down_3cm took
its place).
a1_stairs_down_3cm (3 cm steps 0.4 m deep) is the staircase nobody looked at while choosing the
contacts' rules on stairs."""
HELD_OUT = tuple(name for name in SPECS if name not in TUNED)
"""Whole conditions held out: steeper slopes, the staircases, a real heightfield (DeepLoco's),
rigid toes, and a whole robot, Unitree's published Aliengo (flat, 3 cm stairs down, a slope up and
PyBullet's POSITION_CONTROL motors; its 4 cm staircase down tuned since stop 48)."""
