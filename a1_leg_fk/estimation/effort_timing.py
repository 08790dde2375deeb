"""Efforts that are late and off in scale, put back as the motors gave them, causally, without
ROS: a robot's effort (from its motor current) can read ``scale`` times the torque (a torque
constant off) and ``latency_s`` late against its joint positions (a bus, a filter). Neither can
be told from a recording by the package (docs/forces.md, "Latency and torque scale": the stance
forces against gravity measure the scale times the true mass, a payload alike; the swing residual
does not single out a lag), so both come from a calibration's file, set from what the robot's
maker or a bench test says.

Per joint state: ``(tau + latency_s dtau/dt) / scale``, ``dtau/dt`` [N m/s] the difference from
the previous joint state's effort over the time between them (a first-order prediction of the
effort ``latency_s`` ahead; none for the first, after a gap over :data:`MAX_STEP_S`, or a
non-finite one).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

MAX_STEP_S = 0.05
"""[s] Joint states further apart than this give no rate (the prediction waits for the next)."""


class EffortTiming:
    """The efforts' correction of one robot: ``scale`` (reported over true, > 0) and
    ``latency_s`` [s] (>= 0), stepped with each joint state in time order.
    """

    def __init__(self, scale: float = 1.0, latency_s: float = 0.0) -> None:
        self.scale, self.latency_s = scale, latency_s
        self._previous: tuple[float, Sequence[float]] | None = None

    @property
    def identity(self) -> bool:
        """True when nothing is changed (scale 1, no latency)."""
        return self.scale == 1.0 and self.latency_s == 0.0

    def efforts(self, stamp_s: float, efforts: Sequence[float]) -> list[float]:
        """The efforts [N m] at ``stamp_s`` [s] (slot order, NaN where unknown) as the motors
        gave them.
        """
        previous, self._previous = self._previous, (stamp_s, efforts)
        step = stamp_s - previous[0] if previous is not None else math.nan
        inverse = 1.0 / self.scale
        if previous is None or not 0.0 < step <= MAX_STEP_S or self.latency_s == 0.0:
            return [effort * inverse for effort in efforts]
        ahead = self.latency_s / step
        return [
            (effort + ahead * (effort - before)) * inverse if math.isfinite(before) else
            effort * inverse
            for effort, before in zip(efforts, previous[1], strict=True)
        ]  # fmt: skip
