"""The live view's grouping by stamp (:class:`a1_leg_fk.view.live.LiveRows`), by construction:
messages of several topics in any order come out as one row per stamp, in stamp order, each value
in its place, NaN where no message came, and only once a row has waited ``HOLD_S``."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

pytest.importorskip("rerun")

from a1_leg_fk.view.live import HOLD_S, LiveRows  # after the skip

JOINTS = ["FR_hip_joint", "FR_upper_joint", "FR_lower_joint"]


def test_rows_by_stamp() -> None:
    rows = LiveRows(JOINTS)
    rows.odometry(300, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0), (0.1, 0.2, 0.3), (1e-4, 2e-4, 3e-4))
    rows.foot(2, 100, (0.2, -0.1, -0.3))  # RR
    rows.contacts(100, ["RL", "FR", "XX"], (0.9, 0.2, 0.5), (80.0, 5.0, 1.0))
    rows.force(0, 300, (1.0, 2.0, 30.0))
    rows.angles(100, ["FR_lower_joint", "other", "FR_hip_joint"], (-1.5, 9.0, 0.1))
    assert rows.take(time.monotonic()) is None  # not waited HOLD_S yet
    taken = rows.take(time.monotonic() + HOLD_S)
    assert taken is not None
    feet, base = taken
    assert feet.stamps_ns.tolist() == [100, 300] and base.stamps_ns.tolist() == [100, 300]
    assert feet.positions[0, 2].tolist() == [0.2, -0.1, -0.3]
    assert np.isnan(feet.positions[0, [0, 1, 3]]).all() and np.isnan(feet.positions[1]).all()
    assert feet.contacts is not None and feet.normal_forces is not None
    assert feet.contacts[0, 3] == 0.9 and feet.contacts[0, 0] == 0.2
    assert feet.normal_forces[0, 3] == 80.0 and np.isnan(feet.contacts[0, 1])
    assert feet.forces is not None and feet.forces[1, 0].tolist() == [1.0, 2.0, 30.0]
    assert feet.angles is not None
    assert feet.angles[0, 0] == 0.1 and feet.angles[0, 2] == -1.5 and math.isnan(feet.angles[0, 1])
    assert base.positions[1].tolist() == [1.0, 2.0, 3.0] and np.isnan(base.positions[0]).all()
    assert base.orientations[1].tolist() == [0.0, 0.0, 0.0, 1.0]
    assert base.linear_variances[1].tolist() == [1e-4, 2e-4, 3e-4]
    assert rows.take(time.monotonic() + HOLD_S, everything=True) is None  # all handed over


def test_everything_takes_the_waiting_rows() -> None:
    rows = LiveRows(JOINTS)
    rows.foot(0, 5, (0.0, 0.0, -0.3))
    taken = rows.take(time.monotonic(), everything=True)
    assert taken is not None and taken[0].stamps_ns.tolist() == [5]


def test_a_joint_state_without_the_robots_joints_makes_no_row() -> None:
    rows = LiveRows(JOINTS)
    rows.angles(7, ["gripper_joint"], (0.5,))
    rows.angles(8, [], ())
    assert rows.take(time.monotonic(), everything=True) is None
    rows.foot(1, 9, (0.1, 0.0, -0.3))
    assert rows.messages == 3  # every message counted (echo's drain waits on the count)
