"""The ``/diagnostics`` status of ``leg_odometry_node``, as a pure function (no ROS imports).

Joint states are judged as ``foot_fk_node`` judges them (:mod:`a1_leg_fk.ros.diagnostics`); the
odometry adds its own counts: samples (of the state filter, and of the legs alone without an
accelerometer), the feet the filter's gate used and rejected, its gate resets, mean NIS, bias
estimates and the feet's noise scale; samples without a stance foot and feet dropped as slipping
(the legs alone); stamp gaps, the IMU's state, the contacts' evidence and the distance travelled.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from a1_leg_fk.estimation.contact_estimator import EvidenceCounts
from a1_leg_fk.estimation.filter_model import FilterCounts
from a1_leg_fk.estimation.model_corrections import ModelCorrections, correction_values
from a1_leg_fk.estimation.odometry import OdometryCounts
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.ros.diagnostics import (
    INPUTS_REJECTED,
    OK,
    WARN,
    rejected_messages,
    robot_description_status,
)
from a1_leg_fk.tracking import TrackerCounts


@dataclass(frozen=True)
class OdometryReport:
    """What the node knows at one report; ``*_in_period`` since the previous report."""

    tracker: TrackerCounts
    odometry: OdometryCounts
    received_in_period: int
    rejected_in_period: int
    no_stance_in_period: int
    period_s: float
    imu_topic: str
    imu_received: int
    samples_with_imu: int
    imu_pairing: tuple[int, int]  # joint states held for their IMU sample, released without it
    without_velocities: int  # joint states accepted that gave no foot velocity
    model: str
    description_topic: str
    description_status: str
    description_rejected: bool
    contacts: str  # the contacts parameter: auto, force or kinematic
    contact_counts: EvidenceCounts
    contacts_note: str  # why there are no foot forces ("" when there are)
    corrections: ModelCorrections | None  # the contacts' model corrections (None: off)
    corrections_refused: str  # why the corrections' file was refused ("" none)
    filtered: int  # samples the state filter gave
    filter: FilterCounts
    biases: tuple[tuple[float, ...], tuple[float, ...]]  # gyro [rad/s], accelerometer [m/s^2]
    noise_scales: tuple[float, float]  # the feet's noise scales: horizontal, vertical
    distance_m: float
    inputs_rejected_in_period: int = 0  # input messages rejected (unreadable...) in the period
    inputs_rejected: Mapping[str, int] = field(default_factory=dict)  # GuardedInputs.values()


def odometry_status(report: OdometryReport) -> tuple[bytes, str, dict[str, object]]:
    """(level, summary, values). WARN for: no joint state yet, rejected joint states in the
    period, input messages rejected in the period (:mod:`a1_leg_fk.ros.guarded_input`), joint
    states without velocities, no IMU sample, samples without a stance foot in the
    period, force contacts asked for a robot without masses, a rejected robot description; else
    OK.
    """
    tracker, odometry = report.tracker, report.odometry
    level, summary = OK, "odometry published"
    if not tracker.messages:
        level, summary = WARN, "no joint_states received yet"
    elif report.without_velocities and not (odometry.samples or report.filtered):
        level, summary = WARN, "joint_states carry no velocities: no odometry"
    elif report.rejected_in_period:
        level, summary = WARN, "some joint_states rejected"
    elif report.inputs_rejected_in_period:
        level, summary = WARN, INPUTS_REJECTED
    elif report.no_stance_in_period:
        level, summary = WARN, "samples without a stance foot: velocity held and decaying"
    elif report.contacts == "force" and report.contacts_note:
        level, summary = WARN, "contacts force, but no foot forces: no foot stands"
    elif not report.imu_received:
        level, summary = WARN, f"no IMU on {report.imu_topic}: legs alone, planar pose"
    level, summary, description = robot_description_status(
        level,
        summary,
        report.model,
        report.description_topic,
        report.description_status,
        report.description_rejected,
    )
    values: dict[str, object] = {
        "joint_states_received": tracker.messages,
        "joint_states_rejected": rejected_messages(tracker),
        "joint_states_without_velocities": report.without_velocities,
        "input_rate_hz": f"{report.received_in_period / report.period_s:.1f}",
        "imu_topic": report.imu_topic,
        "imu_received": report.imu_received,
        "samples": odometry.samples + report.filtered,
        "samples_with_imu": report.samples_with_imu,
        "joint_states_held_for_imu": report.imu_pairing[0],
        "joint_states_released_without_imu": report.imu_pairing[1],
        "samples_filtered": report.filtered,
        "samples_legs_alone": odometry.samples,
        "samples_without_stance": odometry.no_stance,
        "contacts": report.contacts,
        "samples_with_force_evidence": report.contact_counts.force,
        "samples_with_kinematic_evidence_only": report.contact_counts.kinematic,
        **correction_values(report.corrections, report.corrections_refused),
        **{f"feet_used_{leg}": n for leg, n in zip(LEG_NAMES, report.filter.used)},
        **{f"feet_rejected_{leg}": n for leg, n in zip(LEG_NAMES, report.filter.rejected)},
        "gate_resets": report.filter.gate_resets,
        "zero_velocity_updates": report.filter.still,
        "mean_nis": f"{report.filter.mean_nis:.3f}",
        "gyro_bias_radps": " ".join(f"{value:.5f}" for value in report.biases[0]),
        "accel_bias_mps2": " ".join(f"{value:.4f}" for value in report.biases[1]),
        "feet_noise_scale": f"{report.noise_scales[0]:.4f}",
        "feet_vertical_noise_scale": f"{report.noise_scales[1]:.4f}",
        **{f"slips_{leg}": n for leg, n in zip(LEG_NAMES, odometry.slips)},
        "stamp_gaps": odometry.gaps + report.filter.gaps,
        "distance_m": f"{report.distance_m:.3f}",
        **description,
        **report.inputs_rejected,
    }
    if report.contacts_note:
        values["contacts_note"] = f"no foot forces: {report.contacts_note}"
    return level, summary, values
