"""foot_fk_node's /diagnostics status as a pure function: fed a FootTracker with known messages."""

from __future__ import annotations

import dataclasses
import math

from diagnostic_msgs.msg import DiagnosticStatus

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.ros.diagnostics import (
    ERROR,
    OK,
    WARN,
    FkReport,
    PeriodCounter,
    fk_status,
    robot_description_status,
)
from a1_leg_fk.tracking import FootTracker

NAMES = [
    f"{leg}_{joint}_joint"
    for leg in ("FR", "FL", "RR", "RL")
    for joint in ("hip", "upper", "lower")
]
STANDING = [0.0, 0.8, -1.5] * 4


def _report(tracker: FootTracker, counter: PeriodCounter, **changes: object) -> FkReport:
    received, rejected = counter.take(tracker.counts)
    report = FkReport(
        counts=tracker.counts,
        received_in_period=received,
        rejected_in_period=rejected,
        period_s=0.5,
        joints_outside_limits=tracker.joints_outside_limits(),
        stamp_jumps_back=0,
        model="a1.urdf",
        description_topic="/robot_description",
        description_status="nothing received",
        description_rejected=False,
        last_verify="not called",
        verify_disagreed=False,
    )
    return dataclasses.replace(report, **changes)  # type: ignore[arg-type]  # fields by name


def test_levels_are_the_diagnostic_msgs_constants():
    assert (OK, WARN, ERROR) == (
        DiagnosticStatus.OK,
        DiagnosticStatus.WARN,
        DiagnosticStatus.ERROR,
    )


def test_counts_rate_and_level_through_a_session():
    tracker, counter = FootTracker(Quadruped.from_urdf()), PeriodCounter()
    level, summary, values = fk_status(_report(tracker, counter))
    assert (level, summary) == (WARN, "no joint_states received yet")
    assert values["messages_received"] == 0 and values["input_rate_hz"] == "0.0"

    for _ in range(3):
        tracker.update(NAMES, STANDING, [])
    tracker.update(NAMES, STANDING[:11], [])  # rejected: 12 names, 11 positions
    tracker.update(["arm_joint"], [0.1], [])
    level, summary, values = fk_status(_report(tracker, counter))
    assert level == WARN and "rejected" in summary
    assert (
        values["messages_received"] == 5 and values["input_rate_hz"] == "10.0"
    )  # 5 messages in 0.5 s
    assert values["messages_accepted"] == 3 and values["messages_position_length_mismatch"] == 1
    assert values["messages_no_leg_joints"] == 1 and values["unknown_joint_names"] == "arm_joint"
    assert values["feet_published"] == 12 and values["joints_outside_limits"] == "none"

    tracker.update(NAMES, STANDING, [])  # the rejection is from the previous period: OK again
    level, summary, values = fk_status(_report(tracker, counter))
    assert (level, summary) == (OK, "feet published") and values["input_rate_hz"] == "2.0"


def test_a_new_tracker_counts_the_period_across_the_change():
    """As foot_fk_node swaps the robot: one rejection reported, then messages for the old and the
    new tracker within one period; the period holds exactly those, none negative."""
    old, counter = FootTracker(Quadruped.from_urdf()), PeriodCounter()
    for _ in range(4):
        old.update(NAMES, STANDING, [])
    old.update(NAMES, STANDING[:11], [])  # rejected
    level, _, values = fk_status(_report(old, counter))
    assert level == WARN and values["input_rate_hz"] == "10.0"  # 5 messages in 0.5 s
    old.update(NAMES, STANDING, [])  # one more for the old robot in the next period
    counter.new_tracker(old.counts)
    new = FootTracker(Quadruped.from_urdf())
    new.update(NAMES, STANDING, [])
    level, summary, values = fk_status(_report(new, counter))
    assert (level, summary) == (OK, "feet published")
    assert values["input_rate_hz"] == "4.0" and values["messages_received"] == 1  # 2 in 0.5 s
    assert counter.take(new.counts) == (0, 0)
    new.update(NAMES, STANDING[:11], [])
    counter.new_tracker(new.counts)  # a rejection just before a change still counts
    assert counter.take(FootTracker(Quadruped.from_urdf()).counts) == (1, 1)


def test_joints_outside_limits_and_non_finite_values_warn():
    tracker, counter = FootTracker(Quadruped.from_urdf()), PeriodCounter()
    tracker.update(
        NAMES, [0.0, 0.8, 0.0, *STANDING[3:]], []
    )  # FR knee straight: outside its limits
    level, _, values = fk_status(_report(tracker, counter))
    assert level == WARN and values["joints_outside_limits"] == "FR_lower_joint"
    assert values["messages_out_of_limits"] == 1
    tracker, counter = FootTracker(Quadruped.from_urdf()), PeriodCounter()
    tracker.update(NAMES, [math.nan, *STANDING[1:]], [])
    level, _, values = fk_status(_report(tracker, counter))
    assert level == WARN and values["non_finite_joint_values"] == 1


def test_a_rejected_description_warns_and_a_verify_disagreement_is_an_error():
    tracker, counter = FootTracker(Quadruped.from_urdf()), PeriodCounter()
    tracker.update(NAMES, STANDING, [])
    level, summary, values = fk_status(
        _report(
            tracker,
            counter,
            description_rejected=True,
            description_status="rejected: malformed XML",
        )
    )
    assert (level, summary) == (WARN, "robot description on /robot_description rejected")
    assert values["robot_description_topic"] == "/robot_description: rejected: malformed XML"
    level, summary, _ = fk_status(
        _report(tracker, counter, description_rejected=True, verify_disagreed=True)
    )
    assert level == ERROR and summary.startswith("verify_fk")
    _, _, values = fk_status(_report(tracker, counter, description_topic=""))
    assert values["robot_description_topic"] == "none: nothing received"


def test_the_robot_description_part_keeps_or_overrides_any_node_status():
    """The part foot_ik_node shares: its own level and summary kept, or a rejection's WARN."""
    kept = robot_description_status(OK, "joint commands published", "a1.urdf", "", "x", False)
    assert kept == (
        OK,
        "joint commands published",
        {"model": "a1.urdf", "robot_description_topic": "none: x"},
    )
    level, summary, values = robot_description_status(
        OK,
        "anything",
        "/r1/robot_description",
        "/r2/robot_description",
        "rejected: leg FR",
        True,
    )
    assert (level, summary) == (WARN, "robot description on /r2/robot_description rejected")
    assert values == {
        "model": "/r1/robot_description",
        "robot_description_topic": "/r2/robot_description: rejected: leg FR",
    }
