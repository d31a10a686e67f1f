"""Calibration-of-uncertainty checks shared by the tests.

A reported standard deviation is *calibrated* when the z-scores
z = (estimate - truth) / sigma_reported over independent seeded runs have unit
RMS.  For n independent standard-normal z, n RMS^2 ~ chi^2(n), so the 99 %
interval of the RMS is

    [sqrt(chi2.ppf(0.005, n) / n), sqrt(chi2.ppf(0.995, n) / n)].

:func:`assert_rms_calibrated` checks that, and also that the interval is tight
enough to reject a sigma wrong by ``FACTOR`` = 1.5 either way (RMS 1/1.5 or
1.5 must fall outside it): a test with too few z-values fails on its own
rather than passing vacuously.  For NEES/NIS-type statistics (a sum of dof
squared z per run, averaged over runs) :func:`assert_nees_calibrated` uses the
chi^2(n dof) interval of the mean in the same way.

``IMUNAV_SIGMA_SCALE`` (e.g. ``1.5`` or ``0.6667``) multiplies every reported
sigma (covariances by its square) before the check: running the tests with it
set shows that they fail when an uncertainty is wrong by that factor.
"""

from __future__ import annotations

import os

import numpy as np
from scipy.stats import chi2

FACTOR = 1.5
LEVEL = 0.99


def sigma_scale() -> float:
    """The factor IMUNAV_SIGMA_SCALE applies to reported sigmas (1 when unset)."""
    return float(os.environ.get("IMUNAV_SIGMA_SCALE", "1"))


def rms_interval(n: int, level: float = LEVEL) -> tuple[float, float]:
    """The ``level`` interval of the RMS of n independent standard-normal values."""
    a = (1.0 - level) / 2.0
    return float(np.sqrt(chi2.ppf(a, n) / n)), float(np.sqrt(chi2.ppf(1.0 - a, n) / n))


def z_scores(estimate, truth, sigma) -> np.ndarray:
    """(estimate - truth) / (sigma * IMUNAV_SIGMA_SCALE), flattened."""
    est, tru, sig = (np.asarray(x, dtype=float) for x in (estimate, truth, sigma))
    return ((est - tru) / (sig * sigma_scale())).ravel()


def assert_rms_calibrated(z, what: str = "z") -> float:
    """Assert RMS(z) lies in the 99 % chi-square interval for len(z) values; returns the RMS.

    ``z`` must already include :func:`sigma_scale` (use :func:`z_scores`)."""
    z = np.asarray(z, dtype=float).ravel()
    assert np.all(np.isfinite(z)), f"{what}: non-finite z-scores"
    n = z.size
    lo, hi = rms_interval(n)
    assert lo > 1 / FACTOR and hi < FACTOR, (
        f"{what}: {n} z-values give the interval [{lo:.3f}, {hi:.3f}], too wide to reject sigma x {FACTOR}")
    rms = float(np.sqrt(np.mean(z**2)))
    assert lo <= rms <= hi, f"{what}: RMS z = {rms:.3f} over {n} values, outside the 99 % interval [{lo:.3f}, {hi:.3f}]"
    return rms


def nees_interval(n_runs: int, dof: int, level: float = LEVEL) -> tuple[float, float]:
    """The ``level`` interval of the mean over n_runs of independent chi^2(dof) values."""
    a = (1.0 - level) / 2.0
    k = n_runs * dof
    return float(chi2.ppf(a, k) / n_runs), float(chi2.ppf(1.0 - a, k) / n_runs)


def assert_nees_calibrated(values, dof: int, what: str = "NEES") -> float:
    """Assert the mean of independent chi^2(dof) statistics lies in its 99 % interval; returns the mean.

    ``values`` are NEES/NIS computed with the reported covariance; they are
    divided here by IMUNAV_SIGMA_SCALE^2.  The interval must exclude
    dof * 1.5^2 and dof / 1.5^2."""
    v = np.asarray(values, dtype=float).ravel() / sigma_scale() ** 2
    assert np.all(np.isfinite(v)), f"{what}: non-finite values"
    lo, hi = nees_interval(v.size, dof)
    assert lo > dof / FACTOR**2 and hi < dof * FACTOR**2, (
        f"{what}: {v.size} values give [{lo:.3f}, {hi:.3f}], too wide to reject sigma x {FACTOR}")
    mean = float(v.mean())
    assert lo <= mean <= hi, (
        f"{what}: mean {mean:.3f} over {v.size} values (dof {dof}) outside the 99 % interval [{lo:.3f}, {hi:.3f}]")
    return mean
