"""A leg's chain folded into three *stages*, one per movable joint.

Each stage maps a point ``p`` in the joint's child frame to the parent side of the joint, with
every fixed transform before it folded in: ``p -> o + M Rot(a, q) p`` (``o`` [m], ``M`` a
rotation, ``a`` the unit axis, ``q`` [rad]). Writing ``M Rot(a, q) = C0 + cos(q) C1 + sin(q) C2``
(Rodrigues, with ``C0 = M a a^T``, ``C1 = M (I - a a^T)``, ``C2 = M [a]x``) makes a leg's forward
kinematics straight-line arithmetic in the cosines and sines of its angles (see
:mod:`a1_leg_fk.kinematics.fk_codegen`), and gives the inverse kinematics its geometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from a1_leg_fk.model.legs import LegChain
from a1_leg_fk.model.urdf import Joint


@dataclass(frozen=True)
class Stage:
    """One movable joint, with the fixed transforms before it folded in.

    It maps ``p -> o + M Rot(axis, q) p``.
    """

    joint: Joint
    rotation: np.ndarray  # M, 3x3
    offset: np.ndarray  # o [m], 3
    axis: np.ndarray  # unit, in the joint frame

    @cached_property
    def rodrigues_terms(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(C0, C1, C2) with ``M Rot(axis, q) = C0 + cos(q) C1 + sin(q) C2``."""
        outer = np.outer(self.axis, self.axis)
        x, y, z = self.axis
        cross = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        return self.rotation @ outer, self.rotation @ (np.eye(3) - outer), self.rotation @ cross


PARALLEL_TOLERANCE = 1e-9
"""``|1 - |cos||`` between two axes below which they count as parallel."""


@dataclass(frozen=True)
class KneeCircle:
    """The foot as the knee turns, in the plane normal to the hip-pitch axis (knee axis parallel
    to it): at knee angle ``q`` the foot is ``u + cos(q) v + sin(q) w`` [m] in the coordinates of
    :attr:`basis`, relative to the pitch axis, so its squared distance from that axis is
    ``alpha + beta cos(q) + gamma sin(q)`` [m^2] (the cos^2, sin^2 and cos*sin terms cancel).
    """

    basis: np.ndarray  # (2, 3): orthonormal rows spanning that plane, in the pitch child frame
    u: np.ndarray  # (2,) [m]
    v: np.ndarray
    w: np.ndarray
    along: float  # the foot's coordinate along the pitch axis [m], the same at every knee angle

    @property
    def alpha(self) -> float:
        """The constant term [m^2]."""
        return float(self.u @ self.u + self.v @ self.v)

    @property
    def beta(self) -> float:
        """The cosine's coefficient [m^2]."""
        return 2.0 * float(self.u @ self.v)

    @property
    def gamma(self) -> float:
        """The sine's coefficient [m^2]."""
        return 2.0 * float(self.u @ self.w)


def knee_circle(pitch: Stage, knee: Stage, foot_offset: np.ndarray) -> KneeCircle | None:
    """The :class:`KneeCircle` of a leg's pitch and knee stages and foot offset [m] (in the knee's
    child frame), or ``None`` when the knee axis is not parallel to the pitch axis.
    """
    if abs(abs(float(pitch.axis @ knee.rotation @ knee.axis)) - 1.0) > PARALLEL_TOLERANCE:
        return None
    c0, c1, c2 = knee.rodrigues_terms
    # The foot in the pitch joint's child frame: u + cos v + sin w.
    u = knee.offset + c0 @ foot_offset
    v, w = c1 @ foot_offset, c2 @ foot_offset
    first = np.cross(pitch.axis, [1.0, 0.0, 0.0])
    if np.linalg.norm(first) < 0.5:
        first = np.cross(pitch.axis, [0.0, 1.0, 0.0])
    first /= np.linalg.norm(first)
    basis = np.stack([first, np.cross(pitch.axis, first)])
    return KneeCircle(basis, basis @ u, basis @ v, basis @ w, float(pitch.axis @ u))


def rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF ``rpy`` [rad] -> rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def fold_chain(chain: LegChain) -> tuple[tuple[Stage, ...], np.ndarray]:
    """Stages for the three movable joints, and the foot's offset [m] in the last one's child
    frame.
    """
    stages = []
    rotation, offset = np.eye(3), np.zeros(3)
    for joint in chain.joints:
        offset = offset + rotation @ np.array(joint.origin_xyz)
        rotation = rotation @ rpy_matrix(joint.origin_rpy)
        if joint.movable:
            stages.append(Stage(joint, rotation, offset, np.array(joint.axis)))
            rotation, offset = np.eye(3), np.zeros(3)
    return tuple(stages), offset
