"""vqf on the shared BROAD trials, for the attitude tests that compare against it (a test helper; vqf is a test
extra, skipped where it is not installed)."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.attitude.metrics import AttitudeRmse, attitude_rmse
from imunav.io.broad import from_enu, load_broad


def vqf_errors(files, dim: str = "9D") -> list[AttitudeRmse]:
    """The attitude errors of vqf with its defaults (``dim``: "9D" or "6D") against each trial's optical reference,
    over its movement phases; vqf's Earth frame is ENU, converted to NED by :func:`imunav.io.broad.from_enu`."""
    vqf = pytest.importorskip("vqf")
    out = []
    for f in files:
        tr = load_broad(f)
        g, a, m = (np.ascontiguousarray(x) for x in (tr.imu.gyro, tr.imu.accel, tr.imu.mag))
        q = from_enu(vqf.VQF(1.0 / tr.fs).updateBatch(g, a, m)[f"quat{dim}"])
        out.append(attitude_rmse(q, tr.q_ref_nb, tr.movement))
    return out
