"""One update of the state filter (:mod:`a1_leg_fk.estimation.state_filter`): its measurements
stacked, the rows of ``H``, the residuals and the block-diagonal noise, in this order.

- the IMU's orientation (3 rows, when it gives one): ``dθ`` observed directly, residual
  ``Log(R̂ᵀ R_m)``;
- each standing foot's velocity (3 rows): ``z = e - ω_m x r = Rᵀ v + r x b_g``, rows
  ``[[Rᵀv]x, Rᵀ, 0, [r]x, 0]``, noise :func:`~a1_leg_fk.estimation.filter_model.foot_noise`
  with its horizontal part scaled by the feet's noise scale;
- on flat ground with a known ground, each foot's contact point's height ``p_z + R₃·r`` (1 row:
  ``r x R₃`` on dθ, 1 on p_z); with the local ground, against the ground's height under that
  foot, its variance added to the noise;
- the zero-velocity update (3 rows: ``Rᵀ v = 0``).

The values are written out in floats and set in one call per array, at flat indices computed
once per shape (:func:`layout`): numpy's cost per call, not the arithmetic, sets the filter's
speed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from a1_leg_fk.estimation.filter_model import (
    STATE,
    FilterSettings,
    LegMeasurement,
    foot_noise,
    scaled,
)
from a1_leg_fk.estimation.so3 import rotation_between
from a1_leg_fk.kinematics.frames import Quaternion, Vector

FOOT_COLUMNS = (0, 1, 2, 3, 4, 5, 9, 10, 11)
"""A foot's velocity row's columns: dθ, dv, db_g."""
HEIGHT_COLUMNS = (0, 1, 2, 8)
"""A foot's height row's columns: dθ, dp_z."""


@dataclass(frozen=True)
class Layout:
    """Where one shape of stack puts its values: its size, its blocks' rows, and the flat
    indices of the values :class:`Stack` writes, in its order, into ``H`` (size x 15) and into
    the noise (size x size).
    """

    size: int
    feet: slice
    heights: slice
    still: slice
    rows: np.ndarray
    noise: np.ndarray


@functools.lru_cache(maxsize=64)
def layout(orientation: bool, feet: int, heights: bool, still: bool) -> Layout:
    """The layout of a stack with (or without) the orientation, ``feet`` feet (and their
    heights) and the zero-velocity update.
    """
    first = 3 if orientation else 0
    foot_rows = slice(first, first + 3 * feet)
    height_rows = slice(foot_rows.stop, foot_rows.stop + (feet if heights else 0))
    still_rows = slice(height_rows.stop, height_rows.stop + (3 if still else 0))
    size = still_rows.stop
    rows = [k * STATE + k for k in range(first)]
    rows += [row * STATE + column for row in range(*foot_rows.indices(size))
             for column in FOOT_COLUMNS]  # fmt: skip
    rows += [row * STATE + column for row in range(*height_rows.indices(size))
             for column in HEIGHT_COLUMNS]  # fmt: skip
    rows += [
        row * STATE + column for row in range(*still_rows.indices(size)) for column in range(6)
    ]
    noise = [k * (size + 1) for k in range(first)]
    for foot in range(feet):
        block = range(first + 3 * foot, first + 3 * foot + 3)
        noise += [row * size + column for row in block for column in block]
    noise += [k * (size + 1) for k in range(height_rows.start, still_rows.stop)]
    return Layout(size, foot_rows, height_rows, still_rows, np.array(rows), np.array(noise))


class Point(NamedTuple):
    """The state one update linearises about: the rows of the rotation base -> world, the
    base's velocity in its own frame ``Rᵀ v`` [m/s], the gyro's last sample and bias [rad/s]
    (base frame), the base's height ``p_z`` and the ground's [m] (None: not known yet), the
    feet's horizontal and vertical noise scales; ``grounds``: per stacked foot, the local
    ground's height [m] under it and its variance [m²] (None: the one ``ground`` for all).
    """

    rows: list[list[float]]
    local: tuple[float, float, float]
    gyro: Vector
    gyro_bias: Vector
    height: float
    ground: float | None
    noise_scales: tuple[float, float]
    grounds: list[tuple[float, float]] | None = None


class Stack:
    """One update's stacked ``rows`` (H), ``residual`` and ``noise`` (see the module text), with
    the standing feet's own residuals, noises and contact-point heights (for the gate, the
    scatter, the doubt and the ground) and world ``up`` in the base frame.
    """

    def __init__(
        self,
        point: Point,
        settings: FilterSettings,
        orientation: tuple[Quaternion, Vector | None] | None,
        feet: list[tuple[LegMeasurement, float]],
        heights: bool,
        still: bool,
    ) -> None:
        self.layout = shape = layout(orientation is not None, len(feet), heights, still)
        self.up: list[float] = point.rows[2]
        self.foot_residuals: list[tuple[float, float, float]] = []
        self.foot_noises: list[tuple[float, ...]] = []
        self.foot_heights: list[float] = []
        self._contact_points: list[tuple[float, float, float]] = []
        lx, ly, lz = point.local
        (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = point.rows
        base = ((0.0, -lz, ly, r0, r3, r6), (lz, 0.0, -lx, r1, r4, r7), (-ly, lx, 0.0, r2, r5, r8))
        rows: list[float] = []
        noise: list[float] = []
        residual: list[float] = []
        if orientation is not None:
            quaternion, variance = orientation
            rows += (1.0, 1.0, 1.0)
            noise += variance or (settings.orientation_noise_rad**2,) * 3
            residual += rotation_between(point.rows, quaternion)
        if feet:
            self._feet(point, settings, feet, base, (rows, noise, residual))
        if heights and feet:
            self._heights(point, settings, (rows, noise, residual))
        if still:
            rows += base[0] + base[1] + base[2]
            noise += (settings.still_noise_mps**2,) * 3
            residual += (-lx, -ly, -lz)
        self.rows = np.zeros((shape.size, STATE))
        self.rows.ravel()[shape.rows] = rows
        self.noise = np.zeros((shape.size, shape.size))
        self.noise.ravel()[shape.noise] = noise
        self.residual = np.array(residual)

    def _feet(
        self,
        point: Point,
        settings: FilterSettings,
        feet: list[tuple[LegMeasurement, float]],
        base: tuple[tuple[float, ...], ...],
        into: tuple[list[float], list[float], list[float]],
    ) -> None:
        """Append each foot's velocity rows, noise and residual to ``into`` (``feet``: each
        foot's measurement and touchdown variance); keep its residual, its noise and its contact
        point's height.
        """
        rows, noise, residual = into
        s = settings
        wx, wy, wz = point.gyro
        bx, by, bz = point.gyro_bias
        lx, ly, lz = point.local
        ux, uy, uz = self.up
        foot2 = s.foot_noise_mps**2
        extra = s.foot_vertical_noise_mps**2 - foot2
        fixed = (
            s.joint_rate_noise_radps**2,
            s.gyro_sample_noise_radps**2,
            (foot2 + extra * ux * ux, extra * ux * uy, extra * ux * uz,
             extra * uy * ux, foot2 + extra * uy * uy, extra * uy * uz,
             extra * uz * ux, extra * uz * uy, foot2 + extra * uz * uz),
        )  # fmt: skip
        horizontal, vertical = point.noise_scales
        roots = (math.sqrt(horizontal), math.sqrt(vertical))
        for measurement, impact in feet:
            (ex, ey, ez), (rx, ry, rz), _ = measurement.motion
            rows += base[0] + (0.0, -rz, ry) + base[1] + (rz, 0.0, -rx) + base[2] + (-ry, rx, 0.0)
            foot = (
                ex - (wy * rz - wz * ry) - lx - (ry * bz - rz * by),
                ey - (wz * rx - wx * rz) - ly - (rz * bx - rx * bz),
                ez - (wx * ry - wy * rx) - lz - (rx * by - ry * bx),
            )
            self.foot_residuals.append(foot)
            residual += foot
            own = foot_noise(measurement, fixed)
            if roots != (1.0, 1.0) or impact:
                own = scaled(own, roots, (ux, uy, uz), impact)
            self.foot_noises.append(own)
            noise += own
            self.foot_heights.append(point.height + ux * rx + uy * ry + uz * rz)
            self._contact_points.append((rx, ry, rz))

    def _heights(
        self,
        point: Point,
        settings: FilterSettings,
        into: tuple[list[float], list[float], list[float]],
    ) -> None:
        """Append each foot's height row (``r x R₃`` on dθ, 1 on p_z), noise (the ground's
        variance added) and residual (the ground's height less the contact point's) to ``into``.
        """
        rows, noise, residual = into
        grounds = point.grounds
        if grounds is None:
            assert point.ground is not None
            grounds = [(point.ground, 0.0)] * len(self.foot_heights)
        ux, uy, uz = self.up
        floor = settings.height_noise_m**2
        for (rx, ry, rz), height, (ground, variance) in zip(
            self._contact_points, self.foot_heights, grounds
        ):
            rows += (ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux, 1.0)
            residual.append(ground - height)
            noise.append(floor + variance)

    def keep(self, accepted: list[int]) -> np.ndarray:
        """The rows left when only the feet at positions ``accepted`` (of the stacked feet) are
        kept: the orientation's, theirs, their heights', the zero-velocity update's.
        """
        shape = self.layout
        rows = list(range(shape.feet.start))
        for index in accepted:
            rows += range(shape.feet.start + 3 * index, shape.feet.start + 3 * index + 3)
        if shape.heights.stop > shape.heights.start:
            rows += [shape.heights.start + index for index in accepted]
        rows += range(shape.still.start, shape.still.stop)
        return np.array(rows, dtype=np.intp)
