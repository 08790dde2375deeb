"""The inverse kinematics of one leg, :class:`LegSolver` (see
:mod:`a1_leg_fk.kinematics.ik.four_legs` for the method, the statuses and the seed rule): the
closed form where the leg has one, else damped least squares; its statuses and answers. No ROS.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.ik.closed_form import Geometry, branches, closed_form_geometry
from a1_leg_fk.kinematics.ik.codegen import fast_solver
from a1_leg_fk.kinematics.ik.search import REACHED_M, least_squares
from a1_leg_fk.kinematics.ik.seed import (
    ARRAY,
    SCALAR,
    FloatsOrArrays,
    range_middle,
    representative_angle,
    wrapped_distance,
)

OK, OUTSIDE_LIMITS, UNREACHABLE = 0, 1, 2
"""Status codes of :meth:`LegSolver.solve_batch` (small integers, ``int8`` arrays)."""
STATUS_NAMES: tuple[str, ...] = ("ok", "outside_limits", "unreachable")
"""Status names by code."""
GRID_STEPS = 3
"""Starts per joint of the grid the least-squares searches start from (GRID_STEPS^3 starts)."""


@dataclass(frozen=True)
class Solution:
    """One exact solution of a leg: its three angles [rad] (root side first) and whether all three
    lie inside the URDF limits (each angle is the value modulo 2 pi nearest the seed, inside the
    limits where one is).
    """

    angles: tuple[float, float, float]
    inside_limits: bool


class LegIk(NamedTuple):
    """One leg's answer: three angles [rad], the status code, and the distance [m] from the foot
    at those angles to the target; a named tuple, as it is made on every call and must be cheap.
    """

    angles: tuple[float, float, float]
    status: int
    residual_m: float


class LegSolver:
    """IK of one compiled leg: :meth:`solve` (one target), :meth:`solve_batch` (N targets) and
    :meth:`solutions` (every exact solution).
    """

    def __init__(self, leg: CompiledLeg, use_closed_form: bool = True) -> None:
        """``use_closed_form=False`` solves an A1-topology leg by damped least squares as well
        (for comparisons: the statuses and residuals agree).
        """
        self.leg = leg
        joints = [stage.joint for stage in leg.stages]
        self.lower = np.array([-math.inf if j.lower is None else j.lower for j in joints])
        self.upper = np.array([math.inf if j.upper is None else j.upper for j in joints])
        self.middle = np.array([range_middle(joint) for joint in joints])
        # Ranges for the searches: a continuous joint's full turn around its middle.
        self.search_lower = np.where(np.isfinite(self.lower), self.lower, self.middle - math.pi)
        self.search_upper = np.where(np.isfinite(self.upper), self.upper, self.middle + math.pi)
        self._limits = tuple(zip(self.lower.tolist(), self.upper.tolist()))
        self._middle = tuple(self.middle.tolist())
        self.geometry = closed_form_geometry(leg) if use_closed_form else None
        self.closed_form = self.geometry is not None
        generated = (
            None
            if self.geometry is None
            else fast_solver(
                self.geometry, self._limits, leg.chain.leg, self, leg.position(*self._middle)
            )
        )
        self._fast: Callable[..., Any] | None = None
        self._fast_batch: Callable[..., Any] | None = None
        self._first_roll_sign: float | None = None  # of the generated code (None: there is none)
        if generated is not None:
            self._fast, self._fast_batch, self._first_roll_sign = generated

    # --- public --------------------------------------------------------------------------

    def solutions(
        self, point: Sequence[float], seed: Sequence[float] | None = None
    ) -> list[Solution]:
        """Every exact solution for ``point`` [m, base frame]: the closed form's up to four (two
        roll x two knee branches), else the distinct ones the least-squares runs converge to.
        """
        seed_angles = self._middle if seed is None else tuple(seed)
        if self.geometry is not None:
            x, y, z = point
            candidates = branches(self.geometry, x, y, z, SCALAR)
            found: list[Solution] = []
            for angles, exact in candidates:
                if exact:
                    representative, inside = self._representatives(angles, seed_angles)
                    # Branches meet at singularities.
                    if all(s.angles != representative for s in found):
                        found.append(Solution(representative, inside))
            return found
        return self._searched_solutions(np.asarray(point, dtype=float), seed_angles)

    def solve(self, point: Sequence[float], seed: Sequence[float] | None = None) -> LegIk:
        """The angles [rad] for ``point`` [m, base frame] nearest ``seed`` (3 angles; ``None``: the
        middle of the ranges), the status code and the residual [m].
        """
        seed_angles = self._middle if seed is None else tuple(seed)
        if self.geometry is None:
            return self._solve_by_search(np.asarray(point, dtype=float), seed_angles)
        found = None if self._fast is None else self._fast(*point, *seed_angles)
        best, reachable = (
            self._choose(self.geometry, point, seed_angles) if found is None else found
        )
        if best is not None:
            x, y, z = self.leg.position(*best)
            residual = math.hypot(x - point[0], y - point[1], z - point[2])  # hypot: no overflow
            return LegIk(best, OK, residual)
        return self._nearest_in_limits(np.asarray(point, dtype=float), seed_angles, reachable)

    def _choose(
        self, geometry: Geometry, point: Sequence[float], seed_angles: Sequence[float]
    ) -> tuple[tuple[float, float, float] | None, bool]:
        """The closed form's in-limit solution nearest the seed (``None`` if none) and whether any
        branch reaches ``point``: the general path, for what the generated :func:`fast_solver`
        does not decide (a joint range of 2 pi or more, a target on the roll axis).
        """
        best: tuple[float, float, float] | None = None
        best_distance, reachable = math.inf, False
        roll_seen, roll_choice = None, None
        (roll_lower, roll_upper), knee_limits = self._limits[0], self._limits[1:]
        x, y, z = point
        for angles, exact in branches(geometry, x, y, z, SCALAR):
            if not exact:
                continue
            reachable = True
            if angles[0] != roll_seen:  # the two knee branches share the roll angle
                roll_seen = angles[0]
                roll, inside = representative_angle(
                    roll_seen, seed_angles[0], roll_lower, roll_upper, SCALAR
                )
                roll_choice = roll if inside else None
            if roll_choice is None:
                continue
            chosen = [roll_choice]
            for angle, reference, (lower, upper) in zip(angles[1:], seed_angles[1:], knee_limits):
                value, inside = representative_angle(angle, reference, lower, upper, SCALAR)
                if not inside:
                    break
                chosen.append(value)
            else:
                distance = sum((a - s) ** 2 for a, s in zip(chosen, seed_angles))
                if distance < best_distance:
                    best, best_distance = (chosen[0], chosen[1], chosen[2]), distance
        return best, reachable

    @np.errstate(over="ignore")  # far targets: squares overflow to inf, which reads "not reached"
    def solve_batch(
        self, points: np.ndarray, seeds: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For (N, 3) targets [m] and (N, 3) seeds [rad] (``None``: the middle): (N, 3) angles
        [rad], (N,) int8 status codes, (N,) residuals [m]; row by row the same as :meth:`solve`.
        """
        rows = points.shape[0]
        if seeds is None:
            seeds = np.broadcast_to(self.middle, (rows, 3))
        angles = np.empty((rows, 3))
        status = np.full(rows, UNREACHABLE, dtype=np.int8)
        if self.geometry is None:
            for row in range(rows):
                result = self._solve_by_search(points[row], tuple(seeds[row].tolist()))
                angles[row], status[row] = result.angles, result.status
            return angles, status, self._residuals(angles, points)
        seed_columns = tuple(np.ascontiguousarray(seeds.T))
        # Contiguous rows of x, y, z: faster elementwise math.
        columns = np.ascontiguousarray(points.T)
        if self._fast_batch is not None:
            # A target on the roll axis or far away: not found here.
            with np.errstate(all="ignore"):
                *chosen, found, trig = self._fast_batch(*columns, *seed_columns)
            status[found] = OK
            redo = ~found  # rows whose residual needs the FK of the angles' own cosines and sines
            for row in np.flatnonzero(redo).tolist():  # the rare rows: the scalar path decides
                result = self.solve(points[row].tolist(), seeds[row].tolist())
                for column, angle in zip(chosen, result.angles):
                    column[row] = angle
                status[row] = result.status
            angles[:] = np.stack(chosen, axis=1)
            for column, (lower, upper) in zip(chosen, self._limits):
                # An angle clamped onto a limit: its cosine is not the branch's.
                if lower != -math.inf:
                    redo |= (column == lower) | (column == upper)
            x, y, z = self.leg.position_from_trig(*trig)
            x, y, z = x - columns[0], y - columns[1], z - columns[2]
            # Found rows: feet in reach, no overflow (the others are redone).
            residuals = np.sqrt(x * x + y * y + z * z)
            rows_redone = np.flatnonzero(redo)
            if rows_redone.size:
                residuals[rows_redone] = self._column_residuals(
                    [c[rows_redone] for c in chosen], [c[rows_redone] for c in columns]
                )
            return angles, status, residuals
        best_distance = np.full(rows, math.inf)
        reachable = np.zeros(rows, dtype=bool)
        chosen = [np.zeros(rows)] * 3
        for branch, exact in branches(self.geometry, columns[0], columns[1], columns[2], ARRAY):
            representative, inside = self._representatives(branch, seed_columns, ARRAY)
            reachable |= exact
            distance = sum((a - s) ** 2 for a, s in zip(representative, seed_columns))
            better = exact & inside & (distance < best_distance)
            best_distance = np.where(better, distance, best_distance)
            chosen = [
                np.where(better, value, previous)
                for value, previous in zip(representative, chosen)
            ]
        angles[:] = np.stack(chosen, axis=1)
        status[np.isfinite(best_distance)] = OK
        for row in np.flatnonzero(~np.isfinite(best_distance)).tolist():
            result = self._nearest_in_limits(
                points[row], tuple(seeds[row].tolist()), bool(reachable[row])
            )
            angles[row], status[row] = result.angles, result.status
        return angles, status, self._residuals(angles, points)

    # --- choosing angles -----------------------------------------------------------------

    def _representatives(
        self,
        angles: Sequence[FloatsOrArrays],
        seed: Sequence[FloatsOrArrays],
        xp: SimpleNamespace = SCALAR,
    ) -> tuple[tuple[FloatsOrArrays, FloatsOrArrays, FloatsOrArrays], FloatsOrArrays]:
        """Each angle's value modulo 2 pi by :func:`representative_angle` (inside its limits where
        it can be), and whether all three are inside (within :data:`LIMIT_TOLERANCE_RAD`).
        """
        chosen, all_inside = [], True
        for angle, reference, (lower, upper) in zip(angles, seed, self._limits):
            value, inside = representative_angle(angle, reference, lower, upper, xp)
            chosen.append(value)
            all_inside = all_inside & inside
        return (chosen[0], chosen[1], chosen[2]), all_inside

    def _residuals(self, angles: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(N,) distances [m] from the feet at (N, 3) angles [rad] to (N, 3) targets [m]."""
        return self._column_residuals(
            tuple(np.ascontiguousarray(angles.T)), tuple(np.ascontiguousarray(points.T))
        )

    def _column_residuals(
        self, angles: Sequence[np.ndarray], points: Sequence[np.ndarray]
    ) -> np.ndarray:
        """:meth:`_residuals` for the angles and targets given as three (N,) columns each."""
        trig = [f(angle) for angle in angles for f in (np.cos, np.sin)]
        x, y, z = self.leg.position_from_trig(*trig)
        residuals: np.ndarray = np.hypot(np.hypot(x - points[0], y - points[1]), z - points[2])
        return residuals  # hypot: no overflow for far targets

    # --- searches: nearest in-limit point, and the damped-least-squares solver ---------------

    def _starts(self, point: np.ndarray, seed: Sequence[float]) -> np.ndarray:
        """Starts of the searches: the seed, the closed form's (clipped) branches, and a grid."""
        steps = [
            np.linspace(lo, hi, GRID_STEPS) for lo, hi in zip(self.search_lower, self.search_upper)
        ]
        grid = np.stack(np.meshgrid(*steps, indexing="ij"), axis=-1).reshape(-1, 3)
        starts = [np.asarray(seed, dtype=float)[np.newaxis], grid]
        if self.geometry is not None:
            x, y, z = point.tolist()
            starts.append(
                np.array([angles for angles, _ in branches(self.geometry, x, y, z, SCALAR)])
            )
        return np.concatenate(starts)

    def _nearest_in_limits(
        self, point: np.ndarray, seed: Sequence[float], reachable: bool
    ) -> LegIk:
        """The in-limit angles whose foot is nearest ``point``; status by ``reachable``."""
        angles, residual = least_squares(
            self.leg, point, self._starts(point, seed), self.search_lower, self.search_upper
        )
        return LegIk(
            tuple(angles.tolist()), OUTSIDE_LIMITS if reachable else UNREACHABLE, residual
        )

    def _solve_by_search(self, point: np.ndarray, seed: Sequence[float]) -> LegIk:
        """Damped least squares from the seed; if that does not reach the target inside the
        limits, from every start, and without limits to tell outside_limits from unreachable.
        """
        start = np.asarray(seed, dtype=float)[np.newaxis]
        angles, residual = least_squares(
            self.leg, point, start, self.search_lower, self.search_upper
        )
        if residual <= REACHED_M:
            return LegIk(tuple(angles.tolist()), OK, residual)
        starts = self._starts(point, seed)
        angles, residual = least_squares(
            self.leg, point, starts, self.search_lower, self.search_upper
        )
        if residual <= REACHED_M:
            return LegIk(tuple(angles.tolist()), OK, residual)
        unlimited = np.full(3, math.inf)
        _, free_residual = least_squares(self.leg, point, starts, -unlimited, unlimited)
        return LegIk(
            tuple(angles.tolist()),
            OUTSIDE_LIMITS if free_residual <= REACHED_M else UNREACHABLE,
            residual,
        )

    def _searched_solutions(self, point: np.ndarray, seed: Sequence[float]) -> list[Solution]:
        """Distinct exact solutions (limits ignored) that the least-squares runs converge to."""
        unlimited = np.full(3, math.inf)
        starts = self._starts(point, seed)
        found: list[Solution] = []
        for start in starts:
            angles, residual = least_squares(
                self.leg, point, start[np.newaxis], -unlimited, unlimited
            )
            if residual > REACHED_M:
                continue
            representative, inside = self._representatives(angles.tolist(), seed)
            if all(wrapped_distance(representative, s.angles) > 1e-6 for s in found):
                found.append(Solution(representative, bool(inside)))
        return found
