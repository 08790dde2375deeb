"""The parameters of ``foot_fk_node`` (:mod:`a1_leg_fk.ros.foot_fk_node`): names, defaults, types,
descriptions and the ranges rclpy enforces; the model parameters are
:class:`a1_leg_fk.ros.robot_source.RobotSource`'s.
"""

from __future__ import annotations

from rcl_interfaces.msg import ParameterType

from a1_leg_fk.estimation.model_corrections import DEFAULT_MODEL_CORRECTIONS, MODEL_CORRECTIONS
from a1_leg_fk.ros.correction_choice import FILE
from a1_leg_fk.ros.joint_input import INPUT_PARAMETER
from a1_leg_fk.ros.robot_source import BASE_FRAME_PARAMETER, ParameterSpec

MARKER_RATE_RANGE_HZ = (0.001, 1000.0)
PUBLISH_RATE_RANGE_HZ = (0.0, 1_000_000.0)
VERIFY_TOLERANCE_RANGE_M = (1e-12, 1.0)
CONTACT_FORCE_RANGE_N = (0.0, 1e6)
GAIT_PHASE_TIMEOUT_RANGE_S = (0.001, 3600.0)
"""Inclusive ranges rclpy enforces (FloatingPointRange) on the node's double parameters."""
FORCE_PARAMETERS = (
    "publish_forces",
    "force_model",
    "contact_rule",
    "touchdown_force_n",
    "liftoff_force_n",
)
"""The parameters whose change rebuilds the force and contact rules."""
MODEL_CORRECTIONS_PARAMETER = ParameterSpec(
    "model_corrections",
    DEFAULT_MODEL_CORRECTIONS,
    ParameterType.PARAMETER_STRING,
    "The joints' friction and torque bias the URDF does not list, learnt while a foot is surely "
    "in the air and taken off the momentum observer's torques, each term once it is "
    "significant ('online'; force_model 'dynamic', contact_rule 'filter'), read from "
    "model_corrections_file ('file'; a file given with 'online' is used too), or not ('off'); "
    "the terms in /diagnostics",
    read_only=True,
    choices=(*MODEL_CORRECTIONS, FILE),
)
"""``model_corrections`` of both nodes (foot_fk_node's forces, leg_odometry_node's contacts)."""
MODEL_CORRECTIONS_FILE_PARAMETER = ParameterSpec(
    "model_corrections_file",
    "",
    ParameterType.PARAMETER_STRING,
    "A calibration's file (a1-leg-fk calibrate -o FILE): its joints' bias and friction taken "
    "off as they are, its payload added to the weight; one that cannot be read or does not "
    "match the robot is refused in one logged line and the node runs on the nominal model "
    "(model_corrections_refused in /diagnostics); '' none",
    read_only=True,
)
"""``model_corrections_file`` of both nodes."""

PARAMETERS = (
    BASE_FRAME_PARAMETER,
    INPUT_PARAMETER,
    ParameterSpec(
        "publish_velocities",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish foot_velocities/<leg> (J q_dot, m/s) when a message has the leg's three "
        "velocities",
    ),
    ParameterSpec(
        "publish_markers",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish foot_markers (MarkerArray) while someone subscribes",
    ),
    ParameterSpec(
        "marker_rate_hz",
        30.0,
        ParameterType.PARAMETER_DOUBLE,
        f"Highest rate of foot_markers [Hz], in {MARKER_RATE_RANGE_HZ}",
        value_range=MARKER_RATE_RANGE_HZ,
    ),
    ParameterSpec(
        "max_publish_rate_hz",
        0.0,
        ParameterType.PARAMETER_DOUBLE,
        "Highest rate of foot positions/velocities [Hz], in "
        f"{PUBLISH_RATE_RANGE_HZ}; 0 = one set per joint state (no throttling)",
        value_range=PUBLISH_RATE_RANGE_HZ,
    ),
    ParameterSpec(
        "enable_verify",
        True,
        ParameterType.PARAMETER_BOOL,
        "Offer the verify_fk service (compares the FK with PyBullet's)",
    ),
    ParameterSpec(
        "verify_tolerance_m",
        1e-6,
        ParameterType.PARAMETER_DOUBLE,
        "verify_fk succeeds when every foot is within this distance [m] of PyBullet's, in "
        f"{VERIFY_TOLERANCE_RANGE_M}",
        value_range=VERIFY_TOLERANCE_RANGE_M,
    ),
    ParameterSpec(
        "preserialized_output",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish the foot messages as bytes patched into a pre-serialized message (the same "
        "messages, cheaper); false = as message objects",
    ),
    ParameterSpec(
        "publish_forces",
        True,
        ParameterType.PARAMETER_BOOL,
        "Publish foot_forces/<leg> (N, the ground's force on the foot) when a message has the "
        "efforts of a leg's three joints, and foot_contacts (with or without efforts)",
    ),
    ParameterSpec(
        "force_model",
        "dynamic",
        ParameterType.PARAMETER_STRING,
        "Foot forces from the legs' dynamics ('dynamic': momentum observer, the imu's gyro and "
        "accelerometer for the base's motion) or quasi-statically ('static': F = J^-T (g - tau))",
    ),
    ParameterSpec(
        "contact_rule",
        "filter",
        ParameterType.PARAMETER_STRING,
        "foot_contacts from the fused filter ('filter': normal force, foot heights and speeds; "
        "contacts without efforts too) or the normal force between two thresholds ('threshold')",
    ),
    ParameterSpec(
        "touchdown_force_n",
        0.0,
        ParameterType.PARAMETER_DOUBLE,
        "contact_rule 'threshold': a foot touches down when its normal force reaches this [N], in "
        f"{CONTACT_FORCE_RANGE_N}; 0 = 8 % of the robot's weight (URDF masses)",
        value_range=CONTACT_FORCE_RANGE_N,
    ),
    ParameterSpec(
        "liftoff_force_n",
        0.0,
        ParameterType.PARAMETER_DOUBLE,
        "contact_rule 'threshold': a foot in stance lifts off below this normal force [N] (at "
        "most the touchdown force), in "
        f"{CONTACT_FORCE_RANGE_N}; 0 = 4 % of the robot's weight",
        value_range=CONTACT_FORCE_RANGE_N,
    ),
    MODEL_CORRECTIONS_PARAMETER,
    MODEL_CORRECTIONS_FILE_PARAMETER,
    ParameterSpec(
        "gait_phase_timeout_s",
        0.1,
        ParameterType.PARAMETER_DOUBLE,
        "contact_rule 'filter': the latest gait_phase (sensor_msgs/JointState, name = feet, "
        "position = probability of stance) is the filter's prior for this long [s] after it "
        f"arrived, then stale (no prior), in {GAIT_PHASE_TIMEOUT_RANGE_S}",
        value_range=GAIT_PHASE_TIMEOUT_RANGE_S,
    ),
)
"""The node's own parameters; the model parameters are
:class:`a1_leg_fk.ros.robot_source.RobotSource`'s."""
