"""Runs of the contact family (test/contact_runs.py) recorded as a robot would: the bags the tool
and node tests read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from bag_factory import T0, BagSpec, JointStateMsg, T, header, pose, write_bag
from contact_runs import ContactRun


def stamp_of(run: ContactRun, row: int) -> int:
    """Sample ``row``'s stamp [ns] in the bag: the run's time after :data:`T0`."""
    return T0 + round(float(run.stamps_s[row]) * 1e9)


def write_run_bag(
    path: Path,
    run: ContactRun,
    efforts: bool = True,
    rows: int | None = None,
    imu_after: bool = False,
) -> Path:
    """The run (its first ``rows`` samples) as a robot would record it: /joint_states, /imu (the
    IMU's three readings; written just before its joint state, or with ``imu_after`` just after)
    and /base_pose (the root's pose, for the gait tool's world feet)."""
    spec = BagSpec()
    vector, quaternion = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    for row in range(len(run.stamps_s) if rows is None else rows):
        stamp = stamp_of(run, row)
        spec.add_joint_state(
            "/joint_states",
            stamp + 2,
            JointStateMsg(
                stamp,
                run.joint_names,
                run.angles[row].tolist(),
                run.rates[row].tolist(),
                "",
                run.torques[row].tolist() if efforts else [],
            ),
        )
        xyzw = run.quaternions[row].tolist()
        spec.add(
            "/imu",
            "sensor_msgs/msg/Imu",
            stamp + (3 if imu_after else 1),
            T["sensor_msgs/msg/Imu"](
                header(stamp, "imu_link"),
                quaternion(*xyzw),
                np.zeros(9),
                vector(*run.gyro[row].tolist()),
                np.zeros(9),
                vector(*run.specific_force[row].tolist()),
                np.zeros(9),
            ),
        )
        spec.add(
            "/base_pose",
            "geometry_msgs/msg/PoseStamped",
            stamp + 3,
            T["geometry_msgs/msg/PoseStamped"](
                header(stamp, "world"), pose(run.base_positions[row].tolist(), xyzw)
            ),
        )
    return write_bag(path, spec)
