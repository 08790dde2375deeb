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

Up to four solutions. An ``acos`` argument beyond 1 (by more than :data:`ARGUMENT_TOLERANCE`)
means that branch does not reach the target.

**Other three-joint legs**: damped least squares on the compiled FK and Jacobian (Levenberg-damped
Newton steps on the squared distance, see :func:`_least_squares`), from the seed, then from a
fixed grid of starts, each run bounded to :data:`MAX_ITERATIONS` iterations.

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

import functools
import math
import operator
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from a1_leg_fk.urdf import Joint, LegFkError

if TYPE_CHECKING:  # kinematics imports this module: no import cycle at run time
    from a1_leg_fk.kinematics import CompiledLeg

OK, OUTSIDE_LIMITS, UNREACHABLE = 0, 1, 2
"""Status codes of :func:`solve_batch` (small integers, ``int8`` arrays)."""
STATUS_NAMES: tuple[str, ...] = ("ok", "outside_limits", "unreachable")
"""Status names by code."""

ARGUMENT_TOLERANCE = 1e-12
"""How far beyond +-1 an ``acos`` argument may be (rounding of a target on the boundary of the
workspace) and still count as reaching the target; it is then clamped to +-1."""
LIMIT_TOLERANCE_RAD = 1e-10
"""An angle this close outside a limit [rad] counts as inside, and is clamped to the limit."""
REACHED_M = 1e-9
"""The damped-least-squares solver counts a target as reached within this distance [m]."""
MAX_ITERATIONS = 60
"""Iterations of one damped-least-squares run (every start runs them at once, vectorised)."""
STALLED_ITERATIONS = 6
"""The search stops when its best distance has not improved for this many iterations."""
MAX_STEP_RAD = 0.3
"""The largest change of any joint angle in one least-squares step [rad] (a trust region)."""
GRID_STEPS = 3
"""Starts per joint of the grid the least-squares searches start from (GRID_STEPS^3 starts)."""
PERPENDICULAR_TOLERANCE = 1e-9
"""|cos| between axes below which they count as perpendicular, and |1 - |cos|| for parallel."""
BATCH_BLOCK_ROWS = 8192
"""Rows per block of :func:`solve_feet_batch`."""
TWO_PI = 2.0 * math.pi
Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Solution:
    """One exact solution of a leg: its three angles [rad] (root side first) and whether all three
    lie inside the URDF limits (each angle is the value modulo 2 pi nearest the seed, inside the
    limits where one is)."""

    angles: tuple[float, float, float]
    inside_limits: bool


class LegIk(NamedTuple):
    """One leg's answer: three angles [rad], the status code, and the distance [m] from the foot
    at those angles to the target. (A named tuple: made on every call, it must be cheap.)"""

    angles: tuple[float, float, float]
    status: int
    residual_m: float


# --- the math namespaces: one formula for floats and for numpy arrays ----------------------------


_SCALAR = SimpleNamespace(
    sqrt=math.sqrt, hypot=math.hypot, atan2=math.atan2, ceil=math.ceil, round=round, minimum=min, maximum=max,
    where=lambda condition, yes, no: yes if condition else no, not_=operator.not_,
)
_ARRAY = SimpleNamespace(
    sqrt=np.sqrt, hypot=np.hypot, atan2=np.arctan2, ceil=np.ceil, round=np.round, minimum=np.minimum, maximum=np.maximum,
    where=np.where, not_=np.logical_not,
)


class LegSolver:
    """IK of one compiled leg: :meth:`solve` (one target), :meth:`solve_batch` (N targets) and
    :meth:`solutions` (every exact solution)."""

    def __init__(self, leg: CompiledLeg, use_closed_form: bool = True) -> None:
        """``use_closed_form=False`` solves an A1-topology leg by damped least squares as well
        (for comparisons: the statuses and residuals agree)."""
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
        self.geometry = _closed_form_geometry(leg) if use_closed_form else None
        self.closed_form = self.geometry is not None
        generated = None if self.geometry is None else _fast_solver(self.geometry, self._limits, leg.chain.leg)
        self._fast, self._fast_batch, self._fast_body = (None, None, None) if generated is None else generated

    # --- public --------------------------------------------------------------------------

    def solutions(self, point: Sequence[float], seed: Sequence[float] | None = None) -> list[Solution]:
        """Every exact solution for ``point`` [m, base frame]: the closed form's up to four (two
        roll x two knee branches), else the distinct ones the least-squares runs converge to."""
        seed_angles = self._middle if seed is None else tuple(seed)
        if self.closed_form:
            candidates = _branches(self.geometry, *point, _SCALAR)
            found: list[Solution] = []
            for angles, exact in candidates:
                if exact:
                    representative, inside = self._representatives(angles, seed_angles)
                    if all(s.angles != representative for s in found):  # branches meet at singularities
                        found.append(Solution(representative, inside))
            return found
        return self._searched_solutions(np.asarray(point, dtype=float), seed_angles)

    def solve(self, point: Sequence[float], seed: Sequence[float] | None = None) -> LegIk:
        """The angles [rad] for ``point`` [m, base frame] nearest ``seed`` (3 angles; ``None``: the
        middle of the ranges), the status code and the residual [m]."""
        seed_angles = self._middle if seed is None else tuple(seed)
        if not self.closed_form:
            return self._solve_by_search(np.asarray(point, dtype=float), seed_angles)
        found = None if self._fast is None else self._fast(*point, *seed_angles)
        best, reachable = self._choose(point, seed_angles) if found is None else found
        if best is not None:
            x, y, z = self.leg.position(*best)
            residual = math.hypot(x - point[0], y - point[1], z - point[2])  # hypot: no overflow
            return LegIk(best, OK, residual)
        return self._nearest_in_limits(np.asarray(point, dtype=float), seed_angles, reachable)

    def _choose(self, point: Sequence[float], seed_angles: Sequence[float]) -> tuple[tuple[float, ...] | None, bool]:
        """The closed form's in-limit solution nearest the seed (``None`` if none) and whether any
        branch reaches ``point``: the general path, for what the generated :func:`_fast_solver`
        does not decide (a joint range of 2 pi or more, a target on the roll axis)."""
        best, best_distance, reachable = None, math.inf, False
        roll_seen, roll_choice = None, None
        (roll_lower, roll_upper), knee_limits = self._limits[0], self._limits[1:]
        for angles, exact in _branches(self.geometry, *point, _SCALAR):
            if not exact:
                continue
            reachable = True
            if angles[0] != roll_seen:  # the two knee branches share the roll angle
                roll_seen = angles[0]
                roll, inside = _representative(roll_seen, seed_angles[0], roll_lower, roll_upper, _SCALAR)
                roll_choice = roll if inside else None
            if roll_choice is None:
                continue
            chosen = [roll_choice]
            for angle, reference, (lower, upper) in zip(angles[1:], seed_angles[1:], knee_limits):
                value, inside = _representative(angle, reference, lower, upper, _SCALAR)
                if not inside:
                    break
                chosen.append(value)
            else:
                distance = sum((a - s) ** 2 for a, s in zip(chosen, seed_angles))
                if distance < best_distance:
                    best, best_distance = tuple(chosen), distance
        return best, reachable

    @np.errstate(over="ignore")  # far targets: squares overflow to inf, which reads "not reached"
    def solve_batch(self, points: np.ndarray, seeds: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For (N, 3) targets [m] and (N, 3) seeds [rad] (``None``: the middle): (N, 3) angles [rad],
        (N,) int8 status codes, (N,) residuals [m]; row by row the same as :meth:`solve`."""
        rows = points.shape[0]
        if seeds is None:
            seeds = np.broadcast_to(self.middle, (rows, 3))
        angles = np.empty((rows, 3))
        status = np.full(rows, UNREACHABLE, dtype=np.int8)
        if not self.closed_form:
            for row in range(rows):
                result = self._solve_by_search(points[row], tuple(seeds[row].tolist()))
                angles[row], status[row] = result.angles, result.status
            return angles, status, self._residuals(angles, points)
        seed_columns = tuple(np.ascontiguousarray(seeds.T))
        columns = np.ascontiguousarray(points.T)  # contiguous rows of x, y, z: faster elementwise math
        if self._fast_batch is not None:
            with np.errstate(all="ignore"):  # a target on the roll axis or far away: not found here
                *chosen, best_distance, trig = self._fast_batch(*columns, *seed_columns)
            found = np.isfinite(best_distance)
            status[found] = OK
            redo = ~found  # rows whose residual needs the FK of the angles' own cosines and sines
            for row in np.flatnonzero(redo):  # the rare rows: the scalar path decides
                result = self.solve(points[row].tolist(), seeds[row].tolist())
                for column, angle in zip(chosen, result.angles):
                    column[row] = angle
                status[row] = result.status
            angles[:] = np.stack(chosen, axis=1)
            for column, (lower, upper) in zip(chosen, self._limits):
                if lower != -math.inf:  # an angle clamped onto a limit: its cosine is not the branch's
                    redo |= (column == lower) | (column == upper)
            x, y, z = self.leg.position_from_trig(*trig)
            x, y, z = x - columns[0], y - columns[1], z - columns[2]
            residuals = np.sqrt(x * x + y * y + z * z)  # found rows: feet in reach, no overflow (others redone)
            rows_redone = np.flatnonzero(redo)
            if rows_redone.size:
                residuals[rows_redone] = self._column_residuals([c[rows_redone] for c in chosen], [c[rows_redone] for c in columns])
            return angles, status, residuals
        best_distance = np.full(rows, math.inf)
        reachable = np.zeros(rows, dtype=bool)
        chosen = [np.zeros(rows)] * 3
        for branch, exact in _branches(self.geometry, columns[0], columns[1], columns[2], _ARRAY):
            representative, inside = self._representatives(branch, seed_columns, _ARRAY)
            reachable |= exact
            distance = sum((a - s) ** 2 for a, s in zip(representative, seed_columns))
            better = exact & inside & (distance < best_distance)
            best_distance = np.where(better, distance, best_distance)
            chosen = [np.where(better, value, previous) for value, previous in zip(representative, chosen)]
        angles[:] = np.stack(chosen, axis=1)
        status[np.isfinite(best_distance)] = OK
        for row in np.flatnonzero(~np.isfinite(best_distance)):
            result = self._nearest_in_limits(points[row], tuple(seeds[row].tolist()), bool(reachable[row]))
            angles[row], status[row] = result.angles, result.status
        return angles, status, self._residuals(angles, points)

    # --- choosing angles -----------------------------------------------------------------

    def _representatives(self, angles, seed, xp=_SCALAR):  # noqa: ANN001, ANN202 (floats or arrays)
        """Each angle's value modulo 2 pi by :func:`_representative` (inside its limits where it
        can be), and whether all three are inside (within :data:`LIMIT_TOLERANCE_RAD`)."""
        chosen, all_inside = [], True
        for angle, reference, (lower, upper) in zip(angles, seed, self._limits):
            value, inside = _representative(angle, reference, lower, upper, xp)
            chosen.append(value)
            all_inside = all_inside & inside
        return tuple(chosen), all_inside

    def _residuals(self, angles: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(N,) distances [m] from the feet at (N, 3) angles [rad] to (N, 3) targets [m]."""
        return self._column_residuals(tuple(np.ascontiguousarray(angles.T)), tuple(np.ascontiguousarray(points.T)))

    def _column_residuals(self, angles: Sequence[np.ndarray], points: Sequence[np.ndarray]) -> np.ndarray:
        """:meth:`_residuals` for the angles and targets given as three (N,) columns each."""
        trig = [f(angle) for angle in angles for f in (np.cos, np.sin)]
        x, y, z = self.leg.position_from_trig(*trig)
        return np.hypot(np.hypot(x - points[0], y - points[1]), z - points[2])  # no overflow for far targets

    # --- searches: nearest in-limit point, and the damped-least-squares solver ---------------

    def _starts(self, point: np.ndarray, seed: Sequence[float]) -> np.ndarray:
        """Starts of the searches: the seed, the closed form's (clipped) branches, and a grid."""
        steps = [np.linspace(lo, hi, GRID_STEPS) for lo, hi in zip(self.search_lower, self.search_upper)]
        grid = np.stack(np.meshgrid(*steps, indexing="ij"), axis=-1).reshape(-1, 3)
        starts = [np.asarray(seed, dtype=float)[np.newaxis], grid]
        if self.closed_form:
            starts.append(np.array([angles for angles, _ in _branches(self.geometry, *point.tolist(), _SCALAR)]))
        return np.concatenate(starts)

    def _nearest_in_limits(self, point: np.ndarray, seed: Sequence[float], reachable: bool) -> LegIk:
        """The in-limit angles whose foot is nearest ``point``; status by ``reachable``."""
        angles, residual = _least_squares(self.leg, point, self._starts(point, seed), self.search_lower, self.search_upper)
        return LegIk(tuple(angles.tolist()), OUTSIDE_LIMITS if reachable else UNREACHABLE, residual)

    def _solve_by_search(self, point: np.ndarray, seed: Sequence[float]) -> LegIk:
        """Damped least squares from the seed; if that does not reach the target inside the
        limits, from every start, and without limits to tell outside_limits from unreachable."""
        start = np.asarray(seed, dtype=float)[np.newaxis]
        angles, residual = _least_squares(self.leg, point, start, self.search_lower, self.search_upper)
        if residual <= REACHED_M:
            return LegIk(tuple(angles.tolist()), OK, residual)
        starts = self._starts(point, seed)
        angles, residual = _least_squares(self.leg, point, starts, self.search_lower, self.search_upper)
        if residual <= REACHED_M:
            return LegIk(tuple(angles.tolist()), OK, residual)
        unlimited = np.full(3, math.inf)
        _, free_residual = _least_squares(self.leg, point, starts, -unlimited, unlimited)
        return LegIk(tuple(angles.tolist()), OUTSIDE_LIMITS if free_residual <= REACHED_M else UNREACHABLE, residual)

    def _searched_solutions(self, point: np.ndarray, seed: Sequence[float]) -> list[Solution]:
        """Distinct exact solutions (limits ignored) that the least-squares runs converge to."""
        unlimited = np.full(3, math.inf)
        starts = self._starts(point, seed)
        found: list[Solution] = []
        for start in starts:
            angles, residual = _least_squares(self.leg, point, start[np.newaxis], -unlimited, unlimited)
            if residual > REACHED_M:
                continue
            representative, inside = self._representatives(angles.tolist(), seed)
            if all(_wrapped_distance(representative, s.angles) > 1e-6 for s in found):
                found.append(Solution(representative, bool(inside)))
        return found


def range_middle(joint: Joint) -> float:
    """The middle of a joint's range [rad], 0 for a continuous joint: the seed when none is given."""
    return 0.0 if joint.lower is None or joint.upper is None else (joint.lower + joint.upper) / 2.0


def _wrapped_distance(a: Sequence[float], b: Sequence[float]) -> float:
    return max(abs((x - y + math.pi) % TWO_PI - math.pi) for x, y in zip(a, b))


def _representative(angle, reference, lower: float, upper: float, xp):  # noqa: ANN001, ANN202
    """``angle + 2 pi k`` inside ``[lower, upper]`` nearest ``reference`` where there is one (then
    clamped into the range, and ``True``); else ``False`` with, for a range narrower than 2 pi,
    the value just above the lower limit, and otherwise the value nearest ``reference``."""
    if upper - lower < TWO_PI:  # at most one value in range: no need for the reference
        low = lower - LIMIT_TOLERANCE_RAD
        value = low + (angle - low) % TWO_PI
        inside = value <= upper + LIMIT_TOLERANCE_RAD
        return xp.where(inside, xp.minimum(xp.maximum(value, lower), upper), value), inside
    if lower == -math.inf:  # continuous: the value within pi of the reference
        return reference + (angle - reference + math.pi) % TWO_PI - math.pi, True
    nearest = angle + TWO_PI * xp.round((reference - angle) / TWO_PI)
    low, high = lower - LIMIT_TOLERANCE_RAD, upper + LIMIT_TOLERANCE_RAD
    inside = (nearest >= low) & (nearest <= high)
    raised = nearest + TWO_PI * xp.ceil((low - nearest) / TWO_PI)  # the smallest value >= low
    lowered = nearest - TWO_PI * xp.ceil((nearest - high) / TWO_PI)  # the largest value <= high
    outside = xp.not_(inside)
    raised_inside = outside & (raised <= high)
    lowered_inside = outside & (lowered >= low)
    # Of two in-range values (a range wider than 2 pi), the nearer the reference.
    prefer_raised = raised_inside & (xp.not_(lowered_inside) | (abs(raised - reference) <= abs(lowered - reference)))
    value = xp.where(prefer_raised, raised, xp.where(lowered_inside, lowered, nearest))
    inside = inside | raised_inside | lowered_inside
    value = xp.where(inside, xp.minimum(xp.maximum(value, lower), upper), value)
    return value, inside


# --- the closed form ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Geometry:
    """The closed form's constants, from the compiled stages (see the module docstring)."""

    roll_rotation_t: tuple[Vector3, Vector3, Vector3]  # M0^T, by rows
    roll_origin: Vector3  # o0 [m]
    roll_axis: Vector3  # a0
    pitch_axis: Vector3  # b = M1 a1, in the roll joint's child frame
    pitch_cross: Vector3  # a0 x b
    pitch_origin: Vector3  # o1 [m]
    lateral_m: float  # h = b . x for every pitch and knee angle [m]
    plane: tuple[Vector3, Vector3]  # M1 e1, M1 e2: a basis of the plane normal to the pitch axis
    foot_u: tuple[float, float]  # the foot in that plane at knee angle q2: U + cos q2 V + sin q2 W [m]
    foot_v: tuple[float, float]
    foot_w: tuple[float, float]
    alpha: float  # squared distance from the pitch axis: alpha + kappa cos(q2 - peak) [m^2]
    kappa: float
    cos_peak: float
    sin_peak: float


def _closed_form_geometry(leg: CompiledLeg) -> _Geometry | None:
    """The constants of the closed form, or ``None`` when the leg is not of the A1 topology."""
    roll, pitch, knee = leg.stages
    pitch_axis = pitch.rotation @ pitch.axis
    knee_in_pitch = knee.rotation @ knee.axis
    if abs(float(roll.axis @ pitch_axis)) > PERPENDICULAR_TOLERANCE:
        return None
    if abs(abs(float(pitch.axis @ knee_in_pitch)) - 1.0) > PERPENDICULAR_TOLERANCE:
        return None
    c0, c1, c2 = knee.rodrigues_terms
    u = knee.offset + c0 @ leg.foot_offset  # the foot in the pitch joint's child frame: u + cos v + sin w
    v, w = c1 @ leg.foot_offset, c2 @ leg.foot_offset
    first = np.cross(pitch.axis, [1.0, 0.0, 0.0])
    if np.linalg.norm(first) < 0.5:
        first = np.cross(pitch.axis, [0.0, 1.0, 0.0])
    first /= np.linalg.norm(first)
    second = np.cross(pitch.axis, first)
    basis = np.stack([first, second])
    foot_u, foot_v, foot_w = basis @ u, basis @ v, basis @ w
    alpha = float(foot_u @ foot_u + foot_v @ foot_v)
    beta, gamma = 2.0 * float(foot_u @ foot_v), 2.0 * float(foot_u @ foot_w)
    kappa = math.hypot(beta, gamma)
    if kappa < 1e-12:  # the foot on the knee axis, or the knee on the pitch axis: the knee moves nothing
        return None
    return _Geometry(
        roll_rotation_t=tuple(_floats(row) for row in roll.rotation.T),
        roll_origin=_floats(roll.offset),
        roll_axis=_floats(roll.axis),
        pitch_axis=_floats(pitch_axis),
        pitch_cross=_floats(np.cross(roll.axis, pitch_axis)),
        pitch_origin=_floats(pitch.offset),
        lateral_m=float(pitch_axis @ pitch.offset + pitch.axis @ u),
        plane=tuple(_floats(row) for row in basis @ pitch.rotation.T),
        foot_u=tuple(foot_u.tolist()),
        foot_v=tuple(foot_v.tolist()),
        foot_w=tuple(foot_w.tolist()),
        alpha=alpha,
        kappa=kappa,
        cos_peak=beta / kappa,
        sin_peak=gamma / kappa,
    )


def _floats(vector: np.ndarray) -> Vector3:
    x, y, z = vector.tolist()
    return (x, y, z)


def _dot(row: Vector3, x, y, z):  # noqa: ANN001, ANN202
    return row[0] * x + row[1] * y + row[2] * z


def _branches(g: _Geometry, tx, ty, tz, xp):  # noqa: ANN001, ANN202 (floats, or arrays with xp=_ARRAY)
    """The four branches ``((q0, q1, q2), exact)`` for a target (tx, ty, tz) [m, base frame]:
    roll branch +-, knee branch +-. ``exact`` is False where a branch does not reach the target
    (its ``acos`` argument was clamped)."""
    dx, dy, dz = tx - g.roll_origin[0], ty - g.roll_origin[1], tz - g.roll_origin[2]
    rt = g.roll_rotation_t
    t0 = (_dot(rt[0], dx, dy, dz), _dot(rt[1], dx, dy, dz), _dot(rt[2], dx, dy, dz))
    along = _dot(g.roll_axis, *t0)
    a, b = _dot(g.pitch_axis, *t0), _dot(g.pitch_cross, *t0)
    radius = xp.hypot(a, b)
    on_axis = radius == 0.0
    safe_radius = xp.where(on_axis, 1.0, radius)
    cos_base, sin_base = xp.where(on_axis, 1.0, a / safe_radius), xp.where(on_axis, 0.0, b / safe_radius)
    roll_argument = xp.where(on_axis, xp.where(g.lateral_m == 0.0, 0.0, math.inf), g.lateral_m / safe_radius)
    roll_exact = abs(roll_argument) <= 1.0 + ARGUMENT_TOLERANCE
    cos_roll = xp.minimum(xp.maximum(roll_argument, -1.0), 1.0)
    sin_roll = xp.sqrt(1.0 - cos_roll * cos_roll)
    ax, ay, az = g.roll_axis
    ox, oy, oz = g.pitch_origin
    out = []
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll  # cos(base + sign * acos)
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        # x = Rot(a0, -q0) t0 = a0 (a0 . t0) + c0 (t0 - a0 (a0 . t0)) - s0 (a0 x t0), relative to o1
        px, py, pz = t0[0] - ax * along, t0[1] - ay * along, t0[2] - az * along
        cx, cy, cz = ay * t0[2] - az * t0[1], az * t0[0] - ax * t0[2], ax * t0[1] - ay * t0[0]
        ex = ax * along + c0 * px - s0 * cx - ox
        ey = ay * along + c0 * py - s0 * cy - oy
        ez = az * along + c0 * pz - s0 * cz - oz
        gx, gy = _dot(g.plane[0], ex, ey, ez), _dot(g.plane[1], ex, ey, ez)
        knee_argument = (gx * gx + gy * gy - g.alpha) / g.kappa
        exact = roll_exact & (abs(knee_argument) <= 1.0 + ARGUMENT_TOLERANCE)
        cos_knee = xp.minimum(xp.maximum(knee_argument, -1.0), 1.0)
        sin_knee = xp.sqrt(1.0 - cos_knee * cos_knee)
        q0 = xp.atan2(s0, c0)
        for knee_sign in (1.0, -1.0):
            c2 = g.cos_peak * cos_knee - knee_sign * g.sin_peak * sin_knee  # cos(peak + sign * acos)
            s2 = g.sin_peak * cos_knee + knee_sign * g.cos_peak * sin_knee
            fx = g.foot_u[0] + c2 * g.foot_v[0] + s2 * g.foot_w[0]
            fy = g.foot_u[1] + c2 * g.foot_v[1] + s2 * g.foot_w[1]
            q1 = xp.atan2(fx * gy - fy * gx, fx * gx + fy * gy)
            out.append(((q0, q1, xp.atan2(s2, c2)), exact))
    return out


# --- the closed form as generated straight-line code (the common case, fast) --------------------


def _knee_branch_can_be_inside(peak: float, sign: float, lower: float, upper: float) -> bool:
    """Whether the knee branch ``peak + sign * acos(...)`` (the acos in [0, pi]) has any value
    modulo 2 pi inside ``[lower, upper]`` [rad] (with a margin of 1e-6 rad: a branch kept in doubt
    only costs time); always for a continuous joint."""
    if lower == -math.inf:
        return True
    start, end = sorted((peak, peak + sign * math.pi))
    low, high = lower - 1e-6, upper + 1e-6
    turns = math.ceil((low - end) / TWO_PI)  # the first shift of the interval that ends at or above low
    return start + TWO_PI * turns <= high


def _fast_solver(g: _Geometry, limits: Sequence[tuple[float, float]], leg: str):  # noqa: ANN202
    """The closed form of :func:`_branches` and the choice of :meth:`LegSolver.solve` as one
    generated function on floats with the leg's constants folded in, as the FK is (see
    :func:`a1_leg_fk.fk_codegen.leg_source`), or ``None`` when a joint has finite limits 2 pi or more
    apart (then the general path decides). ``solve(tx, ty, tz, r0, r1, r2)`` takes a target
    [m, base frame] and the seed [rad]; it returns ``(angles, reachable)`` with ``angles`` the
    in-limit exact solution nearest the seed (``None`` if there is none), or ``None`` for the
    general path to decide (a target on the roll axis; no solution in the limits and a roll
    angle outside them, whose branch was not followed). Returned with it: ``solve_batch``, the
    same code on (N,) numpy columns (the branch chosen by ``np.where``), returning the three angle
    columns, the seed distance (``inf`` in rows without an in-limit solution, whose other columns
    are then meaningless) and the chosen branch's cosines and sines ``(c0, s0, c1, s1, c2, s2)``
    (of the angles before any clamping onto a limit); and the text of
    ``solve``'s body for :func:`_fused_solver` (``return None`` wherever ``solve`` would not return
    an in-limit solution, ``best`` the chosen angles or ``None``)."""
    from a1_leg_fk.fk_codegen import Code as _Code, Term, linear as _linear, weighted_sum as _sum

    if any(lower != -math.inf and not upper - lower < TWO_PI for lower, upper in limits):
        return None
    code = _Code("t")

    def bind(code: _Code, expressions: Sequence[Term]) -> tuple[Term, ...]:
        """Constants and names as they are, other expressions bound to fresh variables."""
        return tuple(e if isinstance(e, float) or e.lstrip("-").isidentifier() else code.assign([e])[0] for e in expressions)

    target = tuple(_sum([("", name), ("", -origin)]) for name, origin in zip(("tx", "ty", "tz"), g.roll_origin))
    relative = bind(code, target)
    t0 = bind(code, [_linear(row, relative) for row in g.roll_rotation_t])
    along, a, b = bind(code, [_linear(g.roll_axis, t0), _linear(g.pitch_axis, t0), _linear(g.pitch_cross, t0)])
    ax, ay, az = g.roll_axis
    across = bind(code, [_sum([("", t), (along, -axis)]) for t, axis in zip(t0, g.roll_axis)])  # t0 - a0 (a0 . t0)
    crossed = bind(code, [_linear(row, t0) for row in ((0.0, -az, ay), (az, 0.0, -ax), (-ay, ax, 0.0))])  # a0 x t0
    head = "\n    ".join(code.lines)
    knee = _Code("k")
    moved = bind(
        knee,
        [_sum([(along, axis), ("", -origin), ("c0", p), ("-s0", c)]) for axis, origin, p, c in zip(g.roll_axis, g.pitch_origin, across, crossed)],
    )
    gx, gy = bind(knee, [_linear(row, moved) for row in g.plane])
    cos_knee = _sum([("cos_knee", g.cos_peak), ("knee_sign * sin_knee", -g.sin_peak)])
    sin_knee = _sum([("cos_knee", g.sin_peak), ("knee_sign * sin_knee", g.cos_peak)])
    peak = math.atan2(g.sin_peak, g.cos_peak)  # q2 = peak +- acos(knee argument)
    roll_body = "\n        ".join(knee.lines)
    fx = _sum([("", g.foot_u[0]), ("c2", g.foot_v[0]), ("s2", g.foot_w[0])])
    fy = _sum([("", g.foot_u[1]), ("c2", g.foot_v[1]), ("s2", g.foot_w[1])])
    tolerance = 1.0 + ARGUMENT_TOLERANCE

    def representative(name: str, angle: str, slot: int, indent: str, outside: str = "continue") -> str:
        """:func:`_representative` for a range narrower than 2 pi (``outside`` when outside) or
        a continuous joint."""
        lower, upper = limits[slot]
        if lower == -math.inf:
            return f"{name} = r{slot} + ({angle} - r{slot} + {math.pi!r}) % {TWO_PI!r} - {math.pi!r}"
        low = lower - LIMIT_TOLERANCE_RAD
        return (
            f"{name} = {low!r} + ({angle} - {low!r}) % {TWO_PI!r}\n{indent}if {name} > {upper!r}:\n"
            f"{indent}    if {name} > {upper + LIMIT_TOLERANCE_RAD!r}:\n{indent}        {outside}\n"
            f"{indent}    {name} = {upper!r}\n{indent}elif {name} < {lower!r}:\n{indent}    {name} = {lower!r}"
        )

    knee_signs = tuple(sign for sign in (1.0, -1.0) if _knee_branch_can_be_inside(peak, sign, *limits[2])) or (1.0, -1.0)

    def knee_loop(branch: str) -> str:
        """The code of one knee branch (``branch``, its lines indented 12) for each knee sign that
        can give an angle inside the knee's limits: a loop, or the one branch without a loop."""
        if len(knee_signs) == 2:
            return f"for knee_sign in {knee_signs!r}:\n            {branch}"
        return f"knee_sign = {knee_signs[0]!r}\n        " + branch.replace("\n    ", "\n")

    scalar_branch = f"""c2, s2 = {cos_knee}, {sin_knee}
            {representative("q2", f"{peak!r} + knee_sign * knee_angle", 2, " " * 12)}
            fx, fy = {fx}, {fy}
            {representative("q1", f"_atan2(fx * {gy} - fy * {gx}, fx * {gx} + fy * {gy})", 1, " " * 12)}
            distance = d0 + (q1 - r1) ** 2 + (q2 - r2) ** 2
            if distance < best_distance:
                best, best_distance = (q0, q1, q2), distance"""
    body = f"""{head}
    radius = _hypot({a}, {b})
    if radius == 0.0:
        return None
    roll_argument = {g.lateral_m!r} / radius
    if abs(roll_argument) > {tolerance!r}:
        return UNREACHED
    cos_roll = 1.0 if roll_argument > 1.0 else -1.0 if roll_argument < -1.0 else roll_argument
    sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
    cos_base, sin_base = {a} / radius, {b} / radius
    best, best_distance, reachable, roll_outside = None, _inf, False, False
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        {representative("q0", "_atan2(s0, c0)", 0, " " * 8, "ROLL_OUTSIDE")}
        {roll_body}
        knee_argument = ({gx} * {gx} + {gy} * {gy} - {g.alpha!r}) / {g.kappa!r}
        if abs(knee_argument) > {tolerance!r}:
            continue
        reachable = True
        d0 = (q0 - r0) ** 2
        cos_knee = 1.0 if knee_argument > 1.0 else -1.0 if knee_argument < -1.0 else knee_argument
        sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
        knee_angle = _atan2(sin_knee, cos_knee)
        {knee_loop(scalar_branch)}
"""
    source = "def solve(tx, ty, tz, r0, r1, r2):\n    " + body.replace("UNREACHED", "None, False").replace(
        "ROLL_OUTSIDE", "roll_outside = True; continue"
    ) + """    if best is None and roll_outside:  # whether a roll branch outside the limits reaches the target
        return None
    return best, reachable
"""

    def representatives(name: str, angle: str, slot: int, indent: str = " " * 12) -> str:
        """:func:`_representative` on arrays for a range narrower than 2 pi: ``name`` clamped into
        the range and ``name_inside`` (by floor: numpy's ``%`` on floats is several times slower);
        for a continuous joint the value within pi of the seed."""
        lower, upper = limits[slot]
        if lower == -math.inf:
            return (
                f"{name} = {angle} - r{slot} + {math.pi!r}\n{indent}"
                f"{name} = {name} - {TWO_PI!r} * _floor({name} * {1.0 / TWO_PI!r}) - {math.pi!r} + r{slot}\n{indent}"
                f"{name}_inside = True"
            )
        low = lower - LIMIT_TOLERANCE_RAD
        return (
            f"{name} = {angle}\n{indent}{name} = {name} - {TWO_PI!r} * _floor(({name} - {low!r}) * {1.0 / TWO_PI!r})\n{indent}"
            f"{name}_inside = {name} <= {upper + LIMIT_TOLERANCE_RAD!r}\n{indent}"
            f"{name} = _minimum(_maximum({name}, {lower!r}), {upper!r})"
        )

    def select(value: str, previous: str) -> str:
        """The code choosing ``value`` where this knee branch is the better one: with one knee
        branch, ``value`` itself (where it is not usable the distance is inf, so the row is
        decided by the scalar path and its other columns are never read)."""
        return f"_where(better, {value}, {previous})" if len(knee_signs) == 2 else value

    batch_branch = f"""c2, s2 = {cos_knee}, {sin_knee}
            {representatives("q2", f"{peak!r} + knee_sign * knee_angle", 2)}
            fx, fy = {fx}, {fy}
            along, across = fx * gx + fy * gy, fx * gy - fy * gx
            {representatives("q1", "_atan2(across, along)", 1)}
            distance = d0 + (q1 - r1) ** 2 + (q2 - r2) ** 2
            better = usable & q1_inside & q2_inside & (distance < best_distance)
            best_distance = _where(better, distance, best_distance)
            best0, best1, best2 = {select("q0", "best0")}, {select("q1", "best1")}, {select("q2", "best2")}
            cos0, sin0, cos2, sin2 = {select("c0", "cos0")}, {select("s0", "sin0")}, {select("c2", "cos2")}, {select("s2", "sin2")}
            x1, y1 = {select("along", "x1")}, {select("across", "y1")}"""
    source += f"""
def knee_batch(c0, s0, q0, gx, gy, knee_argument, usable, r0, r1, r2):
    d0 = (q0 - r0) ** 2
    cos_knee = _minimum(_maximum(knee_argument, -1.0), 1.0)
    sin_knee = _sqrt(1.0 - cos_knee * cos_knee)
    knee_angle = _atan2(sin_knee, cos_knee)
    best_distance = _full(q0.shape, _inf)
    best0 = best1 = best2 = cos0 = sin0 = x1 = y1 = cos2 = sin2 = best_distance
    {knee_loop(batch_branch).replace(chr(10) + "    ", chr(10))}
    return [best0, best1, best2, best_distance, cos0, sin0, x1, y1, cos2, sin2]

def solve_batch(tx, ty, tz, r0, r1, r2):
    {head}
    radius = _hypot({a}, {b})
    roll_argument = {g.lateral_m!r} / radius
    roll_exact = abs(roll_argument) <= {tolerance!r}
    cos_roll = _minimum(_maximum(roll_argument, -1.0), 1.0)
    sin_roll = _sqrt(1.0 - cos_roll * cos_roll)
    cos_base, sin_base = {a} / radius, {b} / radius
    roll_branches = []
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        {representatives("q0", "_atan2(s0, c0)", 0, " " * 8)}
        {roll_body}
        gx, gy = {gx}, {gy}
        knee_argument = (gx * gx + gy * gy - {g.alpha!r}) / {g.kappa!r}
        roll_branches.append((c0, s0, q0, gx, gy, knee_argument, roll_exact & q0_inside & (abs(knee_argument) <= {tolerance!r})))
    first, second = roll_branches
    # The knee stage once, on the first usable roll branch; again on the rows where both are usable.
    best = knee_batch(*[_where(first[6], one, other) for one, other in zip(first, second)], r0, r1, r2)
    both = _flatnonzero(first[6] & second[6])
    if both.size:
        other = knee_batch(*[value[both] for value in second], r0[both], r1[both], r2[both])
        closer = other[3] < best[3][both]  # on a tie the first branch, as the scalar code
        for column, value in zip(best, other):
            column[both] = _where(closer, value, column[both])
    best0, best1, best2, best_distance, cos0, sin0, x1, y1, cos2, sin2 = best
    norm1 = _sqrt(x1 * x1 + y1 * y1)  # a distance in the knee's plane, < 1 m where a branch was found
    return best0, best1, best2, best_distance, (cos0, sin0, x1 / norm1, y1 / norm1, cos2, sin2)
"""
    namespace = {"_hypot": math.hypot, "_sqrt": math.sqrt, "_atan2": math.atan2, "_inf": math.inf}
    exec(compile(source, f"<a1_leg_fk generated IK of leg {leg}>", "exec"), namespace)
    arrays = {"_hypot": np.hypot, "_sqrt": np.sqrt, "_atan2": np.arctan2, "_inf": math.inf, "_minimum": np.minimum,
              "_maximum": np.maximum, "_where": np.where, "_full": np.full, "_floor": np.floor, "_flatnonzero": np.flatnonzero}
    exec(compile(source, f"<a1_leg_fk generated IK of leg {leg}, arrays>", "exec"), arrays)
    fused_body = body.replace("UNREACHED", "None").replace("ROLL_OUTSIDE", "continue")
    return namespace["solve"], arrays["solve_batch"], fused_body


# --- damped least squares -------------------------------------------------------------------------


def _positions(leg: CompiledLeg, angles: np.ndarray) -> np.ndarray:
    """(K, 3) feet [m] for (K, 3) angles [rad]."""
    cos, sin = np.cos(angles), np.sin(angles)
    out = np.empty((angles.shape[0], 3))
    out[:, 0], out[:, 1], out[:, 2] = leg.position_from_trig(cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2])
    return out


def _jacobians(leg: CompiledLeg, angles: np.ndarray) -> np.ndarray:
    """(K, 3, 3) d foot / d angles for (K, 3) angles [rad]."""
    cos, sin = np.cos(angles), np.sin(angles)
    columns = leg.jacobian_from_trig(cos[:, 0], sin[:, 0], cos[:, 1], sin[:, 1], cos[:, 2], sin[:, 2])
    out = np.empty((angles.shape[0], 3, 3))
    for joint in range(3):
        for axis in range(3):
            out[:, axis, joint] = columns[3 * joint + axis]
    return out


@np.errstate(over="ignore", invalid="ignore")  # a target 1e200 m away: squared distances overflow to inf
def _least_squares(
    leg: CompiledLeg, point: np.ndarray, starts: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[np.ndarray, float]:
    """Minimise |FK(q) - point| over ``lower <= q <= upper`` from every start at once.

    Damped Newton steps on ``0.5 |FK(q) - point|^2``: the Hessian is ``J^T J`` plus the residual
    times the FK's second derivatives (central differences of the Jacobian), so a target out of
    reach (a large residual) converges as fast as one in reach. A joint at a bound that the
    gradient pushes outward is held; the damping grows until a step lowers the cost. At most
    :data:`MAX_ITERATIONS` iterations. Returns the best angles [rad] and their distance [m].
    """
    q = np.clip(starts, lower, upper)
    error = _positions(leg, q) - point
    cost = np.einsum("ki,ki->k", error, error)
    damping = np.full(q.shape[0], 1e-4)
    identity = np.eye(3)
    previous_best, stalled = cost.min(), 0
    for _ in range(MAX_ITERATIONS):
        jacobian, curvature = _jacobian_and_curvature(leg, q, error)
        gradient = np.einsum("kij,ki->kj", jacobian, error)
        held = ((q <= lower) & (gradient > 0.0)) | ((q >= upper) & (gradient < 0.0))
        free = ~held
        hessian = np.einsum("kij,kil->kjl", jacobian, jacobian) + curvature
        mask = free[:, :, np.newaxis] & free[:, np.newaxis, :]
        hessian = np.where(mask, hessian, 0.0) + held[:, :, np.newaxis] * identity
        system = hessian + damping[:, np.newaxis, np.newaxis] * identity
        try:
            step = -np.linalg.solve(system, (gradient * free)[:, :, np.newaxis])[:, :, 0]
        except np.linalg.LinAlgError:  # a singular system (vanishingly rare): more damping, try again
            damping = damping * 8.0
            continue
        step *= np.minimum(1.0, MAX_STEP_RAD / np.maximum(np.abs(step).max(axis=1), 1e-300))[:, np.newaxis]
        trial = np.clip(q + step, lower, upper)
        trial_error = _positions(leg, trial) - point
        trial_cost = np.einsum("ki,ki->k", trial_error, trial_error)
        better = trial_cost < cost
        moved = np.abs(trial - q).max(axis=1)
        q = np.where(better[:, np.newaxis], trial, q)
        error = np.where(better[:, np.newaxis], trial_error, error)
        cost = np.where(better, trial_cost, cost)
        damping = np.where(better, np.maximum(damping / 4.0, 1e-12), np.minimum(damping * 8.0, 1e12))
        if np.all((moved < 1e-12) | (damping >= 1e6)) or cost.min() <= (REACHED_M * 1e-3) ** 2:
            break
        best_cost = cost.min()
        stalled = stalled + 1 if best_cost >= previous_best * (1.0 - 1e-12) else 0
        if stalled >= STALLED_ITERATIONS:
            break
        previous_best = best_cost
    best = int(np.argmin(cost))
    return q[best], math.hypot(*error[best].tolist())  # not sqrt(cost): no overflow for far targets


def _jacobian_and_curvature(leg: CompiledLeg, q: np.ndarray, error: np.ndarray, step: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3, 3) Jacobians at (K, 3) angles [rad], and (K, 3, 3) sum over axes i of
    ``error_i d^2 FK_i / dq_j dq_l`` by central differences of the Jacobian (one batched call)."""
    rows = q.shape[0]
    shifts = np.concatenate([np.zeros((1, 3)), step * np.eye(3), -step * np.eye(3)])
    jacobians = _jacobians(leg, (q[np.newaxis] + shifts[:, np.newaxis]).reshape(-1, 3)).reshape(7, rows, 3, 3)
    derivatives = (jacobians[1:4] - jacobians[4:7]) / (2.0 * step)  # (joint, K, axis, column)
    curvature = np.einsum("ki,jkil->klj", error, derivatives)
    return jacobians[0], (curvature + curvature.transpose(0, 2, 1)) / 2.0


def checked_point(point: Sequence[float], leg: str) -> tuple[float, float, float]:
    """Three finite floats [m], or a :class:`LegFkError` naming the leg."""
    try:
        values = tuple(float(v) for v in point)
    except (TypeError, ValueError) as error:
        raise LegFkError(f"leg {leg}: the target must be 3 numbers (x, y, z in m): {error}") from error
    if len(values) != 3:
        raise LegFkError(f"leg {leg}: the target must be 3 numbers (x, y, z in m), got {len(values)}")
    if not all(math.isfinite(v) for v in values):
        raise LegFkError(f"leg {leg}: the target {values} is not finite")
    return values  # type: ignore[return-value]


# --- four legs ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class IkResult:
    """:meth:`Quadruped.ik`'s answer: 12 angles [rad] in slot order, one status name per leg
    (FR, FL, RR, RL), and per leg the distance [m] from the foot at those angles to its target."""

    angles: np.ndarray  # (12,)
    status: tuple[str, str, str, str]
    residual_m: np.ndarray  # (4,)


@dataclass(frozen=True)
class IkBatchResult:
    """:meth:`Quadruped.ik_batch`'s answer: (N, 12) angles [rad], (N, 4) int8 status codes
    (:data:`OK`, :data:`OUTSIDE_LIMITS`, :data:`UNREACHABLE`), (N, 4) residuals [m]."""

    angles: np.ndarray
    status: np.ndarray
    residual_m: np.ndarray


@functools.lru_cache(maxsize=16)
def _fused_solver(solvers: tuple[LegSolver, ...]):  # noqa: ANN202
    """The generated bodies of every leg's :func:`_fast_solver` in one function, and the default
    seed (the middles, 12 angles [rad]); ``None`` when a leg has no generated solver.

    ``solve(x0, y0, z0, ..., z3, r0, ..., r11)`` takes the targets [m, base frame] and the seed
    [rad] in slot order; it returns the 12 angles [rad] and the 4 residuals [m] (the distance from
    :meth:`CompiledLeg.position` at those angles to the target) as one flat tuple, or ``None``
    when some leg has no in-limit solution there or needs the general path (:meth:`LegSolver.solve`
    then decides every leg, as it would have)."""
    if any(solver._fast_body is None for solver in solvers):
        return None
    targets = ", ".join(f"_{axis}{slot}" for slot in range(len(solvers)) for axis in "xyz")
    seeds = ", ".join(f"_r{joint}" for joint in range(3 * len(solvers)))
    lines = [f"def solve({targets}, {seeds}):"]
    namespace = {"_hypot": math.hypot, "_sqrt": math.sqrt, "_atan2": math.atan2, "_inf": math.inf, "_cos": math.cos, "_sin": math.sin}
    for slot, solver in enumerate(solvers):
        lines += [
            f"    tx, ty, tz, r0, r1, r2 = _x{slot}, _y{slot}, _z{slot}, _r{3 * slot}, _r{3 * slot + 1}, _r{3 * slot + 2}",
            "    " + solver._fast_body,
            "    if best is None:\n        return None",
            f"    q0, q1, q2 = _q{3 * slot}, _q{3 * slot + 1}, _q{3 * slot + 2} = best",
            _position_body(solver.leg.source, "fx, fy, fz"),
            f"    _e{slot} = _hypot(fx - tx, fy - ty, fz - tz)  # hypot: no overflow",
        ]
    outputs = [f"_q{joint}" for joint in range(3 * len(solvers))] + [f"_e{slot}" for slot in range(len(solvers))]
    lines.append(f"    return ({', '.join(outputs)})\n")
    exec(compile("\n".join(lines), "<a1_leg_fk generated IK of the legs>", "exec"), namespace)
    return namespace["solve"], sum((solver._middle for solver in solvers), ())


def _position_body(source: str, names: str) -> str:
    """The body of the generated ``position(q0, q1, q2)`` in a leg's FK ``source`` (see
    :class:`CompiledLeg`), assigning the foot [m, base frame] to ``names`` instead of returning it."""
    header = "def position(q0, q1, q2):\n"
    body, _ = source[source.index(header) + len(header) :].split("\n\n", 1)  # the functions are blank-line separated
    return body.replace("\n    return ", f"\n    {names} = ")


def solve_feet(solvers: Sequence[LegSolver], feet: np.ndarray, seed: Sequence[float] | None) -> IkResult:
    """IK of four legs for (4, 3) checked targets [m] and 12 checked seed angles (or ``None``)."""
    fused = _fused_solver(tuple(solvers))
    if fused is not None:  # the common case: every leg has an in-limit solution
        solve, middle = fused
        found = solve(*feet.ravel().tolist(), *(middle if seed is None else seed))
        if found is not None:
            values = np.array(found)
            return IkResult(values[: 3 * len(solvers)], ("ok",) * len(solvers), values[3 * len(solvers) :])  # type: ignore[arg-type]
    angles: list[float] = []
    status, residuals = [], []
    targets = feet.tolist()  # floats: Python arithmetic on numpy scalars is several times slower
    for slot, solver in enumerate(solvers):
        leg_seed = None if seed is None else seed[3 * slot : 3 * slot + 3]
        result = solver.solve(targets[slot], leg_seed)
        angles.extend(result.angles)
        status.append(STATUS_NAMES[result.status])
        residuals.append(result.residual_m)
    return IkResult(np.array(angles), tuple(status), np.array(residuals))  # type: ignore[arg-type]


def solve_feet_batch(solvers: Sequence[LegSolver], feet: np.ndarray, seeds: np.ndarray | None) -> IkBatchResult:
    """IK of four legs for (N, 4, 3) checked targets [m] and (N, 12) checked seeds (or ``None``)."""
    rows = feet.shape[0]
    angles = np.empty((rows, 3 * len(solvers)))
    status = np.empty((rows, len(solvers)), dtype=np.int8)
    residuals = np.empty((rows, len(solvers)))
    for block in range(0, rows, BATCH_BLOCK_ROWS):  # blocks whose temporaries stay in the CPU cache
        rows_in_block = slice(block, min(block + BATCH_BLOCK_ROWS, rows))
        for slot, solver in enumerate(solvers):
            columns = slice(3 * slot, 3 * slot + 3)
            leg_seeds = None if seeds is None else seeds[rows_in_block, columns]
            angles[rows_in_block, columns], status[rows_in_block, slot], residuals[rows_in_block, slot] = solver.solve_batch(
                feet[rows_in_block, slot], leg_seeds
            )
    return IkBatchResult(angles, status, residuals)
