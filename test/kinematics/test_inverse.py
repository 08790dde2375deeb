"""Inverse kinematics (a1_leg_fk.kinematics.ik.four_legs via Quadruped.ik/ik_batch/ik_solutions).

Independent references: PyBullet's FK of our angles (pybullet_reference), the configurations the
test draws itself (IK(FK(q)) must give q back), the A1's reach typed here (0.088 m and 0.359 m from
the hip-pitch axis: 0.4 cos(q/2) at the knee limits), and for the statuses a dense grid search
over the joint ranges refined by scipy's bounded least squares (never our solver).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet_data
import pybullet_reference
import pytest
from conftest import raises_leg_fk_error
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import least_squares
from shared import A1_FEET, LEGS
from synthetic_urdf import quadruped_urdf

from a1_leg_fk.kinematics.ik import four_legs
from a1_leg_fk.kinematics.quadruped import Quadruped

DATA = Path(pybullet_data.getDataPath())
MINI_CHEETAH_FEET = {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"}
ROBOTS = {
    "a1": (DATA / "a1" / "a1.urdf", None, A1_FEET),
    "aliengo": (DATA / "aliengo" / "aliengo.urdf", None, A1_FEET),
    "mini_cheetah": (
        DATA / "mini_cheetah" / "mini_cheetah.urdf",
        MINI_CHEETAH_FEET,
        list(MINI_CHEETAH_FEET.values()),
    ),
}
ROUND_TRIPS = 2000
A1_HIP_PITCH_FR = np.array([0.183, -0.047 - 0.08505, 0.0])  # FR hip-pitch joint, base frame [m]


def ranges(quadruped: Quadruped) -> tuple[np.ndarray, np.ndarray]:
    """Joint ranges [rad] per slot; [-pi, pi] for continuous joints."""
    lower = np.array([-math.pi if j.lower is None else j.lower for j in quadruped.joints])
    upper = np.array([math.pi if j.upper is None else j.upper for j in quadruped.joints])
    return lower, upper


def wrapped(difference: np.ndarray) -> np.ndarray:
    return (np.asarray(difference) + math.pi) % (2.0 * math.pi) - math.pi


@pytest.fixture(scope="module")
def a1() -> Quadruped:
    return Quadruped.from_urdf()


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request) -> tuple[str, Quadruped]:
    path, feet, _ = ROBOTS[request.param]
    return request.param, Quadruped.from_urdf(str(path), foot_links=feet)


# --- round trips ----------------------------------------------------------------------------


def test_round_trips_against_fk_and_pybullet(robot) -> None:
    """2,000 in-limit configurations per leg: FK(IK(FK(q))) = FK(q) within 1e-9 m (and PyBullet's
    FK of our angles within its float32 1e-7 m); IK(FK(q)) = q within 1e-9 rad where the in-limit
    solution is unique; the batch equals the single call."""
    name, quadruped = robot
    assert all(solver.closed_form for solver in quadruped._ik_solvers)
    lower, upper = ranges(quadruped)
    q = np.random.default_rng(11).uniform(lower, upper, size=(ROUND_TRIPS, 12))
    feet = quadruped.fk_batch(q)
    batch = quadruped.ik_batch(feet)
    assert (batch.status == four_legs.OK).all()
    np.testing.assert_allclose(quadruped.fk_batch(batch.angles), feet, rtol=0.0, atol=1e-9)
    assert batch.residual_m.max() <= 1e-9
    assert ((batch.angles >= lower - 1e-12) | np.isinf(lower)).all() and (
        batch.angles <= upper + 1e-12
    ).all()
    unique_checked = 0
    for row in range(ROUND_TRIPS):
        single = quadruped.ik(feet[row])
        assert single.status == ("ok",) * 4
        np.testing.assert_allclose(single.angles, batch.angles[row], rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(single.residual_m, batch.residual_m[row], rtol=0.0, atol=1e-12)
        for slot, leg in enumerate(LEGS):
            drawn = q[row, 3 * slot : 3 * slot + 3]
            inside = [
                s.angles for s in quadruped.ik_solutions(leg, feet[row, slot]) if s.inside_limits
            ]
            assert (
                min(np.abs(wrapped(np.subtract(angles, drawn))).max() for angles in inside) <= 1e-9
            )
            if len(inside) == 1:
                unique_checked += 1
                np.testing.assert_allclose(
                    wrapped(single.angles[3 * slot : 3 * slot + 3] - drawn), 0.0, atol=1e-9
                )
    # The A1's roll branches are both inside the limits only near the roll axis; the continuous
    # joints of mini_cheetah make all four in-limit.
    assert unique_checked > (4000 if name == "a1" else -1)
    path, _, foot_links = ROBOTS[name]
    with pybullet_reference.PyBulletRobot(path) as pybullet_robot:
        for row in range(ROUND_TRIPS):
            bullet_feet = pybullet_robot.feet(
                list(quadruped.joint_names), foot_links, batch.angles[row]
            )
            np.testing.assert_allclose(bullet_feet, feet[row], rtol=0.0, atol=1e-7)


def test_mini_cheetah_has_four_in_limit_solutions_and_the_seed_picks_each() -> None:
    path, feet, _ = ROBOTS["mini_cheetah"]
    cheetah = Quadruped.from_urdf(str(path), foot_links=feet)
    q = [0.3, 0.7, -1.4] * 4
    target = cheetah.fk(q)
    solutions = cheetah.ik_solutions("FR", target[0])
    assert len(solutions) == 4 and all(s.inside_limits for s in solutions)
    for solution in solutions:
        np.testing.assert_allclose(
            cheetah.legs[0].position(*solution.angles), target[0], atol=1e-12
        )
        seed = list(solution.angles) + q[3:]
        np.testing.assert_allclose(
            cheetah.ik(target, seed=seed).angles[:3], solution.angles, atol=1e-12
        )


def random_a1_topology_urdf(rng: np.random.Generator) -> str:
    """Four legs of the A1 topology with random rpy on every joint, random offsets, axis signs and
    limits: roll axis perpendicular to the pitch axis, knee axis parallel to it, in their
    frames."""

    def rotation(rpy) -> np.ndarray:
        from a1_leg_fk.kinematics.leg_stages import rpy_matrix

        return rpy_matrix(rpy)

    def numbers(values) -> str:
        return " ".join(repr(float(value)) for value in values)

    legs = []
    for leg in LEGS:
        rpy = rng.uniform(-math.pi, math.pi, size=(4, 3))
        offsets = rng.uniform(-0.15, 0.15, size=(4, 3))
        pitch_axis = rng.normal(size=3)
        pitch_axis /= np.linalg.norm(pitch_axis)
        pitch_in_roll = rotation(rpy[1]) @ pitch_axis
        roll_axis = np.cross(pitch_in_roll, rng.normal(size=3))
        roll_axis /= np.linalg.norm(roll_axis)
        knee_axis = rotation(rpy[2]).T @ pitch_axis * rng.choice([-1.0, 1.0])
        axes = [roll_axis, pitch_axis, knee_axis]
        centres = rng.uniform(-1.0, 1.0, size=3)
        joints = ""
        parents = ["base", f"{leg}_a", f"{leg}_b", f"{leg}_c"]
        for index in range(3):
            joints += (
                f'<joint name="{leg}_j{index}" type="revolute"><parent '
                f'link="{parents[index]}"/><child link="{parents[index + 1]}"/><origin '
                f'xyz="{numbers(offsets[index])}" rpy="{numbers(rpy[index])}"/><axis '
                f'xyz="{numbers(axes[index])}"/><limit lower="{float(centres[index]) - 1.2!r}" '
                f'upper="{float(centres[index]) + 1.2!r}" effort="1" velocity="1"/></joint>'
            )
        joints += (
            f'<joint name="{leg}_foot_fixed" type="fixed"><parent link="{leg}_c"/><child '
            f'link="{leg}_foot"/><origin xyz="{numbers(offsets[3] + [0, 0, -0.2])}" '
            f'rpy="{numbers(rpy[3])}"/></joint>'
        )
        legs.append(
            "".join(f'<link name="{link}"/>' for link in [*parents[1:], f"{leg}_foot"]) + joints
        )
    return f'<robot name="random"><link name="base"/>{"".join(legs)}</robot>'


@pytest.mark.parametrize("seed", range(6))
def test_random_urdfs_with_rpy_and_offsets_round_trip(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    quadruped = Quadruped.from_urdf(random_a1_topology_urdf(rng))
    assert all(solver.closed_form for solver in quadruped._ik_solvers)
    lower, upper = ranges(quadruped)
    q = rng.uniform(lower, upper, size=(300, 12))
    feet = quadruped.fk_batch(q)
    result = quadruped.ik_batch(feet, seed=q)
    assert (result.status == four_legs.OK).all()
    np.testing.assert_allclose(quadruped.fk_batch(result.angles), feet, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(result.angles, q, rtol=0.0, atol=1e-9)  # seeded with q: q itself


def test_a_leg_of_another_topology_uses_damped_least_squares() -> None:
    """The synthetic leg with its knee axis tilted off the pitch axis: no closed form; DLS round
    trips."""
    urdf = quadruped_urdf().replace(
        '<origin xyz="0 0 -0.2"/><axis xyz="0 1 0"/>',
        '<origin xyz="0 0 -0.2"/><axis xyz="0 1 0.3"/>',
    )
    quadruped = Quadruped.from_urdf(urdf)
    assert not any(solver.closed_form for solver in quadruped._ik_solvers)
    rng = np.random.default_rng(5)
    q = rng.uniform(-1.9, 1.9, size=(40, 12))
    feet = quadruped.fk_batch(q)
    for row in range(len(q)):
        result = quadruped.ik(feet[row], seed=q[row] + 0.05)
        assert result.status == ("ok",) * 4
        np.testing.assert_allclose(quadruped.fk(result.angles), feet[row], rtol=0.0, atol=1e-9)
    solutions = quadruped.ik_solutions("FR", feet[0, 0])
    assert solutions and all(
        np.linalg.norm(quadruped.legs[0].position(*s.angles) - feet[0, 0]) <= 1e-9
        for s in solutions
    )
    far = quadruped.ik(feet[0] + [5.0, 0.0, 0.0])
    assert far.status == ("unreachable",) * 4


# --- branch continuity ------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["a1", "mini_cheetah"])
def test_seeded_trajectory_follows_the_same_branch(name: str) -> None:
    """A smooth in-limit trajectory, each IK seeded with the previous answer: the angles equal the
    trajectory's own (no jump to another branch), and successive answers differ by small steps."""
    path, feet, _ = ROBOTS[name]
    quadruped = Quadruped.from_urdf(str(path), foot_links=feet)
    t = np.linspace(0.0, 2.0, 400)[:, np.newaxis]
    start = np.array([0.2, 0.9, -1.6] * 4) if name == "a1" else np.array([0.2, -0.7, 1.6] * 4)
    q = start + np.array([0.3, 0.5, 0.6] * 4) * np.sin(2.0 * math.pi * t + np.arange(12))
    targets = quadruped.fk_batch(q)
    seed = q[0]
    for row in range(len(t)):
        result = quadruped.ik(targets[row], seed=seed)
        assert result.status == ("ok",) * 4
        assert np.abs(result.angles - seed).max() < 0.1, f"jump at row {row}"
        np.testing.assert_allclose(result.angles, q[row], atol=1e-9)
        seed = result.angles


# --- reach boundaries, singular and far targets --------------------------------------------


def fr_target_at(distance_m: float, direction_rad: float = 0.0) -> np.ndarray:
    """A point in the FR leg's pitch plane (roll 0) at ``distance_m`` from the hip-pitch axis,
    ``direction_rad`` from straight down towards +x."""
    return A1_HIP_PITCH_FR + distance_m * np.array(
        [math.sin(direction_rad), 0.0, -math.cos(direction_rad)]
    )


REACH_MIN_M, REACH_MAX_M = (
    0.4 * math.cos(2.69653369433 / 2.0),
    0.4 * math.cos(0.916297857297 / 2.0),
)


@pytest.mark.parametrize(
    ("distance", "status"),
    [
        (REACH_MIN_M + 1e-6, "ok"),
        (REACH_MAX_M - 1e-6, "ok"),
        (REACH_MIN_M - 1e-4, "outside_limits"),  # the knee would have to fold beyond -2.697
        (REACH_MAX_M + 1e-4, "outside_limits"),  # the knee would have to open beyond -0.916
        (0.4 + 1e-4, "unreachable"),  # beyond the straight leg
    ],
)
def test_just_inside_and_just_outside_the_a1_reach(
    a1: Quadruped, distance: float, status: str
) -> None:
    assert abs(REACH_MIN_M - 0.088) < 5e-4 and abs(REACH_MAX_M - 0.359) < 5e-4
    feet = a1.fk([0.0, 0.8, -1.5] * 4)
    feet[0] = fr_target_at(distance, 0.3)
    result = a1.ik(feet)
    assert result.status[0] == status
    if status == "ok":
        assert result.residual_m[0] <= 1e-9
    else:  # no farther than the in-plane point on the reach circle; as near as the dense search's
        assert (
            result.residual_m[0]
            <= abs(distance - (REACH_MIN_M if distance < 0.2 else REACH_MAX_M)) + 1e-12
        )
        assert abs(result.residual_m[0] - dense_search(a1, 0, feet[0]).in_limits_m) <= 1e-8
    assert abs(np.linalg.norm(a1.fk(result.angles)[0] - feet[0]) - result.residual_m[0]) <= 1e-12
    assert not a1.joints_outside_limits(result.angles)


def test_behind_the_hip_on_the_axis_and_far_away(a1: Quadruped) -> None:
    feet = a1.fk([0.0, 0.8, -1.5] * 4)
    targets = {
        "behind the hip": A1_HIP_PITCH_FR + np.array([-0.25, 0.0, 0.05]),
        "on the roll axis (singular)": np.array([0.183, -0.047, 0.0]),
        "on the hip-pitch axis (singular: the knee folded flat)": A1_HIP_PITCH_FR,
        "on the roll axis, below": np.array([0.3, -0.047, 0.0]),
        "far away": np.array([10.0, -3.0, 7.0]),
    }
    for name, target in targets.items():
        feet[0] = target
        result = a1.ik(feet)
        assert np.isfinite(result.angles).all() and np.isfinite(result.residual_m).all(), name
        reference = dense_search(a1, 0, target)
        assert result.status[0] == reference.expected_status(), (
            name,
            result.status[0],
            reference.in_limits_m,
            reference.anywhere_m,
        )
        assert result.residual_m[0] <= reference.in_limits_m + 1e-9, name


# --- statuses over a uniform cloud, judged by a dense search ---------------------------------


class DenseSearch:
    """The nearest foot position over the joint ranges (and over full turns), by a grid search
    refined with scipy's bounded least squares from the best grid points."""

    def __init__(self, in_limits_m: float, anywhere_m: float) -> None:
        self.in_limits_m, self.anywhere_m = in_limits_m, anywhere_m

    def expected_status(self) -> str | None:
        if self.in_limits_m < 1e-7:
            return "ok"
        if self.in_limits_m > 1e-6 and self.anywhere_m < 1e-7:
            return "outside_limits"
        if self.anywhere_m > 1e-6:
            return "unreachable"
        return None  # too close to a boundary to judge


def dense_search(
    quadruped: Quadruped, slot: int, target: np.ndarray, steps: int = 24
) -> DenseSearch:
    leg = quadruped.legs[slot]
    lower, upper = ranges(quadruped)
    lower, upper = lower[3 * slot : 3 * slot + 3], upper[3 * slot : 3 * slot + 3]

    def nearest(low: np.ndarray, high: np.ndarray) -> float:
        grid = np.stack(
            np.meshgrid(*[np.linspace(a, b, steps) for a, b in zip(low, high)], indexing="ij"), -1
        ).reshape(-1, 3)
        configurations = np.zeros((len(grid), 12))
        configurations[:, 3 * slot : 3 * slot + 3] = grid
        distances = np.linalg.norm(quadruped.fk_batch(configurations)[:, slot] - target, axis=1)
        best = math.inf
        for start in grid[np.argsort(distances)[:6]]:
            fit = least_squares(
                lambda q: np.array(leg.position(*q)) - target,
                start,
                bounds=(low, high),
                xtol=1e-15,
                ftol=1e-15,
                gtol=1e-15,
            )
            best = min(best, float(np.linalg.norm(np.array(leg.position(*fit.x)) - target)))
        return best

    return DenseSearch(nearest(lower, upper), nearest(np.full(3, -math.pi), np.full(3, math.pi)))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["a1", pytest.param("aliengo", marks=pytest.mark.accept)])
def test_statuses_over_a_uniform_cloud_match_a_dense_search(name: str) -> None:
    path, feet, _ = ROBOTS[name]
    quadruped = Quadruped.from_urdf(str(path), foot_links=feet)
    rng = np.random.default_rng(3)
    hip = quadruped.fk([0.0] * 12)[0] + [0.0, 0.0, 0.4]  # the FR hip pitch height, roughly
    targets = hip + rng.uniform(-0.6, 0.6, size=(150, 3))
    rows = np.repeat(quadruped.fk([0.0, 0.8, -1.5] * 4)[np.newaxis], len(targets), axis=0)
    rows[:, 0] = targets
    batch = quadruped.ik_batch(rows)
    judged = {"ok": 0, "outside_limits": 0, "unreachable": 0}
    for row, target in enumerate(targets):
        status = four_legs.STATUS_NAMES[batch.status[row, 0]]
        single = quadruped.ik(rows[row])
        assert single.status[0] == status
        np.testing.assert_allclose(single.angles[:3], batch.angles[row, :3], rtol=0.0, atol=1e-12)
        assert abs(single.residual_m[0] - batch.residual_m[row, 0]) <= 1e-12
        assert np.isfinite(batch.angles[row]).all()
        assert not quadruped.joints_outside_limits(batch.angles[row])
        reference = dense_search(quadruped, 0, target)
        expected = reference.expected_status()
        if expected is not None:
            judged[expected] += 1
            assert status == expected, f"target {target}: {status}, dense search says {expected}"
        assert batch.residual_m[row, 0] <= reference.in_limits_m + 1e-9, (
            f"target {target}: not the nearest"
        )
    assert min(judged.values()) >= 5, judged


# --- bad input ----------------------------------------------------------------------------------


def test_non_finite_target_names_the_leg(a1: Quadruped) -> None:
    feet = a1.fk([0.0, 0.8, -1.5] * 4)
    feet[2, 1] = math.nan
    with raises_leg_fk_error("RR"):
        a1.ik(feet)
    feet[2, 1] = 0.0
    feet[3, 0] = math.inf
    with raises_leg_fk_error("RL"):
        a1.ik_batch(np.stack([feet, feet]))


@pytest.mark.parametrize("shape", [(4,), (3, 3), (4, 2), (12,)])
def test_wrong_target_shape(a1: Quadruped, shape) -> None:
    with raises_leg_fk_error("shape"):
        a1.ik(np.zeros(shape))
    with raises_leg_fk_error("shape"):
        a1.ik_batch(np.zeros((2, *shape)))


def test_bad_seed(a1: Quadruped) -> None:
    feet = a1.fk([0.0, 0.8, -1.5] * 4)
    with raises_leg_fk_error("seed"):
        a1.ik(feet, seed=[0.0] * 11)
    with raises_leg_fk_error("seed"):
        a1.ik(feet, seed=[math.nan] * 12)
    with raises_leg_fk_error("rows"):
        a1.ik_batch(feet[np.newaxis], seed=np.zeros((2, 12)))


def test_ik_solutions_of_an_unknown_leg_and_bad_point(a1: Quadruped) -> None:
    with raises_leg_fk_error("XX"):
        a1.ik_solutions("XX", (0.2, -0.1, -0.3))
    with raises_leg_fk_error("FL"):
        a1.ik_solutions("FL", (0.2, math.nan, -0.3))


def test_the_least_squares_path_agrees_with_the_closed_form_on_the_a1(a1: Quadruped) -> None:
    """The same targets through both solvers: same statuses, residuals within 1e-9 m."""
    searching = [four_legs.LegSolver(leg, use_closed_form=False) for leg in a1.legs]
    rng = np.random.default_rng(9)
    lower, upper = ranges(a1)
    inside = a1.fk_batch(rng.uniform(lower, upper, size=(6, 12)))
    outside = inside + rng.uniform(-0.3, 0.3, size=inside.shape)
    for feet in np.concatenate([inside, outside]):
        closed = a1.ik(feet)
        searched = four_legs.solve_feet(searching, feet.ravel().tolist(), None)
        assert searched.status == closed.status
        np.testing.assert_allclose(searched.residual_m, closed.residual_m, rtol=0.0, atol=1e-9)


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(st.tuples(*[st.floats(-1e6, 1e6, allow_nan=False)] * 3), st.sampled_from(LEGS))
def test_any_finite_target_gives_finite_angles_and_a_residual(
    a1: Quadruped, point, leg: str
) -> None:
    """Never a NaN or an exception for finite input; the residual is the foot's real distance."""
    result = a1.ik_leg(leg, point)
    assert all(math.isfinite(a) for a in result.angles)
    assert result.status in (four_legs.OK, four_legs.OUTSIDE_LIMITS, four_legs.UNREACHABLE)
    foot = a1.legs[LEGS.index(leg)].position(*result.angles)
    assert math.isclose(
        result.residual_m,
        float(np.linalg.norm(np.subtract(foot, point))),
        rel_tol=1e-9,
        abs_tol=1e-12,
    )


@pytest.mark.parametrize(
    "point",
    [
        (1e200, 0.0, 0.0),
        (1e300, -1e300, 1e300),
        (0.3, -1e300, 1e300),  # the roll plane's squares overflow, the knee's do not
        (5e-324, 0.0, -0.0),
        (0.183, -0.047, 0.0),
    ],
)
def test_extreme_targets_give_finite_angles_and_residuals(a1: Quadruped, point) -> None:
    """Also where the squares of the coordinates overflow (1e300): the batch and the four-leg call
    answer as the one-leg call."""
    result = a1.ik_leg("FR", point)
    assert all(math.isfinite(a) for a in result.angles) and math.isfinite(result.residual_m)
    assert result.status == four_legs.UNREACHABLE
    assert abs(result.residual_m - math.hypot(*point)) <= 1.0 + 1e-12 * math.hypot(
        *point
    )  # the leg is < 1 m from the base
    feet = a1.fk([0.0, 0.8, -1.5] * 4)
    feet[0] = point
    batch, single = a1.ik_batch(feet[np.newaxis]), a1.ik(feet)
    assert batch.status[0, 0] == four_legs.UNREACHABLE and single.status[0] == "unreachable"
    assert single.status[1:] == ("ok",) * 3 and (batch.status[0, 1:] == four_legs.OK).all()
    np.testing.assert_allclose(batch.angles[0], single.angles, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(single.angles[:3], result.angles, rtol=0.0, atol=1e-12)
    assert batch.residual_m[0, 0] == single.residual_m[0] == result.residual_m


def test_joint_ranges_wider_than_a_turn() -> None:
    """Limits -4..4 rad (8 rad > 2 pi): two values of an angle can be in range; the seed picks
    the one nearest it, and the unseeded answer is inside the limits."""
    quadruped = Quadruped.from_urdf(
        quadruped_urdf().replace('lower="-2" upper="2"', 'lower="-4" upper="4"')
    )
    rng = np.random.default_rng(21)
    q = rng.uniform(-4.0, 4.0, size=(200, 12))
    feet = quadruped.fk_batch(q)
    seeded = quadruped.ik_batch(feet, seed=q)
    assert (seeded.status == four_legs.OK).all()
    np.testing.assert_allclose(seeded.angles, q, rtol=0.0, atol=1e-9)
    unseeded = quadruped.ik_batch(feet)
    assert (unseeded.status == four_legs.OK).all() and (np.abs(unseeded.angles) <= 4.0).all()
    np.testing.assert_allclose(quadruped.fk_batch(unseeded.angles), feet, rtol=0.0, atol=1e-9)
    # By hand: the value of 3.5 rad nearest -3.5 in -4..4 is 3.5 - 2 pi = -2.783; of -3 nearest 3,
    # 3.283.
    shifted = quadruped.ik(quadruped.fk([0.0, 0.3, 3.5] * 4), seed=[0.0, 0.3, -3.5] * 4)
    assert shifted.angles[2] == pytest.approx(3.5 - 2 * math.pi, abs=1e-9)
    shifted = quadruped.ik(quadruped.fk([0.0, -3.0, 1.0] * 4), seed=[0.0, 3.0, 1.0] * 4)
    assert shifted.angles[1] == pytest.approx(2 * math.pi - 3.0, abs=1e-9)


# --- the generated closed form (the fast path) ------------------------------------------------


@pytest.mark.parametrize("name", list(ROBOTS))
def test_the_generated_closed_form_picks_the_nearest_in_limit_solution(name: str) -> None:
    """Reference: every branch the general closed form enumerates (``solutions``, with the seed
    rule), and the seed distance computed here; 400 targets around each hip, many outside the
    limits or the reach, with random seeds; the batch (generated array code) equals the scalar."""
    path, feet, _ = ROBOTS[name]
    quadruped = Quadruped.from_urdf(str(path), foot_links=feet)
    lower, upper = ranges(quadruped)
    rng = np.random.default_rng(11)
    for slot, leg in enumerate(LEGS):
        solver = quadruped._ik_solvers[slot]
        hip = quadruped.fk(np.zeros(12))[slot]
        targets = hip + rng.uniform(-0.45, 0.45, size=(400, 3))
        seeds = rng.uniform(
            lower[3 * slot : 3 * slot + 3], upper[3 * slot : 3 * slot + 3], size=(400, 3)
        )
        batch_angles, batch_status, batch_residual = solver.solve_batch(targets, seeds)
        counts = np.zeros(3, dtype=int)
        for row, (target, seed) in enumerate(zip(targets, seeds)):
            result = quadruped.ik_leg(leg, target, seed)
            inside = [s.angles for s in solver.solutions(target, seed) if s.inside_limits]
            reachable = bool(solver.solutions(target, seed))
            expected = (
                four_legs.OK
                if inside
                else four_legs.OUTSIDE_LIMITS
                if reachable
                else four_legs.UNREACHABLE
            )
            assert result.status == expected == batch_status[row], f"leg {leg} target {target}"
            counts[expected] += 1
            if inside:
                nearest = min(
                    inside, key=lambda angles: sum((a - s) ** 2 for a, s in zip(angles, seed))
                )
                np.testing.assert_allclose(result.angles, nearest, rtol=0.0, atol=1e-9)
                foot = quadruped.fk(
                    np.concatenate([np.zeros(3 * slot), result.angles, np.zeros(9 - 3 * slot)])
                )[slot]
                assert abs(result.residual_m - float(np.linalg.norm(foot - target))) <= 1e-12
            np.testing.assert_allclose(batch_angles[row], result.angles, rtol=0.0, atol=1e-12)
            assert abs(batch_residual[row] - result.residual_m) <= 1e-12
        assert counts[four_legs.OK] >= 20 and counts[four_legs.UNREACHABLE] >= 20, (leg, counts)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_four_legs_at_once_equal_each_leg_alone(name: str) -> None:
    """Reference: ``ik_leg`` of each leg (the per-leg path) on the same targets and seeds; ``ik``
    solves all four legs in one generated function when each has an in-limit solution. Targets:
    FK of random in-limit configurations, some legs pushed out of reach (then the per-leg path)."""
    path, feet, _ = ROBOTS[name]
    quadruped = Quadruped.from_urdf(str(path), foot_links=feet)
    lower, upper = ranges(quadruped)
    rng = np.random.default_rng(5)
    for trial in range(200):
        targets = quadruped.fk(rng.uniform(lower, upper))
        if trial % 4 == 3:
            targets[trial % 16 // 4] += 0.5  # one leg out of reach
        seed = rng.uniform(lower, upper)
        result = quadruped.ik(targets, seed)
        for slot, leg in enumerate(LEGS):
            alone = quadruped.ik_leg(leg, targets[slot], seed[3 * slot : 3 * slot + 3])
            assert result.status[slot] == four_legs.STATUS_NAMES[alone.status]
            assert tuple(result.angles[3 * slot : 3 * slot + 3]) == alone.angles
            # The same distance, with the cosines and sines of the branch (``ik``) or of the
            # angles.
            assert abs(result.residual_m[slot] - alone.residual_m) <= 1e-15
            foot = quadruped.fk(result.angles)[slot]
            assert (
                abs(result.residual_m[slot] - float(np.linalg.norm(foot - targets[slot]))) <= 1e-12
            )


def test_residual_of_an_angle_clamped_onto_its_limit_is_the_fk_distance() -> None:
    """Targets from angles 5e-11 rad beyond a limit (within LIMIT_TOLERANCE_RAD): the angle is
    clamped onto the limit, so the foot misses by ~1e-11 m, which the residual must show (the
    batch takes cosines from the branch, except for such rows). Reference: numpy FK distance."""
    a1 = Quadruped.from_urdf()
    lower, upper = ranges(a1)
    angles = np.tile([0.1, 0.7, -1.5], (6, 4))
    for row, joint in enumerate(range(3)):
        angles[2 * row, joint::3] = upper[joint] + 5e-11
        angles[2 * row + 1, joint::3] = lower[joint] - 5e-11
    targets = a1.fk_batch(angles)
    batch = a1.ik_batch(targets)
    assert (batch.status == four_legs.OK).all()
    distances = np.linalg.norm(a1.fk_batch(batch.angles) - targets, axis=2)
    assert distances.min() > 1e-13  # the clamping moved the feet
    np.testing.assert_allclose(batch.residual_m, distances, rtol=0.0, atol=1e-15)
    for row in range(6):
        np.testing.assert_allclose(
            a1.ik(targets[row]).residual_m, batch.residual_m[row], rtol=0.0, atol=1e-15
        )
