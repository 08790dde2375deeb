"""The ``/diagnostics`` status of ``foot_fk_node``, as a pure function (no ROS imports).

:func:`fk_status` turns what the node knows at one report (the :class:`FootTracker` counts, the
joints outside their limits, the robot description's and ``verify_fk``'s state) into a level, a
one-line summary and the key/value pairs; :class:`PeriodCounter` gives the messages and
rejections since the previous report. The node wraps the result in a DiagnosticArray.
:func:`robot_description_status` is the robot-description part, shared with ``foot_ik_node``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from a1_leg_fk.estimation.contact_estimator import ImuSample
from a1_leg_fk.estimation.force_pass import ForcePass
from a1_leg_fk.estimation.model_corrections import correction_values
from a1_leg_fk.tracking import REJECTIONS, TrackerCounts

OK, WARN, ERROR = b"\x00", b"\x01", b"\x02"
"""``diagnostic_msgs/msg/DiagnosticStatus`` levels (byte constants, as the message defines
them)."""

MAX_LISTED_UNKNOWN_NAMES = 20
INPUTS_REJECTED = "some input messages rejected (rejected_<topic>_<reason>)"
"""The summary of a period in which some input's messages were rejected
(:mod:`a1_leg_fk.ros.guarded_input`)."""


def rejected_messages(counts: TrackerCounts) -> int:
    """Messages rejected so far, for any of :data:`a1_leg_fk.tracking.REJECTIONS`."""
    return sum(counts.outcomes[rejection] for rejection in REJECTIONS)


@dataclass
class PeriodCounter:
    """Messages received and rejected between successive :meth:`take` calls, over the
    cumulative counts of a tracker that may be replaced by a fresh one (:meth:`new_tracker`).
    """

    _previous: tuple[int, int] = (0, 0)  # the counts at the previous take (or tracker change)
    _carried: tuple[int, int] = (0, 0)  # counted by replaced trackers since the previous take

    def take(self, counts: TrackerCounts) -> tuple[int, int]:
        """(received, rejected) since the previous call; the first call counts from zero."""
        now = (counts.messages, rejected_messages(counts))
        since = (
            self._carried[0] + now[0] - self._previous[0],
            self._carried[1] + now[1] - self._previous[1],
        )
        self._previous, self._carried = now, (0, 0)
        return since

    def new_tracker(self, old: TrackerCounts) -> None:
        """The tracker whose counts are ``old`` is being replaced by a fresh one (counts from
        zero): what ``old`` counted since the previous take goes into the next take's result.
        """
        self._carried = self.take(old)
        self._previous = (0, 0)


@dataclass(frozen=True)
class FkReport:
    """What the node knows at one report. ``period_s`` [s] is the time between reports;
    ``received_in_period``/``rejected_in_period`` come from :meth:`PeriodCounter.take`.
    """

    counts: TrackerCounts
    received_in_period: int
    rejected_in_period: int
    period_s: float
    joints_outside_limits: Sequence[str]
    stamp_jumps_back: int
    model: str
    description_topic: str  # the resolved topic name, "" when none is followed
    description_status: str
    description_rejected: bool
    last_verify: str
    verify_disagreed: bool  # the latest verify_fk found a foot beyond the tolerance
    forces: Mapping[str, object] = field(default_factory=dict)  # force_values()
    inputs_rejected_in_period: int = 0  # input messages rejected (unreadable...) in the period
    inputs_rejected: Mapping[str, int] = field(default_factory=dict)  # GuardedInputs.values()


def fk_status(report: FkReport) -> tuple[bytes, str, dict[str, object]]:
    """(level, summary, values) of the report. ERROR when verify_fk disagreed with PyBullet; else
    WARN for a rejected robot description, no joint state yet, or rejected messages in the
    period, non-finite values or joints outside limits, messages of an input that could not be
    read in the period; else OK.
    """
    counts = report.counts
    outside = report.joints_outside_limits
    level, summary = OK, "feet published"
    if not counts.messages:
        level, summary = WARN, "no joint_states received yet"
    elif report.rejected_in_period or outside or counts.non_finite_joints:
        level, summary = WARN, "some joint_states rejected or joints outside limits"
    elif report.inputs_rejected_in_period:
        level, summary = WARN, INPUTS_REJECTED
    level, summary, description = robot_description_status(
        level,
        summary,
        report.model,
        report.description_topic,
        report.description_status,
        report.description_rejected,
    )
    if report.verify_disagreed:
        level, summary = ERROR, "verify_fk: FK disagrees with PyBullet beyond the tolerance"
    unknown = sorted(counts.unknown_names)[:MAX_LISTED_UNKNOWN_NAMES]
    values: dict[str, object] = {
        "messages_received": counts.messages,
        **{f"messages_{outcome}": n for outcome, n in sorted(counts.outcomes.items())},
        "non_finite_joint_values": counts.non_finite_joints,
        "feet_published": counts.feet,
        "input_rate_hz": f"{report.received_in_period / report.period_s:.1f}",
        "joints_outside_limits": ",".join(outside) or "none",
        "messages_out_of_limits": counts.out_of_limit_messages,
        "unknown_joint_names": ",".join(unknown) or "none",
        "stamp_jumps_back": report.stamp_jumps_back,
        "last_verify": report.last_verify,
        **description,
        **report.forces,
        **report.inputs_rejected,
    }
    return level, summary, values


def force_values(
    forces: ForcePass | None, problem: str, imu: ImuSample, gait_phase: str, refused: str = ""
) -> dict[str, object]:
    """The foot-force part of the status: whether forces are estimated (else ``problem``), the
    force model and contact rule, the leg forces estimated, the legs without one (efforts
    missing, not finite or of the wrong length; near-singular), the joint states whose contacts
    had force evidence and those with kinematic evidence alone, what the latest ``imu`` gave
    (gravity's direction, gyro, accelerometer), the ``gait_phase`` input's state and the
    threshold rule's forces [N], the model corrections' terms (``refused``: why their file was
    refused, "" none).
    """
    if forces is None:
        return {"foot_forces": problem}
    counts, thresholds, estimator = forces.counts, forces.thresholds, forces.estimator
    return {
        "foot_forces": "on",
        "force_model": estimator.force_model,
        "contact_rule": estimator.contact_rule,
        "leg_forces_estimated": counts.estimated,
        "legs_without_efforts": counts.missing,
        "legs_near_singular": counts.singular,
        "contacts_with_force_evidence": estimator.counts.force,
        "contacts_with_kinematic_evidence_only": estimator.counts.kinematic,
        "gravity_from": "imu orientation"
        if imu.gravity is not None
        else "base -z (no imu orientation)",
        "base_motion_from": ", ".join(
            name
            for name, value in (
                ("gyro", imu.angular_velocity),
                ("accelerometer", imu.specific_force),
            )
            if value is not None
        )
        or "none (the base taken as inertial)",
        "gait_phase": gait_phase,
        "touchdown_force_n": f"{thresholds.touchdown_n:.3f}",
        "liftoff_force_n": f"{thresholds.liftoff_n:.3f}",
        **correction_values(estimator.corrections, refused),
    }


def robot_description_status(
    level: bytes, summary: str, model: str, topic: str, status: str, rejected: bool
) -> tuple[bytes, str, dict[str, object]]:
    """A node's ``level`` and ``summary``, turned to WARN "robot description on ``topic``
    rejected" when the latest description from ``topic`` was rejected, and the ``model`` and
    ``robot_description_topic`` values ("``topic`` or none: ``status``") of its status.
    """
    if rejected:
        level, summary = WARN, f"robot description on {topic} rejected"
    return (
        level,
        summary,
        {"model": model, "robot_description_topic": f"{topic or 'none'}: {status}"},
    )
