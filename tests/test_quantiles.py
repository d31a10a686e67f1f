"""imunav._quantiles returns what scipy.stats returns, bit for bit, without importing scipy.stats."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import chi2, norm

from imunav._quantiles import chi2_isf, chi2_ppf, norm_isf, norm_ppf

RNG = np.random.default_rng(20261202)
P = np.concatenate([RNG.uniform(0.0, 1.0, 20_000), 10.0 ** RNG.uniform(-15, -1, 5_000), [0.0, 1.0, 0.5]])
K = np.concatenate([RNG.integers(1, 400, 25_000).astype(float), [1.0, 3.0, 6.0]])


@pytest.mark.parametrize(("ours", "theirs"), [(chi2_ppf, chi2.ppf), (chi2_isf, chi2.isf)])
def test_chi2_quantiles_equal_scipy_stats(ours, theirs):
    assert np.array_equal(ours(P, K), theirs(P, K))
    assert ours(0.05, 3) == theirs(0.05, 3)


@pytest.mark.parametrize(("ours", "theirs"), [(norm_ppf, norm.ppf), (norm_isf, norm.isf)])
def test_normal_quantiles_equal_scipy_stats(ours, theirs):
    assert np.array_equal(ours(P), theirs(P))


def test_filters_gates_do_not_import_scipy_stats():
    code = ("import sys, imunav.filters, imunav.attitude, imunav.ins.zupt; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr
