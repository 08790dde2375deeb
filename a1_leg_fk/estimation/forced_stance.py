"""Two rules of the contact smoother (:mod:`a1_leg_fk.estimation.contact_smoother`) for the
stances of feet whose force is evidence, where one sample's force within the noise of zero would
otherwise decide: offline only, numpy arrays in and out, without ROS.

- **A touchdown no earlier than the filter's** (:func:`filter_touchdowns`): a force's jump at a
  touchdown is seen by the causal filter at once; at the sample before it, the filter's prior of
  swing and the backward message of the sure stance after it cancel, so the forward-backward's
  odds there are that sample's own evidence, and a noisy reading above even odds stands (on the
  contact smoothing family's nine noisy runs 9 such samples were wrong and 2 right, none on the
  clean runs). A forced foot's stance that the filter joins later begins where the filter's
  does.
- **No lone blip** (:func:`without_blips`): a forced foot's stance of at most
  :data:`MAX_BLIP_SAMPLES` samples with no stance within :data:`BLIP_CLEAR_SAMPLES` samples
  before or after it is the force's noise crossing even odds in a swing, and is removed (a real
  stance lasts tens of samples; a flicker a sample before or after a stance is left alone).

Both were tuned on the contact smoothing family's runs with efforts (docs/forces.md: with the
load edges' noise floor and confidence, every run's smoothed contacts at or above the causal).
"""

from __future__ import annotations

import numpy as np

MAX_BLIP_SAMPLES = 2
"""The longest stance of a forced foot alone in a swing that is taken for the force's noise."""
BLIP_CLEAR_SAMPLES = 2
"""How many samples before and after a blip must all be swing for it to be alone."""


def filter_touchdowns(
    odds: np.ndarray, filtered: np.ndarray, forced: np.ndarray, before: np.ndarray | None = None
) -> np.ndarray:
    """(N, 4) log-odds of stance: ``odds`` (N, 4), but where a stance (log-odds >= 0) of a foot
    with force evidence (``forced``, (N, 4) bool) begins while the filter's ``filtered`` (N, 4)
    log-odds still say swing, its leading samples of that kind take the filter's log-odds where
    the stance goes on past them. A stance at the first row began before it unless ``before``
    (4,) bool, the stance at the row before the first (None: unknown), says swing; one that
    ends before the filter stands is left as it is (no foot-sample the smoother alone holds is
    judged by this rule).
    """
    result = odds.copy()
    stance = odds >= 0.0
    ahead = stance & (filtered < 0.0) & forced  # the filter not yet standing
    count = len(odds)
    for leg in range(odds.shape[1]):
        col, lead = stance[:, leg], ahead[:, leg]
        stood = np.concatenate([[True if before is None else bool(before[leg])], col[:-1]])
        starts = np.flatnonzero(col & ~stood)
        ends = np.flatnonzero(~lead)  # where the filter joins, or the stance ends
        for start in starts.tolist():
            joined = ends[np.searchsorted(ends, start)] if ends.size else count
            if start < joined < count and col[joined]:
                result[start:joined, leg] = np.minimum(
                    odds[start:joined, leg], filtered[start:joined, leg]
                )
    return result


def without_blips(odds: np.ndarray, forced: np.ndarray) -> np.ndarray:
    """(N, 4) log-odds of stance: ``odds`` (N, 4), with each lone blip of a foot with force
    evidence (``forced`` (N, 4) bool on each of its samples; the module text) turned to swing
    (its log-odds reversed). A stance at the first or the last row may go on beyond the rows,
    and is kept.
    """
    result = odds.copy()
    stance = odds >= 0.0
    count, clear = len(odds), BLIP_CLEAR_SAMPLES
    for leg in range(odds.shape[1]):
        col = stance[:, leg]
        edges = np.flatnonzero(np.diff(np.concatenate([[0], col.astype(np.int8), [0]])))
        for first, end in zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True):
            alone = (
                not col[max(first - clear, 0) : first].any() and not col[end : end + clear].any()
            )
            short = end - first <= MAX_BLIP_SAMPLES and first > 0 and end < count
            if short and alone and forced[first:end, leg].all():
                result[first:end, leg] = -np.abs(odds[first:end, leg])
    return result
