"""The contact estimate and the state filter on ground nobody tuned them on (issue 34): the
terrain family (test/terrain_runs.py: slopes, staircases, rough and DeepLoco heightfields,
mat-soft and rigid toes, POSITION_CONTROL motors; the A1, the Go2-like robot and, held out but
for the staircase its touchdowns were tuned on, Unitree's Aliengo as pybullet_data publishes
it), every estimator at its default settings, judged on the live (causal) estimate against
PyBullet.

:data:`terrain_specs.TUNED` are the conditions one may tune on, :data:`terrain_specs.HELD_OUT`
whole conditions held out. Goals (issue 34), on every run: contacts with efforts >= 98.5 % and
<= 1 % of swing samples called stance, without efforts >= 95 %; odometry RMSE <= 0.03 m/s clean
(0.05 noisy), no 0.1 s window above 0.2 m/s, drift <= 1 % horizontal and <= 0.5 % vertical, the
error inside 3 sigma on >= 95 % of the samples and sigma <= 5x the RMS error; the local ground's
slope within 1° and the base's height above it within 2 cm after the first stride on slopes and
stairs. Where today's defaults miss, the run is a strict xfail naming the measured numbers.
"""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(900)
"""The module's fixture simulates the family (two at a time, about a minute of wall time per
run on a loaded 2-core machine) once per machine and scores it: minutes."""

CONTACTS = "contacts {} % with efforts, {} % without"
UNMET = {
    "a1_stairs_down_4cm": CONTACTS.format(99.01, 94.65)
    + " (without: 93.72 % before a foot's height was taken over the tread under it, 90.63 % "
    "before the speeds were taken against the feet that stood at any height; 3.09 % swing "
    "called stance; with efforts met since a landed foot with a force stands, 0.44 % swing "
    "called stance); the odometry meets every goal (the noisy kinematic vertical drift 0.29 %, "
    "0.73 % before a touchdown's noise was its own height's: tuned since)",
    "go2_stairs_down_6cm": CONTACTS.format(98.79, 92.36)
    + " (with efforts met since the force's fade of a loaded foot's speed holds on any ground, "
    "its margin the swing feet's RMS force, with the smoother's rules for a forced foot: 98.09 % "
    "before; without, 91.48 % before a foot's height was taken over the tread under it: the "
    "loaded feet sliding over the treads' edges at a median 0.6 m/s are 81 % of its stance "
    "called swing, docs/forces.md)",
    "a1_position_flat": "contacts 93.45 % without efforts (88.27 % before the rigid feet's "
    "height rule; the best a height-and-speed rule reaches against the true ground is 92.09 %, "
    "the filter's own heights 94.45 %: its feet hover 0.2-0.5 mm over the plane, docs/forces.md;"
    " with efforts met, 99.91 %); every odometry goal met since each touchdown's sideways jolt is "
    "measured (within 3 sigma 99.0-100 %, 88.8-94.9 % before)",
    "a1_stairs_down_3cm": CONTACTS.format(99.47, 94.97)
    + " (the staircase nobody looked at: with efforts met, 0.24 % swing called stance; without "
    "94.44 % before a foot's height was taken over the tread under it)",
    "aliengo_position_flat": "contacts 94.13 % without efforts (89.49 % before the rigid feet's "
    "height rule; with efforts met: 99.73 %, 0.26 % swing called stance); every odometry goal "
    "met since each touchdown's sideways jolt is measured (within 3 sigma 97.4-99.9 %, 88.0-91.1 "
    "% before; clean horizontal drift with efforts 1.52 -> 0.21 %)",
    "go2_stairs_down_5cm": CONTACTS.format(98.70, 92.19)
    + " (held out since stop 47: with efforts met since the force's fade holds on any ground, "
    "97.82 % before; without, 91.54 % before a foot's height was taken over the tread under it: "
    "the sliding feet, as go2_stairs_down_6cm's; its odometry meets every goal)",
    "aliengo_stairs_down_3cm": "noisy vertical drift with efforts 0.63 % (held out since stop "
    "48 in the place of aliengo_stairs_down_4cm, whose 0.72 % the treads' votes brought to 0.11 "
    "%: here, clean 0.03 %, kinematic noisy 0.41 %; contacts 99.47 / 96.49 % met)",
}
"""Runs whose goals the defaults (``ground: footholds``, the contacts' heights against the
footholds' slope or the tread under each foot, the rigid feet's height scales, the feet's give,
the contacts' rise above a foot's own foothold and a landed foot's height taken for no swing;
the speeds against the feet that stood at any height; with efforts the force's fade of a loaded
foot's speed on any ground, the observer's lag undone where a foot lets go, and no low-and-still
stance for a forced foot whose force says swing; a touchdown's noise its own height's, each
landing's transient and each touchdown's sideways jolt measured, a staircase's touchdowns judged
against its treads) miss, with the numbers (strict xfail): four staircases down and two
POSITION_CONTROL runs on their contacts without efforts (92.19-94.97 %: on the stairs loaded feet
slide over the treads' edges, under the position motors the feet hover 0.2-0.5 mm over the
plane), and the Aliengo's new held-out staircase on its noisy vertical drift with efforts. With
efforts every run meets the contacts' goals (go2_stairs_down_6cm and go2_stairs_down_5cm since
the force's fade holds on any ground); every odometry goal is met on every run but that one
(within 3 sigma 96.3-100 % on every estimate; the POSITION_CONTROL runs since each touchdown's
sideways jolt is measured, 87-95 % before). go2_position_flat meets every goal since the rigid
feet's height rule (contacts without efforts 91.11 -> 95.03 %) and the jolt (within 3 sigma 89.2
-> 98.9 % clean kinematic); aliengo_stairs_down_4cm since a staircase's touchdowns are judged
against its treads (noisy vertical drift with efforts 0.72 -> 0.11 %: tuned since, k48d). The
fourteen others meet every goal: aliengo_flat and aliengo_slope_up_5 (the held-out robot's),
a1_rigid_toes, a1_slope_up_5, go2_slope_up_5, a1_mat_toes (the feet's give: within 3 sigma 44-48
% without it), a1_slope_down_5, a1_rough_2cm, go2_rough_1cm, a1_heightmap, a1_slope_down_10,
go2_slope_down_8, a1_stairs_up_3cm and go2_stairs_up_4cm. The vertical drift is met on every
slope and stair run but the new held-out one (0.00-0.45 %; ``ground: flat`` drifted 4.8-16.7 %;
the noise model's 0.3° IMU mounting tilt, which no filter can tell from its accelerometer bias,
leaves 0.43-0.45 % on the steeper slopes down)."""
GROUND = (
    "slope off by up to {}° (p95 {}°; {}° where the truth held over the last stride; {}°, p95 {}°,"
    " against the staircase where the feet stood)"
)
GROUND_UNMET = {
    "a1_stairs_up_3cm": GROUND.format(2.20, 1.92, 2.19, 2.37, 1.92),
    "a1_stairs_down_4cm": GROUND.format(4.68, 3.58, 1.56, 2.02, 1.36),
    "go2_stairs_down_6cm": GROUND.format(6.67, 5.26, 3.46, 3.21, 2.76) + ", height 1.93 cm",
    "go2_stairs_up_4cm": GROUND.format(2.94, 2.20, 2.94, 2.94, 2.00),
    "a1_stairs_down_3cm": GROUND.format(2.50, 1.84, 1.71, 1.78, 1.22),
    "aliengo_stairs_down_4cm": GROUND.format(4.23, 3.41, 2.21, 2.21, 1.63),
    "go2_stairs_down_5cm": GROUND.format(4.78, 4.01, 2.51, 3.11, 2.35),
    "aliengo_stairs_down_3cm": GROUND.format(3.08, 2.36, 1.61, 1.61, 1.33),
}
"""Runs whose local ground misses its goal (strict xfail), against a staircase's ground
(:func:`terrain_scoring.stair_ground`: the rays' plane through the staircase averaged over one
tread, whose slope is rise over run on the flight), its slope across the base's heading the
standing feet's (before: 2.50-6.72°, against the feet's span 2.04-4.04°, the footholds' plane
tilting 1.98-3.65° across treads that are level across): the plane through the last eight
footholds samples the treads where the feet happened to land (two clusters, the front and the
rear feet's), and at the staircase's ends it lags the truth, which sees a tread and a half ahead
of the root.
On 0.3 m treads that truth bends 0.92-0.97 s before any foothold lies past the first edge (on
0.4-0.5 m treads from the first sample; the rays and the tread's average reach 0.45-0.55 m ahead
of the root, the front feet 0.18-0.19 m): no causal estimate from footholds can follow it there
(the plane is 1.87-5.70° off in that time). Against the staircase where the feet stood over the
last two strides (:func:`terrain_scoring.foothold_ground`, the truth such an estimate can know)
the plane is still 1.77-3.29° off (2.04-4.04° before the slope across was the standing feet's);
and even an oracle told the rise finds staircases 2.1-4.1° either way of the truth that put the
last eight footholds on their treads (docs/leg_odometry.md, "Local ground").
Against the rays' plane through the treads (the truth before, swinging 0.6-1.33 times the
staircase's slope) it was 2.32-8.91° off, the heights 0.77-2.15 cm with every stance in the fit.
On every slope the ground is within 0.01-0.13° and 0.37 cm (0.39° before the slope across was
the standing feet's; with the contact estimate's stances shorter than 0.05 s in the fit: 0.92° on
go2_slope_up_5, 0.82° on go2_slope_down_8; ``ground: flat`` bent it by 1.0-4.7°). The robot held
out whole, Unitree's Aliengo, lands in the same ranges: 0.01° on its 5° slope, on its staircase
down 4.23° (2.21° against where its feet stood)."""


def _score(name: str) -> Any:
    """A worker: one run, simulated or loaded, scored; its ground after its first stride (its
    gait's period: 0.4 s, the Aliengo's 0.45 s), not scored."""
    from terrain_runs import terrain_runs
    from terrain_scoring import ground_errors, score_run
    from terrain_specs import SPECS

    run = terrain_runs((name,))[name]
    stride_s = SPECS[name].gait.period_s
    ground = ground_errors(run, stride_s) if run.terrain.kind in ("slope", "stairs") else None
    return score_run(run), ground


@pytest.fixture(scope="module")
def scores() -> dict[str, Any]:
    """Every run's scores (and its ground's on slopes and stairs), one worker per core."""
    from terrain_scoring import GROUND_HEADER, HEADER, rows
    from terrain_specs import HELD_OUT, TUNED

    names = TUNED + HELD_OUT
    with ProcessPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        results = dict(zip(names, pool.map(_score, names)))
    print("\n" + HEADER)
    for group, members in (("tuned", TUNED), ("held out", HELD_OUT)):
        print(f"-- {group}")
        for name in members:
            print("\n".join(rows(name, results[name][0])))
    print("\n" + GROUND_HEADER)
    for name in names:
        if results[name][1] is not None:
            print(results[name][1].row(name))
    return results


def _params(names: tuple[str, ...], unmet: dict[str, str]) -> list[Any]:
    return [
        pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=unmet[name]))
        if name in unmet
        else name
        for name in names
    ]


def _names(held_out: bool) -> tuple[str, ...]:
    from terrain_specs import HELD_OUT, TUNED

    return HELD_OUT if held_out else TUNED


@pytest.mark.accept
@pytest.mark.parametrize("name", _params(_names(False), UNMET))
def test_tuned_terrain_runs_meet_the_goals(name: str, scores) -> None:
    from terrain_scoring import misses

    missed = misses(scores[name][0])
    assert not missed, "\n".join(missed)


@pytest.mark.accept
@pytest.mark.parametrize("name", _params(_names(True), UNMET))
def test_held_out_terrain_runs_meet_the_goals(name: str, scores) -> None:
    from terrain_scoring import misses

    missed = misses(scores[name][0])
    assert not missed, "\n".join(missed)


def _ground_runs() -> tuple[str, ...]:
    from terrain_specs import SPECS

    return tuple(n for n, s in SPECS.items() if s.terrain.kind in ("slope", "stairs"))


@pytest.mark.accept
@pytest.mark.parametrize("name", _params(_ground_runs(), GROUND_UNMET))
def test_the_local_ground_holds_on_slopes_and_stairs(name: str, scores) -> None:
    ground = scores[name][1]
    assert ground.worst_deg <= 1.0 and ground.worst_height_m <= 0.02, ground


@pytest.mark.accept
def test_the_terrain_runs_are_what_the_issue_asks_for() -> None:
    """Slopes of their angle, staircases that descend their steps, bumps of their height; the
    three robots (Unitree's Aliengo held out but for the staircase its touchdowns were tuned on,
    stop 48), both motor kinds, soft and rigid toes; the feet, not other links, carry the robot."""
    from terrain_runs import terrain_runs
    from terrain_scoring import FIRST_EDGE_M, stair_profile
    from terrain_specs import HELD_OUT, SPECS, TUNED

    assert set(TUNED).isdisjoint(HELD_OUT) and set(TUNED) | set(HELD_OUT) == set(SPECS)
    aliengo_tuned = {name for name in TUNED if SPECS[name].robot == "aliengo"}
    assert aliengo_tuned == {"aliengo_stairs_down_4cm"}  # the rest of the robot held out
    assert {spec.robot for spec in SPECS.values()} == {"a1", "go2", "aliengo"}
    assert any(spec.motors is None for spec in SPECS.values())
    for name, run in terrain_runs().items():
        terrain, gait = run.terrain, run.run.gait
        if terrain.kind == "slope":
            assert np.allclose(run.plane_slopes_deg[gait], abs(terrain.slope_deg), atol=0.05)
        if terrain.kind == "stairs":
            steps = abs(run.ground_heights[gait][-1] - run.ground_heights[gait][0])
            assert steps >= 3 * abs(terrain.rise_m) - 1e-6, name  # at least three steps walked
            # the scorer's staircase is the simulated one: its treads are the rays' below the
            # root but where the root is within 1 mm of an edge (the ray hits the riser's top)
            x = run.run.base_positions[:, 0]
            off = np.abs(stair_profile(terrain, x) - run.ground_heights) > 1e-4
            edges = FIRST_EDGE_M + terrain.run_m * np.arange(terrain.steps)
            assert (np.abs(x[off, None] - edges).min(axis=1) < 1e-3).all(), name
        if terrain.kind in ("rough", "heightmap"):
            bumps = run.ground_heights[gait] - run.plane_heights[gait]
            assert 0.002 < np.abs(bumps).max() < 0.05, name
        assert run.run.other_contacts[gait].mean() < 0.05, name
        assert run.run.contacts[gait].any(axis=0).all(), name


@pytest.mark.accept
def test_the_estimators_model_puts_every_robots_standing_feet_on_the_floor() -> None:
    """The estimators get each robot's geometry right, Unitree's Aliengo's too (its URDF's
    ``*_upper_joint``/``*_lower_joint`` names, ``*_toe`` feet): the model loaded from the run's
    description has the run's joints and foot links in PyBullet's order, and its feet, placed by
    the true base pose, are a toe's contact radius (:data:`terrain_specs.ROBOTS`) above the flat
    floor whenever PyBullet has them in contact, within 2 mm (the Go2-like sphere sits 2 mm
    along its calf from the foot link; a wrong foot link or leg order is centimetres off)."""
    from pybullet_sim import rotation_matrices
    from terrain_runs import terrain_runs
    from terrain_specs import ROBOTS, SPECS, Terrain

    from a1_leg_fk.kinematics.quadruped import Quadruped

    flat = tuple(name for name, spec in SPECS.items() if spec.terrain == Terrain())
    assert {SPECS[name].robot for name in flat} == set(ROBOTS)
    for name, terrain in terrain_runs(flat).items():
        run = terrain.run
        model = Quadruped.from_urdf(run.urdf_path)
        assert model.joint_names == run.joint_names, name
        assert tuple(leg.chain.foot_link for leg in model.legs) == run.foot_links, name
        world = run.base_positions[:, None, :] + np.einsum(
            "nij,nkj->nki", rotation_matrices(run.quaternions), model.fk_batch(run.angles)
        )
        standing = world[run.gait][..., 2][run.contacts[run.gait]]
        radius = ROBOTS[SPECS[name].robot].legs.foot_radius_m
        assert np.abs(standing - radius).max() < 0.002, name


def test_a_runs_cache_key_is_its_own(tmp_path) -> None:
    """Each run's files are named by its own key: distinct per run and changed by its spec and
    its description's text; a run added to terrain_specs.py or a run relabelled tuned changes no
    other run's key, an edit of the simulator (terrain_runs.py) every key (copies of the modules
    in ``tmp_path``, each key computed in a fresh interpreter)."""
    from contact_runs import SOURCES
    from terrain_runs import run_key
    from terrain_specs import SPECS

    keys = {name: run_key(name, spec, "<robot/>") for name, spec in SPECS.items()}
    assert len(set(keys.values())) == len(SPECS)
    spec = SPECS["aliengo_flat"]
    assert run_key("aliengo_flat", replace(spec, gait_s=9.0), "<robot/>") != keys["aliengo_flat"]
    assert run_key("aliengo_flat", spec, "<robot name='x'/>") != keys["aliengo_flat"]
    test_dir = Path(__file__).resolve().parents[1]
    edits = {
        "as it is": ("terrain_specs.py", ""),
        "a run added, one relabelled": (
            "terrain_specs.py",
            (
                '\nSPECS["aliengo_long"] = replace(SPECS["aliengo_flat"], gait_s=60.0)'
                '\nTUNED = (*TUNED, "aliengo_slope_up_5")\n'
            ),
        ),
        "the simulator edited": ("terrain_runs.py", "\n# edited\n"),
    }
    found = {}
    for label, (edited, text) in edits.items():
        folder = tmp_path / label.replace(" ", "_").replace(",", "")
        folder.mkdir()
        for name in ("terrain_runs.py", "terrain_specs.py", *SOURCES):
            (folder / name).write_text((test_dir / name).read_text(encoding="utf-8") + (
                text if name == edited else ""), encoding="utf-8")  # fmt: skip
        script = (
            "import sys; sys.path[:0] = sys.argv[1:3]\n"
            "from terrain_runs import run_key; from terrain_specs import SPECS\n"
            "print(' '.join(run_key(n, SPECS[n], '<robot/>') for n in sorted(SPECS)"
            " if n != 'aliengo_long'))"
        )
        done = subprocess.run(
            [sys.executable, "-c", script, str(folder), str(test_dir)],
            capture_output=True, text=True, timeout=60, check=True,
        )  # fmt: skip
        found[label] = done.stdout.split()
    assert found["as it is"] == [keys[name] for name in sorted(SPECS)]
    assert found["a run added, one relabelled"] == found["as it is"]
    assert not set(found["the simulator edited"]) & set(found["as it is"])


def test_a_slope_run_and_its_live_ground() -> None:
    """The family's representative in ``make test`` (a1_slope_up_5, about 5 s to simulate): the
    truth is a 5° slope the robot climbs on its feet; with the default ``ground: footholds`` the
    feed's live local ground keeps its slope within the goal's 1° and the base's height above it
    within 2 cm from the first stride on, and the odometry's vertical drift within 0.5 % (``ground:
    flat``, the old default, bent the plane by 1.02° and drifted 6.8 %)."""
    from odometry_scoring import errors, estimate
    from terrain_runs import terrain_runs
    from terrain_scoring import ground_errors

    run = terrain_runs(("a1_slope_up_5",))["a1_slope_up_5"]
    gait = run.run.gait
    assert np.allclose(run.plane_slopes_deg[gait], 5.0, atol=0.05)
    climb = run.ground_heights[gait][-1] - run.ground_heights[gait][0]
    assert climb > 0.1 and run.run.other_contacts[gait].mean() < 0.01
    ground = ground_errors(run, 0.4)  # after the first stride, the A1's trot period
    print(ground)
    assert ground.coverage == 1.0
    assert ground.worst_deg <= 1.0 and ground.worst_height_m <= 0.02
    odometry = errors(run.run, estimate(run.run, True))
    print(odometry)
    assert odometry.vertical_pct <= 0.5


def test_the_staircase_where_the_feet_stood_is_its_mean_slope_over_their_span() -> None:
    """The truth a causal estimate can know (:func:`terrain_scoring.span_slope`) against hand
    numbers, 6 cm steps 0.3 m deep going down (first edge at x = 0.45 m, the tread-averaged ramp
    from 0.30 m on): a span on the flight has rise over run, -0.2; one on the landing is level;
    one from 0.0 to 0.6 m, half on the landing and half on the ramp, has half the slope (least
    squares over [0, L] of a ramp over its second half: 12/L³ ∫ (x - L/2) s (x - L/2) dx over
    [L/2, L] = s/2), -0.1; an empty span is level."""
    from terrain_scoring import span_slope
    from terrain_specs import Terrain

    stairs = Terrain("stairs", rise_m=-0.06, run_m=0.3)
    low, high = np.array([1.0, -1.0, 0.0, 1.2]), np.array([1.8, 0.2, 0.6, 1.2])
    assert np.allclose(span_slope(stairs, low, high), [-0.2, 0.0, -0.1, 0.0])


def test_a_staircases_ground_is_its_mean_slope_on_the_flight_and_level_on_the_landings() -> None:
    """The staircase's truth (:func:`terrain_scoring.stair_ground`) against hand numbers: 6 cm
    steps 0.3 m deep going down from 0.48 m (eight edges from x = 0.45 m): on the flight (the
    grid and a half tread on treads) the slope is rise over run, -0.2 (11.31°), the height the
    treads' middle line, 0.48 - 0.03 - 0.2 (x - 0.45); level at 0.48 m and 0 m on the landings.
    The rays' plane through the treads (5 rays 0.15 m apart, half a tread) has that slope, but
    its height at the root swings 0.3 rises (1.8 cm) about the middle line; on 0.4 m treads its
    slope swings 0.8-1.33 times the staircase's."""
    from terrain_runs import GRID
    from terrain_scoring import stair_ground, stair_profile
    from terrain_specs import Terrain

    stairs = Terrain("stairs", rise_m=-0.06, run_m=0.3)
    flight = np.linspace(0.45 + 0.45, 0.45 + 7 * 0.3 - 0.45, 200)
    height, gradient = stair_ground(stairs, flight)
    assert np.allclose(gradient, [-0.2, 0.0]) and np.allclose(height, 0.45 - 0.2 * (flight - 0.45))
    landings = np.array([-1.0, 0.0, 3.0, 4.0])  # the grid and half a tread off the flight
    height, gradient = stair_ground(stairs, landings)
    assert np.allclose(gradient, 0.0) and np.allclose(height, [0.48, 0.48, 0.0, 0.0])
    along = np.array(sorted({dx for dx, _ in GRID}))
    roots = flight + 1e-4  # no ray on an edge
    rays = stair_profile(stairs, roots[:, None] + along)
    assert np.allclose(rays @ along / float(along @ along), -0.2)
    swing = rays.mean(axis=1) - stair_ground(stairs, roots)[0]
    assert swing.min() == pytest.approx(-0.018, abs=5e-4)
    assert swing.max() == pytest.approx(0.018, abs=5e-4)
    deeper = Terrain("stairs", rise_m=0.04, run_m=0.4)
    rays = stair_profile(deeper, roots[:, None] + along)
    ratios = rays @ along / float(along @ along) / 0.1
    assert ratios.min() == pytest.approx(0.8) and ratios.max() == pytest.approx(4 / 3)
