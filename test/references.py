"""Independent references the tests compare against: formulas written by hand from the URDF."""

from __future__ import annotations

import math

import numpy as np


def a1_foot_closed_form(leg: str, q0: float, q1: float, q2: float) -> np.ndarray:
    """The A1 foot [m], base frame: hip + Rx(q0) [(0, +-0.08505, 0) + Ry(q1) ((0,0,-0.2) + Ry(q2)
    (0,0,-0.2))]."""
    front = 1.0 if leg[0] == "F" else -1.0
    left = 1.0 if leg[1] == "L" else -1.0
    # In the thigh's pitch plane (Ry(t) (0, 0, -l) = (-l sin t, 0, -l cos t)):
    x = -0.2 * math.sin(q1) - 0.2 * math.sin(q1 + q2)
    z = -0.2 * math.cos(q1) - 0.2 * math.cos(q1 + q2)
    y = left * 0.08505
    # Roll about x:
    return np.array(
        [
            front * 0.183 + x,
            left * 0.047 + y * math.cos(q0) - z * math.sin(q0),
            y * math.sin(q0) + z * math.cos(q0),
        ]
    )
