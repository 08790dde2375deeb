"""Where a foot with force evidence stops standing, placed from its estimated load over the
recording: the contact smoother's last step (:mod:`a1_leg_fk.estimation.contact_smoother`),
offline only. Numpy arrays in and out, without ROS.

A foot is on the ground while its normal force is above zero; the contact filter's force
evidence is at even odds at 3 % of the weight
(:data:`~a1_leg_fk.estimation.contact_model.FORCE_HALF_SHARE`), so a smoothed stance ends while
the foot still carries a little load: a few ms early where the load ramps down slowly, or where
it lingers below that share for a while (a foot unloading slowly, or dipping to a few newtons
while it stands). With the whole recording at hand the load itself can place that end. Where a
stance of a foot with force evidence ends (its last sample of log-odds >= 0, the next below),
three rules may lengthen it, never shorten it:

- **the unloading ramp**: a line fitted to the load over the :data:`RAMP_WINDOW_S` up to the
  stance's last sample; where it falls to zero within :data:`RAMP_REACH_S` after it, the samples
  up to there stand with the probability that their load is above zero (its value over its
  standard error, through the normal distribution), as long as that value is at least
  :data:`RAMP_CONFIDENCE` standard errors. A sample's load is the line's extrapolation and the
  sample's own load weighted by their inverse variances (the line's standard error there; the
  spread of the line's residuals for the sample): a load that falls off a cliff, as a trotting
  foot's does in its last sample, is not carried on by the line, and one that follows it is
  carried with more confidence. Where the load's noise floor (below) is known and the line's
  load at the stance's last sample stands above it, the samples' own loads show where it
  reaches zero and the floor's rule alone places the end: a trotting foot's load ramps down to
  6-10 N, then falls to zero within a sample, and the line would carry the stance one to three
  samples on;
- **the load above the noise floor**: the samples right after the stance whose load stays above
  :data:`FLOOR_SIGMAS` times the load's noise stand (at most :data:`MAX_LOADED_S`): a load's
  last newtons, or a whole dip to a few newtons bridged. The noise is the load's robust spread
  (1.4826 times the median of its absolute value) over every foot's swing samples within
  :data:`NOISE_S` either side of the stance's end; without :data:`MIN_NOISE_SAMPLES` of them,
  this rule is off there. On a clean simulation the floor is a fraction of a newton; with a
  real robot's sensor noise it is tens of newtons, and this rule does nothing;
- **a dip**: a swing after the stance that ends in the next stance within :data:`MAX_LOADED_S`
  and whose load stays above :data:`DIP_SIGMAS` times the same noise on every sample stands
  (a foot whose load dips to a fraction of a newton without ever reaching zero: the walk's
  first stride). A swing's load hovers around zero, so the whole swing above this lower floor
  is a foot still loaded, where the floor above, which carries a stance on sample by sample,
  would take the load's last newtons for it.

The load is the estimated normal force with the momentum observer's first-order lag undone
(:func:`unlagged`): right after a foot lifts, the observer still shows a newton or so decaying
by ``exp(-dt / lag)`` per sample, which the floor would otherwise read as a foot still
loaded. Tuned on the contact family's tuned runs (docs/forces.md).
"""

from __future__ import annotations

import math

import numpy as np

from a1_leg_fk.estimation.force_lag import undo_lag
from a1_leg_fk.estimation.stance_edges import MAD_SIGMA

RAMP_WINDOW_S = 0.010
"""[s] The load's samples a stance's unloading ramp is fitted over, up to its last sample."""
RAMP_REACH_S = 0.008
"""[s] How far after a stance's last sample the ramp may carry it: a ramp reaching zero later
is no unloading ramp, and leaves the stance as it is."""
RAMP_CONFIDENCE = 1.5
"""A sample stands on the ramp while the ramp's load there is this many standard errors above
zero (at 1 a trotting foot's noise was carried a sample past its cliff: with the causal
filter's force fade, a1_trot_soft+noise's smoothed contacts fell below its causal ones; at 2 a
pronk's slow push-off was cut a sample short; docs/forces.md)."""
FLOOR_SIGMAS = 8.0
"""A load above this many times its noise is a foot still loaded."""
MAX_LOADED_S = 0.1
"""[s] The longest a stance is carried on by its load above the noise floor, or a dip bridged
(the transition's mean time between changes)."""
DIP_SIGMAS = 4.0
"""A swing between two stances whose load stays above this many times its noise is a dip (2
to 6 met the same goals on the contact family's tuned runs, docs/forces.md)."""
NOISE_S = 0.4
"""[s] The swing samples the load's noise is taken over, either side of a stance's end."""
MIN_NOISE_SAMPLES = 20
"""Fewer swing samples than this give no noise floor."""
HISTORY_S = NOISE_S + MAX_LOADED_S + RAMP_WINDOW_S
"""[s] The rows before a window that these rules may look back at (the fixed-lag smoother keeps
them)."""
MAX_LOG_ODDS = 20.0
"""Log-odds of stance the rules give are kept within +-this."""


def unlagged(normals: np.ndarray, stamps_s: np.ndarray, lag_s: float) -> np.ndarray:
    """(N, 4) the loads [N]: ``normals`` (N, 4) [N] (NaN: none) with a first-order lag of time
    constant ``lag_s`` [s] undone, ``(n_k - a n_(k-1)) / (1 - a)``, ``a = exp(-dt / lag_s)``
    (the first row, and rows after a missing one or no time, as they are; ``lag_s`` 0: none).
    """
    if lag_s <= 0.0 or len(normals) < 2:
        return normals.copy()
    dt = np.diff(stamps_s)[:, None]
    with np.errstate(over="ignore", invalid="ignore"):
        keep = np.exp(-np.maximum(dt, 0.0) / lag_s)
        undone = undo_lag(normals[1:], normals[:-1], keep)
    usable = np.isfinite(undone) & (dt > 0.0)
    result: np.ndarray = np.vstack([normals[:1], np.where(usable, undone, normals[1:])])
    return result


def loaded_stance(
    odds: np.ndarray, stamps_s: np.ndarray, loads: np.ndarray, forced: np.ndarray
) -> np.ndarray:
    """(N, 4) log-odds of stance: ``odds`` (N, 4) with the stances of feet whose force was
    evidence (``forced``, (N, 4) bool) carried on by their ``loads`` (N, 4) [N] (the module
    text); rows at ``stamps_s`` (N,) [s] (a stamp before an earlier row's counts as that one's).
    """
    result = odds.copy()
    if not len(stamps_s):
        return result
    stamps_s = np.maximum.accumulate(stamps_s)
    stance = odds >= 0.0
    ends = stance[:-1] & ~stance[1:] & forced[:-1]
    swing = ~stance & forced & np.isfinite(loads)
    for last, leg in zip(*np.nonzero(ends), strict=True):
        floor = _noise(loads, swing, stamps_s, float(stamps_s[last]))
        if floor is not None:
            _carried(result, (stamps_s, loads[:, leg], stance[:, leg]), last, leg, floor)
        _ramp(result, (stamps_s, loads[:, leg]), last, leg, floor)
    return result


def _noise(
    loads: np.ndarray, swing: np.ndarray, stamps_s: np.ndarray, at_s: float
) -> float | None:
    """The loads' robust spread [N] over the swing samples within :data:`NOISE_S` of ``at_s``."""
    lo, hi = np.searchsorted(stamps_s, [at_s - NOISE_S, at_s + NOISE_S], side="left")
    values = loads[lo:hi][swing[lo:hi]]
    if values.size < MIN_NOISE_SAMPLES:
        return None
    return MAD_SIGMA * float(np.median(np.abs(values)))


def _carried(
    result: np.ndarray,
    leg_rows: tuple[np.ndarray, np.ndarray, np.ndarray],
    last: int,
    leg: int,
    noise_n: float,
) -> None:
    """The swing samples after row ``last`` that the load carries stand, within
    :data:`MAX_LOADED_S`: those whose load stays above the floor (:data:`FLOOR_SIGMAS` times
    ``noise_n`` [N]), or the whole swing where it is a dip (it ends in a stance, its load above
    :data:`DIP_SIGMAS` times ``noise_n`` on every sample); ``leg_rows``: the stamps [s], the
    leg's loads [N] and its stance before these rules.
    """
    stamps_s, loads, stance = leg_rows
    stop = int(np.searchsorted(stamps_s, stamps_s[last] + MAX_LOADED_S, side="right"))
    standing = np.flatnonzero(stance[last + 1 : stop])
    end = last + 1 + int(standing[0]) if standing.size else stop
    swing = loads[last + 1 : end]
    above = swing > FLOOR_SIGMAS * noise_n  # NaN: unknown, not above
    if standing.size and (swing > DIP_SIGMAS * noise_n).all():
        count = swing.size
    else:
        count = swing.size if above.all() else int(np.argmin(above))
    for k in range(last + 1, last + 1 + count):
        result[k, leg] = max(result[k, leg], _above_zero(loads[k] / max(noise_n, 1e-12)))


def _ramp(
    result: np.ndarray,
    leg_rows: tuple[np.ndarray, np.ndarray],
    last: int,
    leg: int,
    noise_n: float | None,
) -> None:
    """The unloading ramp of the leg's loads [N] before row ``last`` carried to zero (the
    module text), into ``result``: least squares in floats (a handful of samples);
    ``leg_rows``: the stamps [s] and the leg's loads; none where the line's load at ``last``
    stands above the floor of the load's noise ``noise_n`` [N] (None: unknown).
    """
    stamps_s, loads = leg_rows
    end_s = float(stamps_s[last])
    first = int(np.searchsorted(stamps_s, end_s - RAMP_WINDOW_S + 1e-9, side="left"))
    points = [
        (t - end_s, n)
        for t, n in zip(stamps_s[first : last + 1].tolist(), loads[first : last + 1].tolist())
        if math.isfinite(n)
    ]
    count = len(points)
    if count < 3:
        return
    t_mean = sum(t for t, _ in points) / count
    n_mean = sum(n for _, n in points) / count
    spread = sum((t - t_mean) * (t - t_mean) for t, _ in points)
    if not spread > 0.0:
        return
    slope = sum((t - t_mean) * (n - n_mean) for t, n in points) / spread
    offset = n_mean - slope * t_mean
    if not slope < 0.0 or -offset / slope > RAMP_REACH_S:
        return
    if noise_n is not None and offset > FLOOR_SIGMAS * noise_n:
        return  # the samples' own loads resolve the ramp: the floor's rule places its end
    residuals = [n - offset - slope * t for t, n in points]
    variance = sum(r * r for r in residuals) / max(count - 2, 1)
    if not math.isfinite(variance):  # absurd loads: no ramp
        return
    k = last + 1
    while k < len(stamps_s) and (dt := float(stamps_s[k]) - end_s) <= RAMP_REACH_S:
        load, error = _with_own(
            (offset + slope * dt, variance * (1.0 / count + (dt - t_mean) ** 2 / spread)),
            (float(loads[k]), variance),
        )
        if load <= RAMP_CONFIDENCE * error:
            break
        result[k, leg] = max(result[k, leg], _above_zero(load / error))
        k += 1


def _with_own(line: tuple[float, float], own: tuple[float, float]) -> tuple[float, float]:
    """A sample's load [N] and its standard error [N] from the ramp's ``line`` (extrapolated
    load, its variance [N^2]) and its ``own`` (measured load, variance): their inverse-variance
    weighted mean (the line's alone where the sample's load is not finite).
    """
    (line_n, line_var), (own_n, own_var) = line, own
    line_var, own_var = max(line_var, 1e-24), max(own_var, 1e-24)
    if not math.isfinite(own_n):
        return line_n, math.sqrt(line_var)
    weight = 1.0 / line_var + 1.0 / own_var
    return (line_n / line_var + own_n / own_var) / weight, math.sqrt(1.0 / weight)


def _above_zero(z: float) -> float:
    """The log-odds that a normal variable ``z`` standard deviations above zero is above it,
    within +-:data:`MAX_LOG_ODDS`.
    """
    z = min(max(z, -8.0), 8.0)
    above, below = math.erfc(-z / math.sqrt(2.0)), math.erfc(z / math.sqrt(2.0))
    return min(max(math.log(above / below), -MAX_LOG_ODDS), MAX_LOG_ODDS)
