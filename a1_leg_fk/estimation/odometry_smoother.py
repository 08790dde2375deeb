"""The odometry of a recording smoothed over it, in windows (:class:`OdometrySmoother`): the
state filter keeps its steps (:class:`~a1_leg_fk.estimation.filter_history.FilterHistory`), and
once they span ``window_s + overlap_s`` the Rauch-Tung-Striebel pass
(:func:`~a1_leg_fk.estimation.state_smoother.smooth`) runs backward from the latest state; the
samples of the first ``window_s`` are given again smoothed, the last ``overlap_s`` wait for the
next window (their future then reaches further). The filter itself runs on unchanged: the
smoothed states never feed back.

Memory: the history of one window and its overlap (2.9 kB a step, 29 MB for 8 + 2 s at 1 kHz)
and its pending samples, whatever the recording's length.
"""

from __future__ import annotations

from collections import deque
from typing import NamedTuple

import numpy as np

from a1_leg_fk.estimation.odometry import OdometrySample
from a1_leg_fk.estimation.state_filter import StateFilter
from a1_leg_fk.estimation.state_sample import state_sample
from a1_leg_fk.estimation.state_smoother import smooth
from a1_leg_fk.kinematics.frames import Vector

WINDOW_S = 8.0
"""[s] The samples each backward pass gives (see docs/odometry.md for the choice)."""
OVERLAP_S = 2.0
"""[s] The future each window's last samples are smoothed with, beyond the window: the filter's
gains decay over well under a second at its noise settings, so two seconds leave the windowed
pass within a few µm/s of the whole run's (docs/odometry.md)."""


class Pending(NamedTuple):
    """A causal sample waiting for its window: the filter's step when it was taken (None: not
    the filter's, e.g. the legs alone before the IMU), the gyro's sample and the gate's doubt
    then.
    """

    step: int | None
    sample: OdometrySample
    gyro: Vector
    doubt: Vector


class OdometrySmoother:
    """Smooths the samples of ``state_filter`` (which it gives a history): :meth:`add` each
    causal sample as it comes (with the feed's ``samples_filtered``), :meth:`finish` at the
    end; both return the samples that are final, smoothed, in order.
    """

    def __init__(
        self, state_filter: StateFilter, window_s: float = WINDOW_S, overlap_s: float = OVERLAP_S
    ) -> None:
        self.filter = state_filter
        self.history = state_filter.keep_history()
        self.window_s = window_s
        self.overlap_ns = round(overlap_s * 1e9)
        self._pending: deque[Pending] = deque()
        self._filtered = 0

    def add(self, sample: OdometrySample, filtered: int) -> list[OdometrySample]:
        """One causal sample; ``filtered``: the samples the state filter gave so far (the
        feed's ``samples_filtered``: if it grew, this one is the filter's, else it is kept as
        it is).
        """
        step = self.history.steps if filtered > self._filtered else None
        self._filtered = filtered
        self._pending.append(Pending(step, sample, self.filter.gyro, self.filter.doubt))
        history = self.history
        if history.span_s() < self.window_s + self.overlap_ns / 1e9:
            return []
        stamps = history.stamps_ns[: history.count]
        return self._smoothed(int(np.searchsorted(stamps, stamps[-1] - self.overlap_ns)))

    def finish(self) -> list[OdometrySample]:
        """Every sample still waiting, smoothed to the recording's end."""
        return self._smoothed(self.history.count, final=True)

    def _smoothed(self, emit: int, final: bool = False) -> list[OdometrySample]:
        """The pending samples of the first ``emit`` recorded steps (and those not the
        filter's before them; ``final``: all), smoothed; those steps leave the history.
        """
        history, state_filter = self.history, self.filter
        end = (state_filter.rotation, state_filter.nominal, state_filter.covariance)
        states = smooth(history, end, emit)
        first, done = history.first, history.first + emit
        out = []
        while self._pending and (final or self._pending[0].step is None
                                 or self._pending[0].step < done):  # fmt: skip
            step, sample, gyro, doubt = self._pending.popleft()
            if step is None:
                out.append(sample)
                continue
            row = step - first
            state = (
                (states.rotations[row], states.nominals[row], states.covariances[row])
                if row < emit
                else end
            )
            legs = (sample.stance, sample.used)
            out.append(
                state_sample(sample.stamp_ns, state, (gyro, doubt), state_filter.settings, legs)
            )
        history.drop(emit)
        return out
