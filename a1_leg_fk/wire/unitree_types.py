"""Unitree's message definitions, written from the published field lists (facts, not code):
``unitree_go`` of unitree_ros2 (Go2, B2: ``LowState``, ``IMUState``, ``MotorState``,
``BmsState``, ``SportModeState``, ``TimeSpec``) and ``unitree_legged_msgs`` of
unitree_ros_to_real (A1, Go1 on ROS 1: ``LowState``, ``IMU``, ``MotorState``, ``BmsState``, as
its v3.8 release publishes them).

A bag that records its definitions (every ROS 1 bag, rosbag2 from Iron on) is read with its own
(older ``unitree_legged_msgs`` releases differ: an ``IMU`` without ``rpy``, a smaller
``BmsState``); these are for bags without definitions (rosbag2 before Iron) and for writing.
No ROS here.
"""

from __future__ import annotations

GO_LOW_STATE = "unitree_go/msg/LowState"
LEGGED_LOW_STATE = "unitree_legged_msgs/msg/LowState"
SPORT_MODE_STATE = "unitree_go/msg/SportModeState"
HUMANOID_LOW_STATE = "unitree_hg/msg/LowState"
"""A humanoid's (G1, H1) LowState: read by no command here, named in the refusal."""

UNITREE_GO: dict[str, str] = {
    "unitree_go/msg/LowState": """
uint8[2] head
uint8 level_flag
uint8 frame_reserve
uint32[2] sn
uint32[2] version
uint16 bandwidth
IMUState imu_state
MotorState[20] motor_state
BmsState bms_state
int16[4] foot_force
int16[4] foot_force_est
uint32 tick
uint8[40] wireless_remote
uint8 bit_flag
float32 adc_reel
int8 temperature_ntc1
int8 temperature_ntc2
float32 power_v
float32 power_a
uint16[4] fan_frequency
uint32 reserve
uint32 crc
""",
    "unitree_go/msg/IMUState": """
float32[4] quaternion
float32[3] gyroscope
float32[3] accelerometer
float32[3] rpy
int8 temperature
""",
    "unitree_go/msg/MotorState": """
uint8 mode
float32 q
float32 dq
float32 ddq
float32 tau_est
float32 q_raw
float32 dq_raw
float32 ddq_raw
int8 temperature
uint32 lost
uint32[2] reserve
""",
    "unitree_go/msg/BmsState": """
uint8 version_high
uint8 version_low
uint8 status
uint8 soc
int32 current
uint16 cycle
int8[2] bq_ntc
int8[2] mcu_ntc
uint16[15] cell_vol
""",
    "unitree_go/msg/TimeSpec": """
int32 sec
uint32 nanosec
""",
    "unitree_go/msg/SportModeState": """
TimeSpec stamp
uint32 error_code
IMUState imu_state
uint8 mode
float32 progress
uint8 gait_type
float32 foot_raise_height
float32[3] position
float32 body_height
float32[3] velocity
float32 yaw_speed
float32[4] range_obstacle
int16[4] foot_force
float32[12] foot_position_body
float32[12] foot_speed_body
""",
}
"""unitree_ros2's ``unitree_go`` messages that the package reads, by type."""

UNITREE_LEGGED: dict[str, str] = {
    "unitree_legged_msgs/msg/LowState": """
uint8[2] head
uint8 levelFlag
uint8 frameReserve
uint32[2] SN
uint32[2] version
uint16 bandWidth
IMU imu
MotorState[20] motorState
BmsState bms
int16[4] footForce
int16[4] footForceEst
uint32 tick
uint8[40] wirelessRemote
uint32 reserve
uint32 crc
""",
    "unitree_legged_msgs/msg/IMU": """
float32[4] quaternion
float32[3] gyroscope
float32[3] accelerometer
float32[3] rpy
int8 temperature
""",
    "unitree_legged_msgs/msg/MotorState": """
uint8 mode
float32 q
float32 dq
float32 ddq
float32 tauEst
float32 q_raw
float32 dq_raw
float32 ddq_raw
int8 temperature
uint32[2] reserve
""",
    "unitree_legged_msgs/msg/BmsState": """
uint8 version_h
uint8 version_l
uint8 bms_status
uint8 SOC
int32 current
uint16 cycle
int8[2] BQ_NTC
int8[2] MCU_NTC
uint16[10] cell_vol
""",
}
"""unitree_ros_to_real's ``unitree_legged_msgs`` LowState and what it nests, by type."""

DEFINITIONS: dict[str, str] = {**UNITREE_GO, **UNITREE_LEGGED}
"""Every Unitree definition the package carries, by type."""
