"""``foot_markers`` of ``foot_fk_node``: per leg a sphere at the foot and a line strip through its
joints.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point
from visualization_msgs.msg import Marker, MarkerArray

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINTS_PER_LEG

FOOT_DIAMETER_M = 0.04
LINE_WIDTH_M = 0.015
COLOR_RGBA = (0.1, 0.6, 1.0, 1.0)
STANCE_RGBA = (1.0, 0.45, 0.0, 1.0)
"""A foot whose contact probability is >= 0.5 (the others: :data:`COLOR_RGBA`)."""


def foot_markers(
    quadruped: Quadruped,
    angles: Sequence[float],
    frame_id: str,
    stamp: Time,
    contacts: Sequence[float] | None = None,
) -> MarkerArray:
    """Markers of the legs whose three ``angles`` [rad] (12, slot order) are known (not NaN):
    ids ``2 * leg_slot`` (the foot, a sphere) and ``2 * leg_slot + 1`` (root-side joint origins
    to the foot, a line strip), namespace ``feet/<leg>``, points [m] in ``frame_id``. A foot
    whose contact probability (``contacts``, 4) is >= 0.5 is coloured :data:`STANCE_RGBA`.
    """
    markers = MarkerArray()
    for slot, leg in enumerate(quadruped.legs):
        leg_angles = angles[JOINTS_PER_LEG * slot : JOINTS_PER_LEG * (slot + 1)]
        if any(math.isnan(a) for a in leg_angles):
            continue
        points = [
            Point(x=float(x), y=float(y), z=float(z)) for x, y, z in leg.joint_points(leg_angles)
        ]
        header = (frame_id, stamp, leg.chain.leg)
        stance = contacts is not None and contacts[slot] >= 0.5
        foot_color = STANCE_RGBA if stance else COLOR_RGBA
        markers.markers.append(_marker(*header, 2 * slot, Marker.SPHERE, points[-1:], foot_color))
        markers.markers.append(
            _marker(*header, 2 * slot + 1, Marker.LINE_STRIP, points, COLOR_RGBA)
        )
    return markers


def _marker(
    frame_id: str,
    stamp: Time,
    leg: str,
    marker_id: int,
    kind: int,
    points: list[Point],
    color: tuple[float, float, float, float],
) -> Marker:
    marker = Marker(ns=f"feet/{leg}", id=marker_id, type=kind, action=Marker.ADD)
    marker.header.frame_id = frame_id
    marker.header.stamp = stamp
    marker.pose.orientation.w = 1.0
    if kind == Marker.SPHERE:
        marker.pose.position = points[0]
        marker.scale.x = marker.scale.y = marker.scale.z = FOOT_DIAMETER_M
    else:
        marker.points = points
        marker.scale.x = LINE_WIDTH_M
    marker.color.r, marker.color.g, marker.color.b, marker.color.a = color
    return marker
