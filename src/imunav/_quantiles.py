"""Quantiles of the χ² and standard normal distributions, from ``scipy.special``.

``scipy.stats`` takes about a second to import; the gates, consistency bands and fault thresholds of
imunav need only four quantile functions, and ``scipy.special`` (a tenth of that) has them.  Each
function returns what its ``scipy.stats`` counterpart returns for valid arguments, bit for bit (it is the
same special function that ``scipy.stats`` evaluates; ``tests/test_quantiles.py`` checks it):

    χ²_p(k) = 2 P⁻¹(k/2, p)       (P⁻¹ the inverse regularised lower incomplete gamma function)
    χ²_{1−α}(k) = chdtri(k, α)    (upper tail)
    z_{1−α} = −Φ⁻¹(α)             (Φ⁻¹ the standard normal quantile)

Reference: M. Abramowitz and I. A. Stegun, *Handbook of Mathematical Functions*, 1964, §26.4 (χ²) and
§26.2 (normal).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import special

__all__ = ["chi2_ppf", "chi2_isf", "norm_ppf", "norm_isf"]


def chi2_ppf(p: ArrayLike, k: ArrayLike) -> float | NDArray[np.float64]:
    """Lower-tail quantile of χ²(k): the x with P(X ≤ x) = p (``scipy.stats.chi2.ppf``).

    Parameters
    ----------
    p : float or array_like
        Probability in [0, 1].
    k : float or array_like
        Degrees of freedom (> 0).

    Returns
    -------
    float or numpy.ndarray
        The quantile (0 at p = 0, inf at p = 1).
    """
    return 2.0 * special.gammaincinv(np.asarray(k, dtype=float) / 2.0, p)


def chi2_isf(alpha: ArrayLike, k: ArrayLike) -> float | NDArray[np.float64]:
    """Upper-tail quantile of χ²(k): the x with P(X > x) = α (``scipy.stats.chi2.isf``).

    Parameters
    ----------
    alpha : float or array_like
        Tail probability in [0, 1].
    k : float or array_like
        Degrees of freedom (> 0).

    Returns
    -------
    float or numpy.ndarray
        The quantile (inf at α = 0).
    """
    return special.chdtri(k, alpha)


def norm_ppf(p: ArrayLike) -> float | NDArray[np.float64]:
    """Standard normal quantile Φ⁻¹(p) (``scipy.stats.norm.ppf``).

    Parameters
    ----------
    p : float or array_like
        Probability in [0, 1].

    Returns
    -------
    float or numpy.ndarray
        The quantile.
    """
    return special.ndtri(p)


def norm_isf(alpha: ArrayLike) -> float | NDArray[np.float64]:
    """Standard normal upper-tail quantile −Φ⁻¹(α) (``scipy.stats.norm.isf``).

    Parameters
    ----------
    alpha : float or array_like
        Tail probability in [0, 1].

    Returns
    -------
    float or numpy.ndarray
        The quantile.
    """
    return -special.ndtri(alpha)
