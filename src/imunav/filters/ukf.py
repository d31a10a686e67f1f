"""Unscented Kalman filter with scaled sigma points.

Sigma points (Julier 2002; Wan & van der Merwe 2000): ``λ = α²(n + κ) − n``,
``χ₀ = x``, ``χ_i = x ± [√((n + λ) P)]_i``; weights
``Wm₀ = λ/(n+λ)``, ``Wc₀ = λ/(n+λ) + 1 − α² + β``, ``W_i = 1/(2(n+λ))``.
On a linear model the UKF equals the linear Kalman filter exactly (for any
α, β, κ with n + λ > 0).

The unscented transform is the numba core's (:func:`imunav.filters._core.unscented_weights`, ``sigma_offsets``,
``unscented_mean``, ``unscented_cov``, ``unscented_update``), the same primitives as the attitude UKF
(:class:`imunav.attitude.UKF`); only the user's ``f`` and ``h`` run in Python.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError
from imunav.filters._common import as_covariance, as_vector, inv_sqrt_spd
from imunav.filters._core import sigma_offsets, unscented_cov, unscented_mean, unscented_update, unscented_weights
from imunav.filters.kalman import UpdateResult

__all__ = ["UnscentedKalmanFilter", "sigma_points"]

Array = NDArray[np.float64]


def _offsets(P: Array, alpha: float, beta: float, kappa: float) -> tuple[Array, float, float, float]:
    """Sigma-point offsets (2n+1, n) from the mean and the weights ``(Wm₀, Wc₀, W_i)``; checks n + λ > 0 and that
    ``P`` is positive definite."""
    n = P.shape[0]
    if n + alpha**2 * (n + kappa) - n <= 0:
        raise InvalidInputError(f"n + λ = {alpha**2 * (n + kappa):.3g} must be positive; increase alpha or kappa")
    lam, wm0, wc0, wi = unscented_weights(n, float(alpha), float(beta), float(kappa))
    X = np.empty((2 * n + 1, n))
    L = sigma_offsets(np.ascontiguousarray(P, dtype=np.float64), lam, X)
    if np.min(np.diag(L)) <= 1e-150:
        raise InvalidInputError("P is not positive definite: the sigma points need its Cholesky factor; "
                                "check the initial covariance and Q")
    return X, wm0, wc0, wi


def sigma_points(x: Array, P: Array, alpha: float, beta: float, kappa: float) -> tuple[Array, Array, Array]:
    """Scaled sigma points and their mean / covariance weights (module docstring).

    Parameters
    ----------
    x : numpy.ndarray, shape (n,)
        Mean.
    P : numpy.ndarray, shape (n, n)
        Covariance (symmetric positive definite).
    alpha : float
        Spread of the points around the mean (> 0).
    beta : float
        Prior knowledge of the distribution (2 is optimal for a Gaussian).
    kappa : float
        Secondary scaling.

    Returns
    -------
    chi : numpy.ndarray, shape (2n+1, n)
        Sigma points.
    Wm : numpy.ndarray, shape (2n+1,)
        Mean weights.
    Wc : numpy.ndarray, shape (2n+1,)
        Covariance weights.

    Raises
    ------
    InvalidInputError
        If ``n + λ <= 0`` (increase alpha or kappa) or ``P`` is not positive definite.
    """
    X, wm0, wc0, wi = _offsets(np.asarray(P, dtype=np.float64), alpha, beta, kappa)
    Wm = np.full(X.shape[0], wi)
    Wc = Wm.copy()
    Wm[0] = wm0
    Wc[0] = wc0
    return np.asarray(x, dtype=np.float64) + X, Wm, Wc


class UnscentedKalmanFilter:
    """UKF with state ``x`` and covariance ``P`` (module docstring).

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state.
    P0 : array_like, shape (n, n)
        Initial covariance.
    f : callable
        ``f(x, u) -> x_next`` process model.
    h : callable
        ``h(x) -> z_pred`` measurement model.
    Q : array_like, shape (n, n)
        Additive process-noise covariance of a step.
    R : array_like, shape (m, m)
        Additive measurement-noise covariance.
    alpha : float, optional
        Spread of the sigma points, > 0 (default 1e-3).
    beta : float, optional
        Prior knowledge of the distribution (default 2, optimal for a Gaussian).
    kappa : float, optional
        Secondary scaling (default 0).
    residual : callable, optional
        ``residual(z, z_pred)`` (e.g. wrapping angles); default ``z - z_pred``.

    Attributes
    ----------
    x : numpy.ndarray, shape (n,)
        Current state estimate.
    P : numpy.ndarray, shape (n, n)
        Current covariance.
    """

    def __init__(self, x0: ArrayLike, P0: ArrayLike, f: Callable[..., ArrayLike], h: Callable[[Array], ArrayLike],
                 Q: ArrayLike, R: ArrayLike, alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0,
                 residual: Callable[[Array, Array], ArrayLike] | None = None) -> None:
        self.x = as_vector(x0, "x0")
        n = self.x.shape[0]
        self.P = as_covariance(P0, "P0", n)
        self.f, self.h, self.residual = f, h, residual
        self.Q = as_covariance(Q, "Q", n)
        self.R = as_covariance(R, "R")
        if not alpha > 0:
            raise InvalidInputError(f"alpha must be > 0, got {alpha}")
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    def predict(self, u: ArrayLike | None = None, *, Q: ArrayLike | None = None) -> tuple[Array, Array]:
        """Propagate the sigma points through ``f``: ``x⁻`` and ``P⁻`` are their weighted mean and covariance
        plus ``Q``.

        Parameters
        ----------
        u : array_like, optional
            Control input passed to ``f``.
        Q : array_like, shape (n, n), optional
            Process-noise covariance of this step (default: the filter's ``Q``).

        Returns
        -------
        x : numpy.ndarray, shape (n,)
            Predicted state.
        P : numpy.ndarray, shape (n, n)
            Predicted covariance.

        Raises
        ------
        InvalidInputError
            If ``P`` is not positive definite or ``n + λ <= 0``.
        """
        Qm = self.Q if Q is None else as_covariance(Q, "Q", self.n)
        X, wm0, wc0, wi = _offsets(self.P, self.alpha, self.beta, self.kappa)
        Y = np.array([np.asarray(self.f(xi, u), dtype=np.float64).reshape(-1) for xi in self.x + X])
        x = unscented_mean(Y, wm0, wi)
        D = Y - x
        self.x = x
        self.P = unscented_cov(D, D, wc0, wi) + Qm
        return self.x, self.P

    def update(self, z: ArrayLike, *, R: ArrayLike | None = None) -> UpdateResult:
        """Measurement update from sigma points redrawn around the prior (the core's ``unscented_update``:
        ``K = P_xz P_zz⁻¹``, ``P ← P − K P_zz Kᵀ``).

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement.
        R : array_like, shape (m, m), optional
            Measurement-noise covariance (default: the filter's ``R``).

        Returns
        -------
        UpdateResult
            Innovation, its covariance ``P_zz``, the gain, the normalised innovation and the NIS.

        Raises
        ------
        InvalidInputError
            If ``R`` does not match the size of the measurement, or ``P`` is not positive definite.
        """
        X, wm0, wc0, wi = _offsets(self.P, self.alpha, self.beta, self.kappa)
        Z = np.array([np.atleast_1d(np.asarray(self.h(xi), dtype=np.float64)) for xi in self.x + X])
        zp = unscented_mean(Z, wm0, wi)
        zv = as_vector(z, "z", zp.shape[0])
        Rm = self.R if R is None else as_covariance(R, "R")
        if Rm.shape[0] != zp.shape[0]:
            raise InvalidInputError(f"R is {Rm.shape} but the measurement has {zp.shape[0]} values")
        if self.residual is None:
            Dz = Z - zp
            nu = zv - zp
        else:
            Dz = np.array([np.asarray(self.residual(zi, zp), dtype=np.float64) for zi in Z])
            nu = np.asarray(self.residual(zv, zp), dtype=np.float64)
        S = unscented_cov(Dz, Dz, wc0, wi) + Rm
        Pxz = unscented_cov(X, Dz, wc0, wi)
        P = self.P.copy()
        dx = np.empty(self.n)
        K = np.empty((self.n, nu.shape[0]))
        nis = float(unscented_update(P, Pxz, S, nu, dx, K))
        self.x = self.x + dx
        self.P = P
        m = nu.shape[0]
        return UpdateResult(nu, S, K, inv_sqrt_spd(S) @ nu, nis, np.ones(m, dtype=bool), np.ones(m))
