"""The nodes and their input topics under fuzz (issue 38; the harness: test/node_fuzz.py); with
``input: unitree_lowstate``, ``foot_fk_node`` and ``leg_odometry_node`` on ``lowstate``
(:data:`LOWSTATE_NODES`: need Unitree's message package built, test/unitree_workspace.py)."""

from __future__ import annotations

import random

import numpy as np
from fuzz_messages import (
    ABSURD_DESCRIPTIONS,
    absurd_joint_state,
    frame_stamp,
    imu_bytes,
    joint_state_bytes,
    point_bytes,
    string_bytes,
)
from geometry_msgs.msg import PointStamped, Vector3Stamped, WrenchStamped
from hostile_values import SPECIAL_VALUES
from lowstate_bags import lowstate_cdr
from nav_msgs.msg import Odometry
from node_fuzz import FuzzedNode, InputTopic
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Imu, JointState
from shared import LEGS, STANDING, ik_node_command, node_command, odometry_node_command
from std_msgs.msg import String

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.ros.guarded_input import message_reader, read_imu
from a1_leg_fk.wire.joint_state import JointStateDecoder
from a1_leg_fk.wire.lowstate import LowStateJointStates
from a1_leg_fk.wire.unitree_types import GO_LOW_STATE, LEGGED_LOW_STATE

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


def foot_outputs() -> dict[str, type]:
    """foot_fk_node's outputs, by topic."""
    feet: dict[str, type] = {f"foot_positions/{leg}": PointStamped for leg in LEGS}
    feet |= {f"foot_velocities/{leg}": Vector3Stamped for leg in LEGS}
    return feet | {f"foot_forces/{leg}": WrenchStamped for leg in LEGS}


def fuzzed_nodes(urdf: str) -> dict[str, FuzzedNode]:
    """Every node and all of its inputs (``urdf``: the good robot_description)."""
    feet = foot_outputs()
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


# --- a LowState input (either layout) ------------------------------------------------------


def lowstate_topic(msgtype: str, message: type = object) -> InputTopic:
    """``lowstate`` carrying ``msgtype`` (``message``: its class, for a publisher): a LowState of
    the A1 standing, level, at rest; absurd values in the motors and the IMU; the other layout's
    LowState as another type's bytes. No length field: the message has a fixed size.
    """
    (other,) = (kind for kind in (GO_LOW_STATE, LEGGED_LOW_STATE) if kind != msgtype)
    good = lowstate_cdr(msgtype)

    def absurd(_stamp: int, rng: random.Random) -> bytes:
        def pick(count: int, extra: tuple[float, ...] = ()) -> list[float]:
            return [rng.choice([*SPECIAL_VALUES, *extra]) for _ in range(count)]

        imu = (pick(4, (0.0,)), pick(3, (1e6,)), pick(3, (1e6, -1e6)))
        return lowstate_cdr(msgtype, pick(12), pick(12), pick(12, (1e30, 0.0)), imu)

    return InputTopic(
        "lowstate",
        message,
        lambda _stamp: good,
        absurd,
        LowStateJointStates(msgtype, lambda: 0).fields,
        length_offsets=(),
        other=lambda _stamp, rng: lowstate_cdr(other)[: rng.choice([None, -4, 600])],
    )


def foot_key(xyz: tuple[float, float, float]) -> tuple[int, ...]:
    """A foot position [m] to 0.1 um: what identifies a drive's answer."""
    return tuple(round(value * 1e7) for value in xyz)


def lowstate_node(msgtype: str, message: type, env: dict[str, str]) -> FuzzedNode:
    """``foot_fk_node`` with ``input: unitree_lowstate`` reading ``msgtype`` (``message``: its
    class, ``env``: its package's environment). A LowState has no header (its answer is stamped
    with the receive time), so each drive carries its own FR calf angle (from its stamp) and is
    answered by the FR foot this pose's forward kinematics gives.
    """
    model = Quadruped.from_urdf()

    def pose(stamp_ns: int) -> list[float]:
        angles = [float(angle) for angle in STANDING]
        angles[2] += (1 + stamp_ns // 1_000_000 % 500) * 2e-4  # [rad]: another per millisecond
        return angles

    def expected(stamp_ns: int) -> object:
        as_sent = np.asarray(pose(stamp_ns), np.float32).astype(float).tolist()
        return foot_key(model.fk(as_sent)[0])

    def answer_key(msg: object) -> object:
        point = msg.point  # type: ignore[attr-defined]
        return foot_key((point.x, point.y, point.z))

    return FuzzedNode(
        lowstate_name("foot_fk_node", msgtype),
        node_command("-p", "input:=unitree_lowstate"),
        [lowstate_topic(msgtype, message)],
        "foot kinematics",
        "lowstate",
        lambda stamp: lowstate_cdr(msgtype, pose(stamp)),
        ("foot_positions/FR", PointStamped),
        foot_outputs(),
        env=env,
        answer_key=answer_key,
        expected=expected,
    )


ODOMETRY_DRIVES = 3
"""Good LowStates per check of ``leg_odometry_node``, each owed one odometry message."""


def lowstate_odometry_node(msgtype: str, message: type, env: dict[str, str]) -> FuzzedNode:
    """``leg_odometry_node`` with ``input: unitree_lowstate`` reading ``msgtype`` (``message``:
    its class, ``env``: its package's environment). Its odometry is stamped with the receive
    time and carries no pose of the drive, so answers are counted: every good LowState (the A1
    standing, at rest) owes one ``leg_odometry`` message (:attr:`FuzzedNode.counted`).
    """
    return FuzzedNode(
        lowstate_name("leg_odometry_node", msgtype),
        odometry_node_command("-p", "input:=unitree_lowstate"),
        [lowstate_topic(msgtype, message)],
        "leg odometry",
        "lowstate",
        lambda _stamp: lowstate_cdr(msgtype),
        ("leg_odometry", Odometry),
        {"leg_odometry": Odometry},
        env=env,
        counted=ODOMETRY_DRIVES,
    )


LOWSTATE_NODES = {"foot_fk_node": lowstate_node, "leg_odometry_node": lowstate_odometry_node}
"""The nodes fuzzed on ``lowstate``, by executable: (msgtype, message class, environment) to
the node."""


def lowstate_name(executable: str, msgtype: str) -> str:
    """A LowState run's name: the node and the package of the layout it reads."""
    return f"{executable} ({msgtype.split('/', maxsplit=1)[0]})"
