"""Shared test fixtures.

Real recordings live outside the repository (``IMUNAV_DATA`` or
``../shared/data``); tests that need them call :func:`data_path`, which skips
with the missing path named when they are absent.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def data_path(*parts: str) -> Path:
    """Path inside the shared data folder, or skip the test naming what is missing."""
    env = os.environ.get("IMUNAV_DATA")
    root = Path(env) if env else ROOT.parent / "shared" / "data"
    p = root.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"shared data not found: {p} (set IMUNAV_DATA to the shared/data folder)")
    return p


@pytest.fixture
def rng():
    import numpy as np

    return np.random.default_rng(20261122)
