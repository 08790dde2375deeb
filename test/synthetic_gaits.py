"""Synthetic gaits whose true stance intervals the tests know, written from the gait definitions,
not from the implementation: each leg touches down at ``(offset + k) * period``, stays on a fixed
foothold for ``duty * period``, then swings to the next foothold (horizontal cosine blend,
vertical ``clearance * sin``) while the body moves at ``speed``. The ground is a plane inclined a
few degrees, not at z = 0, and the foot frame sits a foot radius above it; stamps jitter;
positions get Gaussian noise."""

from __future__ import annotations

import math

import numpy as np

PHASES = {  # touchdown phase of FR, FL, RR, RL (cycles); walk: lateral sequence LH, LF, RH, RF
    "trot": (0.0, 0.5, 0.5, 0.0),
    "pace": (0.0, 0.5, 0.0, 0.5),
    "bound": (0.0, 0.0, 0.5, 0.5),
    "pronk": (0.0, 0.0, 0.0, 0.0),
    "walk": (0.0, 0.5, 0.75, 0.25),
}


DUTY = {"trot": 0.5, "pace": 0.5, "bound": 0.4, "pronk": 0.4, "walk": 0.75}


HIPS_XY = np.array([[0.18, -0.13], [0.18, 0.13], [-0.18, -0.13], [-0.18, 0.13]])


PERIOD_S = 0.4731  # not a multiple of any sampling interval, so events fall all over the grid


CLEARANCE_M = 0.07


FOOT_RADIUS_M = 0.02


SLOPE_DEG = (3.0, 1.0)  # about x and y


GROUND_Z0_M = 0.31


NOISE_M = 0.0005


def synthetic(
    gait: str,
    speed: float,
    rate_hz: float,
    seconds: float = 8.0,
    seed: int = 0,
    pause: tuple[float, float] | None = None,
    phases: tuple[float, float, float, float] | None = None,
    duty: float | None = None,
    slip_mps: float = 0.0,
):
    """(stamps [s], world feet (N, 4, 3) [m], true stances per leg [(t_on, t_off)] [s from the
    first stamp]).

    ``pause=(at, length)`` [s] freezes the gait from ``at`` for ``length`` (the true stances then
    hold for gait time, not for the stamps). ``phases`` (FR, FL, RR, RL touchdowns [cycles]) and
    ``duty`` replace the gait's own; ``slip_mps`` slides each stance foot forward at that speed
    through its foothold (as retargeted motion and slipping robots do), the swing taking it back.
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    times = np.arange(0.0, seconds, dt)
    times[1:] += rng.uniform(-0.2, 0.2, times.size - 1) * dt
    duty = duty or DUTY[gait]
    pattern = phases or PHASES[gait]
    swing = (1.0 - duty) * PERIOD_S
    a, b = (math.tan(math.radians(d)) for d in SLOPE_DEG)
    radius_dz = FOOT_RADIUS_M * math.sqrt(
        1 + a * a + b * b
    )  # sphere centre above an inclined plane
    feet = np.empty((times.size, 4, 3))
    truth = []
    stamps = times
    if pause is not None:
        at, length = pause
        times = np.where(times < at, times, np.maximum(at, times - length))
    for leg in range(4):
        touchdowns = (pattern[leg] + np.arange(-2, int(seconds / PERIOD_S) + 3)) * PERIOD_S
        holds = HIPS_XY[leg, 0] + speed * (touchdowns + 0.5 * duty * PERIOD_S)
        k = np.searchsorted(touchdowns, times, side="right") - 1
        since = times - touchdowns[k]
        x, lift = holds[k].copy(), np.zeros(times.size)
        swinging = since > duty * PERIOD_S
        s = (since[swinging] - duty * PERIOD_S) / swing
        blend = (1 - np.cos(np.pi * s)) / 2
        x[swinging] += (holds[k[swinging] + 1] - holds[k[swinging]]) * blend
        half_slide = 0.5 * slip_mps * duty * PERIOD_S
        x += np.where(swinging, 0.0, slip_mps * since - half_slide)
        x[swinging] += half_slide * (1 - 2 * blend)
        lift[swinging] = CLEARANCE_M * np.sin(np.pi * s)
        y = np.full(times.size, HIPS_XY[leg, 1])
        feet[:, leg] = np.column_stack((x, y, GROUND_Z0_M + a * x + b * y + radius_dz + lift))
        truth.append([(on, on + duty * PERIOD_S) for on in touchdowns])
    return stamps + 1234.5, feet + rng.normal(0.0, NOISE_M, feet.shape), truth


SLOW_RISE_S = 0.01
"""[s] How long a walk's foot rises slowly from rest before its swing proper (the contact
family's walks: 0.24 mm at 10 ms, then ~20x steeper)."""


def slow_rise(after_s: np.ndarray) -> np.ndarray:
    """[m] A walk's foot height ``after_s`` [s] after it left (0 before): 2 m/s^2 t^2 for
    :data:`SLOW_RISE_S` (0.2 mm), then 24 m/s^2 on top of 40 mm/s, up to 60 mm."""
    late = after_s - SLOW_RISE_S
    lift = np.where(late < 0.0, 2.0 * after_s**2, 2e-4 + 0.04 * late + 24.0 * late**2)
    return np.where(after_s > 0.0, np.clip(lift, 0.0, 0.06), 0.0)


def slow_rise_walk(
    noise_m: float, seconds: float = 12.0, seed: int = 3
) -> tuple[np.ndarray, np.ndarray, list[list[float]]]:
    """(stamps [s], world feet (N, 4, 3) [m], true liftoff times [s] per leg) of a walk at 500 Hz
    (period 0.6 s, duty 0.75) whose feet rise as :func:`slow_rise` and land as its mirror image,
    with ``noise_m`` [m] of Gaussian noise; each leg's events 0.7 ms later than the previous
    leg's, off the sampling grid."""
    period, stance = 0.6, 0.45
    stamps = np.arange(0.0, seconds, 0.002)
    feet = np.zeros((stamps.size, 4, 3))
    feet[:, :, :2] = HIPS_XY
    liftoffs = []
    for leg, phase in enumerate(PHASES["walk"]):
        shift = phase * period + 0.0007 * leg
        since = np.mod(stamps - shift, period) - stance
        feet[:, leg, 2] = np.minimum(slow_rise(since), slow_rise(period - stance - since))
        downs = np.arange(-1.0, seconds / period + 1.0) * period + shift
        liftoffs.append([d + stance for d in downs if d > 0.1 and d + stance < seconds - 0.1])
    noise = np.random.default_rng(seed).normal(0.0, noise_m, feet.shape)
    return stamps, feet + noise, liftoffs
