"""The local ground (a1_leg_fk.estimation.ground) against footholds built by hand: a known plane,
noisy footholds (Monte Carlo against the reported covariance), feet in a line, too few feet, the
window, and the contact points of a turned base."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from a1_leg_fk.estimation.ground import LocalGround
from a1_leg_fk.estimation.ground_plane import DEFAULT_MIN_SIGMA_M, DEFAULT_SLOPE_PRIOR, fit_plane
from a1_leg_fk.estimation.leg_motion import contact_points

FOOTHOLDS = [(x, y) for x in (-0.2, -0.05, 0.1, 0.25) for y in (-0.13, 0.13)]
"""[m] two strides of a trot's footholds about the base (odom x, y)."""


def _on_plane(a: float, b: float, c: float, noise: np.ndarray | None = None) -> list:
    heights = [a + b * x + c * y for x, y in FOOTHOLDS]
    if noise is not None:
        heights = list(np.add(heights, noise))
    return [(x, y, z) for (x, y), z in zip(FOOTHOLDS, heights)]


def _rx(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def test_a_known_plane_is_found_with_its_normal_and_tilt() -> None:
    b, c = math.tan(math.radians(10.0)), -math.tan(math.radians(4.0))  # 10° up x, 4° down y
    plane = fit_plane(_on_plane(0.3, b, c), (0.5, -0.2))
    assert plane is not None and plane.footholds == 8
    assert plane.height_m == pytest.approx(0.3 + 0.5 * b - 0.2 * c, abs=1e-4)
    assert plane.gradient == pytest.approx((b, c), abs=1e-3)
    by_hand = np.array([-b, -c, 1.0]) / math.sqrt(1 + b * b + c * c)
    assert plane.normal == pytest.approx(tuple(by_hand), abs=1e-3)
    tilted = _ry(plane.pitch) @ _rx(plane.roll) @ [0.0, 0.0, 1.0]
    assert tuple(tilted) == pytest.approx(tuple(by_hand), abs=1e-3)
    assert plane.slope_deg == pytest.approx(math.degrees(math.acos(by_hand[2])), abs=0.05)
    # exact footholds: the noise floor, not zero
    assert math.sqrt(plane.covariance[0][0]) >= 0.3 * DEFAULT_MIN_SIGMA_M


def test_the_reported_covariance_matches_the_scatter_of_noisy_fits() -> None:
    """2,000 fits of footholds with 1 cm of noise: the height's and tilt's errors against the
    true plane have the spread the fits report (within 25 %), and each lies within its 3 sigma
    on >= 95 % of the fits (the residuals of 8 footholds estimate the noise: Student's t, 5
    degrees of freedom, 97 %)."""
    rng = np.random.default_rng(3)
    b, c = 0.15, 0.05
    errors, sigmas = [], []
    truth = (0.1, -math.atan(b), math.atan2(c, math.sqrt(1 + b * b)))
    for _ in range(2000):
        plane = fit_plane(_on_plane(0.1, b, c, rng.normal(0.0, 0.01, 8)), (0.0, 0.0))
        assert plane is not None
        errors.append(np.subtract((plane.height_m, plane.pitch, plane.roll), truth))
        cov = plane.covariance
        sigmas.append(np.sqrt([cov[0][0], cov[2][2], cov[1][1]]))
    spread, reported = np.std(errors, axis=0), np.sqrt(np.mean(np.square(sigmas), axis=0))
    assert reported == pytest.approx(spread, rel=0.25)
    inside = (np.abs(errors) <= 3 * np.array(sigmas)).mean(axis=0)
    assert inside.min() >= 0.95, inside


def test_feet_in_a_line_leave_the_slope_across_them_level_and_uncertain() -> None:
    points = [(x, 0.0, 0.1 * x) for x in (-0.2, 0.0, 0.2, 0.4)]
    plane = fit_plane(points, (0.0, 0.0))
    assert plane is not None
    assert plane.gradient == pytest.approx((0.1, 0.0), abs=1e-3)
    assert plane.covariance[1][1] > 0.9 * DEFAULT_SLOPE_PRIOR**2  # roll: across the line
    assert plane.covariance[2][2] < 1e-3  # pitch: along it


def test_one_foothold_gives_its_height_and_no_slope() -> None:
    plane = fit_plane([(1.0, 2.0, 0.25)], (1.0, 2.0))
    assert plane is not None
    assert plane.height_m == pytest.approx(0.25) and plane.gradient == (0.0, 0.0)
    assert plane.covariance[2][2] == pytest.approx(DEFAULT_SLOPE_PRIOR**2, rel=0.01)
    assert fit_plane([], (0.0, 0.0)) is None


def test_footholds_are_stances_kept_for_the_window() -> None:
    ground = LocalGround(window_s=1.0, max_footholds=3)
    assert ground.plane(0.0, 0.0) is None
    ground.update(0.0, [(0, (0.1, 0.1, 0.0)), (3, (-0.1, -0.1, 0.0))])
    ground.update(0.1, [(0, (0.12, 0.1, 0.02)), (3, (-0.1, -0.1, 0.0))])
    assert np.allclose(ground.points(), [(0.1, 0.1, 0.0), (-0.1, -0.1, 0.0)])  # touchdowns
    ground.update(0.2, [(1, (0.1, -0.1, 0.0))])  # 0 and 3 lift: two footholds
    assert [foothold.samples for foothold in ground.footholds] == [2, 2]
    # the stance's mean (x, y) at its touchdown's anchored height, not the sinking foot's mean
    assert np.allclose(ground.footholds[0].point, (0.11, 0.1, 0.0))
    assert len(ground.points()) == 3
    ground.update(1.25, [(1, (0.1, -0.1, 0.0))])  # 0.2 + 1.0 < 1.25: both expired
    assert len(ground.footholds) == 0 and len(ground.points()) == 1
    for stamp in range(5):  # at most three kept
        ground.update(2.0 + stamp / 10, [(stamp % 2 * 2, (0.0, 0.0, 0.0))])
    assert len(ground.footholds) == 3


def test_contact_points_turn_the_feet_into_odom_and_drop_the_radius() -> None:
    half = math.radians(90.0) / 2.0  # yaw 90°: base x is odom y
    orientation = (0.0, 0.0, math.sin(half), math.cos(half))
    feet = [(0.2, -0.1, -0.3), None, (-0.2, -0.1, -0.3), (-0.2, 0.1, -0.3)]
    points = contact_points((1.0, 2.0, 0.3), orientation, feet, [0.02] * 4, [0, 1, 3])
    assert [leg for leg, _ in points] == [0, 3]
    assert points[0][1] == pytest.approx((1.1, 2.2, -0.02))
    assert points[1][1] == pytest.approx((0.9, 1.8, -0.02))


def test_the_kept_fit_moved_to_the_base_is_the_fit_about_the_base() -> None:
    """LocalGround fits once about its footholds' centre and moves the plane to the point asked
    for: the same numbers as a fit about that point."""
    rng = np.random.default_rng(5)
    points = _on_plane(0.2, 0.12, -0.07, rng.normal(0.0, 0.01, 8))
    ground = LocalGround(max_footholds=8, step_gate=1e-9)  # every foothold at its own height
    for stamp, point in enumerate(points):
        ground.update(stamp * 0.1, [(stamp % 4, point)])
    ground.update(0.8, [])
    direct = fit_plane(points, (0.7, -0.3))
    moved = ground.plane(0.7, -0.3)
    assert direct is not None and moved is not None
    assert moved.height_m == pytest.approx(direct.height_m, abs=1e-9)
    assert np.allclose(moved.covariance, direct.covariance, rtol=1e-6, atol=1e-12)


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="settings"):
        LocalGround(window_s=0.0)


def test_touchdowns_are_anchored_on_the_ground_not_on_the_drifting_estimate() -> None:
    """A trot's diagonals (0.2 s each, 0.1 m apart) over a floor with a 4 cm step up at x = 1 m,
    the contact points carrying the estimate's drift (2 cm/s up, common to every foot of a
    sample): a touchdown's height is taken against the standing feet's anchors, so the drift
    cancels (but for the 10 ms between the last sample of the feet that lift and the first of
    those that land: 0.2 mm a step); where the floor predicts it (level, the same tread) the
    foothold takes the prediction, where a step lifts it, its own height: every anchor is the
    truth's."""
    ground = LocalGround()
    for step in range(40):
        pair = (0, 3) if step % 2 == 0 else (1, 2)
        feet = []
        for leg in pair:
            x = 0.1 * step + (0.18 if leg < 2 else -0.18)
            feet.append((leg, x, 0.13 if leg % 2 else -0.13, 0.04 if x > 1.0 else 0.0))
        for t in (0.2 * step, 0.2 * step + 0.19):  # touchdown, the stance's last sample
            ground.update(t, [(leg, (x, y, z + 0.02 * t)) for leg, x, y, z in feet])
        anchored = ground.under([(leg, (x, y, math.nan)) for leg, x, y, _ in feet], 4)
        for leg, x, _, z in feet:
            assert anchored[leg] == pytest.approx((z, 0.0), abs=5e-4), (step, leg, x)


def test_a_tilt_below_a_degree_is_taken_as_level() -> None:
    """A trot over a flat floor seen through an IMU mounted 0.3° off (the noise model's mounting
    error: every contact point's height tilted by tan 0.3° along x): the feet's differences show a
    0.3° slope, which the anchors do not follow (a floor taken for a slope would climb 0.5 % of
    the path); a 5° slope, which they do."""
    for degrees, follows in ((0.3, False), (5.0, True)):
        slope = math.tan(math.radians(degrees))
        ground = LocalGround()
        for step in range(30):
            pair = (0, 3) if step % 2 == 0 else (1, 2)
            feet = [(leg, 0.1 * step + (0.18 if leg < 2 else -0.18), 0.13 if leg % 2 else -0.13)
                    for leg in pair]  # fmt: skip
            for t in (0.2 * step, 0.2 * step + 0.19):
                ground.update(t, [(leg, (x, y, slope * x)) for leg, x, y in feet])
        heights = [z for _, _, z in ground.points()]
        xs = [x for x, _, _ in ground.points()]
        expected = [slope * x for x in xs] if follows else [heights[0]] * len(xs)
        assert heights == pytest.approx(expected, abs=2e-3), degrees


def test_a_rolling_foot_on_a_slope_keeps_its_ground_from_stance_to_stance() -> None:
    """A trot down a 10° slope (dz/dx = -tan 10°) whose feet roll: each stance's contact point
    moves 6 mm along the slope from touchdown to liftoff, its height with it; the estimate drifts
    2 cm/s up, common to every foot. The ground under a standing foot is its anchor carried along
    the slope it landed on, and a foothold's height the one at its stance's mean point, so the
    anchors stay on the slope: within 1.5 mm of it, growing less than 0.3 mm over 50 steps. (A
    foothold kept at its touchdown's height but its mean point put each stance tan 10° x 3 mm =
    0.53 mm above the slope going down: 13 mm over the 50 steps, the odometry's 0.36 % clean
    vertical drift on the family's a1_slope_down_10.)"""
    slope = -math.tan(math.radians(10.0))
    ground = LocalGround()
    errors = []
    for step in range(60):
        pair = (0, 3) if step % 2 == 0 else (1, 2)
        feet = [(leg, 0.1 * step + (0.18 if leg < 2 else -0.18), 0.13 if leg % 2 else -0.13)
                for leg in pair]  # fmt: skip
        for rolled, t in ((0.0, 0.0), (0.003, 0.095), (0.006, 0.19)):
            stamp = 0.2 * step + t
            points = [(leg, (x + rolled, y, slope * (x + rolled) + 0.02 * stamp))
                      for leg, x, y in feet]  # fmt: skip
            ground.update(stamp, points)
        under = [ground_ for ground_ in ground.under(points, 4) if ground_ is not None]
        errors.append(max(abs(z - slope * x) for (z, _), (_, (x, _, _)) in zip(under, points)))
    assert max(errors) < 1.5e-3
    assert abs(errors[-1] - errors[10]) < 3e-4
    for x, _, z in ground.points():
        assert z == pytest.approx(slope * x, abs=1.5e-3)


def _trot_step(ground: LocalGround, step: int, height: Callable[[float], float]) -> None:
    """Step ``step`` of a trot 0.1 m a step (FR and RL, then FL and RR, 0.36 m apart along x,
    0.26 m across; each stance 0.19 s long in two samples) on the ground ``height`` (x) [m]."""
    pair = (0, 3) if step % 2 == 0 else (1, 2)
    feet = [(leg, 0.1 * step + (0.18 if leg < 2 else -0.18), 0.13 if leg % 2 else -0.13)
            for leg in pair]  # fmt: skip
    for t in (0.2 * step, 0.2 * step + 0.19):
        ground.update(t, [(leg, (x, y, height(x))) for leg, x, y in feet])


def test_unanchored_footholds_keep_their_measured_heights() -> None:
    """``anchored=False`` (the contact filter's footholds): a foothold is its stance's mean
    contact point, height too (a foot sinking 2 cm: 1 cm), and a trot onto an 8° ramp (flat to
    x = 0.3 m) fits the ramp's slope, tan 8° = 0.1405, within 0.002 once every foothold is on it
    (anchored, the touchdowns snap to the lagging slope's and the level predictions: 0.1315)."""
    ground = LocalGround(anchored=False)
    ground.update(0.0, [(0, (0.1, 0.1, 0.0))])
    ground.update(0.1, [(0, (0.12, 0.1, -0.02))])
    ground.update(0.2, [])
    assert ground.footholds[0].point == pytest.approx((0.11, 0.1, -0.01))
    slope = math.tan(math.radians(8.0))
    ground = LocalGround(anchored=False)
    for step in range(30):
        _trot_step(ground, step, lambda x: slope * max(x - 0.3, 0.0))
    assert min(x for x, _, _ in ground.points()) > 0.3
    plane = ground.plane(3.0, 0.0)
    assert plane is not None
    assert plane.gradient[0] == pytest.approx(slope, abs=0.002)


def test_the_reported_plane_leaves_out_a_stance_too_short_to_be_a_foothold() -> None:
    """A trot up a 10° slope (footholds on z = tan 10° x, each stance 0.19 s), and one foot's
    stance of 10 ms, 2 cm above the slope (the contact estimate's flicker as a foot lands before
    it settles): the reported plane keeps the slope, tan 10° = 0.1763, within 0.002 and the
    height under the base within 1 mm; the plane through every stance (what the filter holds a
    landing foot to, unchanged) is tilted by the flicker (0.1846 here)."""
    slope = math.tan(math.radians(10.0))
    ground = LocalGround(anchored=False)
    for step in range(12):
        _trot_step(ground, step, lambda x: slope * x)
        if step == 10:  # leg 1 (swinging) touches 2 cm high for 10 ms
            flicker = (0.1 * step + 0.25, 0.13, slope * (0.1 * step + 0.25) + 0.02)
            for t in (0.2 * step + 0.192, 0.2 * step + 0.198):
                ground.update(t, [(1, flicker)])
            ground.update(0.2 * step + 0.199, [])
    assert all(foothold.point != flicker for foothold in ground.settled)
    reported, every = ground.reported(1.2, 0.0), ground.plane(1.2, 0.0)
    assert reported is not None and every is not None
    assert reported.gradient[0] == pytest.approx(slope, abs=0.002)
    assert reported.height_m == pytest.approx(slope * 1.2, abs=0.001)
    assert abs(every.gradient[0] - slope) > 0.005


def test_a_short_stance_alone_still_gives_the_reported_ground() -> None:
    """The first foot to land flickers (10 ms) and lifts; no foot stands for a while: the
    reported ground is that stance's (a level plane at its 0.3 m), not none, until a foothold
    that counts comes."""
    ground = LocalGround()
    ground.update(0.0, [(0, (0.2, -0.1, 0.3))])
    ground.update(0.01, [])
    assert not ground.settled and len(ground.footholds) == 1
    reported = ground.reported(0.0, 0.0)
    assert reported is not None and reported.height_m == pytest.approx(0.3)
    assert reported.gradient == pytest.approx((0.0, 0.0), abs=1e-9)


def _turns(ground: LocalGround, stances: int, flight: bool, drift: float) -> list[float]:
    """Two feet taking turns, one on the floor (0 m), the other on a 4 cm box 0.3 m ahead, one
    standing at a time, 0.1 s each at 500 Hz, the estimate drifting ``drift`` [m/s] up (every
    point of a sample alike); ``flight``: a sample with no foot standing before each stance (its
    touchdown has no foot to take its height against). Each stance's anchor under its foot [m].
    """
    treads = {0: (0.3, 0.0, 0.04), 1: (0.0, 0.0, 0.0)}
    anchors = []
    for stance in range(stances):
        leg = stance % 2
        x, y, z = treads[leg]
        for sample in range(50):
            t = 0.1 * stance + 0.002 * sample
            ground.update(t, [] if flight and sample == 0 else [(leg, (x, y, z + drift * t))])
        under = ground.under([(leg, (x, y, math.nan))], 4)[leg]
        assert under is not None
        anchors.append(under[0])
    return anchors


def test_a_step_taken_against_the_standing_feet_stays_a_step() -> None:
    """The feet taking turns on the floor and the box (:func:`_turns`, drifting 2 cm/s); the
    footholds last 0.05 s, so each touchdown's prediction is the other foot's tread: every
    touchdown is a 4 cm step, its height taken against the foot that lifts in its sample (the
    drift cancels but for the one sample between: 0.04 mm a stance). Every anchor is its
    tread's, by construction: a step is no touchdown noise (counted as such, the steps made
    that noise 12.6 cm after eight, and the ninth was taken for the other tread, 4 cm off, as
    on a1_stairs_down_4cm); a touchdown taken against a standing foot counts toward no scatter."""
    ground = LocalGround(window_s=0.05)
    anchors = _turns(ground, 24, flight=False, drift=0.02)
    assert anchors == pytest.approx([0.04 * (1 - stance % 2) for stance in range(24)], abs=1e-3)
    assert ground.gate.scatter_m() == DEFAULT_MIN_SIGMA_M


def test_touchdowns_with_no_foot_to_measure_against_widen_the_noise_by_their_offsets() -> None:
    """The same two treads with a flight before each touchdown (no drift): its height is the
    estimate's own, and its offset from the prediction counts as the touchdowns' noise, taken
    or not (an IMU that jumps moves such touchdowns by cm as a rule: the retargeted Laikago
    walk's): after eight 4 cm offsets the noise of a lone touchdown on level ground is their
    lower quartile over a normal sigma's, 0.04 / 0.3186; a touchdown taken against a standing
    foot keeps the base noise (its height is not the estimate's)."""
    ground = LocalGround(window_s=0.05)
    _turns(ground, 9, flight=True, drift=0.0)
    assert ground.gate.scatter_m() == pytest.approx(0.04 / 0.3186, rel=1e-9)
    assert ground.gate.sigma_m(True, False, 0.0) == pytest.approx(0.04 / 0.3186, rel=1e-9)
    assert ground.gate.sigma_m(False, False, 0.0) == DEFAULT_MIN_SIGMA_M


def test_a_planes_slope_across_a_heading_is_replaced_its_height_and_slope_along_kept() -> None:
    """``with_slope_across`` against a rotation done with numpy: a plane (a, b, c) = (0.3, 0.2,
    0.1) and a covariance, heading 30°: its slope along (0.2 cos 30° + 0.1 sin 30° = 0.2232)
    and height kept, its slope across -0.05 with variance 1e-4 and no correlation with the rest;
    the covariance the plane's turned into (height, along, across), across replaced, turned back.
    """
    from a1_leg_fk.estimation.ground_plane import with_slope_across

    heading = math.radians(30.0)
    along = (math.cos(heading), math.sin(heading))
    covariance = ((4e-4, 1e-5, -2e-5), (1e-5, 3e-3, 5e-4), (-2e-5, 5e-4, 2e-3))
    solution, turned = with_slope_across((0.3, 0.2, 0.1), covariance, along, -0.05, 1e-4)
    across = (-along[1], along[0])
    slope = 0.2 * along[0] + 0.1 * along[1]
    assert slope == pytest.approx(0.2232, abs=1e-4)
    expected = np.array(along) * slope - 0.05 * np.array(across)
    assert np.allclose(solution, (0.3, *expected))
    rotation = np.array([[1.0, 0.0, 0.0], [0.0, *along], [0.0, *across]])
    inner = rotation @ np.array(covariance) @ rotation.T
    inner[2, :] = inner[:, 2] = 0.0
    inner[2, 2] = 1e-4
    assert np.allclose(turned, rotation.T @ inner @ rotation, rtol=0, atol=1e-15)


def _stairs_trot(start_m: float) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """A trot down a staircase (6 cm steps 0.3 m deep, edges across x at 0, 0.3, 0.6 ... m),
    the base at ``start_m`` + 0.75 m/s along x (a stride per 0.4 s cycle: one tread), the feet
    at (±0.2, ∓0.13) m about it landing where they are and standing half a cycle, diagonal
    pairs: the reported plane's gradient from 3 to 6 s, as the footholds' plane and with the
    slope across the base's heading (+x) the standing feet's."""
    offsets = [(0.2, -0.13), (0.2, 0.13), (-0.2, -0.13), (-0.2, 0.13)]
    ground, gradients = LocalGround(), []
    feet: dict[int, tuple[float, float, float]] = {}
    for row in range(1200):
        stamp = row * 0.005
        base = start_m + 0.75 * stamp
        pair = (0, 3) if stamp % 0.4 < 0.2 else (1, 2)
        for leg in pair:
            x = base + offsets[leg][0]
            feet.setdefault(leg, (x, offsets[leg][1], -0.06 * (math.floor(x / 0.3) + 1)))
        feet = {leg: feet[leg] for leg in pair}
        ground.update(stamp, list(feet.items()))
        if stamp >= 3.0:
            plane, across = ground.reported(base, 0.0), ground.reported(base, 0.0, (0, 0, 0, 1))
            assert plane is not None and across is not None
            gradients.append((plane.gradient, across.gradient))
    return gradients


def test_on_a_staircase_the_slope_across_is_the_standing_feets_not_the_footholds() -> None:
    """Treads are level across: the slope across is 0. The base starting at 0.05 m, every
    diagonal pair stands across one edge (front feet 0.1-0.25 m past an edge, rear feet 0.4 m
    behind), so the standing feet's height differences are the same for both pairs while their
    offsets across are opposite: their slope across is 0 by hand. The footholds are not: the
    left feet land 0.15 m further into their treads than the right ones, and the plane through
    them tilts across (1.6°). (Started at 0 m the two pairs span different numbers of edges and
    both tilt: 7.4° the plane, 6.6° the standing feet, docs/leg_odometry.md.)"""
    gradients = _stairs_trot(0.05)
    plane = max(abs(math.degrees(math.atan(grade[1]))) for grade, _ in gradients)
    across = max(abs(math.degrees(math.atan(grade[1]))) for _, grade in gradients)
    assert plane > 1.0
    assert across <= 1.0
    along = [(grade[0], turned[0]) for grade, turned in gradients]
    assert all(first == pytest.approx(second) for first, second in along)
