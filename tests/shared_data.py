"""Locating the shared real-data folder from tests.

Import as ``from shared_data import data_path`` (not from ``conftest``: test
sub-folders have conftest files of their own, and the name would clash).
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
