"""PyBullet's own answer, for tests: a URDF in a DIRECT client of its own, base fixed at the
origin.

Independent of :mod:`a1_leg_fk.verify` (the code under test): joints and links are found by
name, angles set with ``resetJointState`` and link frames read with ``getLinkState(...)[4]``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Self

import numpy as np
import pybullet
import pybullet_data

A1_URDF = Path(pybullet_data.getDataPath()) / "a1" / "a1.urdf"


class PyBulletRobot:
    """One URDF in its own DIRECT client, fixed base at the origin; use as a context manager."""

    def __init__(self, urdf_path: Path | str) -> None:
        self.client = pybullet.connect(pybullet.DIRECT)
        try:
            self.body = pybullet.loadURDF(
                str(urdf_path),
                basePosition=[0, 0, 0],
                baseOrientation=[0, 0, 0, 1],
                useFixedBase=True,
                physicsClientId=self.client,
            )
            count = pybullet.getNumJoints(self.body, physicsClientId=self.client)
            self.info = [
                pybullet.getJointInfo(self.body, j, physicsClientId=self.client)
                for j in range(count)
            ]
        except BaseException:
            pybullet.disconnect(self.client)
            raise
        self.joint_index = {info[1].decode(): info[0] for info in self.info}
        self.link_index = {info[12].decode(): info[0] for info in self.info}

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    def limits(self, joint_names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        """PyBullet's own limits [rad]; [-pi, pi] where it has none (lower > upper: continuous)."""
        lower, upper = [], []
        for name in joint_names:
            info = self.info[self.joint_index[name]]
            low, high = (info[8], info[9]) if info[8] <= info[9] else (-math.pi, math.pi)
            lower.append(low)
            upper.append(high)
        return np.array(lower), np.array(upper)

    def set_joints(self, joint_names: list[str], angles) -> None:
        for name, angle in zip(joint_names, angles):
            pybullet.resetJointState(
                self.body, self.joint_index[name], float(angle), physicsClientId=self.client
            )

    def link_state(self, link: str) -> tuple:
        return pybullet.getLinkState(
            self.body,
            self.link_index[link],
            computeForwardKinematics=True,
            physicsClientId=self.client,
        )

    def link_frame(self, link: str) -> np.ndarray:
        """Origin of the link's URDF frame [m], world = base frame."""
        return np.array(self.link_state(link)[4])

    def feet(self, joint_names: list[str], feet: list[str], angles) -> np.ndarray:
        self.set_joints(joint_names, angles)
        return np.array([self.link_frame(foot) for foot in feet])

    def close(self) -> None:
        pybullet.disconnect(self.client)


def assert_twin_agrees(
    twin,
    reference: PyBulletRobot,
    joint_names: list[str],
    feet: list[str],
    configurations,
    tolerance_m: float,
) -> None:
    """The code under test's verify twin (``PyBulletFeet``) passes ``verify`` and its feet are
    ``reference``'s own within ``tolerance_m`` [m], for every configuration [rad] (slot order)."""
    for q in configurations:
        result = twin.verify(q, tolerance_m)
        assert result.success, result
        np.testing.assert_allclose(
            twin.foot_positions(q),
            reference.feet(joint_names, feet, q),
            rtol=0.0,
            atol=tolerance_m,
        )
