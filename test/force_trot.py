"""The A1 trotting in PyBullet with its joint efforts as a robot would record them, a few of them
bad: the shared input of the bag and node force tests (test/recording/test_bag_forces.py,
test/ros/test_node_forces.py)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from bag_factory import T0
from pybullet_sim import A1_URDF, QuadrupedSim, record_trot
from shared import STAND_LEG

from a1_leg_fk.kinematics.quadruped import Quadruped

A1 = Quadruped.from_urdf()
NAMES = list(A1.joint_names)
NAN_FL_ROW, SHORT_ROW, EMPTY_ROW = 100, 200, 300
"""Rows with FL's knee effort NaN, with 11 efforts, with none."""
STEP_NS = 2_000_000
"""[ns] between two rows (500 Hz)."""


def a1_trot(seconds: float) -> dict[str, np.ndarray]:
    """``seconds`` of the A1 dropped standing and trotting in place (from 0.5 s), 500 samples a
    second (:func:`pybullet_sim.record_trot`)."""
    feet = [leg.chain.foot_link for leg in A1.legs]
    stand_height = 0.03 - A1.fk(list(STAND_LEG) * 4)[:, 2].mean()
    with QuadrupedSim(A1_URDF, NAMES, feet) as sim:
        return record_trot(sim, STAND_LEG, stand_height, seconds)


def recorded_efforts(torques: np.ndarray) -> list[list[float]]:
    """The efforts as recorded: FL's knee NaN in row :data:`NAN_FL_ROW`, 11 efforts in
    :data:`SHORT_ROW`, none in :data:`EMPTY_ROW`."""
    efforts = torques.tolist()
    efforts[NAN_FL_ROW][5] = math.nan
    efforts[SHORT_ROW] = efforts[SHORT_ROW][:11]
    efforts[EMPTY_ROW] = []
    return efforts


def joint_state(record: dict[str, np.ndarray], row: int, efforts: list[float]) -> Any:
    """Row ``row`` of ``record`` as a sensor_msgs JointState with ``efforts`` (ROS imported
    here: the bag tests need none)."""
    from sensor_msgs.msg import JointState

    msg = JointState(
        name=NAMES,
        position=record["angles"][row].tolist(),
        velocity=record["rates"][row].tolist(),
        effort=efforts,
    )
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(T0 + STEP_NS * row, 1_000_000_000)
    return msg


def imu(record: dict[str, np.ndarray], row: int) -> Any:
    """Row ``row``'s orientation as a sensor_msgs Imu (no gyro, no accelerometer)."""
    from sensor_msgs.msg import Imu

    msg = Imu()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(T0 + STEP_NS * row, 1_000_000_000)
    q = msg.orientation
    q.x, q.y, q.z, q.w = record["root_orientation"][row].tolist()
    return msg
