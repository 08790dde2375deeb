"""The contact family (test/contact_runs.py) for the tests of this folder: every run, clean and
with sensor noise, simulated once per checkout (pytest's cache folder) and loaded once per
session."""

from __future__ import annotations

from pathlib import Path

import pytest
from contact_runs import ContactRun, contact_runs, with_noise

NOISE_SEED = 7
"""The seed of every run's noisy twin."""


@pytest.fixture(scope="session")
def family(request: pytest.FixtureRequest) -> dict[str, ContactRun]:
    """Every run, clean and noisy, simulated once per checkout (pytest's cache folder)."""
    folder = Path(request.config.cache.mkdir("contact_runs"))
    clean = contact_runs(folder)
    return {**clean, **{f"{n}+noise": with_noise(run, NOISE_SEED) for n, run in clean.items()}}
