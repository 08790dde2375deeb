"""Unitree's ``LowState`` read straight from its serialized bytes: ``unitree_go/msg/LowState``
(Go2, B2; ROS 2 CDR) and ``unitree_legged_msgs/LowState`` (A1, Go1; ROS 1), and the feet of
``unitree_go/msg/SportModeState``.

What is read (the facts of Unitree's published definitions, :mod:`a1_leg_fk.wire.unitree_types`):
motors 0-11 are FR, FL, RR, RL × (hip, thigh, calf) (:data:`MOTOR_NAMES`, the joint names of
Unitree's descriptions); each motor's ``q`` [rad], ``dq`` [rad/s] and ``tau_est`` (``tauEst``)
[N m], float32; the IMU inside the message: ``quaternion`` in the order (w, x, y, z), returned
here as (x, y, z, w), ``gyroscope`` [rad/s] and ``accelerometer`` [m/s^2] in the IMU's (the
body's) frame; ``foot_force`` (``footForce``): FR, FL, RR, RL, raw sensor counts (int16, no
published scale); ``tick`` [ms]. The message has no header: its time is the caller's (a bag's
receive time).

A batch of messages of one length is decoded with numpy views at the layout's offsets
(:mod:`a1_leg_fk.wire.layout`): no per-message Python. No ROS and no ``rosbags`` here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.wire.imu import ImuFields
from a1_leg_fk.wire.joint_state import WireError, WireFields
from a1_leg_fk.wire.layout import CDR_HEADER, Layout, definitions_in, layout_of, normalized
from a1_leg_fk.wire.unitree_types import (
    DEFINITIONS,
    GO_LOW_STATE,
    LEGGED_LOW_STATE,
    SPORT_MODE_STATE,
)

MOTOR_NAMES: tuple[str, ...] = tuple(
    f"{leg}_{role}_joint" for leg in ("FR", "FL", "RR", "RL") for role in ("hip", "thigh", "calf")
)
"""The joints of motors 0-11, in motor order: Unitree's joint names (its URDFs use them)."""
FEET = ("FR", "FL", "RR", "RL")
"""The order of ``foot_force`` and of ``foot_position_body``'s four feet."""
CDR_PADDING = 8
"""A CDR message may end in up to this many bytes of padding after its last field."""


@dataclass(frozen=True)
class LowStateKind:
    """One LowState type's field names and the package that defines it."""

    msgtype: str
    motors: str
    imu: str
    torque: str
    foot_force: str
    package: str  # what a user builds for the live node
    ros1: bool


KINDS: Mapping[str, LowStateKind] = {
    GO_LOW_STATE: LowStateKind(
        GO_LOW_STATE, "motor_state", "imu_state", "tau_est", "foot_force", "unitree_go", False
    ),
    LEGGED_LOW_STATE: LowStateKind(
        LEGGED_LOW_STATE, "motorState", "imu", "tauEst", "footForce", "unitree_legged_msgs", True
    ),
}
"""The LowState types read, by type name."""


@dataclass(frozen=True)
class LowStateRows:
    """N decoded messages: ``positions``, ``velocities``, ``efforts`` (N, 12) float64 in motor
    order [rad, rad/s, N m]; ``orientations`` (N, 4) x, y, z, w; ``gyro`` (N, 3) [rad/s];
    ``accelerometer`` (N, 3) [m/s^2]; ``foot_force`` (N, 4) raw counts; ``tick`` (N,) [ms].
    """

    positions: np.ndarray
    velocities: np.ndarray
    efforts: np.ndarray
    orientations: np.ndarray
    gyro: np.ndarray
    accelerometer: np.ndarray
    foot_force: np.ndarray
    tick: np.ndarray

    def head(self, count: int) -> LowStateRows:
        """The first ``count`` rows."""
        return LowStateRows(*(getattr(self, name)[:count] for name in self.__dataclass_fields__))


def layout_for(msgtype: str, recorded: str | None, ros1: bool) -> Layout:
    """The layout of ``msgtype`` from the bag's recorded definition text, else the package's own
    (:data:`~a1_leg_fk.wire.unitree_types.DEFINITIONS`).
    """
    definitions = definitions_in(recorded, msgtype) if recorded else DEFINITIONS
    return layout_of(msgtype, definitions, ros1)


class LowStateDecoder:
    """Decodes serialized LowState messages of one layout."""

    def __init__(self, layout: Layout) -> None:
        self.layout = layout
        self.kind = KINDS[normalized(layout.msgtype)]
        kind = self.kind
        first = f"{kind.motors}[0]."
        motor = layout.field(f"{first}q")
        stride = layout.field(f"{kind.motors}[1].q").offset - motor.offset
        self._motor_stride = stride
        self._motors = {
            name: layout.field(f"{first}{name}").offset for name in ("q", "dq", kind.torque)
        }
        self._imu = {
            name: layout.field(f"{kind.imu}.{name}")
            for name in ("quaternion", "gyroscope", "accelerometer")
        }
        self._foot_force = layout.field(kind.foot_force)
        self._tick = layout.field("tick")

    def check(self, raw: bytes) -> str:
        """What is wrong with one message's bytes for this layout ("" if nothing)."""
        size = self.layout.size
        if self.layout.ros1:
            if len(raw) != size:
                return f"{len(raw)} bytes, where a {self.layout.msgtype} has {size}"
            return ""
        if len(raw) < CDR_HEADER or raw[0] != 0 or raw[1] > 1:
            return f"not a CDR message (encapsulation {bytes(raw[:4]).hex()})"
        if not size <= len(raw) < size + CDR_PADDING:
            return f"{len(raw)} bytes, where a {self.layout.msgtype} has {size} (CDR)"
        return ""

    def rows(self, raws: Sequence[bytes]) -> tuple[LowStateRows, tuple[int, str] | None]:
        """The rows of consecutive messages, and ``None`` or (index, problem) of the first that
        cannot be decoded (the rows stop before it).
        """
        count, problem = len(raws), None
        for index, raw in enumerate(raws):
            text = self.check(raw)
            if text:
                count, problem = index, (index, text)
                break
        good = raws[:count]
        if not good:
            return _empty(), problem
        lengths = {len(raw) for raw in good}
        orders = {raw[1] for raw in good} if not self.layout.ros1 else {1}
        if len(lengths) == 1 and len(orders) == 1:
            return self._same_length(b"".join(good), count, lengths.pop(), orders.pop()), problem
        parts = [self._same_length(bytes(raw), 1, len(raw), raw[1] if not self.layout.ros1 else 1)
                 for raw in good]  # fmt: skip
        return _concatenate(parts), problem

    def _same_length(
        self, buffer: bytes, count: int, length: int, order_flag: int
    ) -> LowStateRows:
        order = "<" if order_flag == 1 else ">"

        def view(offset: int, code: str, width: int, step: int) -> np.ndarray:
            return np.ndarray(
                (count, width), np.dtype(order + code), buffer, offset, (length, step)
            ).astype(np.float64)

        stride = self._motor_stride
        q, dq, tau = (view(offset, "f4", 12, stride) for offset in self._motors.values())
        quaternion, gyro, accel = (view(f.offset, "f4", f.count, 4) for f in self._imu.values())
        feet = self._foot_force
        tick = self._tick
        return LowStateRows(
            q,
            dq,
            tau,
            quaternion[:, [1, 2, 3, 0]],  # the message's (w, x, y, z) -> (x, y, z, w)
            gyro,
            accel,
            view(feet.offset, "i2", 4, 2),
            view(tick.offset, "u4", 1, 4)[:, 0],
        )


def _empty() -> LowStateRows:
    q, dq, tau, quaternion, gyro, accel, feet = (
        np.zeros((0, width)) for width in (12, 12, 12, 4, 3, 3, 4)
    )
    return LowStateRows(q, dq, tau, quaternion, gyro, accel, feet, np.zeros(0))


def _concatenate(parts: Sequence[LowStateRows]) -> LowStateRows:
    names = LowStateRows.__dataclass_fields__
    return LowStateRows(*(np.concatenate([getattr(p, name) for p in parts]) for name in names))


class LowStateJointStates:
    """A live LowState stream read as a JointState decoder reads a JointState stream (for the
    nodes' raw subscriptions): :meth:`fields` gives the motors as :class:`WireFields` (named
    :data:`MOTOR_NAMES`, stamped ``clock()`` [ns]: the receive time, the message has no header),
    :attr:`imu` the IMU inside the same message as an Imu's fields (no covariances: "unknown").
    """

    def __init__(self, msgtype: str, clock: Callable[[], int]) -> None:
        # CDR whichever package defines it: a live topic is ROS 2 (unitree_legged_msgs, a ROS 1
        # package, reaches it through a bridge); its ROS 1 layout is for ROS 1 bags only
        self._decoder = LowStateDecoder(layout_for(msgtype, None, ros1=False))
        self._clock = clock
        self.names = list(MOTOR_NAMES)
        self.imu: ImuFields | None = None
        self._first = True

    def fields(self, raw: bytes | memoryview) -> WireFields:
        """One message's motors; :class:`WireError` if it is not a whole LowState."""
        rows, problem = self._decoder.rows([bytes(raw)])
        if problem is not None:
            raise WireError(f"malformed {self._decoder.layout.msgtype}: {problem[1]}")
        stamp = self._clock()
        unknown = (0.0,) * 9
        self.imu = (
            stamp,
            tuple(rows.orientations[0].tolist()),
            unknown,
            tuple(rows.gyro[0].tolist()),
            unknown,
            tuple(rows.accelerometer[0].tolist()),
            unknown,
        )
        changed, self._first = self._first, False
        order = "<" if np.little_endian else ">"
        values = (rows.positions[0], rows.velocities[0], rows.efforts[0])
        return WireFields(stamp, changed, order, *(array.tobytes() for array in values))


class SportModeFeet:
    """The feet of ``unitree_go/msg/SportModeState`` messages: ``foot_position_body`` (4 × x, y, z
    [m], body frame, FR, FL, RR, RL), Unitree's own estimate.
    """

    def __init__(self, recorded: str | None) -> None:
        self.layout = layout_for(SPORT_MODE_STATE, recorded, False)
        self._feet = self.layout.field("foot_position_body")

    def feet(self, raw: bytes) -> np.ndarray | None:
        """(4, 3) feet [m] of one message, or None (not of this layout)."""
        size = self.layout.size
        if len(raw) < size or len(raw) >= size + CDR_PADDING or raw[0] != 0 or raw[1] > 1:
            return None
        order = "<" if raw[1] == 1 else ">"
        values = np.frombuffer(raw, np.dtype(order + "f4"), 12, self._feet.offset)
        return values.astype(np.float64).reshape(4, 3)
