"""The closed-form inverse kinematics of a leg of the A1 topology (see
:mod:`a1_leg_fk.kinematics.ik.four_legs`): its constants from the compiled stages, and the four
branches for a target [m, base frame], on floats or on numpy arrays. No ROS.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.ik.seed import FloatsOrArrays
from a1_leg_fk.kinematics.leg_stages import knee_circle

ARGUMENT_TOLERANCE = 1e-12
"""How far beyond +-1 an ``acos`` argument may be (rounding of a target on the boundary of the
workspace) and still count as reaching the target; it is then clamped to +-1."""
PERPENDICULAR_TOLERANCE = 1e-9
"""|cos| between the roll and pitch axes below which they count as perpendicular."""
Vector3 = tuple[float, float, float]
Branch = tuple[tuple[FloatsOrArrays, FloatsOrArrays, FloatsOrArrays], FloatsOrArrays]
"""``((q0, q1, q2), exact)``: a branch's angles [rad] and whether it reaches the target."""


@dataclass(frozen=True)
class Geometry:
    """The closed form's constants, from the compiled stages (see the module docstring)."""

    roll_rotation_t: tuple[Vector3, Vector3, Vector3]  # M0^T, by rows
    roll_origin: Vector3  # o0 [m]
    roll_axis: Vector3  # a0
    pitch_axis: Vector3  # b = M1 a1, in the roll joint's child frame
    pitch_cross: Vector3  # a0 x b
    pitch_origin: Vector3  # o1 [m]
    lateral_m: float  # h = b . x for every pitch and knee angle [m]
    plane: tuple[Vector3, Vector3]  # M1 e1, M1 e2: a basis of the plane normal to the pitch axis
    # The foot in that plane at knee angle q2: U + cos q2 V + sin q2 W [m].
    foot_u: tuple[float, float]
    foot_v: tuple[float, float]
    foot_w: tuple[float, float]
    alpha: float  # squared distance from the pitch axis: alpha + kappa cos(q2 - peak) [m^2]
    kappa: float
    cos_peak: float
    sin_peak: float


def closed_form_geometry(leg: CompiledLeg) -> Geometry | None:
    """The constants of the closed form, or ``None`` when the leg is not of the A1 topology."""
    roll, pitch, knee = leg.stages
    pitch_axis = pitch.rotation @ pitch.axis
    if abs(float(roll.axis @ pitch_axis)) > PERPENDICULAR_TOLERANCE:
        return None
    circle = knee_circle(pitch, knee, leg.foot_offset)
    if circle is None:
        return None
    alpha, beta, gamma = circle.alpha, circle.beta, circle.gamma
    kappa = math.hypot(beta, gamma)
    if kappa < 1e-12:  # the foot on the knee axis, or the knee on the pitch axis: no knee motion
        return None
    rows, plane = roll.rotation.T, circle.basis @ pitch.rotation.T
    return Geometry(
        roll_rotation_t=(_floats(rows[0]), _floats(rows[1]), _floats(rows[2])),
        roll_origin=_floats(roll.offset),
        roll_axis=_floats(roll.axis),
        pitch_axis=_floats(pitch_axis),
        pitch_cross=_floats(np.cross(roll.axis, pitch_axis)),
        pitch_origin=_floats(pitch.offset),
        lateral_m=float(pitch_axis @ pitch.offset) + circle.along,
        plane=(_floats(plane[0]), _floats(plane[1])),
        foot_u=tuple(circle.u.tolist()),
        foot_v=tuple(circle.v.tolist()),
        foot_w=tuple(circle.w.tolist()),
        alpha=alpha,
        kappa=kappa,
        cos_peak=beta / kappa,
        sin_peak=gamma / kappa,
    )


def _floats(vector: np.ndarray) -> Vector3:
    """The three floats of a 3-vector."""
    x, y, z = vector.tolist()
    return (x, y, z)


def _dot(row: Vector3, x: FloatsOrArrays, y: FloatsOrArrays, z: FloatsOrArrays) -> FloatsOrArrays:
    """``row . (x, y, z)``."""
    return row[0] * x + row[1] * y + row[2] * z


def branches(
    g: Geometry, tx: FloatsOrArrays, ty: FloatsOrArrays, tz: FloatsOrArrays, xp: SimpleNamespace
) -> list[Branch]:
    """The four branches ``((q0, q1, q2), exact)`` for a target (tx, ty, tz) [m, base frame]:
    roll branch +-, knee branch +-. ``exact`` is False where a branch does not reach the target
    (its ``acos`` argument was clamped).
    """
    dx, dy, dz = tx - g.roll_origin[0], ty - g.roll_origin[1], tz - g.roll_origin[2]
    rt = g.roll_rotation_t
    t0 = (_dot(rt[0], dx, dy, dz), _dot(rt[1], dx, dy, dz), _dot(rt[2], dx, dy, dz))
    along = _dot(g.roll_axis, *t0)
    a, b = _dot(g.pitch_axis, *t0), _dot(g.pitch_cross, *t0)
    radius = xp.hypot(a, b)
    on_axis = radius == 0.0
    safe_radius = xp.where(on_axis, 1.0, radius)
    cos_base, sin_base = (
        xp.where(on_axis, 1.0, a / safe_radius),
        xp.where(on_axis, 0.0, b / safe_radius),
    )
    roll_argument = xp.where(
        on_axis, xp.where(g.lateral_m == 0.0, 0.0, math.inf), g.lateral_m / safe_radius
    )
    roll_exact = abs(roll_argument) <= 1.0 + ARGUMENT_TOLERANCE
    cos_roll = xp.minimum(xp.maximum(roll_argument, -1.0), 1.0)
    sin_roll = xp.sqrt(1.0 - cos_roll * cos_roll)
    ax, ay, az = g.roll_axis
    ox, oy, oz = g.pitch_origin
    out: list[Branch] = []
    for roll_sign in (1.0, -1.0):
        c0 = cos_base * cos_roll - roll_sign * sin_base * sin_roll  # cos(base + sign * acos)
        s0 = sin_base * cos_roll + roll_sign * cos_base * sin_roll
        # x = Rot(a0, -q0) t0 = a0 (a0 . t0) + c0 (t0 - a0 (a0 . t0)) - s0 (a0 x t0), relative to
        # o1
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
            # Cos(peak + sign * acos)
            c2 = g.cos_peak * cos_knee - knee_sign * g.sin_peak * sin_knee
            s2 = g.sin_peak * cos_knee + knee_sign * g.cos_peak * sin_knee
            fx = g.foot_u[0] + c2 * g.foot_v[0] + s2 * g.foot_w[0]
            fy = g.foot_u[1] + c2 * g.foot_v[1] + s2 * g.foot_w[1]
            q1 = xp.atan2(fx * gy - fy * gx, fx * gx + fy * gy)
            out.append(((q0, q1, xp.atan2(s2, c2)), exact))
    return out
