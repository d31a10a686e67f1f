"""Shared helpers of :mod:`imunav.filters`: input checks."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError

Array = NDArray[np.float64]


def as_vector(x: ArrayLike, name: str, n: int | None = None) -> Array:
    """1-D float64 copy of ``x`` with finite values (and length ``n`` if given)."""
    a = np.array(x, dtype=np.float64, copy=True)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise ShapeError(f"{name} must be a vector, got shape {a.shape}; pass a 1-D array")
    if n is not None and a.shape[0] != n:
        raise ShapeError(f"{name} must have length {n}, got {a.shape[0]}; check the state/measurement size")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf at index {int(np.flatnonzero(~np.isfinite(a))[0])}; "
                             "replace or remove the bad values")
    return a


def as_matrix(A: ArrayLike, name: str, rows: int | None = None, cols: int | None = None) -> Array:
    """2-D float64 copy of ``A`` (a scalar becomes 1x1) with the expected shape."""
    a = np.array(A, dtype=np.float64, copy=True)
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim != 2:
        raise ShapeError(f"{name} must be a 2-D matrix, got shape {a.shape}")
    if (rows is not None and a.shape[0] != rows) or (cols is not None and a.shape[1] != cols):
        raise ShapeError(
            f"{name} must have shape ({rows if rows is not None else 'any'}, {cols if cols is not None else 'any'}),"
            f" got {a.shape}; check the state/measurement sizes"
        )
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf; pass a finite matrix")
    return a


def as_covariance(P: ArrayLike, name: str, n: int | None = None) -> Array:
    """Symmetric positive semi-definite covariance matrix (a vector is taken as a diagonal)."""
    a = np.array(P, dtype=np.float64, copy=True)
    if a.ndim <= 1:
        a = np.diag(np.atleast_1d(a))
    a = as_matrix(a, name, n, n)
    if a.shape[0] != a.shape[1]:
        raise ShapeError(f"{name} must be square, got {a.shape}")
    if not np.allclose(a, a.T, rtol=1e-9, atol=1e-12 * max(1.0, float(np.max(np.abs(a))))):
        raise InvalidInputError(f"{name} is not symmetric (max |A - A^T| = {np.max(np.abs(a - a.T)):.3g}); "
                                "pass (A + A.T) / 2 if the asymmetry is round-off")
    a = 0.5 * (a + a.T)
    w = np.linalg.eigvalsh(a)
    if w.size and w[0] < -1e-10 * max(1.0, float(w[-1])):
        raise InvalidInputError(f"{name} is not positive semi-definite (smallest eigenvalue {w[0]:.3g}); "
                                "check the variances")
    return a


def symmetrize(P: Array) -> Array:
    return 0.5 * (P + P.T)


def inv_sqrt_spd(S: Array) -> Array:
    """Symmetric inverse square root ``S^{-1/2}`` of a positive definite matrix."""
    w, V = np.linalg.eigh(S)
    if w[0] <= 0.0:
        raise InvalidInputError(f"innovation covariance is not positive definite (eigenvalue {w[0]:.3g}); "
                                "R must be positive definite")
    return (V / np.sqrt(w)) @ V.T

