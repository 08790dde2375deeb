"""Inverse kinematics of one leg: a foot position [m] -> the leg's three joint angles [rad], with a
status and the residual distance. Pure numpy, no ROS; works on :class:`CompiledLeg` objects.

Frames: the target is in the base frame (the root link's), as :meth:`Quadruped.fk` returns it.

**Closed form** (legs of the A1 topology: the first joint's axis perpendicular to the second's, the
second and third axes parallel), derived from the compiled stages ``p -> o + M Rot(a, q) p``, so it
holds for any rpy, offsets and axis signs in the URDF (A1, aliengo, mini_cheetah):

1. In the roll joint's frame the target is ``t0 = M0^T (t - o0)``, and ``Rot(a0, q0) x = t0`` where
   ``x`` is the foot in the roll joint's child frame. The pitch axis there is ``b = M1 a1``; since
   the knee axis is parallel to it, ``b . x = h`` is the same for every pitch and knee angle (the
   leg's lateral offset). ``b . Rot(a0, -q0) t0 = h`` reads ``A cos q0 + B sin q0 = h`` with
   ``A = b . t0`` and ``B = (a0 x b) . t0``: two roll branches, ``atan2(B, A) +- acos(h / |AB|)``.
2. With ``x`` known, its distance from the pitch axis fixes the knee: the foot's distance from
   that axis is ``sqrt(alpha + beta cos q2 + gamma sin q2)`` (as in :meth:`Quadruped.reach`): two
   knee branches, ``atan2(gamma, beta) +- acos(...)``.
3. The pitch angle is then the angle, about the pitch axis, from the foot's direction at ``q2`` to
   the target's: one value per branch.

Up to four solutions. An ``acos`` argument beyond 1 (by more than
:data:`a1_leg_fk.kinematics.ik.closed_form.ARGUMENT_TOLERANCE`) means that branch does not reach
the target. The constants and branches are in :mod:`a1_leg_fk.kinematics.ik.closed_form`, the
generated straight-line code in :mod:`a1_leg_fk.kinematics.ik.codegen`, the one-leg solver in
:mod:`a1_leg_fk.kinematics.ik.leg_solver`.

**Other three-joint legs**: damped least squares on the compiled FK and Jacobian (Levenberg-damped
Newton steps on the squared distance, see :func:`a1_leg_fk.kinematics.ik.search.least_squares`),
from the seed, then from a fixed grid of starts, each run bounded to
:data:`a1_leg_fk.kinematics.ik.search.MAX_ITERATIONS` iterations.

**Statuses** (:data:`STATUS_NAMES`, codes :data:`OK`, :data:`OUTSIDE_LIMITS`, :data:`UNREACHABLE`):
``ok`` - an exact solution inside the URDF limits; ``outside_limits`` - exact solutions exist,
but each has a joint outside its limits; ``unreachable`` - no angles reach the target. In the last
two cases the angles returned are the in-limit angles whose foot is nearest the target (a box-
constrained least-squares search from the clamped solutions, the seed and a grid of starts), and
the residual is that foot's distance from the target.

**Which solution, and which angle** (the seed rule): each joint angle is taken modulo 2 pi; of its
values ``q + 2 pi k`` the one inside the joint's limits is used (for a range wider than 2 pi: the
one nearest the seed's angle; for a continuous joint: the one within pi of the seed's angle). Among
the in-limit solutions the one nearest the seed in joint space (Euclidean norm of the three
differences, so wrapped angular distance for continuous joints) is returned. Without a seed the
seed is the middle of each joint's range (0 for a continuous joint). An angle that has no value
inside a range narrower than 2 pi is reported (by :meth:`LegSolver.solutions`) as its value just
above the lower limit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from a1_leg_fk.kinematics.ik.fused import fused_solver
from a1_leg_fk.kinematics.ik.leg_solver import (
    OK,
    OUTSIDE_LIMITS,
    STATUS_NAMES,
    UNREACHABLE,
    LegIk,
    LegSolver,
    Solution,
)
from a1_leg_fk.kinematics.ik.seed import range_middle
from a1_leg_fk.model.urdf import LegFkError

__all__ = [
    "OK",
    "OUTSIDE_LIMITS",
    "STATUS_NAMES",
    "UNREACHABLE",
    "IkBatchResult",
    "IkResult",
    "LegIk",
    "LegSolver",
    "Solution",
    "checked_point",
    "range_middle",
    "solve_feet",
    "solve_feet_batch",
]

BATCH_BLOCK_ROWS = 8192
"""Rows per block of :func:`solve_feet_batch`."""


def checked_point(point: Sequence[float], leg: str) -> tuple[float, float, float]:
    """Three finite floats [m], or a :class:`LegFkError` naming the leg."""
    try:
        values = tuple(float(v) for v in point)
    except (TypeError, ValueError) as error:
        raise LegFkError(
            f"leg {leg}: the target must be 3 numbers (x, y, z in m): {error}"
        ) from error
    if len(values) != 3:
        raise LegFkError(
            f"leg {leg}: the target must be 3 numbers (x, y, z in m), got {len(values)}"
        )
    if not all(math.isfinite(v) for v in values):
        raise LegFkError(f"leg {leg}: the target {values} is not finite")
    return values  # three, checked above


# --- four legs -------------------------------------------------------------------------------


class IkResult(NamedTuple):
    """:meth:`Quadruped.ik`'s answer: 12 angles [rad] in slot order, one status name per leg
    (FR, FL, RR, RL), and per leg the distance [m] from the foot at those angles to its target; a
    named tuple, as it is made on every call and must be cheap.
    """

    angles: np.ndarray  # (12,)
    status: tuple[str, ...]  # four: FR, FL, RR, RL
    residual_m: np.ndarray  # (4,)


@dataclass(frozen=True)
class IkBatchResult:
    """:meth:`Quadruped.ik_batch`'s answer: (N, 12) angles [rad], (N, 4) int8 status codes
    (:data:`OK`, :data:`OUTSIDE_LIMITS`, :data:`UNREACHABLE`), (N, 4) residuals [m].
    """

    angles: np.ndarray
    status: np.ndarray
    residual_m: np.ndarray


def solve_feet(
    solvers: Sequence[LegSolver], targets: Sequence[float], seed: Sequence[float] | None
) -> IkResult:
    """IK of the legs for checked targets [m] (x, y, z of each leg in slot order: 12 floats for
    four legs) and 12 checked seed angles [rad] (or ``None``).
    """
    fused = fused_solver(tuple(solvers))
    if fused is not None:  # the common case: every leg has an in-limit solution
        solve, middle = fused
        found = solve(*targets, *(middle if seed is None else seed))
        if found is not None:
            values = np.array(found)
            joints = 3 * len(solvers)
            return IkResult(values[:joints], ("ok",) * len(solvers), values[joints:])
    angles: list[float] = []
    status, residuals = [], []
    for slot, solver in enumerate(solvers):
        leg_seed = None if seed is None else seed[3 * slot : 3 * slot + 3]
        result = solver.solve(targets[3 * slot : 3 * slot + 3], leg_seed)
        angles.extend(result.angles)
        status.append(STATUS_NAMES[result.status])
        residuals.append(result.residual_m)
    return IkResult(np.array(angles), tuple(status), np.array(residuals))


def solve_feet_batch(
    solvers: Sequence[LegSolver], feet: np.ndarray, seeds: np.ndarray | None
) -> IkBatchResult:
    """IK of four legs for (N, 4, 3) checked targets [m] and (N, 12) checked seeds [rad] (or
    ``None``).
    """
    rows = feet.shape[0]
    angles = np.empty((rows, 3 * len(solvers)))
    status = np.empty((rows, len(solvers)), dtype=np.int8)
    residuals = np.empty((rows, len(solvers)))
    # Blocks whose temporaries stay in the CPU cache.
    for block in range(0, rows, BATCH_BLOCK_ROWS):
        rows_in_block = slice(block, min(block + BATCH_BLOCK_ROWS, rows))
        for slot, solver in enumerate(solvers):
            columns = slice(3 * slot, 3 * slot + 3)
            leg_seeds = None if seeds is None else seeds[rows_in_block, columns]
            (
                angles[rows_in_block, columns],
                status[rows_in_block, slot],
                residuals[rows_in_block, slot],
            ) = solver.solve_batch(feet[rows_in_block, slot], leg_seeds)
    return IkBatchResult(angles, status, residuals)
