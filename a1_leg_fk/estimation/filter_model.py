"""The state filter's model: its settings (noise densities, the gate, the feet's noise
adaptation), its counts, and one standing foot's velocity measurement with its noise
(:func:`foot_noise`). The filter itself: :mod:`a1_leg_fk.estimation.state_filter`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from a1_leg_fk.estimation.leg_motion import FootMotion
from a1_leg_fk.estimation.odometry import require_non_negative

LEGS = 4
STATE = 15
FLAT, NO_GROUND = "flat", "none"
GROUND_MODELS = (FLAT, NO_GROUND)
"""``flat``: the stance feet's heights anchor z; ``none``: they do not (stairs, slopes)."""
EVEN_ODDS = 0.5
"""A foot whose contact probability is not above this gives no measurement (even odds: the
contact filter's start, before any evidence)."""


@dataclass(frozen=True)
class FilterSettings:
    """The filter's noise model and rules; units in the names (densities per √Hz)."""

    gyro_noise: float = 5e-4
    """The gyro's white noise density [rad/s/√Hz]."""
    accel_noise: float = 0.05
    """The accelerometer's white noise density [m/s²/√Hz] (the base's vibration included)."""
    gyro_bias_walk: float = 1e-4
    """The gyro bias' random walk [rad/s²/√Hz]."""
    accel_bias_walk: float = 2e-3
    """The accelerometer bias' random walk [m/s³/√Hz]."""
    joint_rate_noise_radps: float = 0.05
    """The joint rates' standard deviation [rad/s], through each foot's Jacobian."""
    foot_noise_mps: float = 0.007
    """A standing foot's own horizontal velocity error [m/s]: rolling, slip."""
    foot_vertical_noise_mps: float = 0.02
    """A standing foot's own vertical velocity error [m/s]: impacts, the ground's compliance."""
    orientation_noise_rad: float = 0.01
    """The IMU orientation's standard deviation [rad] when its message gives none."""
    height_noise_m: float = 0.01
    """A stance foot's height above the flat ground [m]."""
    gyro_sample_noise_radps: float = 0.01
    """One gyro sample's standard deviation [rad/s] (in a foot's ``ω x r``)."""
    still_speed_mps: float = 0.02
    """Every foot in stance and no foot's velocity above this: standing still."""
    still_noise_mps: float = 0.005
    """The zero-velocity update's standard deviation [m/s]."""
    gate_chi2: float = 16.27
    """χ² (3 dof) a foot's velocity innovation must stay below: 99.9 %."""
    max_rejected_s: float = 0.25
    """After this long with every stance foot rejected [s] (at once while no foot has been
    believed yet: a start in motion), the gate resets: the feet that agree are believed again
    (``reset_agreement_mps``), the velocity's covariance widened by their mean innovation."""
    reset_agreement_mps: float = 0.1
    """The gate's reset believes the largest group of feet whose velocities agree within this
    [m/s] (:func:`~a1_leg_fk.estimation.stance.consistent_feet`), a lone foot only as close to
    the estimate: a lone foot far off, or feet that disagree, may be swinging feet taken for
    standing."""
    noise_adapt_s: float = 5.0
    """The time constant [s] of the feet's horizontal noise scale, matched to their mean NIS
    (0: fixed)."""
    min_noise_scale: float = 0.005
    """The feet's horizontal noise variance is scaled by no less than this (nor more than 1)."""
    initial_velocity_mps: float = 0.05
    """The velocity's standard deviation at the start [m/s]: the filter starts at rest (a leg
    kicking in the air at power-on says nothing); a base already moving is taken up by the
    gate's reset once two feet agree (``reset_agreement_mps``)."""
    initial_gyro_bias_radps: float = 0.02
    """The gyro bias' standard deviation at the start [rad/s]."""
    initial_accel_bias_mps2: float = 0.2
    """The accelerometer bias' standard deviation at the start [m/s²]."""
    max_step_s: float = 0.1
    """IMU samples further apart are not integrated across (a gap: the covariance grows)."""

    def __post_init__(self) -> None:
        require_non_negative(self, "filter")


@dataclass(frozen=True)
class LegMeasurement:
    """One standing foot at a joint state: its :class:`FootMotion` (base frame), its contact
    probability and ``JJt`` (its Jacobian times its transpose, row-major 3 x 3, m²/rad²).
    """

    motion: FootMotion
    probability: float
    jjt: tuple[float, ...]


@dataclass
class FilterCounts:
    """Updates, per-leg measurements used and rejected by the gate, gate resets (every foot
    rejected too long), zero-velocity updates, IMU gaps, and the running sum of the normalised
    innovation squared (NIS) of the accepted feet with its count.
    """

    updates: int = 0
    used: list[int] = field(default_factory=lambda: [0] * LEGS)
    rejected: list[int] = field(default_factory=lambda: [0] * LEGS)
    gate_resets: int = 0
    still: int = 0
    gaps: int = 0
    nis_sum: float = 0.0
    nis_count: int = 0

    @property
    def mean_nis(self) -> float:
        """The accepted feet's mean NIS (3 when the noise model is right), NaN before any."""
        return self.nis_sum / self.nis_count if self.nis_count else math.nan


def foot_noise(
    measurement: LegMeasurement, fixed: tuple[float, float, tuple[float, ...]]
) -> tuple[float, ...]:
    """A foot's velocity noise (3 x 3 row-major, [m²/s²]): ``s_dq² J Jᵀ + s_w² [r]x[r]xᵀ`` plus
    the foot's own (``fixed``: s_dq², s_w², its 3 x 3 row-major), over its contact probability.
    """
    rate2, gyro2, own = fixed
    rx, ry, rz = measurement.motion.r
    r2, scale = rx * rx + ry * ry + rz * rz, 1.0 / measurement.probability
    j = measurement.jjt
    xy, xz, yz = gyro2 * rx * ry, gyro2 * rx * rz, gyro2 * ry * rz
    return (
        scale * (rate2 * j[0] + gyro2 * (r2 - rx * rx) + own[0]),
        scale * (rate2 * j[1] - xy + own[1]),
        scale * (rate2 * j[2] - xz + own[2]),
        scale * (rate2 * j[3] - xy + own[3]),
        scale * (rate2 * j[4] + gyro2 * (r2 - ry * ry) + own[4]),
        scale * (rate2 * j[5] - yz + own[5]),
        scale * (rate2 * j[6] - xz + own[6]),
        scale * (rate2 * j[7] - yz + own[7]),
        scale * (rate2 * j[8] + gyro2 * (r2 - rz * rz) + own[8]),
    )


def horizontally_scaled(
    noise: tuple[float, ...], root: float, up: tuple[float, float, float]
) -> tuple[float, ...]:
    """``S N S`` for a symmetric 3 x 3 ``noise`` (row-major) and ``S = h I + (1 - h) u uᵀ``
    (``h = root``, ``u = up`` a unit vector): the noise's variance across ``up`` scaled by
    ``h²``, along it kept. Written out: ``h² N + h (1 - h) (w uᵀ + u wᵀ) + (1 - h)² (uᵀ w) u uᵀ``
    with ``w = N u``.
    """
    a, b, c, _, d, e, _, _, f = noise
    ux, uy, uz = up
    wx, wy, wz = a * ux + b * uy + c * uz, b * ux + d * uy + e * uz, c * ux + e * uy + f * uz
    g = 1.0 - root
    hh, hg, gg = root * root, root * g, g * g * (ux * wx + uy * wy + uz * wz)
    xy = hh * b + hg * (wx * uy + ux * wy) + gg * ux * uy
    xz = hh * c + hg * (wx * uz + ux * wz) + gg * ux * uz
    yz = hh * e + hg * (wy * uz + uy * wz) + gg * uy * uz
    return (
        hh * a + 2.0 * hg * wx * ux + gg * ux * ux, xy, xz,
        xy, hh * d + 2.0 * hg * wy * uy + gg * uy * uy, yz,
        xz, yz, hh * f + 2.0 * hg * wz * uz + gg * uz * uz,
    )  # fmt: skip


def stands(probability: float) -> bool:
    """Whether a foot of this contact probability stands: above :data:`EVEN_ODDS` (NaN: no)."""
    return probability > EVEN_ODDS


def standing_still(legs: Sequence[LegMeasurement | None], fastest_mps: float) -> bool:
    """Every foot standing (:func:`stands`), none saying the base
    moves faster than ``fastest_mps`` on an axis: a zero-velocity update's condition.
    """
    for measurement in legs:
        if measurement is None or not stands(measurement.probability):
            return False
        ex, ey, ez = measurement.motion.e
        if not max(abs(ex), abs(ey), abs(ez)) <= fastest_mps:
            return False
    return True


def normalised_squares(
    innovation: list[list[float]],
    residuals: list[tuple[float, float, float]],
    up: list[float],
) -> tuple[list[float], list[float]]:
    """Per foot, the NIS ``rᵀ S⁻¹ r`` of its residual ``r`` with its innovation covariance ``S``
    (the feet's 3 x 3 diagonal blocks of ``innovation``, symmetric, in the order of
    ``residuals``; by cofactors, in floats: numpy's per-call cost is larger), and the square of
    its part along ``up``, ``(u·r)² / (uᵀ S u)``.
    """
    squares, vertical = [], []
    ux, uy, uz = up
    for first, (x, y, z) in zip(range(0, 3 * len(residuals), 3), residuals):
        a, b, c = innovation[first][first : first + 3]
        d, e = innovation[first + 1][first + 1 : first + 3]
        f = innovation[first + 2][first + 2]
        ca, cb, cc = d * f - e * e, c * e - b * f, b * e - c * d
        determinant = a * ca + b * cb + c * cc
        cd, ce, cf = a * f - c * c, b * c - a * e, a * d - b * b
        quadratic = (
            ca * x * x + cd * y * y + cf * z * z + 2.0 * (cb * x * y + cc * x * z + ce * y * z)
        )
        squares.append(quadratic / determinant)
        along = ux * x + uy * y + uz * z
        spread = (
            a * ux * ux
            + d * uy * uy
            + f * uz * uz
            + 2.0 * (b * ux * uy + c * ux * uz + e * uy * uz)
        )
        vertical.append(along * along / spread)
    return squares, vertical
