"""Unscented Kalman filter with scaled sigma points.

Sigma points (Julier 2002; Wan & van der Merwe 2000): ``λ = α²(n + κ) − n``,
``χ₀ = x``, ``χ_i = x ± [√((n + λ) P)]_i``; weights
``Wm₀ = λ/(n+λ)``, ``Wc₀ = λ/(n+λ) + 1 − α² + β``, ``W_i = 1/(2(n+λ))``.
On a linear model the UKF equals the linear Kalman filter exactly (for any
α, β, κ with n + λ > 0).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError
from imunav.filters._common import as_covariance, as_vector, inv_sqrt_spd, symmetrize
from imunav.filters.kalman import UpdateResult

__all__ = ["UnscentedKalmanFilter", "sigma_points"]

Array = NDArray[np.float64]


def sigma_points(x: Array, P: Array, alpha: float, beta: float, kappa: float) -> tuple[Array, Array, Array]:
    """Scaled sigma points and their mean / covariance weights (module docstring).

    Parameters
    ----------
    x : numpy.ndarray, shape (n,)
        Mean.
    P : numpy.ndarray, shape (n, n)
        Covariance (symmetric positive definite).
    alpha, beta, kappa : float
        Scaling parameters (spread, prior knowledge of the distribution, secondary scaling).

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
        If ``n + λ <= 0`` (increase alpha or kappa).
    """
    n = x.shape[0]
    lam = alpha**2 * (n + kappa) - n
    if n + lam <= 0:
        raise InvalidInputError(f"n + λ = {n + lam:.3g} must be positive; increase alpha or kappa")
    L = np.linalg.cholesky((n + lam) * P)
    X = np.empty((2 * n + 1, n))
    X[0] = x
    X[1:n + 1] = x + L.T
    X[n + 1:] = x - L.T
    Wm = np.full(2 * n + 1, 0.5 / (n + lam))
    Wc = Wm.copy()
    Wm[0] = lam / (n + lam)
    Wc[0] = lam / (n + lam) + 1 - alpha**2 + beta
    return X, Wm, Wc


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
    Q : array_like, shape (n, n), optional
        Additive process-noise covariance of a step.
    R : array_like, shape (m, m), optional
        Additive measurement-noise covariance.
    alpha, beta, kappa : float
        Sigma-point scaling (defaults 1e-3, 2, 0).
    residual : callable, optional
        ``residual(z, z_pred)`` (e.g. wrapping angles); default ``z - z_pred``.
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

    def _sigma(self) -> tuple[Array, Array, Array]:
        return sigma_points(self.x, self.P, self.alpha, self.beta, self.kappa)

    def predict(self, u: ArrayLike | None = None, *, Q: ArrayLike | None = None) -> tuple[Array, Array]:
        """Propagate the sigma points through f.

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
        """
        Qm = self.Q if Q is None else as_covariance(Q, "Q", self.n)
        X, Wm, Wc = self._sigma()
        Y = np.array([np.asarray(self.f(xi, u), dtype=np.float64).reshape(-1) for xi in X])
        x = Wm @ Y
        D = Y - x
        self.x = x
        self.P = symmetrize((D * Wc[:, None]).T @ D + Qm)
        return self.x, self.P

    def update(self, z: ArrayLike, *, R: ArrayLike | None = None) -> UpdateResult:
        """Measurement update from sigma points redrawn around the prior.

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement.
        R : array_like, shape (m, m), optional
            Measurement-noise covariance (default: the filter's ``R``).

        Returns
        -------
        UpdateResult
            Innovation, its covariance, the gain, the normalised innovation and the NIS.

        Raises
        ------
        InvalidInputError
            If ``R`` does not match the size of the measurement.
        """
        X, Wm, Wc = self._sigma()
        Z = np.array([np.atleast_1d(np.asarray(self.h(xi), dtype=np.float64)) for xi in X])
        zp = Wm @ Z
        zv = as_vector(z, "z", zp.shape[0])
        Rm = self.R if R is None else as_covariance(R, "R")
        if Rm.shape[0] != zp.shape[0]:
            raise InvalidInputError(f"R is {Rm.shape} but the measurement has {zp.shape[0]} values")
        if self.residual is None:
            Dz = Z - zp
            nu = zv - zp
        else:
            Dz = np.array([self.residual(zi, zp) for zi in Z])
            nu = np.asarray(self.residual(zv, zp), dtype=np.float64)
        Dx = X - self.x
        S = symmetrize((Dz * Wc[:, None]).T @ Dz + Rm)
        Pxz = (Dx * Wc[:, None]).T @ Dz
        K = np.linalg.solve(S, Pxz.T).T
        self.x = self.x + K @ nu
        self.P = symmetrize(self.P - K @ S @ K.T)
        m = nu.shape[0]
        return UpdateResult(nu, S, K, inv_sqrt_spd(S) @ nu, float(nu @ np.linalg.solve(S, nu)),
                            np.ones(m, dtype=bool), np.ones(m))
