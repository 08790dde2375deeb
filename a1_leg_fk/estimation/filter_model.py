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
THETA, VELOCITY, POSITION, GYRO_BIAS, ACCEL_BIAS = (slice(k, k + 3) for k in range(0, STATE, 3))
"""The error state's blocks: attitude [rad], velocity [m/s], position [m], gyro and accelerometer
biases (odom frame, biases in the base frame)."""
FOOTHOLDS, FLAT, NO_GROUND = "footholds", "flat", "none"
GROUND_MODELS = (FOOTHOLDS, FLAT, NO_GROUND)
"""``footholds`` (the default): each stance foot's height is held to its foothold's anchored
height (:mod:`a1_leg_fk.estimation.ground`: a touchdown where the ground predicts takes the
prediction, a step its own height; slopes, stairs, rough ground and flat floors); ``flat``: the
stance feet's heights anchor z at the first feet's (a known flat floor); ``none``: they do not."""
DEFAULT_GROUND = FOOTHOLDS
MAX_BASE_SPEED_MPS = 1e3
"""[m/s] A standing foot that says the base moves faster (on some axis) says nothing: its joint
rates or foot velocity are corrupt (no leg comes near it), and the sums of squares stay far from
overflow; a larger residual counts as this in :func:`doubt`."""
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
    """A standing foot's own vertical velocity error [m/s]: the ground's compliance (before the
    vertical noise adaptation, ``vertical_adapt_s``; the impacts: ``touchdown_noise_mps``)."""
    touchdown_noise_mps: float = 0.1
    """A foot's vertical velocity error at its touchdown [m/s]: the impact's give (the ground and
    the foot compressed, then springing back), decaying over ``touchdown_s`` (0: none); with
    ``impact_window_s``, a landing's until its own is measured
    (:mod:`~a1_leg_fk.estimation.foot_impact`), and the first touchdown's sideways jolt on the
    standing feet, per horizontal axis (:mod:`~a1_leg_fk.estimation.foot_jolt`)."""
    touchdown_s: float = 0.03
    """The time constant [s] of the touchdown's vertical error."""
    impact_window_s: float = 0.03
    """A landing's touchdown amplitude is measured on its own vertical innovations within this
    [s] of its touchdown (:mod:`~a1_leg_fk.estimation.foot_impact`), and each touchdown's
    sideways jolt on the feet standing on their innovations within it
    (:mod:`~a1_leg_fk.estimation.foot_jolt`); 0: ``touchdown_noise_mps`` for every landing and no
    jolt, the filter as before both."""
    give_s: float = 0.02
    """The correlation time [s] of the standing feet's give (their vertical velocity the IMU does
    not confirm, measured: :mod:`~a1_leg_fk.estimation.foot_give`): PyBullet's mat-soft toes'
    measured one; 0: not modelled (the filter as before it; docs/leg_odometry.md shows what the
    give does on each family)."""
    give_window_s: float = 0.2
    """The give is the feet's vertical velocity less the IMU's, high-passed over this [s]."""
    give_average_s: float = 1.0
    """The give's mean square is averaged over this [s]."""
    give_after_s: float = 0.1
    """A stance (since the accepted feet's last touchdown) counts towards the give, from its
    touchdown on, once it has lasted this long [s] (half a trot's stance): a shorter one, a swing
    foot taken for standing for a few joint states (kinematic contacts on a step down), is no
    give."""
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
    lost_weight: float = 0.5
    """While the gate rejects every standing foot, the weight of the other explanation (the
    state lost, two feet that agree with each other right) in the reported velocity's variance
    (:func:`doubt`; 0: none)."""
    reset_agreement_mps: float = 0.1
    """The gate's reset believes the largest group of feet whose velocities agree within this
    [m/s] (:func:`~a1_leg_fk.estimation.stance.consistent_feet`), a lone foot only as close to
    the estimate: a lone foot far off, or feet that disagree, may be swinging feet taken for
    standing."""
    noise_adapt_s: float = 5.0
    """The time constant [s] of the feet's horizontal noise scale, matched to their mean NIS
    (0: fixed)."""
    vertical_adapt_s: float = 5.0
    """The time constant [s] of the feet's vertical noise scale, matched to their NIS along world
    up (0: fixed); the touchdowns' transients are modelled apart, not scaled."""
    min_noise_scale: float = 0.005
    """The feet's horizontal and vertical noise variances are scaled by no less than this (nor
    more than 1)."""
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


def scaled(
    noise: tuple[float, ...],
    roots: tuple[float, float],
    up: tuple[float, float, float],
    impact: float,
) -> tuple[float, ...]:
    """``S N S + i u uᵀ`` for a symmetric 3 x 3 ``noise`` (row-major), ``S = h I + (v - h) u uᵀ``
    (``roots``: ``h`` and ``v``, the square roots of the horizontal and vertical noise scales;
    ``u = up`` a unit vector) and the touchdown's vertical variance ``i = impact``: the noise's
    variance across ``up`` scaled by ``h²``, along it by ``v²``. Written out: ``h² N + h g (w uᵀ +
    u wᵀ) + (g² (uᵀ w) + i) u uᵀ`` with ``g = v - h``, ``w = N u``.
    """
    a, b, c, _, d, e, _, _, f = noise
    h, v = roots
    ux, uy, uz = up
    wx, wy, wz = a * ux + b * uy + c * uz, b * ux + d * uy + e * uz, c * ux + e * uy + f * uz
    g = v - h
    hh, hg, gg = h * h, h * g, g * g * (ux * wx + uy * wy + uz * wz) + impact
    xy = hh * b + hg * (wx * uy + ux * wy) + gg * ux * uy
    xz = hh * c + hg * (wx * uz + ux * wz) + gg * ux * uz
    yz = hh * e + hg * (wy * uz + uy * wz) + gg * uy * uz
    return (
        hh * a + 2.0 * hg * wx * ux + gg * ux * ux, xy, xz,
        xy, hh * d + 2.0 * hg * wy * uy + gg * uy * uy, yz,
        xz, yz, hh * f + 2.0 * hg * wz * uz + gg * uz * uz,
    )  # fmt: skip


def inverse_square(
    a: float, b: float, c: float, d: float, e: float, f: float, x: float, y: float, z: float
) -> float:
    """``rᵀ M⁻¹ r`` for ``r = (x, y, z)`` and the symmetric 3 x 3 ``M`` of rows ``a b c / b d e
    / c e f``, by cofactors in floats.
    """
    ca, cb, cc = d * f - e * e, c * e - b * f, b * e - c * d
    cd, ce, cf = a * f - c * c, b * c - a * e, a * d - b * b
    quadratic = ca * x * x + cd * y * y + cf * z * z + 2.0 * (cb * x * y + cc * x * z + ce * y * z)
    return quadratic / (a * ca + b * cb + c * cc)


def scattered(residuals: list[tuple[float, float, float]], noises: list[tuple[float, ...]],
              chi2: float) -> float:  # fmt: skip
    """The variance [m²/s², per axis] to add to each accepted foot's noise (3 x 3 row-major
    ``noises``) when the feet disagree beyond them: their ``residuals``' deviations from their
    mean, normalised by their noises and summed (~χ² of 3 (K - 1) dof), above ``chi2`` (K - 1),
    give their sample variance per axis; else 0. Each foot passed the gate alone, but two feet
    sliding apart, one pushing off as it unloads, say the noises are too small for this update
    (the adapted scale is a mean over seconds).
    """
    count = len(residuals)
    if count < 2:
        return 0.0
    mx = my = mz = 0.0
    for x, y, z in residuals:
        mx, my, mz = mx + x, my + y, mz + z
    mx, my, mz = mx / count, my / count, mz / count
    test = spread = 0.0
    for (x, y, z), (a, b, c, _, d, e, _, _, f) in zip(residuals, noises):
        dx, dy, dz = x - mx, y - my, z - mz
        test += inverse_square(a, b, c, d, e, f, dx, dy, dz)
        spread += dx * dx + dy * dy + dz * dz
    return spread / (3.0 * (count - 1)) if test > chi2 * (count - 1) else 0.0


def doubt(
    residuals: list[tuple[float, float, float]],
    noises: list[tuple[float, ...]],
    nis: Sequence[float],
    settings: FilterSettings,
) -> tuple[float, float, float]:
    """The variance [m²/s², per base axis] the reported velocity adds while every standing foot
    fails the gate: the filter keeps its state (the feet slip), but when the two feet of least
    NIS agree with each other (their difference's NIS within ``gate_chi2``) the other
    explanation (the state is lost, their mean residual ``δ`` right) has ``lost_weight`` ``w``:
    the two hypotheses' mixture, moment-matched, adds ``w (1 - w) δ²`` (the diagonal of
    ``δ δᵀ``). One foot alone (a swinging foot taken for standing) raises no doubt.
    """
    if len(residuals) < 2:
        return (0.0, 0.0, 0.0)
    first, second = sorted(range(len(nis)), key=nis.__getitem__)[:2]
    (ax, ay, az), (bx, by, bz) = residuals[first], residuals[second]
    n = [p + q for p, q in zip(noises[first], noises[second])]
    agreement = inverse_square(n[0], n[1], n[2], n[4], n[5], n[8], ax - bx, ay - by, az - bz)
    if not agreement <= settings.gate_chi2:  # also NaN
        return (0.0, 0.0, 0.0)
    weight = settings.lost_weight * (1.0 - settings.lost_weight)
    dx, dy, dz = (min(max((p + q) / 2.0, -MAX_BASE_SPEED_MPS), MAX_BASE_SPEED_MPS)
                  for p, q in ((ax, bx), (ay, by), (az, bz)))  # fmt: skip
    return (weight * dx * dx, weight * dy * dy, weight * dz * dz)


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
        squares.append(inverse_square(a, b, c, d, e, f, x, y, z))
        along = ux * x + uy * y + uz * z
        spread = (
            a * ux * ux
            + d * uy * uy
            + f * uz * uz
            + 2.0 * (b * ux * uy + c * ux * uz + e * uy * uz)
        )
        vertical.append(along * along / spread)
    return squares, vertical
