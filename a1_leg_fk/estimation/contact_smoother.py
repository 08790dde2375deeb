"""Contacts of a recording from the whole recording: the contact filter's hidden Markov model
(:mod:`a1_leg_fk.estimation.contact_filter`) run forward and backward over the evidence it
recorded per sample (:class:`~a1_leg_fk.estimation.contact_filter.SampleEvidence`), giving each
foot's posterior probability of stance given every sample before *and after* it. Without ROS;
numpy arrays in, numpy arrays out.

The evidence does not depend on the filter's state (forces, heights, speeds, free fall and the
phase prior are the kinematics' and the efforts'), so the forward-backward pass over the stored
log-likelihood ratios and switch probabilities is exact for the filter's model. Both passes run in
log-odds: with the symmetric transition (a change of state with probability ``s``), a message
``m`` (log-odds) carried across one step becomes
``log(((1 - s) e^m + s) / (s e^m + 1 - s))``.

One more piece of knowledge only the future can use: a foot unloads before it has moved
measurably (:data:`LIFTOFF_LEAD_S`). Where a foot has no force evidence, its clear kinematic
evidence of swing (:data:`CLEAR_SWING`) ``lead_s`` later also counts as evidence of swing now
(the smaller of the two kinematic log-ratios); a touchdown, where the foot stops as it lands,
is left where the evidence puts it.

Without force evidence, the posterior decides which stances and swings there are and the feet's
heights place their edges (:func:`height_edges`, the rules of
:mod:`a1_leg_fk.estimation.stance_edges` that ``gait``'s own kinematic contacts use for their
liftoffs): a touchdown where the foot stops coming down (the evidence of a foot 1-4 mm up and
still descending already says stance), a liftoff where its rise, fitted as ``c (t - t0)^p``,
starts. A sample they move to swing takes the posterior's odds reversed.

Where a foot's force is evidence, a liftoff is not placed before the filter's own
(:func:`force_liftoffs`): the force's log-ratio is at even odds at 3 % of the weight
(:data:`~a1_leg_fk.estimation.contact_model.FORCE_HALF_SHARE`), and the forward-backward
places a liftoff there, a few ms before the force reaches zero, where the foot still stands; the
filter, which needs the evidence of swing to outweigh its stance, places it later, nearer the
zero. Such a foot stands while either says so, but its stance begins no earlier than the
filter's, and a lone blip of one or two samples in a swing is the force's noise
(:mod:`a1_leg_fk.estimation.forced_stance`); its load itself may carry the stance on to where
it reaches zero (:mod:`a1_leg_fk.estimation.load_edges`; all tuned on the contact family's
tuned runs, docs/forces.md).

:class:`FixedLagSmoother` runs this over a stream of rows in windows: a row is final once the
rows after it cover ``lag_s`` (the backward message from further on is taken as flat; see
:data:`LAG_S`), so memory is bounded by a block plus the lag, whatever the recording's length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.estimation.forced_stance import filter_touchdowns, without_blips
from a1_leg_fk.estimation.load_edges import HISTORY_S, loaded_stance, unlagged
from a1_leg_fk.estimation.pooled_rise import recent_liftoffs
from a1_leg_fk.estimation.stance_edges import CONTEXT_S, against_standing, placed_edges
from a1_leg_fk.model.legs import LEG_NAMES

LEGS = len(LEG_NAMES)
LIFTOFF_LEAD_S = 0.014
"""[s] How long before a foot has moved measurably it has unloaded: its clear kinematic evidence of
swing counts this much earlier (tuned on the contact family's tuned runs, docs/forces.md)."""
CLEAR_SWING = -1.0
"""A kinematic log-likelihood ratio below this is clear evidence of swing, which the lead moves
earlier; weaker evidence is left in place (a noisy foot's stance hovers near zero)."""
LAG_S = 0.5
"""[s] The future a row is smoothed with in :class:`FixedLagSmoother`: five of the transition's
mean times between changes (``switch_time_s``, 0.1 s), after which further evidence moves a
posterior by far less than a sample's own evidence does."""


@dataclass
class EvidenceRows:
    """The filter's evidence over N rows (:class:`~a1_leg_fk.estimation.contact_filter.
    SampleEvidence` stacked): ``stamps_s`` (N,) [s], ``switch`` (N,) probabilities of a change of
    state since the previous row, ``kinematic`` (N, 4) and ``total`` (N, 4) log-likelihood
    ratios, ``forced`` (N, 4) bool (the foot's force was evidence), ``normals`` (N, 4) the normal
    forces [N] the filter was given (NaN: none), ``heights`` (N, 4) [m] the feet's heights the
    kinematic evidence took (NaN: unknown).
    """

    stamps_s: np.ndarray
    switch: np.ndarray
    kinematic: np.ndarray
    forced: np.ndarray
    total: np.ndarray
    normals: np.ndarray
    heights: np.ndarray

    @classmethod
    def empty(cls) -> EvidenceRows:
        """No rows."""
        legs = np.empty((0, LEGS))
        forced = np.empty((0, LEGS), dtype=bool)
        return cls(np.empty(0), np.empty(0), legs, forced, legs.copy(), legs.copy(), legs.copy())

    def __len__(self) -> int:
        return len(self.stamps_s)

    def __getitem__(self, chosen: slice) -> EvidenceRows:
        """The rows ``chosen``."""
        return EvidenceRows(*(getattr(self, name)[chosen] for name in FIELDS))

    def then(self, later: EvidenceRows) -> EvidenceRows:
        """These rows followed by ``later``'s."""
        return EvidenceRows(
            *(np.concatenate([getattr(self, name), getattr(later, name)]) for name in FIELDS)
        )


FIELDS = ("stamps_s", "switch", "kinematic", "forced", "total", "normals", "heights")


def led_evidence(rows: EvidenceRows, lead_s: float = LIFTOFF_LEAD_S) -> np.ndarray:
    """(N, 4) log-likelihood ratios with the kinematic evidence of swing ``lead_s`` [s] later
    counted now too, for the feet without force evidence (the module text).
    """
    kinematic = rows.kinematic
    reached = np.maximum.accumulate(rows.stamps_s) if len(rows) else rows.stamps_s
    later = np.searchsorted(reached, reached + lead_s)
    inside = later < len(rows)
    led = kinematic.copy()
    ahead = kinematic[later[inside]]
    clear = ahead < CLEAR_SWING
    led[inside] = np.where(clear, np.minimum(kinematic[inside], ahead), kinematic[inside])
    led[rows.forced] = kinematic[rows.forced]
    result: np.ndarray = rows.total + (led - kinematic)
    return result


def smooth(
    rows: EvidenceRows, start: np.ndarray, lead_s: float = LIFTOFF_LEAD_S
) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) smoothed log-odds of stance of ``rows`` and (N, 4) filtered (forward) log-odds,
    from ``start``: the 4 feet's log-odds before the first row (zeros: even odds). The
    backward message after the last row is flat.
    """
    evidence = led_evidence(rows, lead_s).tolist()
    with np.errstate(divide="ignore"):
        stay = np.log1p(-rows.switch).tolist()
        move = np.log(rows.switch).tolist()
    count = len(rows)
    forward = [[0.0] * LEGS for _ in range(count)]
    odds = [float(value) for value in start]
    for k in range(count):
        a, b, e, out = stay[k], move[k], evidence[k], forward[k]
        for leg in range(LEGS):
            odds[leg] = out[leg] = _carried(odds[leg], a, b) + e[leg]
    backward = [[0.0] * LEGS for _ in range(count)]
    message = [0.0] * LEGS  # log-odds of the evidence after row k, as seen from row k
    for k in range(count - 2, -1, -1):
        a, b, e, out = stay[k + 1], move[k + 1], evidence[k + 1], backward[k]
        for leg in range(LEGS):
            message[leg] = out[leg] = _carried(message[leg] + e[leg], a, b)
    filtered = np.array(forward).reshape(count, LEGS)
    return filtered + np.array(backward).reshape(count, LEGS), filtered


def smoothed_stance(
    rows: EvidenceRows,
    start: np.ndarray,
    lead_s: float = LIFTOFF_LEAD_S,
    force_lag_s: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) log-odds of stance of a whole recording's ``rows`` as the smoother gives them
    (:func:`posterior` from ``start``, :func:`placed_stance`) and the (N, 4) filtered (forward)
    log-odds.
    """
    stance, filtered = posterior(rows, start, lead_s)
    return placed_stance(rows, stance, force_lag_s), filtered


def placed_stance(
    rows: EvidenceRows, log_odds: np.ndarray, force_lag_s: float, since: int = 0
) -> np.ndarray:
    """(N, 4) log-odds of stance: the posterior ``log_odds`` with the stances' edges placed, by
    the heights for feet without force evidence (:func:`height_edges`, liftoffs pooled from row
    ``since`` on) and by the loads for those with it
    (:func:`~a1_leg_fk.estimation.load_edges.loaded_stance`, the normal forces with their lag
    ``force_lag_s`` [s] undone).
    """
    result = height_edges(rows, log_odds, since)
    if rows.forced.any():
        loads = unlagged(rows.normals, rows.stamps_s, force_lag_s)
        result = without_blips(
            loaded_stance(result, rows.stamps_s, loads, rows.forced), rows.forced
        )
    return result


def posterior(
    rows: EvidenceRows,
    start: np.ndarray,
    lead_s: float = LIFTOFF_LEAD_S,
    before: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) log-odds of stance before the heights place any edge (:func:`smooth` from
    ``start``, :func:`force_liftoffs`, then :func:`~a1_leg_fk.estimation.forced_stance.
    filter_touchdowns` given the (4,) stance ``before`` the first row, None: unknown) and the
    (N, 4) filtered (forward) log-odds.
    """
    smoothed, filtered = smooth(rows, start, lead_s)
    kept = force_liftoffs(smoothed, filtered, rows.forced)
    return filter_touchdowns(kept, filtered, rows.forced, before), filtered


def height_edges(rows: EvidenceRows, log_odds: np.ndarray, since: int = 0) -> np.ndarray:
    """(N, 4) log-odds of stance: ``log_odds``, with the edges of each stance (log-odds >= 0) of
    a foot without force evidence placed by its heights
    (:func:`~a1_leg_fk.estimation.stance_edges.placed_edges`; a stance at the first row began
    before it), then the liftoffs of the stances that end at row ``since`` or later by the
    pooled rise of the leg's stances over the :data:`POOL_S` before
    (:func:`~a1_leg_fk.estimation.pooled_rise.recent_liftoffs`, ``gait``'s rule); a row they
    move to swing takes its log-odds reversed.
    """
    times = np.maximum.accumulate(rows.stamps_s) if len(rows) else rows.stamps_s
    stance = log_odds >= 0.0
    result = log_odds.copy()
    for leg in range(LEGS):
        heights = rows.heights[:, leg]
        against = against_standing(times, rows.heights, stance, leg)
        placed = placed_edges(times, heights, stance[:, leg], against)
        placed = recent_liftoffs(times, heights, placed, POOL_S, since)
        moved = stance[:, leg] & ~placed & ~rows.forced[:, leg]
        result[moved, leg] = -log_odds[moved, leg]
    return result


def force_liftoffs(smoothed: np.ndarray, filtered: np.ndarray, forced: np.ndarray) -> np.ndarray:
    """(N, 4) log-odds of stance: ``smoothed``, but where the foot's force was evidence
    (``forced``) the larger of ``smoothed`` and the filter's ``filtered`` (the module text).
    """
    result: np.ndarray = np.where(forced, np.maximum(smoothed, filtered), smoothed)
    return result


def _carried(m: float, stay: float, move: float) -> float:
    """Log-odds ``m`` carried across one step of the symmetric transition, ``stay`` = log(1 - s)
    and ``move`` = log(s): ``log(((1 - s) e^m + s) / (s e^m + 1 - s))``, finite for any ``m``.
    """
    if move == -math.inf:  # no time passed: nothing changes
        return m
    return _log_add(m + stay, move) - _log_add(m + move, stay)


def _log_add(x: float, y: float) -> float:
    """log(e^x + e^y) without overflow."""
    if x < y:
        x, y = y, x
    return x + math.log1p(math.exp(y - x))


def probabilities(log_odds: np.ndarray) -> np.ndarray:
    """Probabilities of stance from log-odds (NaN stays NaN)."""
    result: np.ndarray = 0.5 * (1.0 + np.tanh(0.5 * log_odds))
    return result


def smoothing_line(smoothed: bool) -> str:
    """The summary's line saying which contacts these are."""
    if smoothed:
        return (
            f"smoothing: contacts smoothed over the recording (forward-backward, {LAG_S:g} s lag, "
            f"liftoff lead {1000 * LIFTOFF_LEAD_S:g} ms, edges by the heights without efforts; "
            "--causal: the node's)"
        )
    return "smoothing: none, the causal filter's contacts as the node has them (--causal)"


POOL_S = 10.0
"""[s] A liftoff is pooled with its leg's stances that ended this long before it (a walk's
strides are 2 s: four or five of them; 4, 6, 8 and 10 s tried on the contact family's tuned
runs, a1_walk with noise seeds 7, 1-5, 11, 12 liftoffs 8 6 10 8 8 8 6 6 ms without pooling,
6 4 4 6 8 6 4 4 with 10 s: docs/forces.md)."""
POOL_MARGIN_S = 3.0
"""[s] The rows kept before the oldest pooled stance's end: its stance and the level before it
(a stance longer than this is left out of the windows' pools, not of one pass's)."""
KEPT_S = max(HISTORY_S, CONTEXT_S, POOL_S + POOL_MARGIN_S)
"""[s] The rows already taken that the edges' rules may look back at."""


class FixedLagSmoother:
    """Smoothed contacts over rows arriving in blocks: :meth:`add` a block's evidence, :meth:`take`
    the rows that are final (every row ``lag_s`` [s] before the latest, or all at the end).
    Keeps only the rows not yet taken, and the last :data:`KEPT_S` of those taken with their
    posterior (log-odds before the edges are placed), for the rules that place the edges.
    ``force_lag_s`` [s]: the time constant of the lag of the normal forces in the evidence (the
    momentum observer's, :attr:`~a1_leg_fk.estimation.contact_estimator.ContactEstimator.
    force_lag_s`; 0: none).
    """

    def __init__(
        self, lag_s: float = LAG_S, lead_s: float = LIFTOFF_LEAD_S, force_lag_s: float = 0.0
    ) -> None:
        self.lag_s, self.lead_s, self.force_lag_s = lag_s, lead_s, force_lag_s
        self.pending = EvidenceRows.empty()
        self.start = np.zeros(LEGS)  # the forward log-odds before the first pending row
        self.history = EvidenceRows.empty()  # the last rows taken, for the edges' rules
        self.history_odds = np.empty((0, LEGS))  # their posterior (log-odds)

    def add(self, rows: EvidenceRows) -> None:
        """Rows after those added before."""
        self.pending = self.pending.then(rows)

    def final_rows(self) -> int:
        """How many of the pending rows are followed by ``lag_s`` of later rows."""
        stamps = self.pending.stamps_s
        if not len(stamps):
            return 0
        reached = np.maximum.accumulate(stamps)
        return int(np.searchsorted(reached, reached[-1] - self.lag_s, side="right"))

    def take(self, count: int) -> np.ndarray:
        """(count, 4) probabilities of stance of the first ``count`` pending rows, smoothed with
        every pending row after them; those rows are then forgotten.
        """
        if count <= 0:
            return np.empty((0, LEGS))
        before = self.history_odds[-1] >= 0.0 if len(self.history_odds) else None
        odds, filtered = posterior(self.pending, self.start, self.lead_s, before)
        rows = self.history.then(self.pending)
        before = len(self.history)
        every = np.vstack([self.history_odds, odds])
        done = before + count
        stance = placed_stance(rows, every, self.force_lag_s, before)[before:done]
        self._keep(rows[:done], every[:done])
        self.start = filtered[count - 1]
        self.pending = self.pending[count:]
        return probabilities(stance)

    def _keep(self, taken: EvidenceRows, odds: np.ndarray) -> None:
        """The last :data:`KEPT_S` of the ``taken`` rows and their ``odds`` become the
        history.
        """
        reached = np.maximum.accumulate(taken.stamps_s)
        first = int(np.searchsorted(reached, reached[-1] - KEPT_S, side="left"))
        self.history, self.history_odds = taken[first:], odds[first:]
