"""Contacts smoothed over a recording, block by block: the rows of a pass
(:class:`~a1_leg_fk.recording.foot_block.FootBlock`, each with the contact filter's evidence)
held until the rows after them cover the smoother's lag, then given again with their contacts
smoothed (:class:`~a1_leg_fk.estimation.contact_smoother.FixedLagSmoother`). Memory: the rows of
a block plus the lag, whatever the recording's length.
"""

from __future__ import annotations

from collections.abc import Iterator

from a1_leg_fk.estimation.contact_smoother import FixedLagSmoother
from a1_leg_fk.estimation.force_pass import ForcePass
from a1_leg_fk.recording.foot_block import FootBlock


def smoothed_blocks(blocks: Iterator[FootBlock], forces: ForcePass) -> Iterator[FootBlock]:
    """``blocks`` (each with its ``evidence``, from the pass ``forces``) again, in order, with
    smoothed ``contacts`` and no evidence; a block may come cut in two where the rows final so
    far end.
    """
    smoother = FixedLagSmoother(force_lag_s=forces.estimator.force_lag_s)
    pending: list[FootBlock] = []
    for block in blocks:
        if block.evidence is None:  # no contacts in it: nothing to smooth
            raise ValueError("smoothed_blocks needs every block's evidence")
        smoother.add(block.evidence)
        pending.append(block)
        yield from _final(smoother, pending, smoother.final_rows())
    yield from _final(smoother, pending, len(smoother.pending))


def _final(
    smoother: FixedLagSmoother, pending: list[FootBlock], count: int
) -> Iterator[FootBlock]:
    """The first ``count`` pending rows, smoothed, as blocks; they leave ``pending``."""
    contacts = smoother.take(count)
    done = 0
    while done < count:
        block = pending[0]
        rows = min(len(block.stamps_ns), count - done)
        part = contacts[done : done + rows]
        if rows == len(block.stamps_ns):
            pending.pop(0)
        else:
            pending[0] = block.rows(slice(rows, None))
        yield block.rows(slice(0, rows), part)
        done += rows
