"""Runs of the contact family (test/contact_runs.py) recorded as a Unitree robot records them: one
``LowState`` per sample (``unitree_go/msg/LowState`` or ROS 1 ``unitree_legged_msgs/LowState``)
with the motors, the IMU (quaternion w first) and the foot sensors; and the same samples as a
JointState + Imu bag, their values rounded to float32 as the LowState carries them: the
reference the LowState path must equal.

The messages are built and serialized by rosbags (its typestores, given Unitree's definitions as
the issue lists them): independent of the package's decoder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from bag_factory import ROS1_TYPESTORE, TYPESTORE, BagSpec, JointStateMsg, T, header, write_bag
from contact_bags import stamp_of
from contact_runs import ContactRun
from rosbags.typesys import get_types_from_msg
from shared import STANDING

from a1_leg_fk.wire.unitree_types import DEFINITIONS, GO_LOW_STATE, LEGGED_LOW_STATE

COUNTS_PER_NEWTON = 2.0
"""The simulated foot sensors' scale [counts/N] (a real one's is unpublished)."""
SENSOR_OFFSET = 5
"""[counts] the simulated sensors' reading of an unloaded foot."""
NUMPY = {"float32": np.float32, "int16": np.int16, "int8": np.int8, "uint8": np.uint8,
         "uint16": np.uint16, "uint32": np.uint32, "int32": np.int32}  # fmt: skip


def register_unitree_types() -> None:
    """Give the factory's typestores Unitree's types (once)."""
    types = {}
    for msgtype, text in DEFINITIONS.items():
        types.update(get_types_from_msg(text, msgtype))
    for store in (TYPESTORE, ROS1_TYPESTORE):
        missing = {name: kind for name, kind in types.items() if name not in store.fielddefs}
        if missing:
            store.register(missing)


def zeroed(msgtype: str):
    """A message of ``msgtype`` with every field zero."""
    fields: dict[str, Any] = {}
    spec: Any
    for name, (node, spec) in TYPESTORE.fielddefs[msgtype][1]:
        if node == 1:  # a primitive
            fields[name] = 0.0 if spec[0].startswith("float") else 0
        elif node == 2:  # a nested message
            fields[name] = zeroed(spec)
        else:  # a fixed array
            (inner_node, inner), count = spec
            fields[name] = (
                np.zeros(count, dtype=NUMPY[inner[0]])
                if inner_node == 1
                else [zeroed(inner) for _ in range(count)]
            )
    return T[msgtype](**fields)


def f32(values) -> np.ndarray:
    """The values as a float32 message carries them, back in float64."""
    return np.asarray(values, dtype=np.float32).astype(np.float64)


def sensor_counts(run: ContactRun, row: int) -> np.ndarray:
    """The simulated foot sensors of a sample [counts]."""
    return np.round(SENSOR_OFFSET + COUNTS_PER_NEWTON * run.normal_forces[row]).astype(np.int16)


def lowstate_message(run: ContactRun, row: int, msgtype: str, x_first: bool = False):
    """Sample ``row`` as a LowState of ``msgtype`` (``x_first``: the quaternion in the wrong,
    x-first order, for the test that must catch it)."""
    go = msgtype == GO_LOW_STATE
    message = zeroed(msgtype)
    motors = message.motor_state if go else message.motorState
    for index in range(12):
        motor = motors[index]
        motor.q, motor.dq = float(run.angles[row, index]), float(run.rates[row, index])
        setattr(motor, "tau_est" if go else "tauEst", float(run.torques[row, index]))
    imu = message.imu_state if go else message.imu
    x, y, z, w = run.quaternions[row]
    imu.quaternion[:] = [x, y, z, w] if x_first else [w, x, y, z]
    imu.gyroscope[:] = run.gyro[row]
    imu.accelerometer[:] = run.specific_force[row]
    (message.foot_force if go else message.footForce)[:] = sensor_counts(run, row)
    message.tick = round(float(run.stamps_s[row]) * 1000)
    return message


def write_lowstate_bag(
    path: Path,
    run: ContactRun,
    rows: int,
    kind: str = "mcap",
    msgtype: str = GO_LOW_STATE,
    topic: str = "/lowstate",
    x_first: bool = False,
) -> Path:
    """The first ``rows`` samples as LowStates on ``topic`` at bag time = the sample's stamp
    (``kind`` as :func:`bag_factory.write_bag`'s)."""
    register_unitree_types()
    spec = BagSpec()
    for row in range(rows):
        spec.add(topic, msgtype, stamp_of(run, row), lowstate_message(run, row, msgtype, x_first))
    return write_bag(path, spec, kind)


def write_reference_bag(path: Path, run: ContactRun, rows: int, names=None) -> Path:
    """The same samples as /joint_states + /imu, values rounded to float32, stamped with the
    LowState's bag time (the IMU one ns earlier in the bag, as a replay delivers it first)."""
    spec = BagSpec()
    vector, quaternion = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    for row in range(rows):
        stamp = stamp_of(run, row)
        spec.add_joint_state(
            "/joint_states",
            stamp,
            JointStateMsg(
                stamp,
                list(names or run.joint_names),
                f32(run.angles[row]).tolist(),
                f32(run.rates[row]).tolist(),
                "",
                f32(run.torques[row]).tolist(),
            ),
        )
        spec.add(
            "/imu",
            "sensor_msgs/msg/Imu",
            stamp - 1,
            T["sensor_msgs/msg/Imu"](
                header(stamp, "imu_link"),
                quaternion(*f32(run.quaternions[row]).tolist()),
                np.zeros(9),
                vector(*f32(run.gyro[row]).tolist()),
                np.zeros(9),
                vector(*f32(run.specific_force[row]).tolist()),
                np.zeros(9),
            ),
        )
    return write_bag(path, spec)


__all__ = ["LEGGED_LOW_STATE", "write_lowstate_bag", "write_reference_bag"]


def lowstate_cdr(
    msgtype: str,
    angles: Any = STANDING,
    rates: Any = (0.0,) * 12,
    torques: Any = (0.0,) * 12,
    imu: tuple[Any, Any, Any] = ((1.0, 0.0, 0.0, 0.0), (0.0,) * 3, (0.0, 0.0, 9.81)),
) -> bytes:
    """A LowState of ``msgtype`` as CDR (a ROS 2 topic carries it so, whichever package defines
    it): motors 0-11 at ``angles`` [rad], ``rates`` [rad/s], ``torques`` [N m]; the IMU's
    quaternion (w first), gyroscope [rad/s], accelerometer [m/s^2] (level, at rest by default).
    Every value as float32 (an overflow becomes an infinity, as a float32 field holds it).
    """
    register_unitree_types()
    go = msgtype == GO_LOW_STATE
    message = zeroed(msgtype)
    motors = message.motor_state if go else message.motorState
    with np.errstate(over="ignore"):
        values = np.asarray([angles, rates, torques], dtype=np.float32)
        sensors = [np.asarray(part, dtype=np.float32) for part in imu]
    for index in range(12):
        motor = motors[index]
        motor.q, motor.dq = values[0, index], values[1, index]
        setattr(motor, "tau_est" if go else "tauEst", values[2, index])
    state = message.imu_state if go else message.imu
    state.quaternion[:], state.gyroscope[:], state.accelerometer[:] = sensors
    return bytes(TYPESTORE.serialize_cdr(message, msgtype))
