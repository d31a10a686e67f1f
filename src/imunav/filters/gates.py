"""Innovation gates: which channels of a measurement an update may use.

* :func:`gate_channels` - the per-channel normalised-innovation gate of
  Akgün (2002, eqs. 4.14-4.19; Hajiyev's robust KF): with
  ``ν̃ = S^{-1/2} ν`` (``S`` is a *covariance*), channel i is used when
  ``|ν̃_i| < m``.
* :func:`isolate_channels` - a χ² test on the NIS of the whole measurement
  followed by sequential isolation (Baarda's w-test data snooping).
* :func:`nis_gate` - vector χ² gate: the whole measurement is rejected when
  ``νᵀS⁻¹ν > χ²_{1−α}(m)``.

The robust updates that use them, and the discussion of which gate suits
which fault, are in :mod:`imunav.filters.robust`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._quantiles import chi2_isf
from imunav.errors import InvalidInputError
from imunav.filters._common import as_covariance, as_vector

__all__ = ["gate_channels", "isolate_channels", "isolation_thresholds", "nis_gate"]

Array = NDArray[np.float64]


def gate_channels(normalized: ArrayLike, m: float = 2.0) -> NDArray[np.bool_]:
    """Per-channel gate: accept channel i when ``|ν̃_i| < m`` (Akgün 2002, eq. 4.17).

    Parameters
    ----------
    normalized : array_like, shape (m,) or (N, m)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` (dimensionless, unit variance under the
        filter's model).
    m : float, optional
        Gate half-width in standard deviations, > 0 (default 2).

    Returns
    -------
    numpy.ndarray of bool, same shape as ``normalized``
        True where the channel is accepted (``|ν̃_i| < m``).

    Raises
    ------
    InvalidInputError
        If ``m`` is not > 0.
    """
    if not m > 0:
        raise InvalidInputError(f"gate m must be > 0, got {m}")
    return np.abs(np.asarray(normalized, dtype=np.float64)) < m


def isolation_thresholds(m: int, alpha: float = 1e-3) -> Array:
    """χ²(k) upper-α points for k = 1..m, used by :func:`isolate_channels`.

    Parameters
    ----------
    m : int
        Largest number of degrees of freedom (the measurement dimension).
    alpha : float, optional
        False-alarm probability of each test, in (0, 1) (default 1e-3).

    Returns
    -------
    numpy.ndarray, shape (m,)
        ``χ²_{1−α}(k)`` for k = 1..m (``scipy.stats.chi2.isf``).

    Raises
    ------
    InvalidInputError
        If ``alpha`` is not in (0, 1).
    """
    if not 0 < alpha < 1:
        raise InvalidInputError(f"alpha must be in (0, 1), got {alpha}")
    return np.asarray(chi2_isf(alpha, np.arange(1, m + 1)), dtype=np.float64)


def isolate_channels(innovation: ArrayLike, S: ArrayLike, alpha: float = 1e-3) -> NDArray[np.bool_]:
    """Accepted-channel mask by NIS χ² test and sequential w-test isolation.

    While ``ν_Aᵀ S_A⁻¹ ν_A > χ²_{1−α}(|A|)`` on the accepted set A, remove the
    channel with the largest ``|(S_A⁻¹ν_A)_i| / √(S_A⁻¹)_ii`` (Baarda's w-test; Baarda 1968,
    *A testing procedure for use in geodetic networks*, Netherlands Geodetic Commission).

    Parameters
    ----------
    innovation : array_like, shape (m,)
        Innovation ``ν = z − H x⁻``, in the measurement's units.
    S : array_like, shape (m, m)
        Innovation covariance ``H P⁻ Hᵀ + R``, units², symmetric positive definite.
    alpha : float, optional
        False-alarm probability of each χ² test, in (0, 1) (default 1e-3).

    Returns
    -------
    numpy.ndarray of bool, shape (m,)
        True for the channels kept; all False if every channel is rejected.
    """
    nu = as_vector(innovation, "innovation")
    Sm = as_covariance(S, "S", nu.shape[0])
    thr = isolation_thresholds(nu.shape[0], alpha)
    acc = np.ones(nu.shape[0], dtype=bool)
    while acc.any():
        idx = np.flatnonzero(acc)
        Si = np.linalg.inv(Sm[np.ix_(idx, idx)])
        g = Si @ nu[idx]
        if nu[idx] @ g <= thr[idx.size - 1]:
            break
        acc[idx[int(np.argmax(np.abs(g) / np.sqrt(np.diag(Si))))]] = False
    return acc


def nis_gate(innovation: ArrayLike, S: ArrayLike, alpha: float = 1e-3) -> NDArray[np.bool_]:
    """Accepted-channel mask of the vector χ² gate: all True if ``νᵀS⁻¹ν <= χ²_{1−α}(m)``, else all False.

    Parameters
    ----------
    innovation : array_like, shape (m,)
        Innovation ``ν = z − H x⁻``, in the measurement's units.
    S : array_like, shape (m, m)
        Innovation covariance, units², symmetric positive definite.
    alpha : float, optional
        False-alarm probability, in (0, 1) (default 1e-3).

    Returns
    -------
    numpy.ndarray of bool, shape (m,)
        All True when the normalised innovation squared passes the test, else all False.
    """
    nu = as_vector(innovation, "innovation")
    Sm = as_covariance(S, "S", nu.shape[0])
    ok = float(nu @ np.linalg.solve(Sm, nu)) <= isolation_thresholds(nu.shape[0], alpha)[-1]
    return np.full(nu.shape[0], ok)
