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
    code = ("import sys, imunav.filters, imunav.attitude, imunav.ins.zupt, imunav.ins.gins, imunav.cli.gins; "
            "print('scipy.stats' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stderr


def test_no_module_of_the_package_imports_scipy_stats():
    import ast
    from pathlib import Path

    src = Path(__file__).resolve().parents[1] / "src" / "imunav"
    found = []
    for f in sorted(src.rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n == "scipy.stats" or n.startswith("scipy.stats.") for n in names) or (
                    isinstance(node, ast.ImportFrom) and node.module == "scipy"
                    and any(a.name == "stats" for a in node.names)):
                found.append(f"{f.relative_to(src)}:{node.lineno}")
    assert not found, f"use imunav._quantiles instead of scipy.stats (a second at import): {found}"
