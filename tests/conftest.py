"""Shared test fixtures.

Real recordings live outside the repository (``IMUNAV_DATA`` or
``../shared/data``); tests that need them use ``from shared_data import
data_path``, which skips with the missing path named when they are absent.
"""

from __future__ import annotations

import pytest

from shared_data import ROOT, data_path  # noqa: E402,F401  (re-exported for old imports)


@pytest.fixture
def rng():
    import numpy as np

    return np.random.default_rng(20261122)
