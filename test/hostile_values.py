"""Joint names and values a JointState stream can carry that the rules must survive: names the
model does not have, and floats at the edges (NaN, infinities, huge, tiny)."""

from __future__ import annotations

import math

UNKNOWN_NAMES = [
    "",
    " ",
    "arm_joint_1",
    "gripper",
    "fr_hip_joint",
    "FR_hip_joint ",
    " FR_hip_joint",
    "FR_HIP_JOINT",
    "FR_knee_joint",
    "FR_upper",
    "Fr_upper_joint",
    "FR_hip_joint\x00",
    "ＦR_hip_joint",  # noqa: RUF001 (a fullwidth F on purpose: not a known joint name)
    "FR_hüft_joint",
    "关节",
    "🦿_joint",
    "RR_calf_joint\n",
    "RL_lower_joint\t",
    "trunk",
    "FR_toe",
    "imu_joint",
    "x" * 300,
]


SPECIAL_VALUES = [
    math.nan,
    -math.nan,
    math.inf,
    -math.inf,
    1e308,
    -1e308,
    1.7976931348623157e308,
    5e-324,
    -5e-324,
    2.2250738585072014e-308,
    0.0,
    -0.0,
    math.pi,
    -math.pi,
    1e-300,
    1e16,
    -1e16,
    2.0**53 + 1,
]
