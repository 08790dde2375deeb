"""Each standing foot's rise above its own foothold, by hand: the foothold follows a foot that
gives under load, a foot held in swing has none (a touchdown on a higher tread starts a new one),
and the standing feet's spread is their RMS rise averaged over 0.5 s."""

from __future__ import annotations

import math

import pytest

from a1_leg_fk.estimation.foot_rise import SPREAD_TIME_S, FootRise

NAN = math.nan


def test_the_foothold_follows_the_give_and_the_rise_is_above_it() -> None:
    rise = FootRise()
    for height in (0.010, 0.008, 0.009):  # lands at 10 mm, gives 2 mm, unloads 1 mm
        rise.update(0.002, [height, 0.0, 0.0, 0.0], [True] * 4)
    assert rise.footholds[0] == pytest.approx(0.008)
    assert rise.rises[0] == pytest.approx(0.001)
    assert rise.rises[1:] == [0.0, 0.0, 0.0]


def test_a_swing_foot_has_no_foothold_and_a_new_stance_starts_one() -> None:
    rise = FootRise()
    rise.update(0.002, [0.0] * 4, [True] * 4)
    rise.update(0.002, [0.05, 0.0, NAN, 0.0], [False, True, True, True])  # FL swings, RR unknown
    assert math.isnan(rise.rises[0]) and math.isnan(rise.footholds[0])
    assert math.isnan(rise.rises[2])
    rise.update(0.002, [0.04, 0.0, 0.0, 0.0], [True] * 4)  # FL lands on a tread 4 cm up
    assert rise.footholds[0] == pytest.approx(0.04) and rise.rises[0] == 0.0


def test_the_spread_is_the_standing_feets_rms_rise_over_half_a_second() -> None:
    rise = FootRise()
    rise.update(0.002, [0.0] * 4, [True] * 4)
    steps = 500  # 1 s: the mean square at 1 - (1 - 0.004)^500 of its value
    for _ in range(steps):
        rise.update(0.002, [0.002, 0.002, 0.0, 0.0], [True] * 4)  # mean square 2e-6 m^2
    share = 0.002 / SPREAD_TIME_S
    expected = math.sqrt(2e-6 * (1.0 - (1.0 - share) ** steps))
    assert rise.spread_m == pytest.approx(expected, rel=1e-9)
