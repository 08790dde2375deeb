"""Each standing foot's rise above its own foothold, by hand: the foothold follows a foot that
gives under load, a foot held in swing has none (a touchdown on a higher tread starts a new one)
a foot lands where it came down to and stays for 20 ms, and the standing feet's spread is their
RMS rise averaged over 0.5 s."""

from __future__ import annotations

import math

import pytest

from a1_leg_fk.estimation.foot_rise import LANDED_S, SPREAD_TIME_S, FootRise

NAN = math.nan
LEVEL = (0.0, 0.0)


def up(heights: list[float]) -> list[tuple[float, float, float] | None]:
    """Contact points straight up from the frame's origin (NaN: an unknown foot, None)."""
    return [None if math.isnan(h) else (0.0, 0.0, h) for h in heights]


def test_the_foothold_follows_the_give_and_the_rise_is_above_it() -> None:
    rise = FootRise()
    for height in (0.010, 0.008, 0.009):  # lands at 10 mm, gives 2 mm, unloads 1 mm
        rise.update(0.002, up([height, 0.0, 0.0, 0.0]), LEVEL, [True] * 4)
    assert rise.footholds[0] == pytest.approx((0.0, 0.0, 0.008))
    assert rise.rises[0] == pytest.approx(0.001)
    assert rise.rises[1:] == [0.0, 0.0, 0.0]


def test_a_swing_foot_has_no_foothold_and_a_new_stance_starts_one() -> None:
    rise = FootRise()
    rise.update(0.002, up([0.0] * 4), LEVEL, [True] * 4)
    swinging = [False, True, True, True]  # FL swings, RR unknown
    rise.update(0.002, up([0.05, 0.0, NAN, 0.0]), LEVEL, swinging)
    assert math.isnan(rise.rises[0]) and rise.footholds[0] is None
    assert math.isnan(rise.rises[2])
    rise.update(0.002, up([0.04, 0.0, 0.0, 0.0]), LEVEL, [True] * 4)  # FL lands on a tread 4 cm up
    assert rise.footholds[0] == pytest.approx((0.0, 0.0, 0.04)) and rise.rises[0] == 0.0


def test_the_spread_is_the_standing_feets_rms_rise_over_half_a_second() -> None:
    rise = FootRise()
    rise.update(0.002, up([0.0] * 4), LEVEL, [True] * 4)
    steps = 500  # 1 s: the mean square at 1 - (1 - 0.004)^500 of its value
    for _ in range(steps):
        rise.update(0.002, up([0.002, 0.002, 0.0, 0.0]), LEVEL, [True] * 4)  # mean square 2e-6 m^2
    share = 0.002 / SPREAD_TIME_S
    expected = math.sqrt(2e-6 * (1.0 - (1.0 - share) ** steps))
    assert rise.spread_m == pytest.approx(expected, rel=1e-9)


def test_a_foot_lands_where_it_came_down_and_stays_for_20_ms() -> None:
    """FL held in swing comes down in 5 mm steps to 4 cm and stays within 1 mm (the band 1.5
    mm): it has landed 20 ms (10 samples) after it got there; FR comes *up* to 4 cm and stays
    (the top of an arc held still): it never lands; RL drifts down 1 mm per sample: never
    within the band for long; RR stands, comes down 5 mm and stays: it lands too."""
    assert LANDED_S == 0.02
    rise = FootRise()
    standing = [False, False, True, False]
    down = [0.055, 0.05, 0.045, 0.04] + [0.04 + 0.001 * (n % 2) for n in range(16)]
    rows = [
        [d, min(0.025 + 0.005 * n, 0.04), 0.005 if n == 0 else 0.0, 0.03 - 0.001 * n]
        for n, d in enumerate(down)
    ]
    landed = []
    for row in rows:
        rise.update(0.002, up(row), LEVEL, standing, band_m=0.0015)
        landed.append([leg for leg in range(4) if rise.landed[leg]])
    assert [0 in legs for legs in landed] == [False] * 13 + [True] * 7  # there from the 4th
    assert [2 in legs for legs in landed] == [False] * 11 + [True] * 9  # there from the 2nd
    assert all(1 not in legs and 3 not in legs for legs in landed)
    assert rise.footholds[0] is None and math.isnan(rise.rises[0])  # no foothold in swing


def test_a_slope_fitted_anew_does_not_move_a_standing_foot() -> None:
    """A foot stands still 2 m along x from the frame's origin while the slope is fitted anew
    from level to -0.05 (on stairs the plane through footholds on two treads jumps by degrees):
    against its own foothold, with today's slope, it has not risen (its height with the slope
    taken off about the origin rose by 0.05 x 2 m = 10 cm, a liftoff and a 10 cm spread); 1 mm
    up, it has risen 1 mm."""
    rise = FootRise()
    still = [(2.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
    rise.update(0.002, still, LEVEL, [True] * 4)
    rise.update(0.002, still, (-0.05, 0.0), [True] * 4)
    assert rise.rises == [0.0] * 4 and rise.spread_m == 0.0
    rise.update(0.002, [(2.0, 0.0, 0.001), *still[1:]], (-0.05, 0.0), [True] * 4)
    assert rise.rises[0] == pytest.approx(0.001)


def test_a_foot_is_over_the_highest_other_foothold_not_above_it() -> None:
    """The tread under a foot, by hand (band 1.5 mm, two levels 16 mm apart): FR and FL stand on
    a tread at 0, RR and RL on one 4 cm up. RL lifts to 5 cm: 1 cm over RR's foothold (its own
    is not its tread); FR is 0 over FL's; a foot 1 mm below a tread (within the band) is on it:
    -1 mm. RR alone up there while RL swings at 2 cm: RR is 4 cm over the lower tread, RL 2 cm
    (RR's tread is above it). Every standing foot on one level (RR and RL 1 cm up): none."""
    rise = FootRise()
    band, step = 0.0015, 0.016

    def over(heights: list[float], standing: list[bool]) -> list[float] | None:
        points = up(heights)
        rise.update(0.002, points, LEVEL, standing, band_m=band)
        return rise.over_treads(points, LEVEL, band, step)

    assert over([0.0, 0.0, 0.04, 0.04], [True] * 4) == pytest.approx([0.0] * 4)
    assert over([0.0, 0.0, 0.039, 0.05], [True] * 4) == pytest.approx([0.0, 0.0, -0.001, 0.011])
    assert over([0.0, 0.0, 0.04, 0.02], [True, True, True, False]) == pytest.approx(
        [0.0, 0.0, 0.04, 0.02]
    )
    unknown = over([0.0, NAN, 0.04, 0.02], [True] * 4)
    assert unknown is not None and math.isnan(unknown[1])
    assert over([0.0, 0.0, 0.01, 0.01], [True] * 4) is None  # one level
    assert over([0.0, 0.0, 0.04, 0.02], [False] * 4) is None  # none stood
