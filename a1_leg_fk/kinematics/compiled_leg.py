"""One leg compiled: its chain folded into three stages (:mod:`a1_leg_fk.kinematics.leg_stages`)
and turned into generated straight-line FK code (:mod:`a1_leg_fk.kinematics.fk_codegen`) that runs
on floats and on numpy arrays. The building block of
:class:`~a1_leg_fk.kinematics.quadruped.Quadruped` and of the IK solvers
(:mod:`a1_leg_fk.kinematics.ik`).

Frames and units: angles in rad, rates in rad/s, positions in m, velocities in m/s, in the root
link's frame (the base frame).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from a1_leg_fk.kinematics.fk_codegen import compile_source, leg_source
from a1_leg_fk.kinematics.leg_stages import fold_chain
from a1_leg_fk.model.legs import LegChain

Angles = Sequence[float] | np.ndarray
"""Joint angles [rad] (or rates [rad/s]): a sequence of numbers or a 1-D numpy array."""

BATCH_CHUNK_ROWS = 4096
"""Rows per block in the batch functions: keeps the temporaries of one block in the CPU cache."""


class CompiledLeg:
    """One leg's generated FK functions and the stages they were made from.

    ``position(q0, q1, q2) -> (x, y, z)`` and ``position_velocity(q0, q1, q2, dq0, dq1, dq2) ->
    (x, y, z, vx, vy, vz)`` take floats; the ``*_from_trig`` variants take ``(c0, s0, c1, s1, c2,
    s2)``, the cosines and sines of the angles, as floats or numpy arrays.
    """

    def __init__(self, chain: LegChain) -> None:
        """Fold ``chain`` into stages and compile its generated FK functions."""
        self.chain = chain
        self.stages, self.foot_offset = fold_chain(chain)
        self.source = leg_source(self.stages, self.foot_offset)
        namespace = compile_source(self.source, f"FK of leg {chain.leg}", self)
        # The generated functions take and return floats (or numpy arrays, the *_from_trig ones).
        self.position: Callable[..., tuple[float, float, float]] = namespace["position"]
        self.position_velocity: Callable[..., tuple[float, ...]] = namespace["position_velocity"]
        self.position_from_trig: Callable[..., tuple[Any, Any, Any]] = namespace[
            "position_from_trig"
        ]
        self.jacobian_from_trig: Callable[..., tuple[Any, ...]] = namespace["jacobian_from_trig"]

    def positions_batch(
        self, cos: np.ndarray, sin: np.ndarray, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(K, 3) feet [m, root frame] for the (K, 3) cosines and sines of the leg's angles,
        written into ``out`` when given (a view of a larger array, say).
        """
        out = np.empty((cos.shape[0], 3)) if out is None else out
        out[:, 0], out[:, 1], out[:, 2] = self.position_from_trig(
            cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2]
        )
        return out

    def jacobians_batch(
        self, cos: np.ndarray, sin: np.ndarray, out: np.ndarray | None = None
    ) -> np.ndarray:
        """(K, 3, 3) d(foot [m]) / d(angles [rad]), root frame, for the (K, 3) cosines and sines of
        the leg's angles, written into ``out`` when given.
        """
        out = np.empty((cos.shape[0], 3, 3)) if out is None else out
        columns = self.jacobian_from_trig(
            cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2]
        )
        for joint in range(3):
            for axis in range(3):
                out[:, axis, joint] = columns[3 * joint + axis]
        return out

    def joint_points(self, angles: Angles) -> np.ndarray:
        """(4, 3): the three movable joints' origins and the foot [m], root frame, root side
        first.
        """
        rotation, origin = np.eye(3), np.zeros(3)
        points = []
        for stage, angle in zip(self.stages, angles):
            origin = origin + rotation @ stage.offset
            points.append(origin)
            c0, c1, c2 = stage.rodrigues_terms
            rotation = rotation @ (c0 + math.cos(angle) * c1 + math.sin(angle) * c2)
        points.append(origin + rotation @ self.foot_offset)
        return np.array(points)
