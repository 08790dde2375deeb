"""The contact smoother against references built independently of it: the posterior of a
two-state hidden Markov model by enumerating every state sequence, a liftoff placed by
construction, and its windowed pass against its whole-recording pass.
"""

from __future__ import annotations

import itertools

import numpy as np

from a1_leg_fk.estimation.contact_filter import ContactFilter, ContactModel
from a1_leg_fk.estimation.contact_smoother import (
    EvidenceRows,
    FixedLagSmoother,
    probabilities,
    smooth,
)

LEGS = 4


def rows_of(evidence: np.ndarray, switch: np.ndarray, step_s: float = 0.002) -> EvidenceRows:
    """Rows whose every foot has force evidence (no lead) and ``evidence`` as its kinematics."""
    count = len(switch)
    forced = np.ones((count, LEGS), dtype=bool)
    return EvidenceRows(
        np.arange(count) * step_s, switch, evidence, forced, evidence, unknown(count)
    )


def unknown(count: int) -> np.ndarray:
    """(count, 4) heights [m] not known: no edges placed by them."""
    return np.full((count, LEGS), np.nan)


def enumerated_posterior(evidence: np.ndarray, switch: np.ndarray) -> np.ndarray:
    """P(stance at k | every sample) of one foot by summing over all 2^N state sequences:
    even odds before the first sample, a change of state before sample k with probability
    ``switch[k]``, likelihood ratio ``exp(evidence[k])`` of stance over swing.
    """
    count = len(evidence)
    stance_mass, total = np.zeros(count), 0.0
    for states in itertools.product((0, 1), repeat=count):
        weight, previous = 0.5, None  # even odds, still even across the first transition
        for k, state in enumerate(states):
            if previous is not None:
                weight *= switch[k] if state != previous else 1.0 - switch[k]
            weight *= np.exp(evidence[k]) if state else 1.0
            previous = state
        total += weight
        stance_mass += weight * np.array(states)
    return stance_mass / total


def test_forward_backward_is_the_enumerated_posterior() -> None:
    rng = np.random.default_rng(36)
    count = 10
    evidence = rng.normal(0.0, 2.0, (count, LEGS))
    switch = rng.uniform(0.0, 0.4, count)
    switch[0] = 0.0
    smoothed, _ = smooth(rows_of(evidence, switch), np.zeros(LEGS), lead_s=0.0)
    for leg in range(LEGS):
        expected = enumerated_posterior(evidence[:, leg], switch)
        np.testing.assert_allclose(probabilities(smoothed[:, leg]), expected, rtol=0, atol=1e-12)


def test_the_forward_pass_is_the_live_filters() -> None:
    """The smoother's forward pass over the filter's recorded evidence gives the filter's own
    probabilities (within the filter's clip of the prior at 2e-9)."""
    model = ContactModel.for_robot(120.0, 0.4)
    live = ContactFilter(model)
    rng = np.random.default_rng(7)
    forces = rng.choice([0.0, 60.0], size=(300, LEGS)) + rng.normal(0.0, 3.0, (300, LEGS))
    expected, kept = [], []
    for row in forces.tolist():
        expected.append(live.update(0.002, [None] * LEGS, ((0.0, 0.0, 0.0), None), row))
        kept.append(live.evidence)
    rows = EvidenceRows(np.arange(300) * 0.002, *(np.array(c) for c in zip(*kept, strict=True)))
    _, filtered = smooth(rows, np.zeros(LEGS))
    np.testing.assert_allclose(probabilities(filtered), np.array(expected), rtol=0, atol=1e-8)


def test_the_lead_moves_a_liftoff_and_not_a_touchdown() -> None:
    """A foot without force evidence: stance, then clear swing evidence from sample 100 (a
    liftoff seen late), then stance again from sample 200. With a 14 ms lead at 500 Hz the
    liftoff moves 7 samples earlier; the touchdown stays."""
    count = 300
    kinematic = np.full((count, LEGS), 2.0)
    kinematic[100:200] = -4.0
    switch = np.full(count, 1.0 - np.exp(-0.002 / 0.1))
    rows = EvidenceRows(
        np.arange(count) * 0.002,
        switch,
        kinematic,
        np.zeros((count, LEGS), bool),
        kinematic,
        unknown(count),
    )
    for lead_s, liftoff in ((0.0, 100), (0.014, 93)):
        stance = probabilities(smooth(rows, np.zeros(LEGS), lead_s)[0])[:, 0] >= 0.5
        assert np.flatnonzero(~stance)[0] == liftoff, lead_s
        assert np.flatnonzero(~stance)[-1] == 199, lead_s


def test_windows_give_the_whole_pass() -> None:
    """Blocks of 137 rows through the fixed-lag smoother against one pass over all 5000 rows:
    the 0.5 s lag leaves the posteriors within 1e-6."""
    rng = np.random.default_rng(3)
    count = 5000
    states = np.repeat(rng.integers(0, 2, count // 50), 50)[:, None].repeat(LEGS, axis=1)
    kinematic = np.where(states, 1.0, -2.0) + rng.normal(0.0, 1.5, (count, LEGS))
    switch = np.full(count, 1.0 - np.exp(-0.002 / 0.1))
    rows = EvidenceRows(
        np.arange(count) * 0.002,
        switch,
        kinematic,
        np.zeros((count, LEGS), bool),
        kinematic,
        unknown(count),
    )
    whole = probabilities(smooth(rows, np.zeros(LEGS))[0])
    smoother, parts = FixedLagSmoother(), []
    for start in range(0, count, 137):
        smoother.add(rows[start : start + 137])
        parts.append(smoother.take(smoother.final_rows()))
        assert len(smoother.pending) <= 137 + 251  # a block and the lag, never the recording
    parts.append(smoother.take(len(smoother.pending)))
    np.testing.assert_allclose(np.concatenate(parts), whole, rtol=0, atol=1e-6)


def test_a_foot_with_force_evidence_lifts_off_where_the_filter_does() -> None:
    """A foot standing 100 rows then swinging 100, its evidence symmetric: the forward-backward
    puts the liftoff at the change itself, the filter a few rows later; with force evidence the
    smoother's output keeps the filter's (force_liftoffs), without it the smoother's own."""
    evidence = np.r_[np.full(100, 2.0), np.full(100, -2.0)][:, None].repeat(LEGS, axis=1)
    switch = np.full(200, 1.0 - np.exp(-0.002 / 0.1))
    forced = rows_of(evidence, switch)
    smoothed, filtered = smooth(forced, np.zeros(LEGS))
    liftoff = {
        name: int(np.argmax(odds[:, 0] < 0.0))
        for name, odds in (("smoothed", smoothed), ("filtered", filtered))
    }
    assert liftoff["smoothed"] == 100 and liftoff["filtered"] > 100, liftoff
    smoother = FixedLagSmoother()
    smoother.add(forced)
    with_force = smoother.take(200)[:, 0] >= 0.5
    assert int(np.argmin(with_force)) == liftoff["filtered"]
    unforced = EvidenceRows(
        forced.stamps_s, switch, evidence, ~forced.forced, evidence, unknown(200)
    )
    smoother = FixedLagSmoother(lead_s=0.0)
    smoother.add(unforced)
    assert int(np.argmin(smoother.take(200)[:, 0] >= 0.5)) == liftoff["smoothed"]
