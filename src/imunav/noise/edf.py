"""Equivalent degrees of freedom and confidence intervals of the Allan family.

* Noise identification by the lag-1 autocorrelation of the (decimated,
  differenced) series: W. J. Riley and C. A. Greenhall, "Power law noise
  identification using the lag 1 autocorrelation", EFTF 2004.
* EDF of ADEV / OADEV / MDEV / TDEV / HDEV / OHDEV: C. A. Greenhall and
  W. J. Riley, "Uncertainty of stability variances based on finite
  differences", 35th PTTI meeting, 2003 (eqs. 7-13 and Tables 1-3).
* EDF of TOTDEV: NIST SP 1065 (Riley 2008), Table 7; other noise types use the
  simple bound of SP 1065 eq. (49).
* Chi-squared interval (SP 1065 eq. 48):
  ``sigma^2 * edf / chi2_{(1+p)/2} <= sigma_true^2 <= sigma^2 * edf / chi2_{(1-p)/2}``.

Noise exponent alpha is that of the *rate* (frequency) PSD, S_y ~ f^alpha:
+2 white phase (quantization), 0 white rate (angle/velocity random walk),
-1 flicker rate (bias instability), -2 random-walk rate (rate random walk).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.special import comb

from imunav._quantiles import chi2_ppf
from imunav.noise._allan_kernels import detrend_quadratic, lag1_acf

__all__ = ["edf_greenhall", "edf_totdev", "noise_id_lag1", "chi2_interval", "ONE_SIGMA"]

#: probability mass within +-1 sigma of a normal distribution
ONE_SIGMA = math.erf(1.0 / math.sqrt(2.0))


def _sw(t: float, alpha: int) -> float:
    # Greenhall & Riley eq. (7): generalized autocovariance of the phase
    # for the power-law noise with rate exponent alpha (constant factors drop out).
    a = abs(t)
    if alpha == 2:
        return -a
    if alpha == 0:
        return a**3
    if alpha == -2:
        return a**5
    if alpha == -4:
        return a**7
    if a == 0.0:
        return 0.0
    if alpha == 1:
        return t * t * math.log(a)
    if alpha == -1:
        return t**4 * math.log(a)
    if alpha == -3:
        return t**6 * math.log(a)
    raise ValueError(alpha)


def _sx(t: float, f: float, alpha: int) -> float:
    # eq. (8): effect of the m-sample averaging filter (f = F); f = inf is the limit.
    if math.isinf(f):
        return _sw(t, alpha + 2)
    return f * f * (2.0 * _sw(t, alpha) - _sw(t - 1.0 / f, alpha) - _sw(t + 1.0 / f, alpha))


_BINOM = {1: (2.0, -1.0), 2: (6.0, -4.0, 1.0), 3: (20.0, -15.0, 6.0, -1.0)}


def _sz(t: float, f: float, alpha: int, d: int) -> float:
    # eq. (9): d-th difference of sx (central binomial weights).
    w = _BINOM[d]
    s = w[0] * _sx(t, f, alpha)
    for k in range(1, d + 1):
        s += w[k] * (_sx(t - k, f, alpha) + _sx(t + k, f, alpha))
    return s


def _basic_sum(jj: int, mm: float, s: float, f: float, alpha: int, d: int) -> float:
    # eq. (10)
    tot = _sz(0.0, f, alpha, d) ** 2
    tot += (1.0 - jj / mm) * _sz(jj / s, f, alpha, d) ** 2
    for j in range(1, int(jj)):
        tot += 2.0 * (1.0 - j / mm) * _sz(j / s, f, alpha, d) ** 2
    return tot


# Greenhall & Riley Tables 1-3 (a0, a1) indexed [alpha][d]
_T1 = {2: {1: (2 / 3, 1 / 3), 2: (7 / 9, 1 / 2), 3: (22 / 25, 2 / 3)},
       1: {1: (0.840, 0.345), 2: (0.997, 0.616), 3: (1.141, 0.843)},
       0: {1: (1.079, 0.368), 2: (1.033, 0.607), 3: (1.184, 0.848)},
       -1: {2: (1.048, 0.534), 3: (1.180, 0.816)},
       -2: {2: (1.302, 0.535), 3: (1.175, 0.777)},
       -3: {3: (1.194, 0.703)},
       -4: {3: (1.489, 0.702)}}
_T2 = {2: {1: (3 / 2, 1 / 2), 2: (35 / 18, 1.0), 3: (231 / 100, 3 / 2)},
       1: {1: (78.6, 25.2), 2: (790.0, 410.0), 3: (9950.0, 6520.0)},
       0: {1: (2 / 3, 1 / 6), 2: (2 / 3, 1 / 3), 3: (7 / 9, 1 / 2)},
       -1: {2: (0.852, 0.375), 3: (0.997, 0.617)},
       -2: {2: (1.079, 0.368), 3: (1.033, 0.607)},
       -3: {3: (1.053, 0.553)},
       -4: {3: (1.302, 0.535)}}
_T3 = {1: (6.0, 4.0), 2: (15.23, 12.0), 3: (47.8, 40.0)}


@lru_cache(maxsize=4096)
def edf_greenhall(alpha: int, d: int, m: int, n: int, overlapping: bool, modified: bool) -> float:
    """EDF of a finite-difference stability variance (Greenhall & Riley 2003).

    Parameters
    ----------
    alpha : int
        Rate-PSD exponent (+2 .. -4); needs ``alpha + 2 d > 1``.
    d : int
        Difference order: 2 Allan family, 3 Hadamard family.
    m : int
        Cluster size (tau = m tau0).
    n : int
        Number of phase points.
    overlapping, modified : bool
        Estimator stride (1 vs m) and filter (modified = extra m-average).

    Returns
    -------
    float
        The equivalent degrees of freedom; NaN when the record is shorter than one estimator term.

    Raises
    ------
    ValueError
        If ``alpha + 2 d <= 1`` (the variance does not converge for that noise).
    """
    if alpha + 2 * d <= 1:
        raise ValueError(f"Greenhall EDF needs alpha + 2d > 1 (alpha={alpha}, d={d})")
    f = 1.0 if modified else float(m)
    s = float(m) if overlapping else 1.0
    length = m / f + m * d
    if n < length:
        return float("nan")
    mm = 1.0 + math.floor(s * (n - length) / m)
    jj = min(mm, (d + 1) * s)
    jmax = 100
    r = mm / s
    if modified:
        if jj <= jmax:
            inv = _basic_sum(int(jj), mm, s, 1.0, alpha, d) / (_sz(0.0, 1.0, alpha, d) ** 2 * mm)
        elif r > d + 1:
            a0, a1 = _T1[alpha][d]
            inv = (a0 - a1 / r) / r
        else:
            mp = jmax / r
            inv = _basic_sum(jmax, jmax, mp, 1.0, alpha, d) / (_sz(0.0, 1.0, alpha, d) ** 2 * jmax)
        return 1.0 / inv
    if alpha <= 0:
        if jj <= jmax:
            fp = float(m) if m * (d + 1) <= jmax else math.inf
            inv = _basic_sum(int(jj), mm, s, fp, alpha, d) / (_sz(0.0, fp, alpha, d) ** 2 * mm)
        elif r > d + 1:
            a0, a1 = _T2[alpha][d]
            inv = (a0 - a1 / r) / r
        else:
            mp = jmax / r
            inv = _basic_sum(jmax, jmax, mp, math.inf, alpha, d) / (_sz(0.0, math.inf, alpha, d) ** 2 * jmax)
        return 1.0 / inv
    if alpha == 1:
        if jj <= jmax:
            inv = _basic_sum(int(jj), mm, s, float(m), 1, d) / (_sz(0.0, float(m), 1, d) ** 2 * mm)
        elif r > d + 1:
            a0, a1 = _T2[1][d]
            b0, b1 = _T3[d]
            inv = (a0 - a1 / r) / ((b0 + b1 * math.log(m)) ** 2 * r)
        else:
            mp = jmax / r
            b0, b1 = _T3[d]
            inv = _basic_sum(jmax, jmax, mp, mp, 1, d) / ((b0 + b1 * math.log(m)) ** 2 * jmax)
        return 1.0 / inv
    # alpha == 2, unmodified
    k = math.ceil(r)
    a0 = comb(4 * d, 2 * d) / comb(2 * d, d) ** 2
    if k <= d:
        # eq. (13) of the paper for very short records: exact finite sum
        inv = _basic_sum(int(jj), mm, s, float(m), 2, d) / (_sz(0.0, float(m), 2, d) ** 2 * mm)
        return 1.0 / inv
    return 1.0 / ((a0 - (d / 2.0) / r) / mm)


def edf_totdev(n: int, m: int, alpha: int) -> float:
    """EDF of the total deviation, NIST SP 1065 Table 7.

    ``edf = b (n - 1) / m - c`` (at least 1) with (b, c) = (1.50, 0), (1.17, 0.22), (0.93, 0.36) for white,
    flicker and random-walk rate noise; for white / flicker phase noise (not tabulated) the overlapping-Allan
    EDF is used, which is conservative since TOTDEV has at least its degrees of freedom.

    Parameters
    ----------
    n : int
        Number of phase points.
    m : int
        Cluster size (tau = m tau0).
    alpha : int
        Rate-PSD exponent of the dominant noise.

    Returns
    -------
    float
        The equivalent degrees of freedom.
    """
    table = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}
    if alpha in table:
        b, c = table[alpha]
        return max(b * (n - 1) / m - c, 1.0)
    # white / flicker phase: treat like the overlapping Allan (conservative)
    return edf_greenhall(alpha, 2, m, n, True, False)


def _lag1(z: np.ndarray) -> float:
    return float(lag1_acf(np.ascontiguousarray(z, dtype=np.float64)))


def noise_id_lag1(x: np.ndarray, m: int, dmax: int = 2, max_points: int = 1 << 14) -> int | None:
    """Dominant power-law noise at cluster size m from phase data (Riley & Greenhall 2004).

    The phase is decimated by m, a quadratic trend removed, and it is
    differenced until the lag-1 autocorrelation r1 gives delta = r1/(1+r1) <
    0.25 (or dmax differences); then alpha = 2 - round(2 delta) - 2 d.

    Parameters
    ----------
    x : numpy.ndarray, shape (N,)
        Phase (integrated rate: rad for a gyro, m/s for an accelerometer).
    m : int
        Cluster size, samples.
    dmax : int
        Largest number of differences.
    max_points : int
        At most this many decimated points are used (the start of the record).

    Returns
    -------
    int or None
        The rate-PSD exponent alpha (+2 white phase ... -2 random-walk rate), or None when fewer than 30
        decimated points are available.
    """

    z = np.ascontiguousarray(x[::m][:max_points], dtype=np.float64)
    if z.size < 30:
        return None
    z = detrend_quadratic(z)
    d = 0
    while True:
        r1 = _lag1(z)
        delta = r1 / (1.0 + r1) if r1 > -1.0 else -0.5
        if delta < 0.25 or d >= dmax:
            return int(-round(2.0 * delta) - 2 * d + 2)
        z = np.diff(z)
        d += 1


def chi2_interval(dev: np.ndarray, edf: np.ndarray, ci: float) -> tuple[np.ndarray, np.ndarray]:
    """Chi-squared confidence interval of a deviation (SP 1065 eq. 48).

    ``lo = dev sqrt(edf / chi2_{(1+ci)/2}(edf))``, ``hi = dev sqrt(edf / chi2_{(1-ci)/2}(edf))``.

    Parameters
    ----------
    dev : array_like
        Estimated deviation(s).
    edf : array_like
        Equivalent degrees of freedom, broadcasting with ``dev``.
    ci : float
        Two-sided confidence level in (0, 1), e.g. :data:`ONE_SIGMA` (0.683).

    Returns
    -------
    lo, hi : numpy.ndarray
        Lower and upper bounds, in the unit of ``dev`` (NaN where ``edf`` is NaN).
    """
    dev = np.asarray(dev, dtype=float)
    edf = np.asarray(edf, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        lo = dev * np.sqrt(edf / chi2_ppf(0.5 + ci / 2.0, edf))
        hi = dev * np.sqrt(edf / chi2_ppf(0.5 - ci / 2.0, edf))
    return lo, hi
