"""What each foot says about the base's velocity, rolling feet included (numpy, N samples at once).

A stance foot does not slip: the point of its sole that touches the ground is still. For a
spherical foot of radius ``r`` (Unitree's feet; the A1's toe collision sphere has r = 0.02 m) that
point is ``c = r d`` from the sphere's centre (the foot frame), ``d`` the unit vector of gravity
("down") in the base frame, and it belongs to the calf. Its velocity in the world, in base
coordinates, is zero::

    0 = v + w x (p + c) + J(q) q_dot + w_leg x c

``v`` [m/s] and ``w`` [rad/s] the base's linear and angular velocity, ``p`` [m] the foot frame,
``J q_dot`` its velocity relative to the base, ``w_leg`` [rad/s] the calf's angular velocity
relative to the base (sum of joint axis x joint rate). So each stance foot gives
``v = e - w x r`` with ``e = -(J q_dot + w_leg x c)`` and ``r = p + c``: :func:`foot_motion`
returns ``e`` and ``r`` per foot, and the sinking ``depth = d . r`` [m] of each contact point that
the kinematic stance test compares. Ignoring the rolling (r = 0) means taking the sphere's centre
for still: it moves at ``|w_calf| r`` (~25 mm/s on a trotting A1).

Frames: the base frame (the URDF root link), as in :mod:`a1_leg_fk.kinematics`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from a1_leg_fk.kinematics import Quadruped
from a1_leg_fk.legs import JOINTS_PER_LEG, LEG_NAMES

LEGS = len(LEG_NAMES)
CENTRED_SPHERE_M = 1e-9
"""A collision sphere whose centre is this close [m] to its link's origin is the foot sphere."""


def foot_radii(quadruped: Quadruped) -> tuple[float, ...]:
    """Each foot's rolling radius [m]: the radius of the foot link's ``<collision>`` sphere when it
    is centred on the link's origin, else 0 (a point foot).
    """
    radii = []
    for leg in quadruped.legs:
        sphere = quadruped.model.spheres.get(leg.chain.foot_link)
        centred = sphere is not None and max(map(abs, sphere.origin_xyz)) <= CENTRED_SPHERE_M
        radii.append(sphere.radius if sphere is not None and centred else 0.0)
    return tuple(radii)


@dataclass(frozen=True)
class FootMotion:
    """Per sample and foot (N, 4, ...), base frame: ``e`` [m/s], the base velocity the foot gives
    when the base does not turn; ``r`` [m], the contact point; ``depth`` [m], ``d . r``, how far
    below the base the contact point is along gravity. NaN for feet without angles or rates.
    """

    e: np.ndarray
    r: np.ndarray
    depth: np.ndarray


class CalfRates:
    """The calf's angular velocity relative to the base [rad/s, base frame], every leg at once.

    With the stages of :mod:`a1_leg_fk.leg_stages` (``p -> o + M Rot(a, q) p``), joint i's axis in
    the base frame is ``R_i M_i a_i`` with ``R_0 = I``, ``R_1 = M_0 Rot(a_0, q_0)`` and ``R_2 =
    R_1 M_1 Rot(a_1, q_1)``; Rodrigues' ``M Rot(a, q) = C0 + cos q C1 + sin q C2`` keeps it to
    products with constants.
    """

    def __init__(self, quadruped: Quadruped) -> None:
        stages = [leg.stages for leg in quadruped.legs]
        self._axis0 = np.array([s[0].rotation @ s[0].axis for s in stages])  # (4, 3)
        self._hip = np.array([s[0].rodrigues_terms for s in stages])  # (4, 3 terms, 3, 3)
        self._axis1 = np.array([s[1].rotation @ s[1].axis for s in stages])  # M_1 a_1
        knee_axis = [s[2].rotation @ s[2].axis for s in stages]  # M_2 a_2
        self._knee = np.array(
            [[term @ axis for term in s[1].rodrigues_terms] for s, axis in zip(stages, knee_axis)]
        )  # (4, 3 terms, 3): M_1 Rot(a_1, q_1) M_2 a_2 = k0 + cos q_1 k1 + sin q_1 k2

    def __call__(self, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """(N, 4, 3) for (N, 12) angles [rad] and rates [rad/s]."""
        q = angles.reshape(-1, LEGS, JOINTS_PER_LEG)
        dq = rates.reshape(-1, LEGS, JOINTS_PER_LEG)
        cos, sin = np.cos(q), np.sin(q)
        hip = self._hip
        rotation = (
            hip[:, 0] + cos[:, :, 0, None, None] * hip[:, 1] + sin[:, :, 0, None, None] * hip[:, 2]
        )  # R_1 (N, 4, 3, 3)
        knee = self._knee
        knee_axis = knee[:, 0] + cos[:, :, 1, None] * knee[:, 1] + sin[:, :, 1, None] * knee[:, 2]
        below_hip = self._axis1 * dq[:, :, 1, None] + knee_axis * dq[:, :, 2, None]
        rate: np.ndarray = self._axis0 * dq[:, :, 0, None] + np.einsum(
            "nlij,nlj->nli", rotation, below_hip
        )
        return rate


class LegMotion:
    """:func:`foot_motion` for one robot: its calf rates and foot radii [m] (``radii`` overrides
    the URDF's, one per leg or one for all).
    """

    def __init__(self, quadruped: Quadruped, radii: Sequence[float] | float | None = None) -> None:
        self.calf_rates = CalfRates(quadruped)
        if radii is None:
            radii = foot_radii(quadruped)
        elif isinstance(radii, (int, float)):
            radii = (float(radii),) * LEGS
        self.radii = tuple(float(radius) for radius in radii)
        self._radii = np.array(self.radii)[:, None]  # (4, 1)

    def __call__(
        self,
        feet: np.ndarray,
        foot_velocities: np.ndarray,
        angles: np.ndarray,
        rates: np.ndarray,
        down: np.ndarray,
    ) -> FootMotion:
        """Per-foot motion for N samples: ``feet`` (N, 4, 3) [m] and ``foot_velocities`` (N, 4, 3)
        [m/s] (``J q_dot``) in the base frame, ``angles`` (N, 12) [rad], ``rates`` (N, 12)
        [rad/s], ``down`` (N, 3) unit gravity direction in the base frame.
        """
        offset = self._radii * down[:, None, :]  # c (N, 4, 3)
        with np.errstate(invalid="ignore"):
            calf = self.calf_rates(angles, rates)
            e = -(foot_velocities + np.cross(calf, offset))
            r = feet + offset
            depth = np.einsum("nlj,nj->nl", r, down)
        return FootMotion(e, r, depth)
