"""A simulated run (:class:`pybullet_sim.SimRun`) as a bag: JointState and Imu at every sample,
the true base pose as PoseStamped; and the messages the node tests publish."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bag_factory import T0, BagSpec, JointStateMsg, T, header, pose, write_bag
from pybullet_sim import SimRun

IMU_TOPIC, TRUTH_TOPIC, JOINT_TOPIC = "/imu", "/truth", "/joint_states"
UNKNOWN = np.zeros(9)  # an all-zero covariance: "unknown"
NO_ORIENTATION = np.array([-1.0] + [0.0] * 8)


def stamp_of(run: SimRun, row: int) -> int:
    """The sample's stamp [ns]: from T0, whole nanoseconds."""
    return T0 + round(run.stamps_s[row] * 1e9)


def stamps_of(run: SimRun) -> np.ndarray:
    """(N,) every sample's stamp [ns] (:func:`stamp_of`)."""
    return np.array([stamp_of(run, row) for row in range(len(run.stamps_s))], np.int64)


def imu_message(run: SimRun, row: int, orientation: bool = True, force: np.ndarray | None = None):
    """sensor_msgs/msg/Imu of a sample: the root's orientation (or none), gyro and specific force
    (``force``: the run's :attr:`SimRun.specific_force` row, computed once by the caller; None:
    computed here)."""
    force = run.specific_force[row] if force is None else force
    x, y, z, w = run.base_quaternions[row] if orientation else (0.0, 0.0, 0.0, 1.0)
    return T["sensor_msgs/msg/Imu"](
        header(stamp_of(run, row), "imu_link"),
        T["geometry_msgs/msg/Quaternion"](x, y, z, w),
        UNKNOWN if orientation else NO_ORIENTATION,
        T["geometry_msgs/msg/Vector3"](*run.gyro[row]),
        UNKNOWN,
        T["geometry_msgs/msg/Vector3"](*force),
        UNKNOWN,
    )


def joint_state_msg(run: SimRun, row: int, efforts: bool = False) -> JointStateMsg:
    """The JointState of a sample: angles, rates and (``efforts``) the motor torques [N m]."""
    return JointStateMsg(
        stamp_of(run, row),
        run.joint_names,
        run.angles[row],
        run.rates[row],
        efforts=run.torques[row] if efforts else (),
    )


def write_sim_bag(
    path: Path,
    run: SimRun,
    imu: bool = True,
    truth: bool = True,
    efforts: bool = False,
    kind: str = "mcap",
    imu_after: bool = False,
) -> Path:
    """The run as a bag (``kind`` as :func:`bag_factory.write_bag`'s, MCAP by default):
    joint_states (positions, velocities, and with ``efforts`` the motor torques), imu (written
    one ns before its joint state, or with ``imu_after`` one ns after: a replay delivers it
    second), truth (PoseStamped of the URDF root in the world)."""
    spec = BagSpec()
    forces = run.specific_force
    for row in range(len(run.stamps_s)):
        stamp = stamp_of(run, row)
        if imu:
            spec.add(
                IMU_TOPIC,
                "sensor_msgs/msg/Imu",
                stamp + 1 if imu_after else stamp - 1,
                imu_message(run, row, force=forces[row]),
            )
        spec.add_joint_state(JOINT_TOPIC, stamp, joint_state_msg(run, row, efforts))
        if truth:
            spec.add(
                TRUTH_TOPIC,
                "geometry_msgs/msg/PoseStamped",
                stamp,
                T["geometry_msgs/msg/PoseStamped"](
                    header(stamp, "world"),
                    pose(run.base_positions[row], run.base_quaternions[row]),
                ),
            )
    return write_bag(path, spec, kind)
