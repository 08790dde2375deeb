"""The state filter's gate on the standing feet (:mod:`a1_leg_fk.estimation.state_filter`): each
foot's normalised innovation squared (NIS) against χ², 3 dof; the gate's reset when every foot
has failed too long (or none was ever believed: a start in motion), on the feet that agree; and
the feet's horizontal and vertical noise scales matched to the accepted feet's NIS (covariance
matching).
"""

from __future__ import annotations

from a1_leg_fk.estimation.filter_model import FilterCounts, FilterSettings
from a1_leg_fk.estimation.stance import consistent_feet


class FootGate:
    """The gate (:meth:`__call__`, once per joint state), its counts (shared with the filter's)
    and the noise scales it keeps.
    """

    def __init__(self, settings: FilterSettings, counts: FilterCounts) -> None:
        self.settings = settings
        self.counts = counts
        self.noise_scale = 1.0
        """The feet's horizontal noise variance over the model's
        (:data:`FilterSettings.noise_adapt_s`)."""
        self.vertical_scale = 1.0
        """Their vertical one's (:data:`FilterSettings.vertical_adapt_s`)."""
        self._rejected_since_ns: int | None = None
        self._stamp_ns: int | None = None

    @property
    def scales(self) -> tuple[float, float]:
        """The feet's noise scales: horizontal, vertical."""
        return (self.noise_scale, self.vertical_scale)

    def __call__(
        self,
        stamp_ns: int,
        candidates: list[int],
        normalised: tuple[list[float], list[float], list[float]],
        residuals: list[tuple[float, float, float]],
    ) -> tuple[list[int], bool]:
        """The candidate legs whose NIS (``normalised``: each foot's, its part along world up, 1
        dof, and its NIS with the last touchdown's horizontal jolt) passes the gate, and whether
        the gate was reset (every foot failed for :data:`FilterSettings.max_rejected_s`, or none
        was ever believed: the feet whose ``residuals`` agree taken); counts kept, the noise
        scales matched to the accepted feet's NIS with the jolt (the jolt is no white noise).
        """
        s, counts = self.settings, self.counts
        nis, vertical, matched = normalised
        accepted = [leg for leg, value in zip(candidates, nis) if value <= s.gate_chi2]
        reset = False
        if accepted:
            self._rejected_since_ns = None
        else:
            if self._rejected_since_ns is None:
                self._rejected_since_ns = stamp_ns
            lost = (stamp_ns - self._rejected_since_ns) / 1e9 >= s.max_rejected_s
            if lost or not sum(counts.used):
                found = dict(zip(candidates, residuals))
                group = consistent_feet(found, (0.0, 0.0, 0.0), 0.0, s.reset_agreement_mps)
                if group:
                    accepted, self._rejected_since_ns, reset = group, None, True
                    counts.gate_resets += 1
        total = up = jolted = 0.0
        for leg, value, along, match in zip(candidates, nis, vertical, matched):
            if leg in accepted:
                counts.used[leg] += 1
                total += value
                up += along
                jolted += match
            else:
                counts.rejected[leg] += 1
        if accepted:
            counts.nis_sum += total
            counts.nis_count += len(accepted)
            count = len(accepted)
            self._adapt(stamp_ns, max(jolted - up, 0.0) / (2.0 * count), up / count)
        return accepted, reset

    def _adapt(self, stamp_ns: int, ratio: float, vertical: float) -> None:
        """Move the feet's noise scales towards consistency: ``ratio`` is the accepted feet's
        mean horizontal NIS over its expectation (2), ``vertical`` their mean NIS along world up
        (1), each held within [0.1, 10] for a step. The touchdowns' impacts, no white noise a
        mean NIS could measure, are modelled apart (they would inflate the scale).
        """
        previous, self._stamp_ns = self._stamp_ns, stamp_ns
        if previous is None:
            return
        s = self.settings
        seconds = min(max((stamp_ns - previous) / 1e9, 0.0), s.max_step_s)
        self.noise_scale = self._moved(self.noise_scale, seconds, s.noise_adapt_s, ratio)
        self.vertical_scale = self._moved(
            self.vertical_scale, seconds, s.vertical_adapt_s, vertical
        )

    def _moved(self, scale: float, seconds: float, time_constant: float, ratio: float) -> float:
        """``scale`` moved over ``seconds`` with ``time_constant`` [s] (0: fixed) towards
        ``ratio`` (held within [0.1, 10] for a step), within [``min_noise_scale``, 1].
        """
        if not time_constant > 0.0:
            return scale
        scale *= 1.0 + seconds / time_constant * (min(max(ratio, 0.1), 10.0) - 1.0)
        return min(max(scale, self.settings.min_noise_scale), 1.0)
