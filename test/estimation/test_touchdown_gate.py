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
    cannot tell them) vote not. Two level votes to one slope vote: treads; one each: not (no
    more level votes than slope votes), nor before the first; a vote counts from the next
    sample on."""
    gate = TouchdownGate(DEFAULT_MIN_SIGMA_M, 3.0)
    assert not gate.treads()
    gate.compare(0.001, (0.012, 0.0), 0.0)
    assert not gate.treads()  # not in its own sample
    gate.close_sample()
    assert gate.treads()
    gate.compare(-0.018, (-0.02, 1e-6), 0.0)
    gate.compare(0.02, (0.040, 0.0), 0.0)  # a step: neither
    gate.compare(0.0, (0.004, 0.0), 0.0)  # the two too near to tell
    gate.close_sample()
    assert not gate.treads()
    gate.compare(0.0, (-0.011, 0.0), 0.0)
    gate.close_sample()
    assert gate.treads()


def _anchors_down_stairs(rise_m: float) -> list[float]:
    """A trot down a staircase (edges across x every 0.3 m, steps ``rise_m`` down), the base
    from x = 0.2 m at 0.5 m/s (a stride of 0.2 m per 0.4 s cycle: shorter than a tread, as the
    Aliengo's on 4 cm steps), the feet at (±0.2, ∓0.13) m about it landing where they are in
    diagonal pairs, standing half a cycle, their heights exact: per sample and standing foot,
    its anchor under it less its tread's height [m]."""
    offsets = [(0.2, -0.13), (0.2, 0.13), (-0.2, -0.13), (-0.2, 0.13)]
    ground, errors = LocalGround(), []
    feet: dict[int, tuple[float, float, float]] = {}
    for row in range(1200):
        stamp = row * 0.005
        pair = (0, 3) if stamp % 0.4 < 0.2 else (1, 2)
        for leg in pair:
            x = 0.2 + 0.5 * stamp + offsets[leg][0]
            feet.setdefault(leg, (x, offsets[leg][1], -rise_m * (math.floor(x / 0.3) + 1)))
        feet = {leg: feet[leg] for leg in pair}
        ground.update(stamp, list(feet.items()))
        for leg, point in feet.items():
            under = ground.under([(leg, point)], 4)[leg]
            assert under is not None
            errors.append(under[0] - point[2])
    return errors


def test_down_a_staircase_a_step_is_not_taken_for_the_slopes_prediction() -> None:
    """:func:`_anchors_down_stairs` (3, 4 and 5 cm steps): every foot is anchored on its own
    tread, by construction (within 1 mm). The feet that land on their nearest foothold's tread
    vote for the level prediction; offered the slope's prediction carried from that foothold
    (the rule before), a foot that stepped a tread down took it where it lay within the 15 mm
    gate, and the feet after it took its error on: 104, 46 and 15 mm off at worst (0.72 % of
    the path on Unitree's Aliengo down 4 cm steps with noise)."""
    for rise in (0.03, 0.04, 0.05):
        assert max(map(abs, _anchors_down_stairs(rise))) < 1e-3, rise
