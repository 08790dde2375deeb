"""Whether a touchdown takes the ground's prediction (a1_leg_fk.estimation.touchdown_gate): its
noise by where its height comes from, against hand numbers and touchdowns built by hand."""

from __future__ import annotations

import math

import pytest

from a1_leg_fk.estimation.ground import LocalGround
from a1_leg_fk.estimation.ground_plane import DEFAULT_MIN_SIGMA_M
from a1_leg_fk.estimation.touchdown_gate import TouchdownGate

RATE_HZ = 500.0
STANCE_SAMPLES = 50
"""0.1 s stances at 500 Hz."""


def test_a_touchdowns_noise_by_where_its_height_comes_from() -> None:
    """Hand numbers (base noise 5 mm, gate 3 sigmas): against the standing feet, 5 mm whatever
    the estimate's variance; alone, the estimate's own, sqrt(5² + 15²) = 15.81 mm with its
    height's sigma 15 mm, so a touchdown 40 mm off agrees (3 x 15.81 = 47.4 mm) where with a
    sure estimate it is a step (15 mm); a prediction's own variance (10 mm)² widens the gate
    to 3 sqrt(10² + 5²) = 33.5 mm."""
    gate = TouchdownGate(0.005, 3.0)
    assert gate.sigma_m(False, False, 0.015**2) == 0.005
    alone = gate.sigma_m(True, True, 0.015**2)
    assert alone == pytest.approx(math.sqrt(0.005**2 + 0.015**2), rel=1e-12)
    assert gate.agrees(0.040, 0.0, alone) and not gate.agrees(0.048, 0.0, alone)
    assert not gate.agrees(0.016, 0.0, gate.sigma_m(True, True, 0.0))
    assert gate.agrees(0.033, 0.010**2, 0.005) and not gate.agrees(0.034, 0.010**2, 0.005)


def test_the_touchdowns_scatter_widens_a_lone_ones_noise_on_level_ground_only() -> None:
    """Eight offsets of 1, 2, ..., 8 cm counted (a wandering estimate's), one a sample: their
    lower quartile, 3 cm, over a normal sigma's 0.3186 is the noise of a lone touchdown where
    the ground is level, from the sample after the eighth on; not where it slopes (a step
    there), nor against the standing feet."""
    gate = TouchdownGate(DEFAULT_MIN_SIGMA_M, 3.0)
    for offset in range(1, 8):
        gate.count(-0.01 * offset)
        gate.close_sample()
    assert gate.scatter_m() == DEFAULT_MIN_SIGMA_M  # fewer than half of the 16
    gate.count(0.08)
    assert gate.scatter_m() == DEFAULT_MIN_SIGMA_M  # not in its own sample
    gate.close_sample()
    assert gate.scatter_m() == pytest.approx(0.03 / 0.3186, rel=1e-12)
    assert gate.sigma_m(True, False, 0.0) == pytest.approx(0.03 / 0.3186, rel=1e-12)
    assert gate.sigma_m(True, True, 0.0) == DEFAULT_MIN_SIGMA_M
    assert gate.sigma_m(False, False, 0.0) == DEFAULT_MIN_SIGMA_M


def _walk_down(ground: LocalGround, stances: int, first: float, give: float) -> list[float]:
    """Two feet taking turns (one standing at a time, the one that lifts measured in the
    sample the other lands), 0.1 m a stance along x, over a floor with a stair ``first`` m
    down at x = 1.05 m; each touchdown's first sample ``give`` [m] off its foot's height,
    alternately up and down, between the first and the stair (an impact's give: the noise the
    gate is for), none after. Per stance, the anchor under its foot [m]."""
    anchors = []
    for stance in range(stances):
        leg, x = stance % 2, 0.1 * stance
        floor = first if x > 1.05 else 0.0
        impact = (give if stance % 2 else -give) if stance > 0 and x < 1.05 else 0.0
        for sample in range(STANCE_SAMPLES):
            t = (stance * STANCE_SAMPLES + sample) / RATE_HZ
            ground.update(t, [(leg, (x, 0.0, floor + (impact if sample == 0 else 0.0)))])
        under = ground.under([(leg, (x, 0.0, math.nan))], 4)[leg]
        assert under is not None
        anchors.append(under[0])
    return anchors


def test_a_stair_after_touchdowns_that_gave_is_still_a_stair() -> None:
    """Ten touchdowns each 13 mm up or down at its impact (within the gate: each takes the
    floor's prediction), then a stair 30 mm down: the foot after it is anchored on the lower
    tread and stays there, by construction. The offsets the gate took, counted as the
    touchdowns' noise (the rule before), widened it to 3 x 13 / 0.3186 = 122 mm and the stair
    was taken for the floor (30 mm off; a1_stairs_down_4cm with noise: 24-40 mm steps taken,
    vertical drift 0.73 %)."""
    ground = LocalGround()
    anchors = _walk_down(ground, 16, -0.03, 0.013)
    assert anchors[:11] == pytest.approx([0.0] * 11, abs=1e-9)
    assert anchors[11:] == pytest.approx([-0.03] * 5, abs=1e-9)


def test_a_lone_touchdown_takes_the_prediction_as_far_as_the_estimate_is_unsure() -> None:
    """A foot standing on a level floor, a flight, and a foot landing alone 20 mm above the
    floor as the estimate places it (its own height: the estimate's error): with the estimate's
    vertical sigma 10 mm (3 sqrt(5² + 10²) = 33.5 mm) it takes the floor's height; sure of its
    height (sigma 0: 15 mm), it keeps its own, a step."""
    for sigma, expected in ((0.010, 0.0), (0.0, 0.02)):
        ground = LocalGround()
        for sample in range(STANCE_SAMPLES):
            ground.update(sample / RATE_HZ, [(0, (0.0, 0.0, 0.0))])
        ground.update(STANCE_SAMPLES / RATE_HZ, [])
        ground.update((STANCE_SAMPLES + 1) / RATE_HZ, [(1, (0.1, 0.0, 0.02))], sigma**2)
        under = ground.under([(1, (0.1, 0.0, math.nan))], 4)[1]
        assert under is not None and under[0] == pytest.approx(expected, abs=1e-12), sigma


def test_the_touchdowns_vote_between_the_slopes_prediction_and_the_level_one() -> None:
    """Hand numbers (base noise 5 mm, gate 3 sigmas, so 15 mm): a touchdown 1 mm off the level
    prediction and 12 mm off the slope's votes level; one 2 mm off the slope's and 20 mm off the
    level one votes slope; a step (20 mm off both) and predictions 4 mm apart (the touchdown
    cannot tell them) vote not. The ground is treads from the eighth level vote on (half of the
    16 kept: the level votes' scatter, their offsets' lower quartile over a normal sigma's, is
    known), a vote counting from the next sample on, while the level votes outnumber the
    slope's; level votes 4 mm off (4 / 0.3186 = 12.6 mm of scatter, more than the 5 mm base
    noise) make no treads."""
    gate = TouchdownGate(DEFAULT_MIN_SIGMA_M, 3.0)
    for vote in range(8):
        assert not gate.treads(), vote
        gate.compare(0.001, (0.012, 0.0), 0.0)
        gate.close_sample()
    assert gate.treads()
    for _ in range(7):
        gate.compare(-0.018, (-0.02, 1e-6), 0.0)
    gate.compare(0.02, (0.040, 0.0), 0.0)  # a step: neither
    gate.compare(0.0, (0.004, 0.0), 0.0)  # the two too near to tell
    gate.close_sample()
    assert gate.treads()  # 8 level votes to 7
    gate.compare(-0.018, (-0.02, 1e-6), 0.0)
    gate.close_sample()
    assert not gate.treads()  # 8 to 8
    gate = TouchdownGate(DEFAULT_MIN_SIGMA_M, 3.0)
    for _ in range(8):
        gate.compare(0.004, (0.02, 0.0), 0.0)
    gate.close_sample()
    assert not gate.treads()


def _shuffle_then_step(jitter_m: float) -> float:
    """Two feet stand on a staircase's lower tread (z -4 cm, edge at x = 0.3 m) at (0.45, ±0.3)
    m; a third takes 24 short steps on the upper tread (z 0), at x = 0 and 0.15 m in turn (0.1 s
    standing, 0.02 s lifted, 500 Hz; footholds kept 0.1 s, so each touchdown's nearest is the
    last one, 0.15 m away), measured on its tread the first time, then ``jitter_m`` [m] above
    it at x = 0.15 m and as much below at x = 0; then it steps down to x = 0.42 m. Its anchor
    there less its tread's height [m]."""
    ground = LocalGround(window_s=0.1)
    lower = [(0, (0.45, -0.3, -0.04)), (2, (0.45, 0.3, -0.04))]
    stamp = 0.0
    for shuffle in range(24):
        height = (jitter_m if shuffle % 2 else -jitter_m) if shuffle else 0.0
        foot = (1, (0.15 * (shuffle % 2), 0.0, height))
        for sample in range(60):
            ground.update(stamp, lower + ([foot] if sample < 50 else []))
            stamp += 1.0 / RATE_HZ
    landed = (1, (0.42, 0.0, -0.04))
    ground.update(stamp, [*lower, landed])
    under = ground.under([landed], 3)[1]
    assert under is not None
    return under[0] + 0.04


def test_a_step_off_a_tread_is_not_taken_for_the_slopes_prediction() -> None:
    """:func:`_shuffle_then_step`, heights exact: the feet standing together measure the slope
    (-0.04 / 0.375 m on average), the short steps land on their nearest foothold's tread (the
    level prediction's, exactly; the slope's 15 mm off), and the step down lands 12 mm from the
    slope's prediction carried 0.27 m from the last foothold: by construction it is anchored on
    its tread, its own height (the slope's taken, the rule before: 12.2 mm off, as the
    Aliengo's feet down 4 cm steps with noise, 0.72 % of the path). With the short steps
    measured 6 mm above and below their tread in turn (feet on a nosing, landing early: the
    A1's on 4 cm steps, 5-9 mm), the level votes' scatter (6 / 0.3186 mm) is more than the base
    noise and the slope's prediction stays offered: 12 mm off, as before."""
    assert _shuffle_then_step(0.0) == pytest.approx(0.0, abs=1e-9)
    assert _shuffle_then_step(0.006) == pytest.approx(0.012, abs=1e-3)
