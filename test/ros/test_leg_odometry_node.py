"""``leg_odometry_node`` over real DDS: a PyBullet-made stream (joint_states + imu at 500 Hz; with
and without the motor torques as efforts, so with force contacts and kinematic stance) gives the
same odometry as ``a1-leg-fk odom`` on a bag of the same stream, message for message; with each
IMU message published after its joint state too (the node holds the joint state for it:
:class:`~a1_leg_fk.estimation.imu_pairing.ImuPairing`), the IMU-first bag's."""

from __future__ import annotations

import numpy as np
import pytest
from bag_factory import joint_state
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from node_harness import LEGS, Diagnostics, SensorStream, to_ros
from odometry_bags import JOINT_TOPIC, imu_message, joint_state_msg, write_sim_bag
from pybullet_sim import simulate, walking_targets
from rclpy.publisher import Publisher
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Imu, JointState
from shared import odometry_node_command

from a1_leg_fk.recording.odometry import odometry_track

RATE_HZ = 500.0
SIM_S = 2.5
AHEAD = 40  # samples the stream may run ahead of the node's answers (its queues hold 100)


@pytest.fixture(scope="module")
def run():
    return simulate(walking_targets(start_s=0.3), SIM_S)


@pytest.mark.parametrize(
    ("efforts", "imu_second"),
    [(False, False), (True, False), (True, True)],
    ids=["kinematic", "force_contacts", "force_contacts_imu_second"],
)
def test_node_gives_the_bag_tools_numbers(
    run, ros, processes, tmp_path, efforts, imu_second
) -> None:
    bag = write_sim_bag(tmp_path / "sim", run, truth=False, efforts=efforts)
    track = odometry_track(bag, topic=JOINT_TOPIC)
    if imu_second:  # the bag tool holds each joint state for its IMU sample as the node does
        after = write_sim_bag(
            tmp_path / "after", run, truth=False, efforts=efforts, imu_after=True
        )
        second = odometry_track(after, topic=JOINT_TOPIC)
        assert np.array_equal(second.linear, track.linear)
        assert np.array_equal(second.positions, track.positions)
    force_samples = len(run.stamps_s) if efforts else 0
    assert track.contact_counts.force == force_samples
    node = processes.start(odometry_node_command())
    diagnostics = Diagnostics(ros, "leg odometry")
    received: list[Odometry] = []
    ros.node.create_subscription(
        Odometry, "leg_odometry", received.append, QoSProfile(depth=10000)
    )
    grounds: list[PoseWithCovarianceStamped] = []
    ros.node.create_subscription(
        PoseWithCovarianceStamped, "ground", grounds.append, QoSProfile(depth=10000)
    )
    stream = SensorStream(ros, "leg_odometry")
    assert stream.ready, processes.output(node)
    samples = len(run.stamps_s)
    stream.send(
        samples,
        lambda row: (
            to_ros(imu_message(run, row), Imu),
            to_ros(joint_state(joint_state_msg(run, row, efforts)), JointState),
        ),
        lambda: len(received),
        RATE_HZ,
        AHEAD,
        imu_first=not imu_second,
    )
    assert ros.spin_until(lambda: len(received) >= samples, 20.0), (
        f"{len(received)} of {samples} odometry messages\n{processes.output(node)}"
    )
    status = diagnostics.fresh()
    assert status["samples"] == str(samples) and status["imu_received"] == str(samples)
    assert status["samples_without_stance"] == str(track.counts.no_stance)
    assert [status[f"slips_{leg}"] for leg in LEGS] == [str(n) for n in track.counts.slips]
    assert status["contacts"] == "auto"
    assert status["samples_with_force_evidence"] == str(force_samples)
    assert status["samples_with_kinematic_evidence_only"] == str(samples - force_samples)
    assert status["samples_filtered"] == str(track.filtered) == str(samples)
    counts = track.filter_counts
    assert [status[f"feet_used_{leg}"] for leg in LEGS] == [str(n) for n in counts.used]
    assert [status[f"feet_rejected_{leg}"] for leg in LEGS] == [str(n) for n in counts.rejected]
    assert status["gate_resets"] == str(counts.gate_resets)
    assert status["mean_nis"] == f"{counts.mean_nis:.3f}"
    assert status["accel_bias_mps2"] == " ".join(f"{v:.4f}" for v in track.biases[1])
    assert processes.interrupt(node) == 0
    stamps = np.array(
        [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in received]
    )
    assert (stamps == track.stamps_ns).all()
    linear = np.array(
        [
            [m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z]
            for m in received
        ]
    )
    position = np.array(
        [
            [m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
            for m in received
        ]
    )
    print(
        f"node vs bag over {samples} samples: linear velocity max difference "
        f"{np.abs(linear - track.linear).max():.2e} m/s, final position "
        f"{np.abs(position[-1] - track.positions[-1]).max():.2e} m"
    )
    assert np.abs(linear - track.linear).max() < 1e-9
    assert np.abs(position - track.positions).max() < 1e-9
    first = received[0]
    assert first.header.frame_id == "odom" and first.child_frame_id == "trunk"
    covariance = np.array(received[-1].pose.covariance).reshape(6, 6)
    assert (np.diag(covariance) > 0).all()
    assert (np.diag(np.array(received[-1].twist.covariance).reshape(6, 6)) > 0).all()
    _check_ground(grounds, track)


def _check_ground(grounds: list[PoseWithCovarianceStamped], track) -> None:
    """The node's ground messages (one per change of the footholds: several per stride) are
    the bag tool's local ground at their stamps: height, normal (the orientation's z axis) and
    the height's variance; in odom, on PyBullet's level plane."""
    assert len(grounds) >= 8  # a trot's touchdowns and liftoffs: several per stride over 2 s
    rows = np.searchsorted(
        track.stamps_ns,
        [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in grounds],
    )
    assert (track.stamps_ns[rows] == [
        m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in grounds
    ]).all()  # fmt: skip
    heights = np.array([m.pose.pose.position.z for m in grounds])
    assert np.abs(heights - track.grounds[rows, 0]).max() < 1e-9
    x, y, z, w = np.array([[m.pose.pose.orientation.x, m.pose.pose.orientation.y,
                            m.pose.pose.orientation.z, m.pose.pose.orientation.w]
                           for m in grounds]).T  # fmt: skip
    normals = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], 1)
    assert np.abs(normals - track.grounds[rows, 1:4]).max() < 1e-9
    variances = np.array([m.pose.covariance[14] for m in grounds])
    assert np.abs(variances - track.grounds[rows, 4]).max() < 1e-15
    assert grounds[0].header.frame_id == "odom"
    assert (normals[:, 2] > np.cos(np.radians(2.0))).all()  # level ground, the first stance's too


def test_bad_joint_states_are_counted_not_fatal(ros, processes) -> None:
    node = processes.start(odometry_node_command("-p", "use_imu:=false"))
    diagnostics = Diagnostics(ros, "leg odometry")
    received, joint_pub, names = _joint_states_in(ros)
    stand = [0.0, 0.8, -1.5] * 4
    bad = [
        JointState(name=names, position=stand[:11], velocity=[0.0] * 12),  # lengths differ
        JointState(name=names, position=stand),  # no velocities: no odometry
        JointState(name=names, position=stand, velocity=[float("nan")] * 12),
    ]
    good = JointState(name=names, position=stand, velocity=[0.0] * 12)
    for index, message in enumerate([*bad, good]):
        message.header.stamp.sec, message.header.stamp.nanosec = 100, index * 1000
        joint_pub.publish(message)
        ros.spin_for(0.05)
    assert ros.spin_until(lambda: len(received) >= 1, 10.0), processes.output(node)
    ros.spin_for(0.3)
    assert len(received) == 1 and received[0].header.stamp.nanosec == 3000
    assert received[0].twist.twist.linear.x == 0.0 and received[0].pose.pose.orientation.w == 1.0
    status = diagnostics.fresh()
    assert status["joint_states_received"] == "4" and status["joint_states_rejected"] == "1"
    assert status["joint_states_without_velocities"] == "2"
    assert status["imu_topic"] == "none (use_imu false)"
    assert processes.interrupt(node) == 0


def test_a_bad_contacts_or_ground_value_names_the_parameter(ros) -> None:
    from rclpy.parameter import Parameter

    from a1_leg_fk.model.urdf import LegFkError
    from a1_leg_fk.ros.leg_odometry_node import LegOdometryNode

    with pytest.raises(LegFkError, match="parameter contacts must be auto, force, kinematic"):
        LegOdometryNode(
            context=ros.context, parameter_overrides=[Parameter("contacts", value="x")]
        )
    with pytest.raises(
        LegFkError, match="parameter ground must be footholds, flat, none: 'stairs'"
    ):
        LegOdometryNode(
            context=ros.context, parameter_overrides=[Parameter("ground", value="stairs")]
        )
    node = LegOdometryNode(
        context=ros.context, parameter_overrides=[Parameter("contacts", value="kinematic")]
    )
    try:
        assert node._feed.source == "kinematic" and node._feed.filter.ground == "footholds"
    finally:
        node.destroy_node()


def test_a_dead_imu_stalls_no_joint_state(ros, processes) -> None:
    """The imu topic is subscribed but silent: each joint state waits for its IMU sample only
    until one stamped ``imu_wait_s`` later comes (here 10 ms later), and the last one until the
    wall-clock bound (0.1 s, checked every 0.05 s): all come out, in order, legs alone; the
    diagnostics count each held and let go without its IMU sample."""
    node = processes.start(odometry_node_command())
    diagnostics = Diagnostics(ros, "leg odometry")
    received, joint_pub, names = _joint_states_in(ros)
    count = 10
    for index in range(count):
        message = JointState(name=names, position=[0.0, 0.8, -1.5] * 4, velocity=[0.0] * 12)
        message.header.stamp.sec, message.header.stamp.nanosec = 100, index * 10_000_000
        joint_pub.publish(message)
        ros.spin_for(0.01)
    assert ros.spin_until(lambda: len(received) >= count, 10.0), (
        f"{len(received)} of {count}\n{processes.output(node)}"
    )
    assert [m.header.stamp.nanosec for m in received] == [i * 10_000_000 for i in range(count)]
    assert all(m.pose.pose.orientation.w == 1.0 for m in received)  # legs alone: no IMU
    values = diagnostics.fresh()
    assert values["joint_states_held_for_imu"] == str(count), values
    assert values["joint_states_released_without_imu"] == str(count), values
    assert processes.interrupt(node) == 0


def _joint_states_in(ros) -> tuple[list[Odometry], Publisher, list[str]]:
    """The node's odometry as received, a joint_states publisher it subscribes (bounded wait, and
    half a second for the match) and the A1's joint names."""
    received: list[Odometry] = []
    ros.node.create_subscription(Odometry, "leg_odometry", received.append, QoSProfile(depth=100))
    joint_pub = ros.node.create_publisher(JointState, "joint_states", QoSProfile(depth=100))
    assert ros.spin_until(lambda: joint_pub.get_subscription_count() > 0, 30.0)
    ros.spin_for(0.5)
    return (
        received,
        joint_pub,
        [f"{leg}_{part}_joint" for leg in LEGS for part in ("hip", "upper", "lower")],
    )
