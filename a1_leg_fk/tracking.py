"""JointState handling without ROS types: merge partial messages, reject bad ones, compute feet.

:class:`FootTracker` is what the node calls for every ``sensor_msgs/JointState``. It takes the
message's ``name``, ``position``, ``velocity`` and ``effort`` sequences and returns the feet to
publish:
one per leg that the message touched and whose three joints are all known. The name -> slot
mapping is cached and rebuilt only when the message's name list changes, so a steady stream
costs one list comparison plus the generated FK arithmetic.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from a1_leg_fk.kinematics.quadruped import Quadruped
from a1_leg_fk.model.legs import JOINT_COUNT, JOINTS_PER_LEG, LEG_NAMES

# Message outcomes; every message received ends in exactly one of them.
ACCEPTED = "accepted"
NO_LEG_JOINTS = "no_leg_joints"  # only names the model does not know (e.g. an arm's joints)
POSITION_LENGTH_MISMATCH = "position_length_mismatch"
VELOCITY_LENGTH_MISMATCH = "velocity_length_mismatch"
DUPLICATE_NAMES = "duplicate_names"
ALL_POSITIONS_NON_FINITE = "all_positions_non_finite"
REJECTIONS = (
    POSITION_LENGTH_MISMATCH,
    VELOCITY_LENGTH_MISMATCH,
    DUPLICATE_NAMES,
    ALL_POSITIONS_NON_FINITE,
)
LEG_COUNT = len(LEG_NAMES)
MAX_REMEMBERED_UNKNOWN_NAMES = 1000  # a flood of new names must not grow memory


class Foot(NamedTuple):
    """One leg's foot from one message: position [m] and, if the message had the leg's three
    joint velocities, velocity [m/s]; base frame, relative to the base.
    """

    leg_slot: int
    position: tuple[float, float, float]
    velocity: tuple[float, float, float] | None


def leg_feet(feet: Sequence[Foot]) -> list[tuple[Sequence[float], Sequence[float]] | None]:
    """Per leg slot, its foot's position [m] and velocity [m/s] (NaN when the message had no
    rates for it), or None when the message gave no foot for that leg.
    """
    out: list[tuple[Sequence[float], Sequence[float]] | None] = [None] * LEG_COUNT
    for foot in feet:
        out[foot.leg_slot] = (foot.position, foot.velocity or (math.nan,) * 3)
    return out


@dataclass(frozen=True)
class BlockResult:
    """What K messages did (see :meth:`FootTracker.update_block`): ``accepted`` (K,) bool;
    ``angles`` (K, 12) [rad], the merged state after each message (NaN for joints not yet known);
    ``rates`` (K, 12) [rad/s], the message's joint velocities where the node publishes that leg's
    velocity for it, NaN elsewhere; ``efforts`` (K, 12) [N m], the merged efforts after each
    message (see :attr:`FootTracker.efforts`).
    """

    accepted: np.ndarray
    angles: np.ndarray
    rates: np.ndarray
    efforts: np.ndarray


@dataclass
class TrackerCounts:
    """What the tracker has seen since it was created."""

    messages: int = 0
    outcomes: Counter[str] = field(default_factory=Counter)  # outcome -> messages
    non_finite_joints: int = 0  # joint values rejected for NaN/inf (their legs were not published)
    feet: int = 0  # feet returned for publishing
    out_of_limit_messages: int = 0  # messages that left some joint outside its URDF limits
    unknown_names: set[str] = field(default_factory=set)


@dataclass(frozen=True)
class _NameLayout:
    """What a message's name list means: (message index, slot) pairs, the legs it touches and,
    per leg slot, the message indices of the leg's three joints (None unless it has all three).
    """

    names: list[str]
    pairs: tuple[tuple[int, int], ...]
    legs: tuple[int, ...]
    unknown: tuple[str, ...]
    duplicates: tuple[str, ...]
    leg_indices: tuple[tuple[int, ...] | None, ...] = (None,) * LEG_COUNT


class FootTracker:
    """Merges JointState messages into the latest 12-angle state and computes the touched feet."""

    def __init__(self, quadruped: Quadruped) -> None:
        self.quadruped = quadruped
        self.angles: list[float] = [math.nan] * JOINT_COUNT  # rad; NaN until first known
        self.rates: list[float] = [math.nan] * JOINT_COUNT
        """[rad/s]: the latest :meth:`update`'s joint velocities of the legs it returned a foot
        velocity for, NaN elsewhere (as :attr:`BlockResult.rates`)."""
        self.efforts: list[float] = [math.nan] * JOINT_COUNT
        """Joint efforts [N m, or N for a prismatic joint] in slot order, merged like the angles
        from accepted messages whose effort list is as long as their names (other lengths are
        ignored); NaN until known. Carried, not used by the feet."""
        self.counts = TrackerCounts()
        self._legs = quadruped.legs
        self._lower = [j.lower if j.lower is not None else -math.inf for j in quadruped.joints]
        self._upper = [j.upper if j.upper is not None else math.inf for j in quadruped.joints]
        self._lower_array, self._upper_array = np.array(self._lower), np.array(self._upper)  # rad
        self._layout = _NameLayout([], (), (), (), ())
        self._last_outcome = NO_LEG_JOINTS
        self.last_problem = ""  # what was wrong with the latest message, naming joints and values
        self.new_unknown_names: list[str] = []  # first seen since take_new_unknown_names()

    @property
    def complete(self) -> bool:
        """True once every one of the 12 joints has had a finite angle."""
        return not any(math.isnan(angle) for angle in self.angles)

    def joints_outside_limits(self) -> list[str]:
        """URDF names of the joints whose latest angle lies outside their limits."""
        return [
            self.quadruped.joint_names[slot]
            for slot, angle in enumerate(self.angles)
            if not math.isnan(angle) and not self._lower[slot] <= angle <= self._upper[slot]
        ]

    def update(
        self,
        names: Sequence[str],
        positions: Sequence[float],
        velocities: Sequence[float],
        efforts: Sequence[float] = (),
    ) -> list[Foot]:
        """Merge one message; return the feet to publish (possibly none). Never raises on bad data.

        ``names``, ``positions`` [rad], ``velocities`` [rad/s] and ``efforts`` [N m] are the
        JointState fields; ``velocities`` and ``efforts`` may be empty. Check
        :attr:`last_outcome` for what happened.
        """
        counts = self.counts
        counts.messages += 1
        self.last_problem = ""
        self.rates = [math.nan] * JOINT_COUNT
        layout = self._layout
        if names != layout.names:
            layout = self._layout = self._describe(list(names))
        outcome = self._check(layout, len(names), len(positions), len(velocities))
        if outcome is not None:
            return self._finish(outcome, [])
        angles, lower, upper = self.angles, self._lower, self._upper
        bad_legs: set[int] = set()
        merged = out_of_limit = False
        isfinite = math.isfinite
        for index, slot in layout.pairs:
            angle = positions[index]
            if isfinite(angle):
                angles[slot] = angle
                merged = True
                if not lower[slot] <= angle <= upper[slot]:
                    out_of_limit = True
            else:
                bad_legs.add(slot // JOINTS_PER_LEG)
                counts.non_finite_joints += 1
                self.last_problem = f"position {angle} of joint '{names[index]}' is not finite"
        if not merged:
            return self._finish(ALL_POSITIONS_NON_FINITE, [])
        if efforts and len(efforts) == len(names):
            merged_efforts = self.efforts
            for index, slot in layout.pairs:
                merged_efforts[slot] = efforts[index]
        counts.out_of_limit_messages += out_of_limit
        return self._finish(ACCEPTED, self._feet(layout, bad_legs, velocities))

    def update_block(
        self,
        names: Sequence[str],
        positions: np.ndarray,
        velocities: np.ndarray,
        efforts: np.ndarray | None = None,
    ) -> BlockResult:
        """:meth:`update` for K consecutive messages that share one name list, as arrays.

        ``positions`` [rad] is (K, len(names)); ``velocities`` [rad/s] and ``efforts`` [N m] are
        (K, len(names)) or (K, 0). Outcomes, counts and the merged state end up exactly as after K
        calls of
        :meth:`update`; messages whose leg joints are all finite are merged with numpy, the others
        go through :meth:`update` one by one.
        """
        rows = positions.shape[0]
        if efforts is None or efforts.shape[1] != len(names):
            efforts = np.empty((rows, 0))
        layout = self._layout
        if names != layout.names:
            layout = self._layout = self._describe(list(names))
        result = BlockResult(
            np.zeros(rows, bool),
            np.empty((rows, JOINT_COUNT)),
            np.full((rows, JOINT_COUNT), math.nan),
            np.empty((rows, JOINT_COUNT)),
        )
        outcome = self._check(layout, len(names), positions.shape[1], velocities.shape[1])
        if outcome is not None:
            self.counts.messages += rows
            self._finish_many(outcome, rows, 0)
            result.angles[:] = self.angles
            result.efforts[:] = self.efforts
            return result
        index = np.array([i for i, _ in layout.pairs])
        slots = np.array([slot for _, slot in layout.pairs])
        values = positions[:, index]
        finite = np.isfinite(values).all(axis=1)
        row = 0
        while row < rows:
            if finite[row]:
                end = row + int(np.argmin(finite[row:])) if not finite[row:].all() else rows
                self._merge_finite(layout, values[row:end], slots, result, slice(row, end))
                block_efforts = efforts[row:end, index] if efforts.shape[1] else efforts[row:end]
                self._merge_efforts(block_efforts, slots, result.efforts[row:end])
                if velocities.shape[1]:
                    result.rates[row:end, slots] = velocities[row:end, index]
                row = end
            else:
                message_rates = velocities[row].tolist()
                feet = self.update(
                    names, positions[row].tolist(), message_rates, efforts[row].tolist()
                )
                result.accepted[row] = self._last_outcome == ACCEPTED
                result.angles[row] = self.angles
                result.efforts[row] = self.efforts
                for foot in feet:
                    if foot.velocity is not None:  # then the leg's three rates are finite
                        first = foot.leg_slot * JOINTS_PER_LEG
                        result.rates[row, first : first + JOINTS_PER_LEG] = self._leg_rates(
                            layout.leg_indices[foot.leg_slot], message_rates
                        )
                row += 1
        return result

    def _merge_finite(
        self,
        layout: _NameLayout,
        values: np.ndarray,
        slots: np.ndarray,
        result: BlockResult,
        rows: slice,
    ) -> None:
        """Merge messages whose leg joints are all finite (``values`` (n, pairs) [rad])."""
        count = values.shape[0]
        angles = result.angles[rows]
        angles[:] = self.angles
        angles[:, slots] = values
        result.accepted[rows] = True
        self.angles = angles[-1].tolist()
        lower, upper = self._lower_array[slots], self._upper_array[slots]
        self.counts.messages += count
        self.counts.out_of_limit_messages += int(
            ((values < lower) | (values > upper)).any(axis=1).sum()
        )
        per_leg = angles.reshape(count, len(self._legs), JOINTS_PER_LEG)
        feet = sum(
            int((~np.isnan(per_leg[:, leg_slot]).any(axis=1)).sum()) for leg_slot in layout.legs
        )
        self.last_problem = ""
        self._finish_many(ACCEPTED, count, feet)

    def _merge_efforts(self, values: np.ndarray, slots: np.ndarray, merged: np.ndarray) -> None:
        """Merge accepted messages' efforts (``values`` (n, pairs) [N m], or (n, 0): none) into
        ``merged`` (n, 12), the state after each of them.
        """
        merged[:] = self.efforts
        if values.shape[1]:
            merged[:, slots] = values
            self.efforts = merged[-1].tolist()

    def _finish_many(self, outcome: str, messages: int, feet: int) -> None:
        self._last_outcome = outcome
        self.counts.outcomes[outcome] += messages
        self.counts.feet += feet

    @property
    def last_outcome(self) -> str:
        """The outcome of the latest message (one of ACCEPTED, NO_LEG_JOINTS or REJECTIONS)."""
        return self._last_outcome

    def _finish(self, outcome: str, feet: list[Foot]) -> list[Foot]:
        self._last_outcome = outcome
        self.counts.outcomes[outcome] += 1
        self.counts.feet += len(feet)
        return feet

    def _check(
        self, layout: _NameLayout, names: int, positions: int, velocities: int
    ) -> str | None:
        """The message's rejection (setting :attr:`last_problem`), NO_LEG_JOINTS, or None if
        usable.
        """
        if positions != names:
            self.last_problem = f"{names} names but {positions} positions"
            return POSITION_LENGTH_MISMATCH
        if velocities and velocities != names:
            self.last_problem = f"{names} names but {velocities} velocities"
            return VELOCITY_LENGTH_MISMATCH
        if layout.duplicates:
            self.last_problem = f"joints given more than once: {list(layout.duplicates[:10])}"
            return DUPLICATE_NAMES
        if not layout.pairs:
            return NO_LEG_JOINTS
        return None

    def _feet(
        self, layout: _NameLayout, bad_legs: set[int], velocities: Sequence[float]
    ) -> list[Foot]:
        """The feet of the legs the message touched whose three angles are known and finite,
        each with its velocity where the message has the leg's three rates and they are finite
        (and the result too: huge rates can overflow). Inlined: the node's per-message path.
        """
        angles, legs, leg_indices = self.angles, self._legs, layout.leg_indices
        isfinite = math.isfinite
        feet = []
        for leg_slot in layout.legs:
            first = leg_slot * JOINTS_PER_LEG
            q0, q1, q2 = angles[first : first + JOINTS_PER_LEG]
            if leg_slot in bad_legs or q0 != q0 or q1 != q1 or q2 != q2:  # noqa: PLR0124 (NaN)
                continue
            indices = leg_indices[leg_slot] if velocities else None
            if indices is not None:
                r0, r1, r2 = velocities[indices[0]], velocities[indices[1]], velocities[indices[2]]
                if isfinite(r0) and isfinite(r1) and isfinite(r2):
                    x, y, z, vx, vy, vz = legs[leg_slot].position_velocity(q0, q1, q2, r0, r1, r2)
                    finite = isfinite(vx) and isfinite(vy) and isfinite(vz)
                    if finite:
                        self.rates[first : first + JOINTS_PER_LEG] = (r0, r1, r2)
                    feet.append(Foot(leg_slot, (x, y, z), (vx, vy, vz) if finite else None))
                    continue
            feet.append(Foot(leg_slot, legs[leg_slot].position(q0, q1, q2), None))
        return feet

    @staticmethod
    def _leg_rates(
        indices: tuple[int, ...] | None, velocities: Sequence[float]
    ) -> tuple[float, ...] | None:
        """The leg's three joint velocities [rad/s] at message ``indices``, or None unless the
        message has all three and they are finite.
        """
        if indices is None or not velocities:
            return None
        rates = (velocities[indices[0]], velocities[indices[1]], velocities[indices[2]])
        isfinite = math.isfinite
        return rates if isfinite(rates[0]) and isfinite(rates[1]) and isfinite(rates[2]) else None

    def _describe(self, names: list[str]) -> _NameLayout:
        slots = self.quadruped.name_to_slot
        pairs, unknown, seen, duplicates = [], [], set(), []
        for index, name in enumerate(names):
            slot = slots.get(name)
            if slot is None:
                unknown.append(name)
                continue
            if slot in seen:
                duplicates.append(name)
            seen.add(slot)
            pairs.append((index, slot))
        self._remember_unknown(unknown)
        legs = tuple(sorted({slot // JOINTS_PER_LEG for _, slot in pairs}))
        index_of = {slot: index for index, slot in pairs}
        leg_indices = tuple(
            tuple(index_of[slot] for slot in range(first, first + JOINTS_PER_LEG))
            if all(slot in index_of for slot in range(first, first + JOINTS_PER_LEG))
            else None
            for first in range(0, JOINT_COUNT, JOINTS_PER_LEG)
        )
        return _NameLayout(
            names, tuple(pairs), legs, tuple(unknown), tuple(duplicates), leg_indices
        )

    def _remember_unknown(self, names: list[str]) -> None:
        known_unknown = self.counts.unknown_names
        for name in names:
            if name not in known_unknown and len(known_unknown) < MAX_REMEMBERED_UNKNOWN_NAMES:
                known_unknown.add(name)
                self.new_unknown_names.append(name)

    def take_new_unknown_names(self) -> list[str]:
        """Names seen for the first time since the last call (for warn-once logging)."""
        names, self.new_unknown_names = self.new_unknown_names, []
        return names
