"""``leg_odometry_node``'s own parameters (the model's are :class:`~a1_leg_fk.ros.robot_source.
RobotSource`'s): names, defaults, types, ranges and descriptions, in one place for the node and
the launch file's checks.
"""

from __future__ import annotations

from rcl_interfaces.msg import ParameterType

from a1_leg_fk.estimation.filter_model import DEFAULT_GROUND
from a1_leg_fk.estimation.imu import DEFAULT_IMU_TIMEOUT_S
from a1_leg_fk.estimation.imu_pairing import DEFAULT_IMU_WAIT_S, WALL_WAIT_S
from a1_leg_fk.estimation.odometry import OdometrySettings
from a1_leg_fk.estimation.odometry_feed import AUTO
from a1_leg_fk.ros.foot_fk_parameters import (
    MODEL_CORRECTIONS_FILE_PARAMETER,
    MODEL_CORRECTIONS_PARAMETER,
)
from a1_leg_fk.ros.joint_input import INPUT_PARAMETER
from a1_leg_fk.ros.robot_source import BASE_FRAME_PARAMETER, ParameterSpec

DEFAULTS = OdometrySettings()
SMALL_RANGE_M = (-1.0, 1.0)
RANGE_S = (0.001, 10.0)
WAIT_RANGE_S = (0.0, 1.0)
RANGE_MPS = (0.001, 100.0)

PARAMETERS = (
    BASE_FRAME_PARAMETER,
    INPUT_PARAMETER,
    ParameterSpec(
        "odom_frame", "odom", ParameterType.PARAMETER_STRING, "header.frame_id of leg_odometry"
    ),
    ParameterSpec(
        "use_imu",
        True,
        ParameterType.PARAMETER_BOOL,
        "Use the imu topic (orientation unless its orientation_covariance[0] is -1, angular "
        "velocity always); false = legs alone (planar pose)",
        read_only=True,
    ),
    ParameterSpec(
        "contacts",
        AUTO,
        ParameterType.PARAMETER_STRING,
        "The contacts' evidence: auto (the joint efforts' foot forces where a joint state has "
        "efforts, with the feet's heights and speeds), force (the same; a joint state without "
        "efforts has no foot standing) or kinematic (the feet's heights and speeds alone)",
        read_only=True,
    ),
    ParameterSpec(
        "ground",
        DEFAULT_GROUND,
        ParameterType.PARAMETER_STRING,
        "footholds (default): each stance foot's height is held to its foothold's, anchored where "
        "it agrees with the ground predicted from the earlier footholds (flat floors, slopes, "
        "stairs, rough ground); flat: to the first feet's height (a known flat floor); none: not "
        "held",
        read_only=True,
    ),
    MODEL_CORRECTIONS_PARAMETER,
    MODEL_CORRECTIONS_FILE_PARAMETER,
    ParameterSpec(
        "imu_timeout_s",
        DEFAULT_IMU_TIMEOUT_S,
        ParameterType.PARAMETER_DOUBLE,
        f"A joint state takes the latest IMU sample stamped at most this long [s] before it, in "
        f"{RANGE_S}",
        read_only=True,
        value_range=RANGE_S,
    ),
    ParameterSpec(
        "imu_wait_s",
        DEFAULT_IMU_WAIT_S,
        ParameterType.PARAMETER_DOUBLE,
        "A joint state stamped after the newest IMU sample waits for one stamped at or after it "
        f"until a joint state this much [s] later arrives (and at most {WALL_WAIT_S:g} s of wall "
        f"time); 0 = never waits, in {WAIT_RANGE_S}",
        read_only=True,
        value_range=WAIT_RANGE_S,
    ),
    ParameterSpec(
        "foot_radius_m",
        -1.0,
        ParameterType.PARAMETER_DOUBLE,
        "Rolling radius of the feet [m], in [0, 1]; negative = the foot links' collision spheres "
        "in the URDF",
        read_only=True,
        value_range=SMALL_RANGE_M,
    ),
    ParameterSpec(
        "slip_threshold_mps",
        DEFAULTS.slip_threshold_mps,
        ParameterType.PARAMETER_DOUBLE,
        f"A stance foot whose velocity estimate is further than this [m/s] from the others' is "
        f"dropped for that sample, in {RANGE_MPS}",
        read_only=True,
        value_range=RANGE_MPS,
    ),
    ParameterSpec(
        "stance_band_m",
        DEFAULTS.stance_band_m,
        ParameterType.PARAMETER_DOUBLE,
        "Kinematic stance: the feet whose contact points lie within this [m] of the lowest along "
        "gravity, in [0, 1]",
        read_only=True,
        value_range=SMALL_RANGE_M,
    ),
)
"""The node's own parameters; the model parameters are :class:`RobotSource`'s."""
