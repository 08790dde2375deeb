"""The contact filter's arithmetic by hand: one step of each kind of evidence from even odds, the
transition model, the asymmetric kinematic evidence, free fall, and absurd inputs (the fuzz of
damaged recordings found speeds of 1e200 m/s overflowing)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from a1_leg_fk.estimation.contact_filter import ContactFilter, gait_phase_prior
from a1_leg_fk.estimation.contact_model import ContactModel
from a1_leg_fk.estimation.leg_motion import FootMotion

MODEL = ContactModel.for_robot(weight_n=120.0, leg_length_m=0.4)
STILL = (0.0, 0.0, 0.0)


def sigmoid(odds: float) -> float:
    return 1.0 / (1.0 + math.exp(-odds))


def foot(depth: float, velocity=STILL) -> FootMotion:
    """A foot whose contact point lies ``depth`` [m] below the base, giving the base velocity
    ``velocity`` [m/s] if it stood."""
    return FootMotion(velocity, (0.0, 0.0, -depth), depth)


def test_force_evidence_alone_is_a_clipped_logistic() -> None:
    assert MODEL.force_half_n == pytest.approx(3.6) and MODEL.force_scale_n == pytest.approx(0.6)
    contacts = ContactFilter(MODEL)
    forces = [3.6 + 2 * 0.6, 3.6 - 0.6, 100.0, math.nan]  # +2, -1, clipped to +4, none
    out = contacts.update(0.0, [None] * 4, (STILL, None), forces)
    assert out == pytest.approx([sigmoid(2.0), sigmoid(-1.0), sigmoid(4.0), 0.5], abs=1e-12)


def test_the_transition_model_pulls_towards_even_odds() -> None:
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [1.0, 0.0, 0.9, 0.5]
    switch = 1.0 - math.exp(-0.01 / MODEL.switch_time_s)
    out = contacts.update(0.01, [None] * 4, (STILL, None))
    expected = [1 - switch, switch, 0.9 + switch * (1 - 1.8), 0.5]
    assert out == pytest.approx(expected, abs=2e-9)


def test_kinematics_say_swing_strongly_and_stance_weakly_beside_a_force() -> None:
    """Three feet on the ground, still, held standing; FL 5 cm up and moving 1 m/s against
    them, held in swing (a foot held standing 5 cm above the others would be one on a higher
    tread, and a speed reference: see the staircase's test)."""
    feet = [foot(0.3), foot(0.25, (1.0, 0.0, 0.0)), foot(0.3), foot(0.3)]
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.9, 0.1, 0.9, 0.9]
    out = contacts.update(0.0, feet, (STILL, None), [MODEL.force_half_n] * 4)  # forces even
    low_still = 2 * MODEL.max_kinematic_stance  # height and speed, each capped
    stood = math.log(0.9 / 0.1)
    assert out == pytest.approx(
        [
            sigmoid(stood + low_still),
            sigmoid(-stood - 2 * MODEL.max_log_ratio),
            *[sigmoid(stood + low_still)] * 2,
        ]
    )
    alone = ContactFilter(MODEL).update(0.0, feet, (STILL, None))  # no force: symmetric clip
    height_odds = MODEL.height_half_m / MODEL.height_scale_m  # 4: at the lowest foot's height
    speed_odds = MODEL.speed_half_mps / MODEL.speed_scale_mps  # 4: still against the others
    assert alone[0] == pytest.approx(sigmoid(height_odds + speed_odds))


def test_speeds_are_taken_against_the_feet_that_stood() -> None:
    """Rough ground: FR and RL stood at the previous sample and are still; FL, a swing foot
    skimming a bump 1 cm above them (within ``height_half_m``: low), moves at 1 m/s. Against
    the mean of every other low foot FR would move 0.5 m/s (log-odds (0.32 - 0.5) / 0.08 =
    -2.25: called swing in mid-stance); against the feet that stood it is still (+4)."""
    feet = [foot(0.3), foot(0.29, (1.0, 0.0, 0.0)), foot(0.2), foot(0.3)]
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.9, 0.1, 0.1, 0.9]
    out = contacts.update(0.0, feet, (STILL, None))
    height_odds = MODEL.height_half_m / MODEL.height_scale_m  # 4: at the lowest foot's height
    speed_odds = MODEL.speed_half_mps / MODEL.speed_scale_mps  # 4: still against RL
    stood = math.log(0.9 / 0.1)
    assert out[0] == pytest.approx(sigmoid(stood + height_odds + speed_odds))
    assert out[3] == pytest.approx(out[0])
    fl_height_odds = (MODEL.height_half_m - 0.01) / MODEL.height_scale_m  # 1.5
    assert out[1] == pytest.approx(sigmoid(-stood + fl_height_odds - MODEL.max_log_ratio))


def test_a_swing_foot_reaching_down_a_step_is_no_reference_for_the_standing_feet() -> None:
    """A staircase down, no forces (go2_stairs_down_6cm at 2.05 s): FR and RL stand still on the
    upper tread (held standing); FL, held in swing, reaches 2 cm below them for the lower tread,
    moving down at 0.5 m/s; RR swings 10 cm up. FL is the lowest foot, so FR and RL are not low
    (height log-odds (16 - 20) / 4 = -1) and no other low foot stood: against every other low
    foot (FL) FR would move 0.5 m/s, (0.32 - 0.5) / 0.08 = -2.25 more, and be called swing in
    mid-stance. Against the feet that stood, at any height, it is still: +4. FL, whose speed had
    no reference (no other low foot), is now 0.5 m/s against the standing feet: -2.25 on its
    +4 height. The smoother's evidence keeps the flat rules (against every low foot)."""
    feet = [foot(0.27), foot(0.29, (0.0, 0.0, 0.5)), foot(0.17, (1.0, 0.0, 0.0)), foot(0.27)]
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.9, 0.1, 0.1, 0.9]
    out = contacts.update(0.0, feet, (STILL, None))
    stood, limit = math.log(0.9 / 0.1), MODEL.max_log_ratio
    height = (MODEL.height_half_m - 0.02) / MODEL.height_scale_m
    moving = (MODEL.speed_half_mps - 0.5) / MODEL.speed_scale_mps
    assert (height, moving) == (pytest.approx(-1.0), pytest.approx(-2.25))
    assert out[0] == pytest.approx(sigmoid(stood + height + limit)) and out[0] > 0.99
    assert out[3] == pytest.approx(out[0])
    assert out[1] == pytest.approx(sigmoid(-stood + limit + moving))
    assert contacts.evidence.kinematic[0] == pytest.approx(height + moving)  # the smoother's
    assert contacts.evidence.kinematic[1] == pytest.approx(limit)


def test_a_foot_with_a_force_on_a_higher_tread_is_still_against_the_standing_feet() -> None:
    """A staircase, forces for every foot: FR stands on a tread 3 cm above RL's (both held
    standing, both still); FL, in swing, comes down to RL's tread at 1 m/s, 5 mm above it (low);
    RR swings 10 cm up. FR is not low (height log-odds (16 - 30) / 4 = -3.5). Against every
    other low foot (RL and FL, mean 0.5 m/s) FR would move 0.5 m/s, (0.32 - 0.5) / 0.08 = -2.25
    more: with its 50 N (+4) and the prior of a foot that stood, called swing in mid-stance.
    As a standing foot stands off the low feet's level, its speed is taken against the feet that
    stood, at any height: RL, still, +0.5 (capped beside a force). RL, low, takes FR the same
    way (still: +0.5 on its +0.5 height)."""
    feet = [foot(0.27), foot(0.295, (0.0, 0.0, -1.0)), foot(0.2), foot(0.3)]
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.9, 0.1, 0.1, 0.9]
    out = contacts.update(0.0, feet, (STILL, None), [50.0, 0.0, 0.0, 50.0])
    stood, cap, limit = math.log(0.9 / 0.1), MODEL.max_kinematic_stance, MODEL.max_log_ratio
    fr_height = (MODEL.height_half_m - 0.03) / MODEL.height_scale_m
    assert fr_height == pytest.approx(-3.5)
    assert out[0] == pytest.approx(sigmoid(stood + limit + fr_height + cap))
    assert out[3] == pytest.approx(sigmoid(stood + limit + 2 * cap))
    # the smoother's: against RL and FL, (0.32 - 0.5) / 0.08 = -2.25, but FR's 50 N (+4) is sure
    # it presses: a speed is then no swing evidence
    assert contacts.evidence.kinematic[0] == pytest.approx(fr_height)


def test_a_standing_foot_risen_above_its_own_foothold_is_let_go() -> None:
    """Four feet stand still 0.3 m under the base; then FL rises 3 mm, still "low" against the
    others (height log-odds (16 - 3) / 4 = +3.25). Against its own foothold it is 3 mm up: past
    the even-odds rise (1.5 mm, 0.375 % of the leg; the standing feet's spread, 0.1 mm, x 3 is
    less), so its height says (1.5 - 3) / 0.5 = -3 instead. Its speed (still against the still
    feet that stood) adds +4. The other feet keep their +4 height. The evidence kept for a
    smoother leaves the cap out (it follows the filter's own state): +3.25 + 4. (The rigid feet's
    rule is off: its least even-odds height is the fixed one.)"""
    down = (0.0, 0.0, -1.0)
    contacts = ContactFilter(replace(MODEL, height_floor_m=MODEL.height_half_m))
    contacts.probabilities = [0.99] * 4
    before = contacts.update(0.002, [foot(0.3)] * 4, (STILL, None), down=down)[1]
    out = contacts.update(
        0.002, [foot(0.3), foot(0.297), foot(0.3), foot(0.3)], (STILL, None), down=down
    )
    assert MODEL.rise_half_m == pytest.approx(0.0015) and MODEL.rise_scale_m == pytest.approx(5e-4)
    limit = MODEL.max_log_ratio
    assert contacts.evidence.heights[1] == pytest.approx(0.003)
    assert contacts.evidence.kinematic[1] == pytest.approx((0.016 - 0.003) / 0.004 + limit)
    assert contacts.evidence.kinematic[0] == pytest.approx(2 * limit)
    assert contacts.evidence.total[1] == pytest.approx(contacts.evidence.kinematic[1])
    prior = before + (1.0 - math.exp(-0.002 / MODEL.switch_time_s)) * (1.0 - 2.0 * before)
    rise_odds = (0.0015 - 0.003) / 5e-4
    assert out[1] == pytest.approx(sigmoid(math.log(prior / (1.0 - prior)) + rise_odds + limit))


def test_a_foot_with_a_force_that_landed_on_a_higher_tread_stands() -> None:
    """Forces for every foot: three feet stand still 0.3 m under the base with 50 N; FL, held in
    swing, comes down in 5 mm steps onto a tread 4 cm up and stays there, still, bearing 5.4 N
    ((5.4 - 3.6) / 0.6 = +3). Its height says swing (-6, clipped to -4), its speed against the
    standing feet stance (+0.5, capped beside a force): -0.5 a sample, never standing (the
    stairs' touchdowns called swing). Once it has landed (20 ms within 1.5 mm of where it came
    down to) its height says no swing (0): +3.5, standing at once (28 ms after its first
    sample). The smoother's evidence keeps the flat rules (-3.5)."""
    down = (0.0, 0.0, -1.0)
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.99, 0.01, 0.99, 0.99]
    limit, cap = MODEL.max_log_ratio, MODEL.max_kinematic_stance
    switch = 1.0 - math.exp(-0.002 / MODEL.switch_time_s)
    force = (5.4 - MODEL.force_half_n) / MODEL.force_scale_n
    assert force == pytest.approx(3.0)
    p, stamps = 0.01, []
    for n in range(1, 31):  # 60 ms at 500 Hz
        depth = min(0.24 + 0.005 * n, 0.26)  # there at the 4th sample
        feet = [foot(0.3), foot(depth), foot(0.3), foot(0.3)]
        out = contacts.update(0.002, feet, (STILL, None), [50.0, 5.4, 50.0, 50.0], down=down)
        prior = p + switch * (1.0 - 2.0 * p)
        landed = n >= 14  # the 4th sample's level, 20 ms (10 samples) on
        height = 0.0 if landed else -limit
        p = sigmoid(math.log(prior / (1.0 - prior)) + force + height + cap)
        assert out[1] == pytest.approx(p, rel=1e-9), n
        stamps.append(0.002 * n if out[1] >= 0.5 else math.nan)
    assert min(s for s in stamps if s == s) == pytest.approx(0.028)  # noqa: PLR0124
    assert contacts.evidence.kinematic[1] == pytest.approx(-limit + cap)  # the flat rules


def swing_noise(contacts: ContactFilter, rms_n: float) -> None:
    """One second of the four feet held in swing reading +-``rms_n`` [N] (their RMS force)."""
    for k in range(500):
        sign = 1.0 if k % 2 else -1.0
        contacts.swing_force.update(0.002, [sign * rms_n, -sign * rms_n] * 2, [True] * 4)


def test_a_loaded_foot_sliding_over_a_treads_edge_stands() -> None:
    """Stairs down, forces for every foot: FR stands on the upper tread, 4 cm above RR and RL on
    the lower one (all three still, held standing, 50 N); FL, held in swing, lands on the lower
    tread's edge 16 mm above them (height at even odds: 0) bearing 20 N (+4, clipped) and slides
    off it at 1 m/s against the standing feet ((0.32 - 1) / 0.08: -4, clipped), as
    go2_stairs_down_6cm's landing feet. The swing feet read 2 N RMS over the last second (FL's
    20 N, 1 sample in 2,001, makes it 2.05 N): the speed's swing evidence fades with the force's
    log-odds from 3.6 + 2.05 N, ``(20 - 5.65) / 0.6`` clipped to 4: ``1 - 4 / 4`` of it is left,
    so the force decides: +4 a sample, standing from the first (0.01, through the transition
    model 0.029: -3.50 + 4 = +0.50). Without the fade force and speed cancel and the foot stays
    in swing while it slides. At 6.8 N ((6.8 - 3.6 - 2) / 0.6 = +2, no foot in swing) half of
    the speed's -4 is left. With every standing foot on one level (FR down with the others) the
    force fades the speed just the same."""
    contacts = ContactFilter(MODEL)
    swing_noise(contacts, 2.0)
    contacts.probabilities = [0.99, 0.01, 0.99, 0.99]
    limit = MODEL.max_log_ratio
    switch = 1.0 - math.exp(-0.002 / MODEL.switch_time_s)
    feet = [foot(0.26), foot(0.284, (1.0, 0.0, 0.0)), foot(0.3), foot(0.3)]
    p = 0.01
    for n in range(1, 11):  # 20 ms at 500 Hz
        out = contacts.update(0.002, feet, (STILL, None), [50.0, 20.0, 50.0, 50.0])
        prior = p + switch * (1.0 - 2.0 * p)
        p = sigmoid(math.log(prior / (1.0 - prior)) + limit)
        assert out[1] == pytest.approx(p, rel=1e-9), n
        assert out[1] > 0.5, n
    assert contacts.evidence.kinematic[1] == pytest.approx(0.0, abs=1e-9)  # the smoother's too
    half = ContactFilter(MODEL)
    swing_noise(half, 2.0)
    half.probabilities = [0.99, 0.5, 0.99, 0.99]
    out = half.update(0.0, feet, (STILL, None), [50.0, 6.8, 50.0, 50.0])
    assert half.evidence.kinematic[1] == pytest.approx(-limit / 2)
    assert out[1] == pytest.approx(sigmoid(limit - limit / 2))
    level = ContactFilter(MODEL)
    swing_noise(level, 2.0)
    level.probabilities = [0.99, 0.25, 0.99, 0.99]
    feet[0] = foot(0.3)
    out = level.update(0.0, feet, (STILL, None), [50.0, 20.0, 50.0, 50.0])
    assert level.evidence.kinematic[1] == pytest.approx(0.0, abs=1e-9)
    assert out[1] == pytest.approx(sigmoid(math.log(0.25 / 0.75) + limit))


def test_a_swing_foot_reading_its_swing_noise_keeps_its_speeds_swing_evidence() -> None:
    """Aliengo under position motors: its swing feet read about 23 N. A foot held in swing,
    sliding at 1 m/s (-4, clipped) on the standing feet's level, reads 20 N (+4 by the force's
    log-odds; its height among the others' at most ``max_kinematic_stance``, 0.5): with the
    swing feet's RMS of 23 N over the last second the fade's margin is 3.6 + 23 N, ``(20 -
    26.6) / 0.6`` < 0, so its speed says swing in full: 0.5 - 4 + 4 = +0.5 from 0.25's odds
    (dt 0). With the force's even odds alone as the margin the speed would be faded away
    (+4.5)."""
    contacts = ContactFilter(MODEL)
    swing_noise(contacts, 23.0)
    contacts.probabilities = [0.99, 0.25, 0.99, 0.99]
    feet = [foot(0.3), foot(0.3, (1.0, 0.0, 0.0)), foot(0.3), foot(0.3)]
    out = contacts.update(0.0, feet, (STILL, None), [50.0, 20.0, 50.0, 50.0])
    weak, limit = MODEL.max_kinematic_stance, MODEL.max_log_ratio
    assert contacts.evidence.kinematic[1] == pytest.approx(weak - limit)
    assert out[1] == pytest.approx(sigmoid(math.log(0.25 / 0.75) + weak))


def test_free_fall_lifts_every_foot() -> None:
    feet = [foot(0.3)] * 4  # all low and still: the kinematics alone would say stance
    contacts = ContactFilter(MODEL)
    for _ in range(5):
        out = contacts.update(0.002, feet, (STILL, (0.0, 0.0, 0.4)))  # |f| = 0.4 m/s^2
    assert max(out) < 0.05
    standing = ContactFilter(MODEL)
    for _ in range(5):
        out = standing.update(0.002, feet, (STILL, (0.0, 0.0, 9.8)))
    assert min(out) > 0.95


def test_absurd_values_give_probabilities_not_errors() -> None:
    contacts = ContactFilter(MODEL)
    feet = [foot(0.3, (1e200, -1e200, 1e300)), foot(0.3, (-1e300, 1e200, 0.0)), foot(math.inf),
            foot(0.3, (math.nan, 0.0, 0.0))]  # fmt: skip
    for _ in range(3):
        out = contacts.update(1e-9, feet, ((1e300, 0.0, 0.0), (1e308, 1e308, 1e308)),
                              [1e308, -math.inf, math.nan, 5.0])  # fmt: skip
        assert all(0.0 <= p <= 1.0 for p in out), out


def test_a_gait_phase_prior_adds_its_log_odds() -> None:
    out = ContactFilter(MODEL).update(
        0.0, [None] * 4, (STILL, None), None, [0.9, 0.1, 0.5, math.nan]
    )
    logit = math.log(0.9 / 0.1) * MODEL.phase_weight
    assert out == pytest.approx([sigmoid(logit), sigmoid(-logit), 0.5, 0.5])


def test_a_gait_phase_message_gives_each_named_foot_its_probability() -> None:
    nan = math.nan
    cases = [
        ((["FR", "FL", "RR", "RL"], [0.9, 0.1, 0.0, 1.0]), [0.9, 0.1, 0.0, 1.0]),
        ((["RL", "FR"], [0.25, 0.75]), [0.75, nan, nan, 0.25]),  # a subset, any order
        ((["FR", "arm", "FR", "RR"], [0.5, 0.5, 0.5, 0.6]), [nan, nan, 0.6, nan]),  # FR twice
        ((["FR", "FL", "RR", "RL"], [1.5, -0.1, nan, 0.5]), [nan, nan, nan, 0.5]),  # not in [0, 1]
        ((["FR", "FL"], [0.5]), [nan, nan, nan, nan]),  # fewer values than names
    ]
    for (names, values), expected in cases:
        prior = gait_phase_prior(names, values)
        assert [None if math.isnan(p) else p for p in prior] == [
            None if math.isnan(p) else p for p in expected
        ], (names, values)


def test_a_swing_foot_that_landed_on_a_higher_tread_stands() -> None:
    """Three feet stand still 0.3 m under the base; FL, held in swing, comes down in 5 mm steps
    onto a tread 4 cm up and stays there, still. Its height above the others says swing ((16 -
    40) / 4 = -6, clipped to -4), its speed against the standing feet stance (+4): the odds only
    drift toward even with the transition model and never cross (go2_stairs_up_4cm's front
    feet: 75 %). Once it has stayed within the even-odds rise (1.5 mm) of where it came down to
    for 20 ms it has landed: its height says no swing (0), its speed +4, and the filter holds it
    standing at once (28 ms after its first sample); a tread's rise is no evidence of swing."""
    down = (0.0, 0.0, -1.0)
    contacts = ContactFilter(MODEL)
    contacts.probabilities = [0.99, 0.01, 0.99, 0.99]
    limit, switch = MODEL.max_log_ratio, 1.0 - math.exp(-0.002 / MODEL.switch_time_s)
    p, stamps = 0.01, []
    for n in range(1, 31):  # 60 ms at 500 Hz
        depth = min(0.24 + 0.005 * n, 0.26)  # there at the 4th sample
        feet = [foot(0.3), foot(depth), foot(0.3), foot(0.3)]
        out = contacts.update(0.002, feet, (STILL, None), down=down)
        prior = p + switch * (1.0 - 2.0 * p)
        landed = n >= 14  # the 4th sample's level, 20 ms (10 samples) on
        p = sigmoid(math.log(prior / (1.0 - prior)) + (limit if landed else 0.0))
        assert out[1] == pytest.approx(p, rel=1e-9), n
        stamps.append(0.002 * n if out[1] >= 0.5 else math.nan)
    assert min(s for s in stamps if s == s) == pytest.approx(0.028)  # noqa: PLR0124
    assert contacts.evidence.kinematic[1] == pytest.approx(0.0)  # the smoother's: the flat rules


def test_a_foot_whose_force_says_swing_gets_no_low_and_still_stance() -> None:
    """A position motor's bounce (docs/forces.md): four feet stand still at one height with
    50 N, FL's force then reads 0 N for two samples and 50 N again; its height and speed stay
    stance-like (+0.5 each beside a force). A foot held standing enters a 2 ms sample with the
    transition's log((1 - s) / s) = +3.90 and its force says -4 (the clip): with the low, still
    foot's +1 it would stand (+0.90); a force that says swing leaves its kinematics no stance
    evidence, so both samples are swing (-0.10, then -4.10), and the evidence kept for the
    smoother says the same (0). Its swing evidence is kept: FL 5 cm up would say -4."""
    limit, cap = MODEL.max_log_ratio, MODEL.max_kinematic_stance
    switch = 1.0 - math.exp(-0.002 / MODEL.switch_time_s)
    contacts, p = ContactFilter(MODEL), 0.5
    for n in range(40):
        fl = 0.0 if n in (30, 31) else 50.0
        out = contacts.update(0.002, [foot(0.3)] * 4, (STILL, None), [50.0, fl, 50.0, 50.0])
        prior = p + switch * (1.0 - 2.0 * p)
        force = -limit if fl == 0.0 else limit
        p = sigmoid(math.log(prior / (1.0 - prior)) + force + (0.0 if fl == 0.0 else 2 * cap))
        assert out[1] == pytest.approx(p, rel=1e-9), n
        assert (out[1] >= 0.5) == (n not in (30, 31)), n
        assert contacts.evidence.kinematic[1] == pytest.approx(0.0 if fl == 0.0 else 2 * cap)
    assert math.log((1.0 - switch) / switch) == pytest.approx(3.90, abs=0.005)
    risen = contacts.update(0.002, [foot(0.3), foot(0.25)] + [foot(0.3)] * 2, (STILL, None),
                            [50.0, 0.0, 50.0, 50.0])  # fmt: skip
    assert contacts.evidence.kinematic[1] == pytest.approx(-limit)  # height -6: clipped
    assert risen[1] < 0.5


def hover(model: ContactModel, bob_m: float = 0.0) -> tuple[list[float], list[float], float]:
    """A trot's handover on rigid feet, by construction: FR and RL stand still 0.3 m under the
    base, FR 0.02 mm lower (the standing feet's height spread: 0.014 mm RMS); RR is up (5 cm);
    FL, held in swing, hovers 0.42 mm above FR for 40 ms (20 samples), moving at 0.3 m/s against
    the standing feet (speed log-odds (0.32 - 0.3) / 0.08 = +0.25), after 10 ms 5 cm up (it came
    down: 20 ms on, it has landed). With ``bob_m``, FR gives that much [m] every other sample,
    for 0.4 s first (200 samples, FL up). Per sample: FL's probability of stance and the
    log-odds the filter added to its prior (its kinematic evidence: no force, no IMU); the
    smoother's kinematic log-odds for FL at the last."""
    down = (0.0, 0.0, -1.0)
    contacts = ContactFilter(model)
    contacts.probabilities = [0.99, 0.01, 0.01, 0.99]
    switch = 1.0 - math.exp(-0.002 / model.switch_time_s)
    probabilities, odds = [], []
    for n in range(-200 if bob_m else -5, 20):
        fl = 0.25 if n < 0 else 0.2996
        fr = 0.30002 + bob_m * (n % 2)
        feet = [foot(fr), foot(fl, (0.3, 0.0, 0.0)), foot(0.25), foot(0.3)]
        before = contacts.probabilities[1]
        prior = before + switch * (1.0 - 2.0 * before)
        p = contacts.update(0.002, feet, (STILL, None), down=down)[1]
        probabilities.append(p)
        odds.append(math.log(p / (1.0 - p)) - math.log(prior / (1.0 - prior)))
    return probabilities, odds, contacts.evidence.kinematic[1]


def test_a_swing_foot_hovering_over_rigid_feet_stays_in_swing() -> None:
    """``hover``: by the fixed rule FL's height says stance ((16 - 0.42) / 4 = +3.9)
    and the filter calls it standing within a few samples. The standing feet are rigid (their
    rise spread 0 < 0.4 x 1.5 mm) and within 0.02 mm of each other: the even-odds height is
    the floor, 0.05 mm (2 x 0.014 mm is less), 0.00625 mm per unit; FL's height, below the fixed
    half, says swing at most -3 (landed, it is not past the fixed half: no rescue); with its
    speed, -2.75 per sample: it stays in swing. The smoother's evidence keeps the fixed scales
    (+3.895 + 0.25: the rigid rule follows the feet the filter holds standing)."""
    probabilities, odds, smoothers = hover(MODEL)
    assert MODEL.height_floor_m == pytest.approx(5e-5)
    assert odds[-1] == pytest.approx(-MODEL.rigid_swing_odds + (0.32 - 0.3) / 0.08)
    assert max(probabilities) < 0.01
    assert smoothers == pytest.approx((0.016 - 0.00042) / 0.004 + (0.32 - 0.3) / 0.08, abs=1e-6)
    fixed, _, _ = hover(replace(MODEL, height_floor_m=MODEL.height_half_m))  # the rule off
    assert fixed[-1] > 0.99


def test_a_swing_foot_hovering_over_feet_that_give_keeps_the_fixed_rule() -> None:
    """``hover`` with FR giving 2 mm every other sample: the standing feet's rises (FR's 0 and
    2 mm, RL's 0) have an RMS of 1 mm, averaged from 0 over 0.44 s (0.5 s constant) 0.75 mm,
    past 0.4 x 1.5 mm: not rigid, and the fixed rule calls FL standing, as before."""
    probabilities, _, _ = hover(MODEL, bob_m=0.002)
    assert probabilities[-1] > 0.99
