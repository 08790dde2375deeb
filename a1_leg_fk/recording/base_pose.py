"""The base's recorded pose: read from a bag's Odometry / PoseStamped / PoseWithCovarianceStamped
/ TFMessage topic and interpolated at JointState stamps (position linearly, orientation by
slerp), so that feet in the base frame become feet in the pose's world frame. No ROS install:
the bag is read through :class:`~a1_leg_fk.recording.reads.RecordingReads`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from a1_leg_fk.model.urdf import LegFkError

if TYPE_CHECKING:  # rosbags is imported when a bag is read
    from rosbags.interfaces import Connection

    from a1_leg_fk.recording.reads import RecordingReads

ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
POSE_COVARIANCE_TYPE = "geometry_msgs/msg/PoseWithCovarianceStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
BASE_POSE_TYPES = (ODOMETRY_TYPE, POSE_TYPE, POSE_COVARIANCE_TYPE, TF_TYPE)
DEFAULT_MAX_POSE_GAP_S = 0.1  # [s]: no pose between two poses further apart


@dataclass(frozen=True)
class BasePoses:
    """The base's pose over time: stamps [ns] sorted, positions (M, 3) [m], unit quaternions
    (M, 4) x, y, z, w, in ``world_frame``; interpolated at query stamps (linear / slerp).
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    world_frame: str
    max_gap_ns: int

    @classmethod
    def read(
        cls, reads: RecordingReads, connection: Connection, base_frame: str, max_gap_s: float
    ) -> BasePoses:
        """All poses of one topic, up to damage (deserialized: a pose stream is small next to
        the joints'); a pose with a non-finite value or an orientation of zero length is none.
        :class:`LegFkError` if there is none (:class:`DamagedRecording` if damage came first).
        """
        stamps, values, frames = [], [], []
        for _, message in reads.decoded(connection):
            for stamp, frame, pose in _poses_of(
                message, connection.msgtype, base_frame.lstrip("/")
            ):
                stamps.append(stamp)
                frames.append(frame)
                values.append(pose)
        data = np.array(values, dtype=float).reshape(-1, 7)
        with np.errstate(over="ignore", invalid="ignore"):
            lengths = np.linalg.norm(data[:, 3:], axis=1, keepdims=True)
        usable = np.isfinite(data).all(axis=1) & np.isfinite(lengths[:, 0]) & (lengths[:, 0] > 0)
        if not usable.any():
            reads.check()
            raise LegFkError(
                f"--base-pose {connection.topic}: no pose of the base frame '{base_frame}' in it"
            )
        kept = np.array(stamps, dtype=np.int64)[usable]
        order = np.argsort(kept, kind="stable")
        data, lengths = data[usable][order], lengths[usable][order]
        frames = [frame for frame, use in zip(frames, usable) if use]
        quaternions = data[:, 3:] / lengths
        return cls(
            kept[order],
            data[:, :3],
            quaternions,
            frames[0],
            round(max_gap_s * 1e9),
        )

    def at(self, stamps_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(positions (N, 3) [m], rotation matrices (N, 3, 3)) at ``stamps_ns``; NaN where a stamp
        lies outside the poses' time range or between two poses further apart than the gap.
        """
        stamps = self.stamps_ns
        lower = np.clip(np.searchsorted(stamps, stamps_ns, side="right") - 1, 0, len(stamps) - 1)
        upper = np.minimum(lower + 1, len(stamps) - 1)
        t0, t1 = stamps[lower], stamps[upper]
        exact = t0 == stamps_ns
        span = t1 - t0
        inside = (
            (stamps_ns >= stamps[0])
            & (stamps_ns <= stamps[-1])
            & (exact | (span <= self.max_gap_ns))
        )
        alpha = np.where(exact | (span == 0), 0.0, (stamps_ns - t0) / np.where(span > 0, span, 1))
        position = self.positions[lower] + alpha[:, None] * (
            self.positions[upper] - self.positions[lower]
        )
        quaternion = _slerp(self.quaternions[lower], self.quaternions[upper], alpha)
        rotation = rotation_matrices(quaternion)
        position[~inside] = math.nan
        rotation[~inside] = math.nan
        return position, rotation


def _poses_of(
    message: Any, msgtype: str, base_frame: str
) -> Iterator[tuple[int, str, list[float]]]:
    """(stamp [ns], parent frame, [x, y, z, qx, qy, qz, qw]) of each base pose in a message."""
    if msgtype == TF_TYPE:
        for transform in message.transforms:
            if transform.child_frame_id.lstrip("/") == base_frame:
                t, r = transform.transform.translation, transform.transform.rotation
                yield (
                    _stamp(transform.header),
                    transform.header.frame_id.lstrip("/"),
                    [t.x, t.y, t.z, r.x, r.y, r.z, r.w],
                )
        return
    pose = message.pose if msgtype == POSE_TYPE else message.pose.pose
    p, r = pose.position, pose.orientation
    yield _stamp(message.header), message.header.frame_id, [p.x, p.y, p.z, r.x, r.y, r.z, r.w]


def _stamp(header: Any) -> int:
    """A ``std_msgs/msg/Header``'s stamp in ns."""
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)


def _slerp(q0: np.ndarray, q1: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Spherical interpolation between unit quaternions (N, 4), the shorter way round."""
    dot = np.sum(q0 * q1, axis=1)
    q1 = np.where(dot[:, None] < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    close = sin_theta < 1e-9
    safe = np.where(close, 1.0, sin_theta)
    w0 = np.where(close, 1.0 - alpha, np.sin((1.0 - alpha) * theta) / safe)
    w1 = np.where(close, alpha, np.sin(alpha * theta) / safe)
    q = w0[:, None] * q0 + w1[:, None] * q1
    unit: np.ndarray = q / np.linalg.norm(q, axis=1, keepdims=True)
    return unit


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of unit quaternions (N, 4) x, y, z, w."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=1),
        ],
        axis=1,
    )
