"""``foot_fk_node``'s optional ``gait_phase`` input: a gait scheduler's probability of stance per
foot, which the contact filter takes as a prior
(:func:`~a1_leg_fk.estimation.contact_filter.gait_phase_prior`; the node works without it).

The message is a ``sensor_msgs/msg/JointState`` laid out as the node's own ``foot_contacts``:
``name`` the feet (``FR``, ``FL``, ``RR``, ``RL``; any of them, in any order), ``position`` each
one's probability of stance in [0, 1]. It is subscribed raw through the node's guarded inputs
(:mod:`a1_leg_fk.ros.guarded_input`: a message that cannot be read is counted as
``rejected_gait_phase_malformed`` and dropped) and read by the JointState decoder
(:mod:`a1_leg_fk.wire.joint_state`). The latest message is held and used for every
joint state until ``gait_phase_timeout_s`` has passed since it arrived (the node's monotonic
clock: a scheduler's stamps may come from another clock); then it is stale and the filter runs
without a prior until the next one.
"""

from __future__ import annotations

import math
import time

from sensor_msgs.msg import JointState

from a1_leg_fk.estimation.contact_filter import gait_phase_prior
from a1_leg_fk.ros.glue import JOINT_STATES_QOS
from a1_leg_fk.ros.guarded_input import MALFORMED, GuardedInputs
from a1_leg_fk.wire.joint_state import JointStateDecoder, WireFields, doubles

TOPIC = "gait_phase"


class GaitPhaseInput:
    """The latest ``gait_phase`` of a node, and whether it is still fresh."""

    def __init__(self, inputs: GuardedInputs, timeout_s: float) -> None:
        """Subscribe a node's ``inputs`` to ``gait_phase``; a message is stale ``timeout_s`` [s]
        after it arrived.
        """
        self.timeout_s = timeout_s
        self.prior: list[float] | None = None
        """Per leg the latest message's probability of stance (NaN: none for that foot)."""
        self.messages = 0
        self._inputs = inputs
        self._received_s = -math.inf  # time.monotonic() of the latest message
        self._decoder = JointStateDecoder()
        inputs.subscribe(
            JointState, TOPIC, self._decoder.fields, self._on_message, JOINT_STATES_QOS
        )

    @property
    def malformed(self) -> int:
        """Messages that could not be read."""
        return self._inputs.rejected[f"{TOPIC}_{MALFORMED}"]

    def _on_message(self, fields: WireFields) -> None:
        positions = doubles(fields.positions, fields.order)
        self.prior = gait_phase_prior(self._decoder.names, positions)
        self._received_s = time.monotonic()
        self.messages += 1

    def current(self, now_s: float) -> list[float] | None:
        """The prior at ``now_s`` (``time.monotonic()`` [s]): the latest message's, or None when
        there is none or it is stale.
        """
        return self.prior if now_s - self._received_s <= self.timeout_s else None

    def status(self) -> str:
        """For diagnostics: none yet, or whether the latest is used or stale, and its age."""
        if self.prior is None:
            return f"none received ({self.malformed} malformed)" if self.malformed else "none"
        age_s = time.monotonic() - self._received_s
        state = "used" if age_s <= self.timeout_s else "stale"
        return (
            f"{state}: latest {age_s:.3f} s ago (timeout {self.timeout_s:g} s), "
            f"{self.messages} messages, {self.malformed} malformed"
        )
