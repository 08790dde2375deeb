"""The contact smoother's rules for feet with force evidence where one sample's force within the
noise decides (issue 34): a touchdown no earlier than the filter's, and no lone blip, on
evidence built by construction (the contact filter's clipped log-ratios written out, 500 Hz,
loads unknown so that the load edges place nothing), the truth known by construction.
"""

from __future__ import annotations

import numpy as np

from a1_leg_fk.estimation.contact_smoother import EvidenceRows, probabilities, smoothed_stance

LEGS, STEP_S = 4, 0.002
SWITCH = 1.0 - np.exp(-STEP_S / 0.1)  # the A1's switch_time_s


def forced_rows(evidence: np.ndarray) -> EvidenceRows:
    """Rows whose every foot has force evidence ``evidence`` (N,) log-ratios (the same for all
    four), no kinematics, loads and heights unknown."""
    count = len(evidence)
    total = np.repeat(evidence[:, None], LEGS, axis=1)
    unknown = np.full((count, LEGS), np.nan)
    forced = np.ones((count, LEGS), dtype=bool)
    switch = np.full(count, SWITCH)
    return EvidenceRows(
        np.arange(count) * STEP_S, switch, np.zeros_like(total), forced, total, unknown, unknown
    )


def stance_of(evidence: np.ndarray) -> np.ndarray:
    """(N,) bool: the smoothed stance of the first foot over the whole recording."""
    rows = forced_rows(evidence)
    return probabilities(smoothed_stance(rows, np.zeros(LEGS))[0][:, 0]) >= 0.5


def test_a_noisy_reading_before_a_touchdown_is_not_stance() -> None:
    """100 samples of swing (force -4, clipped), then one whose noise reads +2 (above even odds,
    the truth still swing), then the touchdown's jump (+4) for 100 samples. The filter is
    at -7.9 in the swing (the transition's log(s) -3.9, then -4), -1.9 on the noisy sample,
    +2.1 on the jump: it stands from the jump. The forward-backward's odds on the noisy sample
    are its forward -1.9 plus the sure stance's backward message (+3.9): +2.0, stance a sample
    early. The smoothed stance begins at the jump, as the filter's and the truth's."""
    evidence = np.r_[np.full(100, -4.0), 2.0, np.full(100, 4.0)]
    stance = stance_of(evidence)
    assert not stance[:101].any()
    assert stance[101:].all()


def test_a_lone_one_or_two_sample_blip_in_a_swing_is_removed() -> None:
    """A swing of 200 samples (force -4) in which the force's noise reads +4 on one sample, and
    later on two in a row (the truth swing: a real stance lasts tens of samples), between two
    stances. The filter stands on each blip (-7.9 carried to -3.9, +4: +0.1); the smoothed
    contacts do not. A flicker 2 samples after a stance's end (one sample of swing between)
    is left alone: it is not alone in the swing."""
    stance_n, swing = np.full(100, 4.0), np.full(200, -4.0)
    swing[60] = 4.0
    swing[120:122] = 4.0
    swing[1] = 4.0  # a flicker right after the first stance's end
    evidence = np.r_[stance_n, swing, stance_n]
    stance = stance_of(evidence)
    assert stance[:100].all() and stance[300:].all()
    assert not stance[160] and not stance[220:222].any()
    assert stance[101]  # the flicker kept
