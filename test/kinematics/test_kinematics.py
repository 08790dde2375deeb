"""Forward kinematics (a1_leg_fk.kinematics.quadruped) against hand-computed poses, closed forms,
symmetry and finite differences.

Independent references only: the reference write-up's FR poses, a closed-form A1 leg typed here
from the URDF numbers (hip at (+-0.183, +-0.047, 0), thigh offset +-0.08505 m, two 0.2 m links),
central finite differences of the positions, and ``0.4 cos(q / 2)`` for the reach.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet_data
import pytest
from conftest import raises_leg_fk_error
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from references import a1_foot_closed_form
from shared import LEGS, STANDING
from shared import PYBULLET_NAMES as A1_JOINT_NAMES

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.urdf import LegFkError

DATA = Path(pybullet_data.getDataPath())
MINI_CHEETAH_FEET = {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"}

# A1 limits as typed in a1.urdf [rad]: hip roll, hip pitch ("upper"), knee ("lower").
A1_LOWER = np.tile([-0.802851455917, -1.0471975512, -2.69653369433], 4)
A1_UPPER = np.tile([0.802851455917, 4.18879020479, -0.916297857297], 4)

PROPERTY = settings(max_examples=60, deadline=None, derandomize=True, database=None)
any_angles = hnp.arrays(np.float64, 12, elements=st.floats(-math.pi, math.pi))
in_limit_angles = hnp.arrays(np.float64, 12, elements=st.floats(0.0, 1.0)).map(
    lambda u: A1_LOWER + u * (A1_UPPER - A1_LOWER)
)
leg_angles = st.tuples(*[st.floats(-math.pi, math.pi)] * 3)


@pytest.fixture(scope="module")
def a1() -> Quadruped:
    return Quadruped.from_urdf()


def central_difference(function, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """d function(q) / dq by central differences: (..., len(q))."""
    columns = []
    for slot in range(len(q)):
        dq = np.zeros_like(q)
        dq[slot] = step
        columns.append((function(q + dq) - function(q - dq)) / (2.0 * step))
    return np.stack(columns, axis=-1)


# --- the reference write-up's poses ---------------------------------------------------------


@pytest.mark.parametrize(
    ("angles", "expected"),
    [
        ((0.0, 0.8, -1.5), (0.1684, -0.1320, -0.2923)),  # standing
        ((0.0, 0.8, -2.697), (0.2290, -0.1320, -0.0753)),  # knee most bent
        ((0.5, 0.8, -1.5), (0.1684, 0.0185, -0.2973)),  # hip rolled inward
        ((0.0, 0.8, -0.916), (0.0627, -0.1320, -0.3380)),  # knee most extended
        ((0.0, 0.0, 0.0), (0.183, -0.132, -0.400)),  # all joints zero (outside the knee range)
    ],
    ids=["standing", "knee-most-bent", "hip-inward", "knee-most-extended", "zero"],
)
def test_reference_fr_poses_to_a_tenth_of_a_millimetre(a1: Quadruped, angles, expected) -> None:
    q = list(angles) + STANDING[3:]
    np.testing.assert_allclose(a1.fk(q)[0], expected, rtol=0.0, atol=1e-4)
    np.testing.assert_allclose(a1.legs[0].position(*angles), expected, rtol=0.0, atol=1e-4)


def test_all_zero_feet_exactly(a1: Quadruped) -> None:
    """y is -0.047 - 0.08505 = -0.13205 m, not the rounded -0.132."""
    expected = [
        (0.183, -0.13205, -0.4),
        (0.183, 0.13205, -0.4),
        (-0.183, -0.13205, -0.4),
        (-0.183, 0.13205, -0.4),
    ]
    np.testing.assert_allclose(a1.fk([0.0] * 12), expected, rtol=0.0, atol=1e-12)


def test_a1_joint_order_and_base_frame(a1: Quadruped) -> None:
    assert list(a1.joint_names) == A1_JOINT_NAMES
    assert a1.base_frame == "trunk"


@PROPERTY
@given(any_angles)
def test_fk_equals_the_closed_form_a1_leg(a1: Quadruped, q: np.ndarray) -> None:
    expected = [a1_foot_closed_form(leg, *q[3 * i : 3 * i + 3]) for i, leg in enumerate(LEGS)]
    np.testing.assert_allclose(a1.fk(q), expected, rtol=0.0, atol=1e-12)


def test_mini_cheetah_zero_pose_and_its_minus_y_axes() -> None:
    """Hand-computed from mini_cheetah.urdf: hip (0.19, -+0.049, 0), thigh -+0.062, links 0.209 and
    0.18 m.

    Its pitch and knee axes are (0, -1, 0): a positive pitch swings the foot forward (+x).
    """
    cheetah = Quadruped.from_urdf(
        str(DATA / "mini_cheetah" / "mini_cheetah.urdf"), foot_links=MINI_CHEETAH_FEET
    )
    expected = [
        (0.19, -0.111, -0.389),
        (0.19, 0.111, -0.389),
        (-0.19, -0.111, -0.389),
        (-0.19, 0.111, -0.389),
    ]
    np.testing.assert_allclose(cheetah.fk([0.0] * 12), expected, rtol=0.0, atol=1e-12)
    swung = cheetah.fk([0.0, 0.5, 0.0] * 4)[0]
    np.testing.assert_allclose(
        swung, (0.19 + 0.389 * math.sin(0.5), -0.111, -0.389 * math.cos(0.5)), rtol=0.0, atol=1e-12
    )


# --- symmetry -----------------------------------------------------------------------------


@PROPERTY
@given(leg_angles)
def test_left_legs_mirror_right_legs(a1: Quadruped, angles) -> None:
    """FL(q0, q1, q2) = FR(-q0, q1, q2) with y negated; the same for RL and RR."""
    q0, q1, q2 = angles
    feet = a1.fk([q0, q1, q2, -q0, q1, q2, q0, q1, q2, -q0, q1, q2])
    mirror = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(feet[1], feet[0] * mirror, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(feet[3], feet[2] * mirror, rtol=0.0, atol=1e-12)


@PROPERTY
@given(leg_angles)
def test_front_and_rear_legs_are_0_366_m_apart(a1: Quadruped, angles) -> None:
    feet = a1.fk(list(angles) * 4)
    np.testing.assert_allclose(feet[0] - feet[2], (0.366, 0.0, 0.0), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(feet[1] - feet[3], (0.366, 0.0, 0.0), rtol=0.0, atol=1e-12)


# --- batch == single ----------------------------------------------------------------------


@PROPERTY
@given(
    hnp.arrays(
        np.float64, st.tuples(st.integers(1, 6), st.just(12)), elements=st.floats(-10.0, 10.0)
    )
)
def test_batch_equals_single(a1: Quadruped, q: np.ndarray) -> None:
    rates = np.cos(np.arange(q.size, dtype=float)).reshape(q.shape) * 3.0
    positions = a1.fk_batch(q)
    jacobians = a1.jacobians_batch(q)
    velocities = a1.foot_velocities_batch(q, rates)
    assert positions.shape == (len(q), 4, 3)
    assert jacobians.shape == (len(q), 4, 3, 3)
    assert velocities.shape == (len(q), 4, 3)
    for row in range(len(q)):
        np.testing.assert_allclose(positions[row], a1.fk(q[row]), rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(jacobians[row], a1.jacobians(q[row]), rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(
            velocities[row], a1.foot_velocities(q[row], rates[row]), rtol=0.0, atol=1e-12
        )


def test_batch_equals_single_across_block_boundaries(a1: Quadruped) -> None:
    """More rows than one internal block (4096), and an odd count."""
    q = np.random.default_rng(7).uniform(A1_LOWER, A1_UPPER, size=(9001, 12))
    positions = a1.fk_batch(q)
    single = np.array([a1.fk(row) for row in q])
    np.testing.assert_allclose(positions, single, rtol=0.0, atol=1e-12)
    assert a1.fk_batch(np.empty((0, 12))).shape == (0, 4, 3)


def test_batch_accepts_lists_and_float32(a1: Quadruped) -> None:
    q = [STANDING, [0.0] * 12]
    np.testing.assert_allclose(a1.fk_batch(q)[1], a1.fk([0.0] * 12), rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(
        a1.fk_batch(np.array(q, dtype=np.float32))[0],
        a1.fk(np.array(STANDING, dtype=np.float32)),
        atol=1e-12,
    )


# --- Jacobians and velocities -------------------------------------------------------------


@PROPERTY
@given(any_angles)
def test_jacobian_equals_central_finite_differences(a1: Quadruped, q: np.ndarray) -> None:
    jacobians = a1.jacobians(q)
    full = central_difference(a1.fk, q)  # (4, 3, 12)
    for leg in range(4):
        expected = full[leg, :, 3 * leg : 3 * leg + 3]
        scale = np.abs(expected).max()
        np.testing.assert_allclose(jacobians[leg], expected, rtol=0.0, atol=1e-6 * scale)
        # A leg's foot does not move with another leg's joints.
        others = np.delete(full[leg], np.s_[3 * leg : 3 * leg + 3], axis=1)
        assert np.abs(others).max() == 0.0


def test_jacobian_at_zero_by_hand(a1: Quadruped) -> None:
    """All zero, FR, columns = joint axis x (foot - joint origin) [m/rad]:

    d/dq0 = x × (0, -0.08505, -0.4) = (0, 0.4, -0.08505); d/dq1 = y × (0, 0, -0.4) = (-0.4, 0, 0);
    d/dq2 = y × (0, 0, -0.2) = (-0.2, 0, 0).
    """
    expected = np.array([[0.0, -0.4, -0.2], [0.4, 0.0, 0.0], [-0.08505, 0.0, 0.0]])
    np.testing.assert_allclose(a1.jacobians([0.0] * 12)[0], expected, rtol=0.0, atol=1e-12)


@PROPERTY
@given(any_angles, hnp.arrays(np.float64, 12, elements=st.floats(-20.0, 20.0)))
def test_foot_velocities_equal_jacobian_times_rates(
    a1: Quadruped, q: np.ndarray, rates: np.ndarray
) -> None:
    expected = np.einsum("lij,lj->li", a1.jacobians(q), rates.reshape(4, 3))
    np.testing.assert_allclose(a1.foot_velocities(q, rates), expected, rtol=0.0, atol=1e-12)


def test_foot_velocities_follow_the_positions_along_a_trajectory(a1: Quadruped) -> None:
    """q(t) = standing + a sin(w t + phase): velocities ~ central differences of fk in time."""
    rng = np.random.default_rng(3)
    amplitude, omega, phase = (
        rng.uniform(0.1, 0.4, 12),
        rng.uniform(2.0, 12.0, 12),
        rng.uniform(0, 2 * np.pi, 12),
    )

    def angles(t: np.ndarray) -> np.ndarray:
        return np.array(STANDING) + amplitude * np.sin(omega * t[:, None] + phase)

    t, step = np.linspace(0.0, 1.0, 201), 1e-6
    rates = amplitude * omega * np.cos(omega * t[:, None] + phase)
    expected = (a1.fk_batch(angles(t + step)) - a1.fk_batch(angles(t - step))) / (2.0 * step)
    velocities = a1.foot_velocities_batch(angles(t), rates)
    scale = np.abs(expected).max()
    assert scale > 0.5  # the feet really move [m/s]
    np.testing.assert_allclose(velocities, expected, rtol=0.0, atol=1e-6 * scale)
    for row in range(0, len(t), 20):
        np.testing.assert_allclose(
            a1.foot_velocities(angles(t)[row], rates[row]),
            expected[row],
            rtol=0.0,
            atol=1e-6 * scale,
        )


# --- limits and reach ---------------------------------------------------------------------


def test_knee_zero_is_outside_its_limits(a1: Quadruped) -> None:
    q = list(STANDING)
    q[2] = 0.0
    violations = a1.joints_outside_limits(q)
    assert len(violations) == 1
    violation = violations[0]
    assert violation.joint == "FR_lower_joint"
    assert violation.value == 0.0
    assert (violation.lower, violation.upper) == (-2.69653369433, -0.916297857297)


def test_all_zero_reports_the_four_knees(a1: Quadruped) -> None:
    assert [v.joint for v in a1.joints_outside_limits([0.0] * 12)] == [
        f"{leg}_lower_joint" for leg in LEGS
    ]


def test_in_limit_and_boundary_angles_are_not_reported(a1: Quadruped) -> None:
    assert a1.joints_outside_limits(STANDING) == []
    assert a1.joints_outside_limits(A1_LOWER) == []
    assert a1.joints_outside_limits(A1_UPPER) == []
    above = A1_UPPER.copy()
    above[7] += 1e-9
    assert [v.joint for v in a1.joints_outside_limits(above)] == ["RR_upper_joint"]


@PROPERTY
@given(in_limit_angles)
def test_random_in_limit_angles_are_not_reported(a1: Quadruped, q: np.ndarray) -> None:
    assert a1.joints_outside_limits(q) == []


def test_continuous_joints_are_never_reported() -> None:
    aliengo = Quadruped.from_urdf(
        str(DATA / "aliengo" / "aliengo.urdf")
    )  # hip pitch ("upper") is continuous
    q = [0.0, 100.0, -1.5] * 4
    assert aliengo.joints_outside_limits(q) == []
    q[2] = 0.0  # aliengo's knee is limited to [-2.775, -0.646]
    assert [v.joint for v in aliengo.joints_outside_limits(q)] == ["FR_lower_joint"]
    cheetah = Quadruped.from_urdf(
        str(DATA / "mini_cheetah" / "mini_cheetah.urdf"), foot_links=MINI_CHEETAH_FEET
    )
    assert cheetah.joints_outside_limits([1e3, -1e3, 50.0] * 4) == []


@pytest.mark.parametrize("leg", LEGS)
def test_a1_reach_is_0_4_cos_half_knee(a1: Quadruped, leg: str) -> None:
    """Two 0.2 m links: the foot is 0.4 cos(q / 2) from the hip-pitch axis."""
    knee_lower, knee_upper = -2.69653369433, -0.916297857297
    reach = a1.reach(leg)
    assert reach.leg == leg
    assert reach.min_m == pytest.approx(0.4 * math.cos(knee_lower / 2.0), abs=1e-9)
    assert reach.min_m == pytest.approx(0.088, abs=5e-4)
    assert reach.knee_at_min == pytest.approx(knee_lower, abs=1e-9)
    assert reach.max_m == pytest.approx(0.4 * math.cos(knee_upper / 2.0), abs=1e-9)
    assert reach.max_m == pytest.approx(0.359, abs=5e-4)
    assert reach.knee_at_max == pytest.approx(knee_upper, abs=1e-9)
    assert reach.max_unlimited_m == pytest.approx(0.400, abs=1e-9)
    assert math.remainder(reach.knee_at_max_unlimited, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_mini_cheetah_reach_with_a_continuous_knee() -> None:
    """Links 0.209 and 0.18 m: sqrt(0.209^2 + 0.18^2 + 2 0.209 0.18 cos q), 0.389 at 0 and 0.029 at
    +-pi."""
    cheetah = Quadruped.from_urdf(
        str(DATA / "mini_cheetah" / "mini_cheetah.urdf"), foot_links=MINI_CHEETAH_FEET
    )
    reach = cheetah.reach("RL")
    assert reach.max_m == pytest.approx(0.389, abs=1e-9)
    assert reach.knee_at_max == pytest.approx(0.0, abs=1e-9)
    assert reach.min_m == pytest.approx(0.029, abs=1e-9)
    assert abs(reach.knee_at_min) == pytest.approx(math.pi, abs=1e-9)
    assert reach.max_unlimited_m == pytest.approx(0.389, abs=1e-9)


def test_reach_of_an_unknown_leg(a1: Quadruped) -> None:
    with raises_leg_fk_error("'LF'"):
        a1.reach("LF")


# --- names --------------------------------------------------------------------------------


def test_angles_from_unitree_and_pybullet_data_names(a1: Quadruped) -> None:
    names = {}
    for slot, leg in enumerate(LEGS):
        names[f"{leg}_hip_joint"] = 0.1 * slot
        names[f"{leg}_thigh_joint" if slot % 2 else f"{leg}_upper_joint"] = 0.8 + 0.01 * slot
        names[f"{leg}_calf_joint" if slot < 2 else f"{leg}_lower_joint"] = -1.5 - 0.01 * slot
    q = a1.angles_from_names(names)
    assert q == pytest.approx(
        [0.0, 0.8, -1.5, 0.1, 0.81, -1.51, 0.2, 0.82, -1.52, 0.3, 0.83, -1.53]
    )
    assert a1.name_to_slot["FR_thigh_joint"] == a1.name_to_slot["FR_upper_joint"] == 1
    assert a1.name_to_slot["FR_calf_joint"] == a1.name_to_slot["FR_lower_joint"] == 2


def test_user_alias_map() -> None:
    aliases = {f"{leg.lower()}_knee": f"{leg}_lower_joint" for leg in LEGS}
    quadruped = Quadruped.from_urdf(joint_aliases=aliases)
    names = {f"{leg}_{part}_joint": 0.0 for leg in LEGS for part in ("hip", "upper")}
    names |= {f"{leg}_knee": -1.0 - 0.1 * i for i, leg in enumerate(("fr", "fl", "rr", "rl"))}
    q = quadruped.angles_from_names(names)
    assert q[2::3] == pytest.approx([-1.0, -1.1, -1.2, -1.3])


def test_unknown_joint_name(a1: Quadruped) -> None:
    names = dict.fromkeys(A1_JOINT_NAMES, 0.0) | {"FR_knee_joint": -1.0}
    with raises_leg_fk_error("'FR_knee_joint'"):
        a1.angles_from_names(names)


def test_missing_joint_names(a1: Quadruped) -> None:
    names = dict.fromkeys(A1_JOINT_NAMES, 0.0)
    del names["RL_hip_joint"]
    with raises_leg_fk_error("RL_hip_joint"):
        a1.angles_from_names(names)


def test_nan_from_names_names_the_slot(a1: Quadruped) -> None:
    names = dict.fromkeys(A1_JOINT_NAMES, 0.0) | {"RR_upper_joint": math.nan}
    with raises_leg_fk_error("slot 7", "RR", "nan"):
        a1.angles_from_names(names)


# --- input refusals -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("bad", "slot", "leg"), [(math.nan, 4, "FL"), (math.inf, 11, "RL"), (-math.inf, 0, "FR")]
)
def test_non_finite_angle(a1: Quadruped, bad: float, slot: int, leg: str) -> None:
    q = list(STANDING)
    q[slot] = bad
    for call in (
        lambda: a1.fk(q),
        lambda: a1.jacobians(q),
        lambda: a1.joints_outside_limits(q),
        lambda: a1.foot_velocities(q, [0.0] * 12),
    ):
        with raises_leg_fk_error(f"slot {slot}", f"leg {leg}", str(bad)):
            call()


def test_non_finite_rate(a1: Quadruped) -> None:
    rates = [0.0] * 12
    rates[5] = math.nan
    with raises_leg_fk_error("joint velocities", "slot 5", "FL"):
        a1.foot_velocities(STANDING, rates)


def test_non_finite_batch_row(a1: Quadruped) -> None:
    q = np.tile(STANDING, (6, 1))
    q[4, 9] = math.nan
    q[5, 0] = math.inf
    for call in (
        lambda: a1.fk_batch(q),
        lambda: a1.jacobians_batch(q),
        lambda: a1.foot_velocities_batch(q, np.zeros_like(q)),
    ):
        with raises_leg_fk_error("rows [4, 5]"):
            call()
    with raises_leg_fk_error("joint velocities", "rows [4, 5]"):
        a1.foot_velocities_batch(np.tile(STANDING, (6, 1)), q)


@pytest.mark.parametrize("count", [0, 11, 13])
def test_wrong_number_of_angles(a1: Quadruped, count: int) -> None:
    for call in (
        lambda: a1.fk([0.0] * count),
        lambda: a1.jacobians([0.0] * count),
        lambda: a1.foot_velocities(STANDING, [0.0] * count),
    ):
        with raises_leg_fk_error("12", f"got {count}"):
            call()


def test_non_numeric_angles(a1: Quadruped) -> None:
    with raises_leg_fk_error("12 numbers"):
        a1.fk(["zero"] * 12)  # type: ignore[list-item]  # not numbers, on purpose
    with pytest.raises(LegFkError):
        a1.fk(None)  # type: ignore[arg-type]  # not a sequence, on purpose


@pytest.mark.parametrize("shape", [(5, 11), (12,), (2, 12, 1), (3, 13)])
def test_wrong_batch_shape(a1: Quadruped, shape) -> None:
    q = np.zeros(shape)
    for call in (lambda: a1.fk_batch(q), lambda: a1.jacobians_batch(q)):
        with raises_leg_fk_error("(N, 12)", str(shape)):
            call()


def test_mismatched_velocity_batch(a1: Quadruped) -> None:
    with raises_leg_fk_error("(3, 12)", "(4, 12)"):
        a1.foot_velocities_batch(np.zeros((4, 12)), np.zeros((3, 12)))
