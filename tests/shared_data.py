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


def doc_pages() -> list[Path]:
    """The pages whose examples run in the tests and whose figures are checked: the README (the front page) and
    the user guide (``docs/guide/*.md``)."""
    return [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]


def doc_text() -> str:
    """The README and the user guide as one text: where a quoted figure must still be found."""
    return "\n".join(p.read_text(encoding="utf-8") for p in doc_pages())
