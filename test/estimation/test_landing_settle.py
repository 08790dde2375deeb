"""A foot that lands on a step after a flight bounces while in contact: the state filter leaves it
out for ``LANDING_SETTLE_S`` (issue 34, go2_stairs_down_6cm's vertical drift). Synthetic, by
construction: the base stands still all along (the IMU says so) over a staircase, its front feet
a tread lower than its rear ones, so its true height never changes; only the landing foot moves:
it reaches a tread lower still, lands 5 mm under that tread and springs back up onto it in 20 ms,
in contact."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from a1_leg_fk.estimation.ground import LocalGround
from a1_leg_fk.estimation.odometry import ImuReading
from a1_leg_fk.estimation.odometry_feed import LANDING_SETTLE_S, OdometryFeed
from a1_leg_fk.kinematics.quadruped import Quadruped

STEP_NS = 2_000_000
RISE_M = 0.06
"""[m] the staircase's rise."""
STILL = ImuReading((0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0), specific_force=(0.0, 0.0, 9.80665))
BOUNCE_M, BOUNCE_S = 0.005, 0.02


def _heights(bounce_m: float) -> list[float]:
    """The base's estimated heights [m] at the end of each phase: four feet standing 0.4 s (the
    front ones :data:`RISE_M` lower), a flight of 40 ms, then FR landing alone :data:`RISE_M`
    lower still, ``bounce_m`` under that tread, rising onto it over :data:`BOUNCE_S` (a half
    cosine, in contact), then standing 0.2 s."""
    quadruped = Quadruped.from_urdf()
    angles = [0.0, 0.8, -1.5] * 4
    feet = quadruped.fk_batch(np.array([angles]))[0]
    feet[:2, 2] -= RISE_M  # FR and FL on the tread below
    feed = OdometryFeed(quadruped, contacts="kinematic")
    stamp, heights = 0, [0.0]

    def phase(seconds: float, contacts: list[float], fr: Callable[[float], tuple]) -> None:
        nonlocal stamp
        for row in range(round(seconds / (STEP_NS * 1e-9))):
            stamp += STEP_NS
            below, speed = fr(row * STEP_NS * 1e-9)  # FR's height under its stance [m], [m/s]
            moved = [(tuple(foot), (0.0, 0.0, 0.0)) for foot in feet.tolist()]
            moved[0] = ((feet[0][0], feet[0][1], feet[0][2] - below), (0.0, 0.0, speed))
            feed.add_imu(stamp, STILL)
            sample = feed.step(stamp, moved, angles, [0.0] * 12, contacts)
            assert sample is not None
            heights[-1] = sample.position[2]
        heights.append(heights[-1])

    def landing(t: float) -> tuple[float, float]:
        if t >= BOUNCE_S:
            return RISE_M, 0.0
        w = np.pi / BOUNCE_S
        return RISE_M + bounce_m * (1 + np.cos(w * t)) / 2, bounce_m * w * np.sin(w * t) / 2

    phase(0.4, [1.0] * 4, lambda _: (0.0, 0.0))
    phase(0.04, [0.0] * 4, lambda _: (0.0, 0.0))
    phase(0.2, [1.0, 0.0, 0.0, 0.0], landing)
    return heights[:-1]


def test_a_foot_landing_on_a_step_after_a_flight_settles_before_it_holds_the_base() -> None:
    assert BOUNCE_S < LANDING_SETTLE_S
    still = _heights(0.0)
    assert still[-1] - still[0] == pytest.approx(0.0, abs=5e-4)  # a clean landing: no change
    # the base stood still: its height may not follow the foot's bounce (the foot held from its
    # first sample, 5 mm under the tread: its rise read as the base falling, 1.6 mm here)
    bounced = _heights(BOUNCE_M)
    assert bounced[-1] - bounced[0] == pytest.approx(0.0, abs=5e-4)


def test_a_lone_touchdown_off_the_prediction_is_a_step_only_where_the_ground_slopes() -> None:
    level, stairs = LocalGround(), LocalGround()
    for stamp in range(200):  # 0.4 s: four feet standing, the front ones a tread lower on stairs
        rows = [(0.18, -0.13, 0.0), (0.18, 0.13, 0.0), (-0.18, -0.13, 0.0), (-0.18, 0.13, 0.0)]
        level.update(stamp * 0.002, list(enumerate(rows)))
        lower = [(x, y, -RISE_M if x > 0 else 0.0) for x, y, _ in rows]
        stairs.update(stamp * 0.002, list(enumerate(lower)))
    assert not level.lands_on_a_step((0.18, -0.13, -RISE_M))  # the estimate wandered
    assert stairs.lands_on_a_step((0.18, -0.13, -2 * RISE_M))  # the next tread down
    assert not stairs.lands_on_a_step((0.18, -0.13, -RISE_M - 0.002))  # its own tread
