"""``foot_fk_node``'s contacts over real DDS on a held-out run of the contact family
(test/contact_runs.py): the Go2-like model's fast trot with sensor noise, its joint states (with
efforts, and without: the kinematic evidence alone, with the feet's rises above their own
footholds) and IMU (orientation, gyro, accelerometer) streamed at 500 Hz. The node's
``foot_contacts`` equal ``a1-leg-fk bag --forces`` on a bag of the same stream (plumbing), and
PyBullet's contacts judge them: the issues' goals on the streamed gait.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import FAMILY_NOISE_SEED, family_folder
from contact_bags import stamp_of, write_run_bag
from contact_runs import ContactRun, contact_runs, with_noise
from node_harness import SensorStream, node_command
from rclpy.qos import QoSProfile
from rosbags.highlevel import AnyReader
from sensor_msgs.msg import Imu, JointState

from a1_leg_fk import cli

RUN = "go2_trot_fast"
SECONDS = 3.0
"""Streamed: the settling and the first seconds of the gait."""


@pytest.fixture(scope="module")
def run() -> ContactRun:
    return with_noise(contact_runs(family_folder(), (RUN,))[RUN], FAMILY_NOISE_SEED)


def rows_of(run: ContactRun) -> int:
    return int(np.searchsorted(run.stamps_s, run.gait_start_s + SECONDS))


def messages(run: ContactRun, row: int, efforts: bool) -> tuple[Imu, JointState]:
    stamp = stamp_of(run, row)
    imu = Imu()
    imu.header.stamp.sec, imu.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
    q = imu.orientation
    q.x, q.y, q.z, q.w = run.quaternions[row].tolist()
    w, a = imu.angular_velocity, imu.linear_acceleration
    w.x, w.y, w.z = run.gyro[row].tolist()
    a.x, a.y, a.z = run.specific_force[row].tolist()
    joints = JointState(
        name=list(run.joint_names),
        position=run.angles[row].tolist(),
        velocity=run.rates[row].tolist(),
        effort=run.torques[row].tolist() if efforts else [],
    )
    joints.header.stamp = imu.header.stamp
    return imu, joints


def bag_contacts(
    run: ContactRun, rows: int, folder: Path, efforts: bool
) -> dict[int, list[float]]:
    """``a1-leg-fk bag --forces --imu --causal`` on the stream (``--contacts`` without efforts):
    {stamp: probabilities}."""
    bag = write_run_bag(folder / "in", run, efforts=efforts, rows=rows)
    out = folder / "out"
    arguments = [
        "bag",
        str(bag),
        "--topic",
        "/joint_states",
        "--imu",
        "/imu",
        "--forces" if efforts else "--contacts",
        "--causal",
    ]
    assert cli.main([*arguments, "--urdf", run.urdf_path, "--output-bag", str(out)]) == 0
    contacts: dict[int, list[float]] = {}
    with AnyReader([out]) as reader:
        connection = next(c for c in reader.connections if c.topic == "/foot_contacts")
        for _, _, raw in reader.messages(connections=[connection]):
            msg: Any = reader.deserialize(raw, connection.msgtype)
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            contacts[stamp] = msg.position.tolist()
    return contacts


@pytest.mark.parametrize("efforts", [True, False], ids=["efforts", "kinematic"])
def test_node_contacts_on_a_held_out_run(run, ros, processes, tmp_path: Path, efforts) -> None:
    """With efforts the contact issue's goals (98.5 %, <= 1 % swing called stance); without,
    issue 34's (95 %: 97.00 % measured on these 3 s, 96.83 % over the whole run)."""
    rows = rows_of(run)
    expected = bag_contacts(run, rows, tmp_path, efforts)
    node = processes.start(
        node_command("-p", "enable_verify:=false", "-p", f"urdf_file:={run.urdf_path}")
    )
    contacts: dict[int, list[float]] = {}

    def take(msg: JointState) -> None:
        contacts[msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = list(
            msg.position
        )

    ros.node.create_subscription(JointState, "foot_contacts", take, QoSProfile(depth=10000))
    stream = SensorStream(ros, "foot_contacts")
    assert stream.ready, processes.output(node)
    stream.send(rows, lambda row: messages(run, row, efforts), lambda: len(contacts))
    assert ros.spin_until(lambda: len(contacts) >= rows, 30.0), (
        f"{len(contacts)} of {rows} contact messages\n{processes.output(node)}"
    )
    assert processes.interrupt(node) == 0
    stamps = [stamp_of(run, row) for row in range(rows)]
    ours = np.array([contacts[s] for s in stamps])
    np.testing.assert_allclose(ours, [expected[s] for s in stamps], rtol=0, atol=1e-9)
    gait = run.gait[:rows]
    stance, truth = ours[gait] >= 0.5, run.contacts[:rows][gait]
    agree = (stance == truth).mean()
    print(f"{RUN}+noise over DDS: {gait.sum()} gait samples, stance agrees {agree:.2%}")
    if efforts:
        assert agree >= 0.985
        assert (stance & ~truth).mean() <= 0.01
    else:
        assert agree >= 0.95
