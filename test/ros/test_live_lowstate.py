"""Issue 38: the nodes' ``lowstate`` input reads both Unitree layouts as a ROS 2 topic carries
them (CDR), each serialized here by rosbags from Unitree's published field lists: the motors'
angles come back, and the other layout's LowState, an Imu or a JointState on the topic cannot be
read (the guarded read counts them as ``rejected_lowstate_malformed``). Before, the
``unitree_legged_msgs`` input expected the ROS 1 layout (937 bytes) and rejected every message
a bridge delivers (1064 bytes).
"""

from __future__ import annotations

import math

import pytest
from lowstate_bags import lowstate_cdr
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Imu, JointState
from shared import STANDING

from a1_leg_fk.wire.joint_state import WireError, doubles
from a1_leg_fk.wire.lowstate import LowStateJointStates
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

LAYOUTS = (GO_LOW_STATE, LEGGED_LOW_STATE)


@pytest.mark.parametrize("msgtype", LAYOUTS)
def test_each_layout_reads_its_own_lowstate_and_nothing_else(msgtype: str) -> None:
    reader = LowStateJointStates(msgtype, lambda: 123)
    fields = reader.fields(lowstate_cdr(msgtype))
    angles = doubles(fields.positions, fields.order)
    assert fields.stamp_ns == 123
    assert all(math.isclose(a, float(b), rel_tol=1e-6) for a, b in zip(angles, STANDING))
    (other,) = (t for t in LAYOUTS if t != msgtype)
    wrong = [lowstate_cdr(other), serialize_message(Imu()), serialize_message(JointState())]
    for raw in wrong:
        with pytest.raises(WireError, match=f"{len(raw)} bytes"):
            reader.fields(raw)
