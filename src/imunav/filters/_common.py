"""Shared helpers of :mod:`imunav.filters`: input checks, and the predict / update steps of the public filters on
the numba core (:mod:`imunav.filters._core`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError
from imunav.filters._core import joseph_update_gain, propagate_cov_sparse

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
    """``½ (P + Pᵀ)`` of a matrix, or of each matrix of a stack (..., n, n)."""
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def inv_sqrt_spd(S: Array) -> Array:
    """Symmetric inverse square root ``S^{-1/2} = V diag(w)^{-1/2} Vᵀ`` of a positive definite matrix, or of each
    matrix of a stack (..., m, m) (``S = V diag(w) Vᵀ``)."""
    w, V = np.linalg.eigh(S)
    if np.any(w[..., 0] <= 0.0):
        raise InvalidInputError(f"innovation covariance is not positive definite (eigenvalue {np.min(w[..., 0]):.3g});"
                                " R must be positive definite")
    return np.einsum("...ij,...j,...kj->...ik", V, 1.0 / np.sqrt(w), V)


def predict_covariance(P: Array, F: Array, Qn: Array) -> Array:
    """``F P Fᵀ + Qn`` by the core's :func:`~imunav.filters._core.propagate_cov_sparse` (exactly symmetric).

    Parameters
    ----------
    P : numpy.ndarray, shape (n, n)
        Covariance (not modified).
    F : numpy.ndarray, shape (n, n)
        Transition matrix (or its Jacobian).
    Qn : numpy.ndarray, shape (n, n)
        Process-noise covariance in the state space.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Predicted covariance.
    """
    n = P.shape[0]
    Pn = np.array(P, dtype=np.float64, order="C")
    propagate_cov_sparse(np.ascontiguousarray(F, dtype=np.float64), Pn, np.ascontiguousarray(Qn, dtype=np.float64),
                         np.empty((n, n)), np.empty((n, n), dtype=np.int64), np.empty(n, dtype=np.int64))
    return Pn


def joseph_step(x: Array, P: Array, nu: Array, H: Array, R: Array) -> tuple[Array, Array, Array, Array, float]:
    """One Joseph-form update by the core's ``joseph_update_gain`` (copies; the inputs are not modified).

    Parameters
    ----------
    x : numpy.ndarray, shape (n,)
        Prior state.
    P : numpy.ndarray, shape (n, n)
        Prior covariance.
    nu : numpy.ndarray, shape (m,)
        Innovation at ``x``.
    H : numpy.ndarray, shape (m, n)
        Measurement matrix (or its Jacobian).
    R : numpy.ndarray, shape (m, m)
        Measurement-noise covariance.

    Returns
    -------
    x : numpy.ndarray, shape (n,)
        Posterior state ``x + K ν``.
    P : numpy.ndarray, shape (n, n)
        Posterior covariance (Joseph form, symmetric).
    K : numpy.ndarray, shape (n, m)
        Gain applied.
    S : numpy.ndarray, shape (m, m)
        Innovation covariance ``H P Hᵀ + R``.
    nis : float
        ``νᵀ S⁻¹ ν``.
    """
    n, m = P.shape[0], H.shape[0]
    Pn = np.array(P, dtype=np.float64, order="C")
    dx = np.zeros(n)
    K = np.empty((n, m))
    S = np.empty((m, m))
    d = joseph_update_gain(Pn, dx, np.ascontiguousarray(H, dtype=np.float64), np.ascontiguousarray(R, dtype=np.float64),
                           np.ascontiguousarray(nu, dtype=np.float64), np.empty(m), S, K)
    return x + dx, Pn, K, S, float(d)
