"""The local ground's plane as the odometry's outputs: the odom CSV's columns
(:data:`GROUND_COLUMNS`, :func:`ground_values`) and the pose with covariance the node publishes
(:func:`plane_pose`).
"""

from __future__ import annotations

import math

from a1_leg_fk.estimation.ground_plane import GroundPlane, Point

GROUND_COLUMNS = (
    "ground_height_m",
    "ground_normal_x",
    "ground_normal_y",
    "ground_normal_z",
    "ground_var_height",
    "ground_var_roll",
    "ground_var_pitch",
)
"""The local ground's values as the odom CSV names them (:func:`ground_values`)."""


def ground_values(plane: GroundPlane | None) -> tuple[float, ...]:
    """``plane`` as :data:`GROUND_COLUMNS`: its height [m, odom], unit normal and the variances
    of the height [m²], roll and pitch [rad²]; NaN each before the first stance (None).
    """
    if plane is None:
        return (math.nan,) * len(GROUND_COLUMNS)
    covariance = plane.covariance
    return (
        plane.height_m,
        *plane.normal,
        covariance[0][0],
        covariance[1][1],
        covariance[2][2],
    )


def plane_pose(
    plane: GroundPlane, x: float, y: float
) -> tuple[Point, tuple[float, float, float, float], list[float]]:
    """``plane`` at (x, y) [m, odom] as a pose with covariance (geometry_msgs'): the point on it
    there [m], the tilt as a quaternion (x, y, z, w; R = Ry(pitch) Rx(roll), no yaw) and the
    6×6 covariance, row-major (x, y, z, rotation about x, y, z): the height's and the tilt's,
    zero for x, y and yaw (the point is under the base by construction, a plane has no yaw).
    """
    half_roll, half_pitch = plane.roll / 2.0, plane.pitch / 2.0
    cr, sr, cp, sp = (
        math.cos(half_roll),
        math.sin(half_roll),
        math.cos(half_pitch),
        math.sin(half_pitch),
    )
    quaternion = (cp * sr, sp * cr, -sp * sr, cp * cr)  # qy(pitch) ⊗ qx(roll)
    covariance = [0.0] * 36
    for row, axis in enumerate((2, 3, 4)):  # z, roll, pitch
        for column, other in enumerate((2, 3, 4)):
            covariance[6 * axis + other] = plane.covariance[row][column]
    return (x, y, plane.height_m), quaternion, covariance
