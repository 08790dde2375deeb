"""A live run into Rerun (``a1-leg-fk echo --rerun``): the messages the nodes publish, gathered
by their stamp (:class:`LiveRows`), are sent a few rows at a time through the recorded view's
:class:`~a1_leg_fk.view.scene.Scene` (:class:`LiveView`), so a live robot and a recording show
the same entities. No ROS here: the subscriptions (``a1_leg_fk.cli.echo_rerun``) call
:class:`LiveRows`' methods with plain values.

Differences from a recording, where the topics say less: the gait diagram is P(stance) at or
above :data:`~a1_leg_fk.estimation.stance.CONTACT_PROBABILITY` (the rule by which the odometry
takes a foot as standing when it has contacts), not the odometry's own stance, and the filter's
NIS and gate counts are not streamed (they are not published per message).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import fields, replace
from typing import TypeVar

import numpy as np

from a1_leg_fk.estimation.stance import CONTACT_PROBABILITY
from a1_leg_fk.model.legs import LEG_NAMES
from a1_leg_fk.view import columns
from a1_leg_fk.view.columns import BaseRows, FeetRows
from a1_leg_fk.view.scene import Scene

BATCH_S = 0.05
"""How often rows are sent [s]."""
HOLD_S = 1.0
"""A row is sent once this long [s] has passed since its first message: its other topics'
messages (same stamp) arrive meanwhile. A second, because ``leg_odometry_node`` answers a stream's
first second up to several hundred ms after ``foot_fk_node`` (measured: with 0.2 s, 40-60 % of a
2 s stream's foot heights had no pose when sent)."""
PATH_PERIOD_S = 1.0
"""How often the paths in odom (static lines, as the recorded view's) are redrawn [s]."""
PATH_SPACING_NS = 20_000_000
"""The paths keep one row per this many nanoseconds of stamps (50 Hz)."""
MAX_PATH_POINTS = 5000
"""At most this many points per line: older rows are thinned out when there are more."""

Vector = Sequence[float]
Rows = TypeVar("Rows", FeetRows, BaseRows)

# One row's values: the columns of FeetRows and BaseRows side by side (NaN: not received).
_FEET, _FORCES, _CONTACTS, _NORMALS = slice(0, 12), slice(12, 24), slice(24, 28), slice(28, 32)
_POSITION, _ORIENTATION, _LINEAR, _VARIANCES = (
    slice(32, 35),
    slice(35, 39),
    slice(39, 42),
    slice(42, 45),
)
_ANGLES = 45


class LiveRows:
    """The latest messages by stamp [ns], until :meth:`take` hands them over as rows. Legs by
    their slot in :data:`~a1_leg_fk.model.legs.LEG_NAMES`; ``joints``: the angles' columns.
    """

    def __init__(self, joints: Sequence[str]) -> None:
        self._joint_slot = {name: slot for slot, name in enumerate(joints)}
        self._width = _ANGLES + len(joints)
        self._rows: dict[int, tuple[float, np.ndarray]] = {}  # stamp -> (arrival, values)
        self.messages = 0
        """Messages taken in so far (every method call is one)."""

    def _row(self, stamp_ns: int) -> np.ndarray:
        self.messages += 1
        entry = self._rows.get(stamp_ns)
        if entry is None:
            entry = self._rows[stamp_ns] = (time.monotonic(), np.full(self._width, math.nan))
        return entry[1]

    def foot(self, slot: int, stamp_ns: int, position: Vector) -> None:
        """``foot_positions/<leg>``: the foot [m] in the base frame."""
        self._row(stamp_ns)[_FEET][3 * slot : 3 * slot + 3] = position

    def force(self, slot: int, stamp_ns: int, force: Vector) -> None:
        """``foot_forces/<leg>``: the ground's force on the foot [N] in the base frame."""
        self._row(stamp_ns)[_FORCES][3 * slot : 3 * slot + 3] = force

    def contacts(
        self, stamp_ns: int, legs: Sequence[str], probabilities: Vector, normals: Vector
    ) -> None:
        """``foot_contacts``: per leg (by name) P(stance) and the normal force [N]."""
        row = self._row(stamp_ns)
        for leg, p, normal in zip(legs, probabilities, normals):
            if leg in LEG_NAMES:
                slot = LEG_NAMES.index(leg)
                row[_CONTACTS][slot], row[_NORMALS][slot] = p, normal

    def odometry(
        self,
        stamp_ns: int,
        position: Vector,
        orientation: Vector,
        linear: Vector,
        variances: Vector,
    ) -> None:
        """``leg_odometry``: the pose in odom (position [m], quaternion x, y, z, w), the velocity
        [m/s] in the base frame and its variances [m^2/s^2].
        """
        row = self._row(stamp_ns)
        row[_POSITION], row[_ORIENTATION] = position, orientation
        row[_LINEAR], row[_VARIANCES] = linear, variances

    def angles(self, stamp_ns: int, names: Sequence[str], positions: Vector) -> None:
        """``joint_states``: the angles [rad] of the joints named (others ignored: a message with
        none of the robot's joints makes no row).
        """
        known = [
            (slot, angle)
            for name, angle in zip(names, positions)
            if (slot := self._joint_slot.get(name)) is not None
        ]
        if not known:
            self.messages += 1
            return
        row = self._row(stamp_ns)
        for slot, angle in known:
            row[_ANGLES + slot] = angle

    def take(self, now: float, everything: bool = False) -> tuple[FeetRows, BaseRows] | None:
        """The rows whose first message came :data:`HOLD_S` before ``now`` [s, monotonic] (all
        of them if ``everything``), in stamp order, and forget them; None when there are none.
        """
        ready = sorted(
            stamp
            for stamp, (arrived, _) in self._rows.items()
            if everything or now - arrived >= HOLD_S
        )
        if not ready:
            return None
        values = np.stack([self._rows.pop(stamp)[1] for stamp in ready])
        stamps = np.array(ready, np.int64)
        feet = FeetRows(
            stamps,
            values[:, _FEET].reshape(-1, len(LEG_NAMES), 3),
            contacts=values[:, _CONTACTS],
            forces=values[:, _FORCES].reshape(-1, len(LEG_NAMES), 3),
            normal_forces=values[:, _NORMALS],
            angles=values[:, _ANGLES:],
        )
        base = BaseRows(
            stamps,
            values[:, _POSITION],
            values[:, _ORIENTATION],
            values[:, _LINEAR],
            values[:, _VARIANCES],
        )
        return feet, base


class LiveView:
    """:class:`LiveRows` into a :class:`~a1_leg_fk.view.scene.Scene`: :meth:`tick` sends the
    rows that are ready, the gait bars, and every :data:`PATH_PERIOD_S` the paths so far.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.rows = LiveRows(scene.joints)
        self.sent = 0
        """Rows sent so far."""
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self._kept: list[tuple[FeetRows, BaseRows]] = []  # the paths' rows, thinned
        self._last_kept_ns = -PATH_SPACING_NS
        self._paths_at = time.monotonic()

    def tick(self, now: float, everything: bool = False) -> None:
        """Send what is ready at ``now`` [s, monotonic] (``everything``: all, e.g. at the end)."""
        taken = self.rows.take(now, everything)
        if taken is not None:
            feet, base = taken
            self.scene.send(feet, base)
            if feet.contacts is not None:
                stance = np.nan_to_num(feet.contacts, nan=0.0) >= CONTACT_PROBABILITY
                columns.send_gait(self.scene.recording, feet.stamps_ns, stance)
            self._keep(feet, base)
            self.sent += len(feet.stamps_ns)
            self.first_ns = self.first_ns if self.first_ns is not None else int(feet.stamps_ns[0])
            self.last_ns = int(feet.stamps_ns[-1])
        if everything or now - self._paths_at >= PATH_PERIOD_S:
            self._paths_at = now
            self._send_paths()

    def _keep(self, feet: FeetRows, base: BaseRows) -> None:
        """Keep for the paths the rows with a pose at least :data:`PATH_SPACING_NS` apart."""
        keep = np.zeros(len(feet.stamps_ns), bool)
        posed = np.isfinite(base.positions).all(axis=1)
        for row in np.flatnonzero(posed):
            if feet.stamps_ns[row] - self._last_kept_ns >= PATH_SPACING_NS:
                keep[row], self._last_kept_ns = True, int(feet.stamps_ns[row])
        if keep.any():
            self._kept.append((_rows_of(feet, keep), _rows_of(base, keep)))

    def _send_paths(self) -> None:
        """The base's path and the feet's trails so far, at most :data:`MAX_PATH_POINTS`."""
        if not self._kept:
            return
        feet = FeetRows(
            np.concatenate([f.stamps_ns for f, _ in self._kept]),
            np.concatenate([f.positions for f, _ in self._kept]),
        )
        base = BaseRows(
            feet.stamps_ns,
            np.concatenate([b.positions for _, b in self._kept]),
            np.concatenate([b.orientations for _, b in self._kept]),
            np.zeros((len(feet.stamps_ns), 3)),
            np.zeros((len(feet.stamps_ns), 3)),
        )
        self._kept = [(feet, base)]
        step = max(1, math.ceil(len(feet.stamps_ns) / MAX_PATH_POINTS))
        rows = np.zeros(len(feet.stamps_ns), bool)
        rows[::step] = True
        rows[-1] = True
        columns.send_paths(self.scene.recording, _rows_of(feet, rows), _rows_of(base, rows))


def _rows_of(rows: Rows, keep: np.ndarray) -> Rows:
    """``rows`` with only the rows where ``keep`` (N,) is true."""
    values = {field.name: getattr(rows, field.name) for field in fields(rows)}
    return replace(rows, **{name: v[keep] for name, v in values.items() if v is not None})
