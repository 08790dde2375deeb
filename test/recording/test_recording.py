"""Recorded runs: bags written here with rosbags (ROS 2 sqlite3 and MCAP, ROS 1), read back with
a1_leg_fk.recording.trajectories; feet against Quadruped.fk of a merged state the test keeps
itself, and against PyBullet; world feet against a transform computed here; counts against what was
put in."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data
import pytest
from bag_factory import (
    ROS1_TYPESTORE,
    T0,
    TYPESTORE,
    BagSpec,
    JointStateMsg,
    T,
    joint_state,
    pose_message,
    rotation_z,
    write_bag,
)
from hypothesis import given, settings
from hypothesis import strategies as st
from pybullet_reference import PyBulletRobot

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.recording.trajectories import read_foot_trajectories
from a1_leg_fk.tracking import FootTracker
from a1_leg_fk.wire.joint_state import JointStateDecoder, doubles

A1 = Quadruped.from_urdf()
NAMES = list(A1.joint_names)
ALIENGO_URDF = Path(pybullet_data.getDataPath()) / "aliengo" / "aliengo.urdf"
KINDS = ("mcap", "sqlite3", "ros1")


def bag_path(tmp_path: Path, kind: str, name: str = "run") -> Path:
    return tmp_path / (f"{name}.bag" if kind == "ros1" else name)


# --- the wire decoder against rosbags ------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=150, deadline=None)
@given(
    frame=st.text(st.characters(min_codepoint=97, max_codepoint=122), max_size=9),
    names=st.lists(
        st.text(st.characters(min_codepoint=65, max_codepoint=122), max_size=7), max_size=5
    ),
    data=st.data(),
    stamp=st.integers(0, 2**31 - 1),
)
def test_wire_decoder_matches_rosbags(frame: str, names: list[str], data, stamp: int) -> None:
    positions = data.draw(st.lists(finite, min_size=0, max_size=6))
    velocities = data.draw(st.lists(finite, min_size=0, max_size=6))
    efforts = data.draw(st.lists(finite, min_size=0, max_size=6))
    message = joint_state(
        JointStateMsg(stamp * 1_000_000_000 + 7, names, positions, velocities, frame, efforts)
    )
    cdr = TYPESTORE.serialize_cdr(message, "sensor_msgs/msg/JointState")
    big_endian = TYPESTORE.serialize_cdr(
        message, "sensor_msgs/msg/JointState", little_endian=False
    )
    ros1 = TYPESTORE.cdr_to_ros1(cdr, "sensor_msgs/msg/JointState")
    reference: Any  # a deserialized sensor_msgs/msg/JointState
    for raw, decoder, reference in (
        (cdr, JointStateDecoder(), TYPESTORE.deserialize_cdr(cdr, "sensor_msgs/msg/JointState")),
        (
            big_endian,
            JointStateDecoder(),
            TYPESTORE.deserialize_cdr(big_endian, "sensor_msgs/msg/JointState"),
        ),
        (
            ros1,
            JointStateDecoder(ros1=True),
            ROS1_TYPESTORE.deserialize_ros1(ros1, "sensor_msgs/msg/JointState"),
        ),
    ):
        for repeat in range(2):  # the second time the names come from the cache
            stamp_ns, changed, order, positions, velocities, efforts = decoder.fields(raw)
            assert (
                stamp_ns
                == reference.header.stamp.sec * 1_000_000_000 + reference.header.stamp.nanosec
            )
            assert decoder.names == list(reference.name)
            assert changed == (repeat == 0)
            assert order == (">" if raw is big_endian else "<")
            dtype = np.dtype(f"{order}f8")
            assert np.frombuffer(positions, dtype).tolist() == list(reference.position)
            assert np.frombuffer(velocities, dtype).tolist() == list(reference.velocity)
            assert np.frombuffer(efforts, dtype).tolist() == list(reference.effort)
            assert list(doubles(efforts, order)) == list(reference.effort)


# --- update_block is update, K times -------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_update_block_equals_update(data) -> None:
    names = data.draw(st.permutations([*NAMES[:6], "arm"]))[: data.draw(st.integers(1, 7))]
    rows = data.draw(st.integers(1, 8))
    value = st.one_of(st.floats(-3, 3), st.sampled_from([math.nan, math.inf]))
    positions = np.array([[data.draw(value) for _ in names] for _ in range(rows)])
    velocities = (
        np.array([[data.draw(value) for _ in names] for _ in range(rows)])
        if data.draw(st.booleans())
        else np.empty((rows, 0))
    )
    efforts = np.array(  # as many as the names, or one too many (ignored)
        [[data.draw(value) for _ in range(len(names) + data.draw(st.integers(0, 1)))]] * rows
    )
    one, block = FootTracker(A1), FootTracker(A1)
    one.update(NAMES[:3], [0.1, 0.7, -1.4], [], [1.0, 2.0, 3.0])
    block.update(NAMES[:3], [0.1, 0.7, -1.4], [], [1.0, 2.0, 3.0])
    result = block.update_block(names, positions, velocities, efforts)
    for row in range(rows):
        feet = one.update(
            names, positions[row].tolist(), velocities[row].tolist(), efforts[row].tolist()
        )
        assert result.accepted[row] == (one.last_outcome == "accepted")
        np.testing.assert_array_equal(result.angles[row], one.angles)
        np.testing.assert_array_equal(result.efforts[row], one.efforts)
        with_velocity = {foot.leg_slot for foot in feet if foot.velocity is not None}
        for leg in range(4):
            rates = result.rates[row, 3 * leg : 3 * leg + 3]
            assert np.isfinite(rates).all() == (leg in with_velocity)
    assert block.counts == one.counts
    np.testing.assert_array_equal(block.angles, one.angles)
    np.testing.assert_array_equal(block.efforts, one.efforts)


def test_efforts_are_merged_per_joint_like_the_angles() -> None:
    tracker = FootTracker(A1)
    tracker.update(NAMES[:3], [0.1, 0.7, -1.4], [], [1.0, 2.0, 3.0])
    tracker.update(NAMES[3:6], [0.1, 0.7, -1.4], [], [4.0, 5.0, 6.0])
    tracker.update(NAMES[:3], [0.1, 0.7, -1.4], [], [7.0])  # not one per name: ignored
    tracker.update(NAMES[:1], [math.nan], [], [8.0])  # rejected: ignored
    tracker.update(["arm", NAMES[2]], [0.0, -1.5], [], [9.0, 10.0])  # the arm's is no joint's
    assert tracker.efforts[:6] == [1.0, 2.0, 10.0, 4.0, 5.0, 6.0]
    assert all(math.isnan(effort) for effort in tracker.efforts[6:])


# --- a bag with everything in it -----------------------------------------------------------------


def scenario() -> tuple[
    BagSpec, list[tuple[int, int, list[float], dict[int, list[float]]]], dict[str, int]
]:
    """A bag's messages and what the test expects: per row (stamp, bag time, merged angles,
    {leg: joint rates}), and the outcome counts."""
    rng = np.random.default_rng(7)
    spec = BagSpec()
    state = [math.nan] * 12
    rows, counts = (
        [],
        {
            "accepted": 0,
            "position_length_mismatch": 0,
            "velocity_length_mismatch": 0,
            "duplicate_names": 0,
            "all_positions_non_finite": 0,
            "no_leg_joints": 0,
        },
    )
    bag_time = T0

    def put(names, positions, velocities=(), outcome="accepted", stamp=None, bad_legs=()):
        nonlocal bag_time
        bag_time += 1_000_000
        stamp = bag_time + 3 if stamp is None else stamp
        spec.add_joint_state(
            "/joint_states",
            bag_time,
            JointStateMsg(stamp, names, positions, velocities, "x" * (bag_time % 5)),
        )
        counts[outcome] += 1
        if outcome != "accepted":
            return
        for name, value in zip(names, positions):
            if name in NAMES and math.isfinite(value):
                state[NAMES.index(name)] = value
        rates = {}
        if velocities:
            by_name = dict(zip(names, velocities))
            for leg in range(4):
                leg_names = NAMES[3 * leg : 3 * leg + 3]
                if leg not in bad_legs and all(n in by_name for n in leg_names):
                    rates[leg] = [by_name[n] for n in leg_names]
        if any(not any(math.isnan(v) for v in state[3 * leg : 3 * leg + 3]) for leg in range(4)):
            rows.append((stamp or bag_time, bag_time, list(state), rates))  # a leg is known

    def q() -> list[float]:
        return rng.uniform(-1.0, 1.0, 12).tolist()

    put(NAMES[1:3], q()[1:3])  # FR without its hip roll: no leg known, no row
    put(NAMES[:3], q()[:3])  # FR only: partial
    put(["arm_joint", *NAMES[3:9]], [0.5, *q()[3:9]])  # FL + RR and an unknown name
    put(NAMES, q()[:11], outcome="position_length_mismatch")
    put([NAMES[0], NAMES[0]], [0.1, 0.2], outcome="duplicate_names")
    put(NAMES[:3], [math.nan] * 3, outcome="all_positions_non_finite")
    put(NAMES, q(), rng.normal(size=12).tolist())
    bad = q()
    bad[9] = math.inf
    put(NAMES, bad, rng.normal(size=12).tolist(), bad_legs=(3,))
    put(NAMES, q(), [1.0] * 5, outcome="velocity_length_mismatch")
    put(["gripper"], [0.3], outcome="no_leg_joints")
    for index in range(40):  # a steady stream; stamps go back once; one stamp unset
        stamp = bag_time + 3 - (50_000_000 if index == 20 else 0)
        put(NAMES, q(), rng.normal(size=12).tolist(), stamp=0 if index == 30 else stamp)
    # a second JointState topic, and a topic of another type
    spec.add_joint_state("/other/joint_states", T0 + 5, JointStateMsg(T0, NAMES, q()))
    spec.add("/chatter", "std_msgs/msg/String", T0 + 6, T["std_msgs/msg/String"]("hello"))
    return spec, rows, counts


@pytest.mark.parametrize("kind", KINDS)
def test_feet_of_a_bag_equal_fk_of_the_merged_state(tmp_path: Path, kind: str) -> None:
    spec, rows, counts = scenario()
    path = write_bag(bag_path(tmp_path, kind), spec, kind)
    result = read_foot_trajectories(path, topic="/joint_states")
    summary = result.summary
    assert {k: v for k, v in summary.outcomes.items() if v} == {
        k: v for k, v in counts.items() if v
    }
    assert summary.messages == sum(counts.values())
    assert summary.rows == len(rows) == len(result.stamps_ns)
    assert summary.non_finite_joints == 3 + 1 and summary.unknown_names == ("arm_joint", "gripper")
    assert result.stamps_ns.tolist() == [row[0] for row in rows]
    assert result.bag_times_ns.tolist() == [row[1] for row in rows]
    assert result.velocities is not None
    for got, got_velocity, (_, _, angles, rates) in zip(result.positions, result.velocities, rows):
        for leg in range(4):
            leg_angles = angles[3 * leg : 3 * leg + 3]
            if any(math.isnan(a) for a in leg_angles):
                assert np.isnan(got[leg]).all()
                continue
            full = [a if not math.isnan(a) else 0.0 for a in angles]
            assert np.abs(got[leg] - A1.fk(full)[leg]).max() <= 1e-12
            if leg in rates:
                all_rates = [0.0] * 12
                all_rates[3 * leg : 3 * leg + 3] = rates[leg]
                assert (
                    np.abs(got_velocity[leg] - A1.foot_velocities(full, all_rates)[leg]).max()
                    <= 1e-12
                )
            else:
                assert np.isnan(got_velocity[leg]).all()
    assert result.world_positions is None and result.base_frame == "trunk"


def test_an_empty_recorded_robot_description_means_the_embedded_a1(tmp_path: Path) -> None:
    """As in the node, an empty description is none: the embedded A1, and the summary says so."""
    spec = BagSpec()
    spec.add("/robot_description", "std_msgs/msg/String", T0, T["std_msgs/msg/String"](""))
    q = np.random.default_rng(5).uniform(-0.8, 0.8, 12).tolist()
    spec.add_joint_state("/joint_states", T0 + 1, JointStateMsg(T0 + 1, NAMES, q))
    result = read_foot_trajectories(write_bag(tmp_path / "empty", spec, "mcap"))
    assert result.summary.model.startswith("embedded A1 (")
    feet = [leg.chain.foot_link for leg in A1.legs]
    with PyBulletRobot(pybullet_data.getDataPath() + "/a1/a1.urdf") as robot:
        assert np.abs(result.positions[0] - robot.feet(NAMES, feet, q)).max() <= 1e-7


def test_a_recorded_robot_description_is_used_and_matches_pybullet(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    spec = BagSpec()
    spec.add(
        "/robot_description",
        "std_msgs/msg/String",
        T0,
        T["std_msgs/msg/String"](ALIENGO_URDF.read_text()),
    )
    angles = [rng.uniform(-0.8, 0.8, 12).tolist() for _ in range(5)]
    for index, q in enumerate(angles):
        spec.add_joint_state(
            "/joint_states", T0 + (index + 1) * 1_000_000, JointStateMsg(T0 + index, NAMES, q)
        )
    # a later description (after the first JointState) must not be used
    spec.add(
        "/robot_description",
        "std_msgs/msg/String",
        T0 + 10**9,
        T["std_msgs/msg/String"]("<robot name='x'/>"),
    )
    path = write_bag(tmp_path / "aliengo", spec, "mcap")
    result = read_foot_trajectories(path)
    assert result.summary.model.startswith("robot_description topic /robot_description in")
    feet = [link.chain.foot_link for link in Quadruped.from_urdf(str(ALIENGO_URDF)).legs]
    with PyBulletRobot(ALIENGO_URDF) as robot:
        for got, q in zip(result.positions, angles):
            assert np.abs(got - robot.feet(NAMES, feet, q)).max() <= 1e-7
            assert np.abs(got - A1.fk(q)).max() > 1e-3  # not the A1


@pytest.mark.parametrize(
    ("kind", "msgtype"),
    [
        ("sqlite3", "nav_msgs/msg/Odometry"),
        ("mcap", "geometry_msgs/msg/PoseStamped"),
        ("ros1", "geometry_msgs/msg/PoseWithCovarianceStamped"),
        ("mcap", "tf2_msgs/msg/TFMessage"),
    ],
)
def test_world_feet_from_each_kind_of_base_pose(tmp_path: Path, kind: str, msgtype: str) -> None:
    rng = np.random.default_rng(11)
    spec = BagSpec()
    topic = "/tf" if msgtype.startswith("tf2") else "/base_pose"
    # poses every 50 ms from 0.1 s to 0.5 s, a gap from 0.5 s to 0.8 s, then 0.8 .. 1.0 s
    pose_times = [100, 150, 200, 250, 300, 350, 400, 450, 500, 800, 850, 900, 950, 1000]
    pose_of = {ms: ([0.01 * ms, -0.002 * ms, 0.3], 0.002 * ms) for ms in pose_times}
    for ms in pose_times:
        spec.add(
            topic,
            msgtype,
            T0 + ms * 1_000_000,
            pose_message(msgtype, T0 + ms * 1_000_000, *pose_of[ms]),
        )
    expected: list[np.ndarray | None] = []
    for ms in range(0, 1100, 25):  # JointStates every 25 ms from 0 to 1.075 s
        q = rng.uniform(-1, 1, 12).tolist()
        spec.add_joint_state(
            "/joint_states", T0 + ms * 1_000_000 + 1, JointStateMsg(T0 + ms * 1_000_000, NAMES, q)
        )
        feet = A1.fk(q)
        below = max((p for p in pose_times if p <= ms), default=None)
        above = min((p for p in pose_times if p >= ms), default=None)
        if below is None or above is None or above - below > 100:
            expected.append(None)
            continue
        fraction = 0.0 if above == below else (ms - below) / (above - below)
        # the test's own interpolation: positions linear; yaw about one axis interpolates linearly
        position = np.array(pose_of[below][0]) + fraction * (
            np.array(pose_of[above][0]) - np.array(pose_of[below][0])
        )
        yaw = pose_of[below][1] + fraction * (pose_of[above][1] - pose_of[below][1])
        expected.append(position + feet @ rotation_z(yaw).T)
    path = write_bag(bag_path(tmp_path, kind), spec, kind)
    result = read_foot_trajectories(path, base_pose=topic)
    assert result.world_frame == "odom"
    assert result.summary.rows_without_pose == sum(e is None for e in expected)
    assert result.summary.rows_without_pose == 4 + 11 + 3  # before 0.1 s, in the gap, after 1.0 s
    assert result.world_positions is not None
    for got, want in zip(result.world_positions, expected, strict=True):
        if want is None:
            assert np.isnan(got).all()
        else:
            assert np.abs(got - want).max() <= 1e-12


@pytest.mark.parametrize("kind", ["mcap", "ros1"])
def test_same_length_messages_with_other_names_are_not_mixed_up(tmp_path: Path, kind: str) -> None:
    """Messages of one byte length whose name lists differ (FR and FL swapped) stay apart, and
    the feet follow the names (against PyBullet)."""
    rng = np.random.default_rng(17)
    swapped = NAMES[3:6] + NAMES[0:3] + NAMES[6:]
    spec, angles = BagSpec(), []
    for index in range(300):
        q = rng.uniform(-0.9, 0.9, 12).tolist()
        angles.append(q)
        names = swapped if (index // 7) % 2 else NAMES
        positions = [q[NAMES.index(name)] for name in names]
        spec.add_joint_state(
            "/joint_states",
            T0 + index * 1_000_000,
            JointStateMsg(T0 + index * 1_000_000, names, positions),
        )
    path = write_bag(bag_path(tmp_path, kind), spec, kind)
    result = read_foot_trajectories(path)
    feet = [leg.chain.foot_link for leg in A1.legs]
    with PyBulletRobot(pybullet_data.getDataPath() + "/a1/a1.urdf") as robot:
        for got, q in zip(result.positions, angles, strict=True):
            assert np.abs(got - A1.fk(q)).max() <= 1e-12
            assert np.abs(got - robot.feet(NAMES, feet, q)).max() <= 1e-7
