"""KF-GINS style text tables (imunav.io.gnss.write_table): the bytes numpy.savetxt writes."""

from __future__ import annotations

import io

import numpy as np
import pytest

from imunav.io.gnss import write_table


@pytest.mark.parametrize("fmt", ["%-15.9f", "%.17g", "%.6e"])
def test_write_table_writes_what_savetxt_writes(tmp_path, fmt):
    """Blocks of rows formatted at once give numpy.savetxt's bytes: every magnitude, signed zero, NaN, inf, and a
    table longer than one block."""
    rng = np.random.default_rng(0)
    a = rng.standard_normal((45_001, 5)) * 10.0 ** rng.integers(-12, 12, (45_001, 5))
    a[3, 2], a[5, 1], a[7, 0] = np.nan, -np.inf, -0.0
    ref = io.BytesIO()
    np.savetxt(ref, a, fmt=fmt, delimiter=" ")
    assert write_table(tmp_path / "t.txt", [a[:, :2], *a[:, 2:].T], fmt=fmt).read_bytes() == ref.getvalue()
