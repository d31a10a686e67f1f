"""Closed-form Allan variances of the IEEE-952 noise terms and of a Gauss-Markov process.

One implementation shared by :mod:`imunav.noise` (the noise-term fit and
:meth:`NoiseFit.model_avar`) and :mod:`imunav.sim` (the error models' Allan
curves), so the two cannot disagree (IEEE Std 952-1997, Annex C; the Gauss-Markov form as in
W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065, 2008, and
N. El-Sheimy, H. Hou, X. Niu, "Analysis and modeling of inertial sensors using Allan variance",
IEEE Trans. Instrum. Meas. 57(1), 2008)::

    quantisation      Q:  3 Q^2 / tau^2
    white (ARW/VRW)   N:  N^2 / tau
    flicker (BI)      B:  (2 ln2 / pi) B^2
    rate random walk  K:  K^2 tau / 3
    rate ramp         R:  R^2 tau^2 / 2
    Gauss-Markov (sigma, T), u = tau / T:
        (2 sigma^2 T / tau) [1 - (3 - 4 e^-u + e^-2u) / (2u)]

For the Gauss-Markov bracket f(u) = 1 - (3 - 4 e^-u + e^-2u)/(2u) the direct
form cancels catastrophically for small u (f ~ u^2/3, so the relative error of
the direct form grows like eps/u^2).  Expanding e^-u and e^-2u,

    3 - 4 e^-u + e^-2u = sum_{k>=1} (-1)^k (2^k - 4) u^k / k!

whose k = 1 term is 2u and k = 2 term vanishes, so

    f(u) = sum_{k>=3} (-1)^(k+1) (2^k - 4) / (2 k!) u^(k-1)
         = u^2/3 - u^3/4 + 7 u^4/60 - u^5/24 + ...

Below u = 1/2 the series is summed to k = 24 (the first omitted term is below
(2u)^25/25! < 1e-25 of f's scale); above it the direct form, whose
cancellation costs at most eps / f(1/2) ~ 4e-15 relative.  Both branches agree
with 50-digit values to 1e-13 relative for u in [1e-8, 1e3] (tested).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError

__all__ = [
    "BI_FACTOR",
    "IEEE952_TERMS",
    "gauss_markov",
    "gauss_markov_bracket",
    "gauss_markov_unit",
    "ieee952",
    "ieee952_term",
]

#: sqrt(2 ln2 / pi): flat Allan deviation of flicker (bias-instability) noise per unit B
BI_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: the IEEE-952 power-law terms, in the order of their tau exponent
IEEE952_TERMS = ("Q", "N", "B", "K", "R")

_SERIES_MAX_U = 0.5
_K_MAX = 24
# coefficient of u^(k-1) in f(u), k = 3 .. _K_MAX (highest power first, for Horner)
_F_COEFS = tuple((-1.0) ** (k + 1) * (2.0**k - 4.0) / (2.0 * math.factorial(k)) for k in range(_K_MAX, 2, -1))


def ieee952_term(name: str, tau: ArrayLike) -> NDArray[np.float64]:
    """Allan variance of one IEEE-952 term per unit squared coefficient (Q^2, N^2, B^2, K^2 or R^2).

    ``Q: 3/τ²``, ``N: 1/τ``, ``B: 2 ln2/π``, ``K: τ/3``, ``R: τ²/2`` (IEEE Std 952-1997, Annex C).

    Parameters
    ----------
    name : {"Q", "N", "B", "K", "R"}
        The term: quantisation, white noise (angle / velocity random walk), flicker (bias instability),
        rate random walk, rate ramp.
    tau : array_like
        Averaging time(s) τ, s, > 0.

    Returns
    -------
    numpy.ndarray
        σ²(τ) / c² for the term's coefficient c, same shape as ``tau``; multiplied by c² (c in SI: N in
        rad/√s, B in rad/s, ...) it gives the Allan variance in (rad/s)² or (m/s²)².

    Raises
    ------
    InvalidInputError
        If ``name`` is not one of the five terms.
    """
    tau = np.asarray(tau, dtype=float)
    if name == "Q":
        return 3.0 / tau**2
    if name == "N":
        return 1.0 / tau
    if name == "B":
        return np.full_like(tau, BI_FACTOR**2)
    if name == "K":
        return tau / 3.0
    if name == "R":
        return tau**2 / 2.0
    raise InvalidInputError(f"unknown IEEE-952 term {name!r}; terms are {IEEE952_TERMS}")


def ieee952(tau: ArrayLike, *, Q: float = 0.0, N: float = 0.0, B: float = 0.0, K: float = 0.0,
            R: float = 0.0) -> NDArray[np.float64]:
    """Sum of the IEEE-952 terms: 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.

    IEEE Std 952-1997, Annex C (the terms are independent, so their Allan variances add).

    Parameters
    ----------
    tau : array_like
        Averaging time(s) τ, s, > 0.
    Q : float
        Quantisation noise, rad (gyro) or m/s (accelerometer).
    N : float
        White noise: angle random walk, rad/√s, or velocity random walk, m/s/√s.
    B : float
        Bias instability (flicker) coefficient, rad/s or m/s².
    K : float
        Rate random walk, rad/s/√s, or acceleration random walk, m/s²/√s.
    R : float
        Rate ramp, rad/s², or m/s³.

    Returns
    -------
    numpy.ndarray
        The model Allan variance σ²(τ), (rad/s)² or (m/s²)², same shape as ``tau``.
    """
    tau = np.asarray(tau, dtype=float)
    out = np.zeros_like(tau)
    for name, c in zip(IEEE952_TERMS, (Q, N, B, K, R)):
        if c != 0.0:
            out = out + c**2 * ieee952_term(name, tau)
    return out


def gauss_markov_bracket(u: ArrayLike) -> NDArray[np.float64]:
    """f(u) = 1 - (3 - 4 e^-u + e^-2u) / (2u), accurate to ~1e-15 relative for every u > 0 (f(0) = 0).

    The series of the module docstring below u = 1/2, the direct form (with ``expm1``) above.

    Parameters
    ----------
    u : array_like
        Ratio τ / T of averaging time to correlation time, >= 0.

    Returns
    -------
    numpy.ndarray
        f(u), same shape as ``u``.

    Raises
    ------
    InvalidInputError
        If some ``u`` is negative.
    """
    u = np.asarray(u, dtype=float)
    if np.any(u < 0):
        raise InvalidInputError("gauss_markov_bracket: u = tau / T must be >= 0")
    small = u < _SERIES_MAX_U
    us = np.where(small, u, 0.0)
    poly = np.zeros_like(us)
    for c in _F_COEFS:
        poly = poly * us + c
    series = poly * us * us  # lowest power is u^2
    ub = np.where(small, 1.0, u)  # placeholder where the series is used
    direct = 1.0 - (-4.0 * np.expm1(-ub) + np.expm1(-2.0 * ub)) / (2.0 * ub)
    return np.where(small, series, direct)


def gauss_markov_unit(tau: ArrayLike, T: float) -> NDArray[np.float64]:
    """Allan variance of a first-order Gauss-Markov process per unit variance sigma^2: (2T/tau) f(tau/T).

    Parameters
    ----------
    tau : array_like
        Averaging time(s) τ, s, > 0.
    T : float
        Correlation time, s, finite and > 0.

    Returns
    -------
    numpy.ndarray
        σ²_A(τ) / σ², dimensionless, same shape as ``tau`` (0 at τ = 0).

    Raises
    ------
    InvalidInputError
        If ``T`` is not finite and positive, or some τ is negative.
    """
    if not (np.isfinite(T) and T > 0):
        raise InvalidInputError("a Gauss-Markov term needs a finite positive correlation time T")
    tau = np.asarray(tau, dtype=float)
    u = tau / T
    f = gauss_markov_bracket(u)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(u > 0, 2.0 * f / np.where(u > 0, u, 1.0), 0.0)


def gauss_markov(tau: ArrayLike, sigma: float, T: float) -> NDArray[np.float64]:
    """Allan variance of a first-order Gauss-Markov process of standard deviation sigma and correlation time T.

    σ²_A(τ) = (2σ²T/τ) [1 − (T/2τ)(3 − 4 e^(−τ/T) + e^(−2τ/T))] (El-Sheimy et al. 2008).

    Parameters
    ----------
    tau : array_like
        Averaging time(s) τ, s, > 0.
    sigma : float
        Standard deviation of the process (steady state), in the sensor's SI unit (rad/s or m/s²).
    T : float
        Correlation time, s, finite and > 0.

    Returns
    -------
    numpy.ndarray
        σ²_A(τ), in the square of ``sigma``'s unit, same shape as ``tau``.

    Raises
    ------
    InvalidInputError
        If ``T`` is not finite and positive, or some τ is negative.
    """
    return sigma**2 * gauss_markov_unit(tau, T)
