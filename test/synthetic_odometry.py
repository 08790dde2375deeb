"""A synthetic 1 kHz recording for the odometry's cost (bench/smoothing_speed.py) and memory
(test/cli/test_odom_memory.py): JointStates of a trot-like motion (positions and velocities, no
efforts) and Imu messages (level, turning at 0.1 rad/s, the accelerometer feeling gravity: the
state filter runs), both at 1 kHz, in a rosbag2 MCAP bag. rosbags and numpy only.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from a1_leg_fk.kinematics.quadruped import Quadruped

T0 = 1_700_000_000_000_000_000
PERIOD_NS = 1_000_000


def write_turning_trot(path: Path, seconds: float) -> Path:
    """A bag of JointStates and Imu messages at 1 kHz for ``seconds``."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    t = typestore.types
    names = list(Quadruped.from_urdf().joint_names)
    base = np.array([0.05, 0.8, -1.5] * 4)
    phase = np.array([0.0] * 3 + [math.pi] * 6 + [0.0] * 3)
    joint_type, imu_type = "sensor_msgs/msg/JointState", "sensor_msgs/msg/Imu"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        joints = writer.add_connection("/joint_states", joint_type, typestore=typestore)
        imu = writer.add_connection("/imu", imu_type, typestore=typestore)
        for index in range(round(seconds * 1000)):
            stamp = T0 + index * PERIOD_NS
            time_msg = t["builtin_interfaces/msg/Time"](stamp // 10**9, stamp % 10**9)
            header = t["std_msgs/msg/Header"](time_msg, "base")
            yaw = 0.1 * index / 1000.0
            quaternion = t["geometry_msgs/msg/Quaternion"](
                0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)
            )
            vector = t["geometry_msgs/msg/Vector3"]
            covariance = np.zeros(9)
            message = t[imu_type](
                header, quaternion, covariance, vector(0.0, 0.0, 0.1), covariance,
                vector(0.0, 0.0, 9.80665), covariance,
            )  # fmt: skip
            writer.write(imu, stamp, typestore.serialize_cdr(message, imu_type))
            angle = 2 * math.pi * 2.0 * index / 1000.0 + phase
            positions = base + np.array([0.0, 0.3, 0.4] * 4) * np.sin(angle)
            velocities = np.array([0.0, 0.3, 0.4] * 4) * 2 * math.pi * 2.0 * np.cos(angle)
            message = t[joint_type](header, names, positions, velocities, np.zeros(0))
            writer.write(joints, stamp, typestore.serialize_cdr(message, joint_type))
    return path
