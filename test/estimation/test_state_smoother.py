"""The smoothed trajectory (a1_leg_fk.estimation.state_smoother, odometry_smoother): the
Rauch-Tung-Striebel pass against a dense batch least-squares solution of a small linear system
(an independent reference), its rotation part included; on a turning run known by
construction, the smoothed estimate against the filter's and its covariances below the
filter's; windows against the whole pass; the history hook leaves the live filter's output bit
for bit."""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.filter_history import FilterHistory
from a1_leg_fk.estimation.filter_model import LegMeasurement
from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.odometry import OdometrySample
from a1_leg_fk.estimation.odometry_smoother import OdometrySmoother
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.estimation.state_smoother import smooth
from a1_leg_fk.kinematics.frames import STANDARD_GRAVITY

N = 15
DT = 0.01


def _linear_system(rng: np.random.Generator, steps: int, heading: bool = False):
    """A linear system of the filter's shape: the transition (dθ turned, dθ by db_g = -dt, dv by
    db_a, dp by dv = dt), diagonal process noise densities, measurements of v, p and the
    accelerometer bias part. Without ``heading`` dθ is never observed, so its mean stays zero and
    every rotation the identity; with it the heading dθ_z is observed too and drives dv (as the
    filter's ``-R [f]x dt`` does), so the rotations turn about z alone (where composing them is
    adding their angles, exactly) while dθ_x and dθ_y, decoupled from every measurement, stay
    zero."""
    transition = np.eye(N)
    angle = 0.3 * DT
    cos, sin = math.cos(angle), math.sin(angle)
    transition[0:3, 0:3] = np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])
    transition[0:3, 9:12] = -DT * np.eye(3)
    transition[3:6, 12:15] = -DT * rng.normal(size=(3, 3))
    transition[6:9, 3:6] = DT * np.eye(3)
    density = rng.uniform(0.01, 0.5, N)
    rows = np.zeros((8 if heading else 7, N))
    rows[0:3, 3:6] = np.eye(3)  # velocity
    rows[3, 6] = rows[4, 7] = 1.0  # horizontal position
    rows[5, 12] = rows[6, 14] = 1.0  # accelerometer bias
    start = np.diag(rng.uniform(0.1, 1.0, N) ** 2)
    start[0:3, 0:3] = start[9:12, 9:12] = 0.0
    start[0:3, 0:3] += 0.01 * np.eye(3)
    start[9:12, 9:12] += 0.01 * np.eye(3)
    if heading:
        rows[7, 2] = 1.0  # the heading
        transition[3:6, 2] = DT * rng.normal(0.0, 5.0, 3)  # dv by dθ_z: a horizontal force
    noise = np.diag(rng.uniform(0.05, 0.3, len(rows)) ** 2)
    truth = [rng.multivariate_normal(np.zeros(N), start)]
    truth[0][0:3] = truth[0][9:12] = 0.0
    q = np.diag(density * DT)
    for _ in range(steps):
        truth.append(transition @ truth[-1] + rng.multivariate_normal(np.zeros(N), q))
    measured = [rows @ x + rng.multivariate_normal(np.zeros(len(rows)), noise) for x in truth]
    return transition, density, rows, noise, start, measured


def _yaw(angle: float) -> np.ndarray:
    """The rotation by ``angle`` [rad] about z."""
    cos, sin = math.cos(angle), math.sin(angle)
    return np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])


def _filtered_history(system, steps: int):
    """A textbook Kalman filter (written here) over ``system``, recording its steps into a
    FilterHistory as the state filter does (the rotation: the error's dθ_z as a yaw, the rest
    nominal); the history and the last state (rotation, nominal, covariance)."""
    transition, density, rows, noise, start, measured = system
    q = np.diag(density * DT)
    history = FilterHistory(density, capacity=4)
    x = np.zeros(N)
    p = start.copy()

    def update(x, p, z):
        s = rows @ p @ rows.T + noise
        gain = p @ rows.T @ np.linalg.inv(s)
        return x + gain @ (z - rows @ x), (np.eye(N) - gain @ rows) @ p

    x, p = update(x, p, measured[0])
    for k in range(steps):
        history.before(k, _yaw(x[2]), x[3:], p)
        x, p = transition @ x, transition @ p @ transition.T + q
        history.after(transition, _yaw(x[2]), x[3:])
        x, p = update(x, p, measured[k + 1])
    assert np.allclose(x[0:2], 0.0, atol=1e-15)
    return history, (_yaw(x[2]), x[3:], p)


def _batch_solution(system, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Every state at once: the normal equations (prior, dynamics and measurements weighted by
    their inverse covariances); the mean ((steps + 1) * 15) and its covariance."""
    transition, density, rows, noise, start, measured = system
    size = (steps + 1) * N
    information, vector = np.zeros((size, size)), np.zeros(size)
    information[:N, :N] += np.linalg.inv(start)
    q_inverse, r_inverse = np.linalg.inv(np.diag(density * DT)), np.linalg.inv(noise)
    for k in range(steps + 1):
        block = slice(k * N, (k + 1) * N)
        information[block, block] += rows.T @ r_inverse @ rows
        vector[block] += rows.T @ r_inverse @ measured[k]
        if k < steps:
            both = np.zeros((N, size))
            both[:, block] = -transition
            both[:, (k + 1) * N : (k + 2) * N] = np.eye(N)
            information += both.T @ q_inverse @ both
    covariance = np.linalg.inv(information)
    return covariance @ vector, covariance


def test_rts_equals_the_batch_least_squares_solution() -> None:
    """The smoother's means and covariances over the textbook filter's history equal the batch
    solution (its inverse's diagonal blocks the covariances); the rotation stays the identity."""
    steps = 25
    system = _linear_system(np.random.default_rng(3), steps)
    history, end = _filtered_history(system, steps)
    states = smooth(history, end, steps)
    mean, covariance = _batch_solution(system, steps)
    for k in range(steps):
        block = slice(k * N, (k + 1) * N)
        assert np.allclose(states.nominals[k], mean[block][3:], atol=1e-8), k
        assert np.allclose(states.rotations[k], np.eye(3))
        assert np.allclose(
            states.covariances[k][3:, 3:], covariance[block, block][3:, 3:], atol=1e-8
        )


def test_rts_with_a_heading_equals_the_batch_solution_rotation_included() -> None:
    """The smoother's rotation path (the updates' injection ``Log(R⁻ᵀ R)``, the smoothed
    ``R Exp(δθ)``) and the orientation's rows and columns of the covariances: with the heading
    observed and driving the velocity, the smoothed rotations are the yaws of the batch
    solution's heading, and every mean and the whole 15 x 15 covariances equal it."""
    steps = 40
    system = _linear_system(np.random.default_rng(8), steps, heading=True)
    history, end = _filtered_history(system, steps)
    states = smooth(history, end, steps)
    mean, covariance = _batch_solution(system, steps)
    headings = mean[2 : steps * N : N]
    assert np.abs(headings).max() > 0.05  # the rotations do turn
    for k in range(steps):
        block = slice(k * N, (k + 1) * N)
        assert np.allclose(states.rotations[k], _yaw(headings[k]), rtol=0, atol=1e-12), k
        assert np.allclose(states.nominals[k], mean[block][3:], rtol=0, atol=1e-10), k
        assert np.allclose(states.covariances[k], covariance[block, block], rtol=0, atol=1e-10), k


SPEED, YAW_RATE, STEP_NS = 0.5, 0.4, 2_000_000
FEET = ((0.18, -0.13, -0.3), (0.18, 0.13, -0.3), (-0.18, -0.13, -0.3), (-0.18, 0.13, -0.3))
JJT = (0.05, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 0.05)
UP_G = np.array([0.0, 0.0, STANDARD_GRAVITY])


def _turning_run(seconds: float, history: bool, window_s: float = 8.0):
    """A level base turning on a circle at SPEED [m/s] and YAW_RATE [rad/s], trotting (two feet
    standing, the diagonals swapped every 0.2 s); the gyro, accelerometer and feet as that
    motion makes them, with white noise (seeded). The filter's samples, and the smoothed ones
    when ``history``."""
    rng = np.random.default_rng(11)
    state = StateFilter()
    smoother = OdometrySmoother(state, window_s, 2.0) if history else None
    causal: list[OdometrySample] = []
    smoothed: list[OdometrySample] = []
    true_body = np.array([SPEED, 0.0, 0.0])
    turn = np.array([0.0, 0.0, YAW_RATE])
    for k in range(round(seconds * 1e9 / STEP_NS)):
        stamp = (k + 1) * STEP_NS
        gyro = turn + rng.normal(0.0, 0.005, 3)
        force = np.cross(turn, true_body) + UP_G + rng.normal(0, 0.05, 3)
        state.propagate(stamp, tuple(gyro), tuple(force), (0.0, 0.0, 0.0, 1.0) if k == 0 else None)
        legs: list[LegMeasurement | None] = [None] * 4
        for leg in (0, 3) if (k // 100) % 2 == 0 else (1, 2):
            e = true_body + np.cross(turn, FEET[leg]) + rng.normal(0.0, 0.02, 3)
            legs[leg] = LegMeasurement(FootMotion(tuple(e), FEET[leg], 0.3), 0.99, JJT)
        used = state.update(stamp, legs)
        sample = state.sample(stamp, [leg for leg in range(4) if legs[leg]], used)
        causal.append(sample)
        if smoother is not None:
            smoothed += smoother.add(sample, k + 1)
    if smoother is not None:
        smoothed += smoother.finish()
    return causal, smoothed, state


def _velocity_errors(samples: list[OdometrySample]) -> np.ndarray:
    return np.array([s.linear for s in samples]) - (SPEED, 0.0, 0.0)


def test_a_turning_run_is_smoothed_below_the_filters_error_and_covariance() -> None:
    causal, smoothed, _ = _turning_run(20.0, history=True)
    assert [s.stamp_ns for s in smoothed] == [s.stamp_ns for s in causal]
    settled = slice(500, None)  # after the first second
    filtered_rmse = np.sqrt((_velocity_errors(causal)[settled] ** 2).sum(axis=1).mean())
    smoothed_rmse = np.sqrt((_velocity_errors(smoothed)[settled] ** 2).sum(axis=1).mean())
    print(f"velocity RMSE: filter {filtered_rmse:.5f} m/s, smoothed {smoothed_rmse:.5f} m/s")
    # a velocity driven by white noise, seen in white noise: at steady state the smoothed
    # variance is half the filtered one (Wiener process; 10 % for a 19 s sample)
    assert smoothed_rmse**2 <= 0.55 * filtered_rmse**2
    twist_f = np.array([s.twist_variance[:3] for s in causal])
    twist_s = np.array([s.twist_variance[:3] for s in smoothed])
    assert (twist_s <= twist_f * (1 + 1e-9)).all()
    errors = _velocity_errors(smoothed)[settled]
    inside = (np.abs(errors) <= 3.0 * np.sqrt(twist_s[settled])).all(axis=1).mean()
    print(f"smoothed velocity error within 3 sigma on {100 * inside:.1f} % of the samples")
    assert inside >= 0.95


def test_smoothed_covariances_are_below_the_filtered_ones() -> None:
    """Pˢ <= P: the difference's eigenvalues are not negative (to rounding), on every step."""
    state = StateFilter()
    history = state.keep_history()
    rng = np.random.default_rng(5)
    for k in range(600):
        stamp = (k + 1) * STEP_NS
        state.propagate(stamp, tuple(rng.normal(0, 0.01, 3)), (0.0, 0.0, STANDARD_GRAVITY), None)
        legs = [
            LegMeasurement(FootMotion(tuple(rng.normal(0, 0.02, 3)), FEET[leg], 0.3), 0.99, JJT)
            for leg in range(4)
        ]
        state.update(stamp, legs)
    filtered = history.covariances[: history.count].copy()
    states = smooth(history, (state.rotation, state.nominal, state.covariance), history.count)
    for before, after in zip(filtered, states.covariances):
        scale = np.sqrt(np.outer(np.diag(before), np.diag(before)))
        assert np.linalg.eigvalsh((before - after) / scale).min() >= -1e-9


def test_windows_are_the_whole_pass_within_a_few_percent_of_the_error() -> None:
    """8 s windows with 2 s overlap against one pass over the whole 20 s run: the windows cost
    under 2 % of the smoothed error (the biases, slowly observed, carry a little information
    further than 2 s)."""
    _, windowed, _ = _turning_run(20.0, history=True)
    _, whole, _ = _turning_run(20.0, history=True, window_s=1e3)
    difference = np.abs(np.array([s.linear for s in windowed]) - [s.linear for s in whole])
    rmse = [
        np.sqrt((_velocity_errors(s)[500:] ** 2).sum(axis=1).mean()) for s in (windowed, whole)
    ]
    print(
        f"windows against the whole pass: velocity within {difference.max():.2e} m/s; RMSE "
        f"{rmse[0]:.6f} against {rmse[1]:.6f} m/s"
    )
    assert rmse[0] <= 1.02 * rmse[1] and difference.max() <= 1e-3


def test_the_history_leaves_the_filter_bit_for_bit() -> None:
    """The live filter's samples, with and without the offline hook: identical floats."""
    plain, _, live = _turning_run(3.0, history=False)
    kept, _, offline = _turning_run(3.0, history=True)
    assert live.history is None and offline.history is not None
    assert plain == kept
