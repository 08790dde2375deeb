"""The nodes and their input topics under fuzz (issue 38; the harness: test/node_fuzz.py)."""

from __future__ import annotations

import random

from geometry_msgs.msg import PointStamped, Vector3Stamped, WrenchStamped
from hostile_values import SPECIAL_VALUES
from nav_msgs.msg import Odometry
from node_fuzz import (
    ABSURD_DESCRIPTIONS,
    FuzzedNode,
    InputTopic,
    absurd_joint_state,
    frame_stamp,
    imu_bytes,
    joint_state_bytes,
    point_bytes,
    string_bytes,
)
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Imu, JointState
from shared import LEGS, ik_node_command, node_command, odometry_node_command
from std_msgs.msg import String

from a1_leg_fk.ros.guarded_input import message_reader, read_imu
from a1_leg_fk.wire.joint_state import JointStateDecoder

# --- the nodes ------------------------------------------------------------------------------

DESCRIPTION_QOS = QoSProfile(
    depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


def description_topic(urdf: str) -> InputTopic:
    """``robot_description``: std_msgs/String, latched; a keep-last-1 reader, so paced."""
    return InputTopic(
        "robot_description",
        String,
        lambda _stamp: string_bytes(urdf),
        lambda _stamp, rng: string_bytes(rng.choice(ABSURD_DESCRIPTIONS)),
        message_reader(String),
        length_offsets=(4,),
        qos=DESCRIPTION_QOS,
        pause_s=0.02,
        good_each_batch=False,  # a new robot takes the node a second: the reader's one slot
    )


def joint_states_topic() -> InputTopic:
    return InputTopic(
        "joint_states",
        JointState,
        joint_state_bytes,
        absurd_joint_state,
        JointStateDecoder().fields,
    )


def imu_topic() -> InputTopic:
    return InputTopic("imu", Imu, imu_bytes, imu_bytes, read_imu)


def target_topic(leg: str) -> InputTopic:
    return InputTopic(
        f"foot_targets/{leg}",
        PointStamped,
        lambda stamp: point_bytes(stamp, (0.18, -0.13, -0.3)),
        lambda stamp, rng: point_bytes(stamp, [rng.choice(SPECIAL_VALUES) for _ in range(3)]),
        message_reader(PointStamped),
    )


def fuzzed_nodes(urdf: str) -> dict[str, FuzzedNode]:
    """Every node and all of its inputs (``urdf``: the good robot_description)."""
    feet = {f"foot_positions/{leg}": PointStamped for leg in LEGS}
    feet |= {f"foot_velocities/{leg}": Vector3Stamped for leg in LEGS}
    feet |= {f"foot_forces/{leg}": WrenchStamped for leg in LEGS}
    return {
        "foot_fk_node": FuzzedNode(
            "foot_fk_node",
            node_command(),
            [joint_states_topic(), imu_topic(), gait_phase_topic(), description_topic(urdf)],
            "foot kinematics",
            "joint_states",
            joint_state_bytes,
            ("foot_positions/FR", PointStamped),
            feet,
        ),
        "leg_odometry_node": FuzzedNode(
            "leg_odometry_node",
            odometry_node_command(),
            [joint_states_topic(), imu_topic(), description_topic(urdf)],
            "leg odometry",
            "joint_states",
            joint_state_bytes,
            ("leg_odometry", Odometry),
            {"leg_odometry": Odometry},
        ),
        "foot_ik_node": FuzzedNode(
            "foot_ik_node",
            ik_node_command(),
            [*(target_topic(leg) for leg in LEGS), description_topic(urdf)],
            "foot inverse kinematics",
            "foot_targets/FR",
            lambda stamp: point_bytes(stamp, (0.18, -0.13, -0.3)),
            ("joint_commands", JointState),
            {"joint_commands": JointState},
        ),
    }


def gait_phase_topic() -> InputTopic:
    """``gait_phase``: a JointState of the feet's probabilities of stance."""

    def good(stamp: int) -> bytes:
        msg = JointState(name=list(LEGS), position=[1.0, 0.0, 0.0, 1.0])
        frame_stamp(msg, stamp)
        return serialize_message(msg)

    def absurd(stamp: int, rng: random.Random) -> bytes:
        msg = JointState(name=rng.sample([*LEGS, "XX", ""], rng.randint(0, 6)))
        msg.position = [rng.choice(SPECIAL_VALUES) for _ in range(rng.choice([0, 4, 9]))]
        frame_stamp(msg, stamp)
        return serialize_message(msg)

    return InputTopic("gait_phase", JointState, good, absurd, JointStateDecoder().fields)
