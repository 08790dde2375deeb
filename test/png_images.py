"""Reading the PNG figures the plots write, for tests that look at them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest


def load_png(path: Path) -> np.ndarray:
    """(H, W, 3) RGB floats in [0, 1] of a PNG written by the plots."""
    image = pytest.importorskip("matplotlib.image").imread(path)
    assert image.dtype == np.float32 and image.ndim == 3
    return image[:, :, :3]


def colour_share(image: np.ndarray, colour: str, tolerance: float = 0.06) -> float:
    """The fraction of pixels within ``tolerance`` of a matplotlib colour."""
    rgb = np.array(pytest.importorskip("matplotlib.colors").to_rgb(colour))
    return float((np.abs(image - rgb).max(axis=2) < tolerance).mean())
