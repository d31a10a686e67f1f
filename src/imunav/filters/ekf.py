"""Extended Kalman filter with user-supplied process / measurement functions.

Predict: ``x⁻ = f(x, u)``, ``P⁻ = F P Fᵀ + Q`` with ``F = ∂f/∂x``; update:
``ν = z − h(x⁻)`` (or ``residual(z, h(x⁻))`` for angles), ``H = ∂h/∂x``,
``S = H P⁻ Hᵀ + R``, ``K = P⁻ Hᵀ S⁻¹``, ``x = x⁻ + K ν`` and the Joseph-form
covariance (Gelb 1974, §6.1).  Jacobians not supplied are formed by central
differences.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, ShapeError
from imunav.filters._common import as_covariance, as_matrix, as_vector, inv_sqrt_spd, symmetrize
from imunav.filters.kalman import UpdateResult, joseph_update

__all__ = ["ExtendedKalmanFilter", "numerical_jacobian"]

Array = NDArray[np.float64]


def numerical_jacobian(fun: Callable[[Array], ArrayLike], x: Array, eps: float = 1e-6) -> Array:
    """Central-difference Jacobian ``∂fun/∂x`` at ``x`` (step ``eps·max(1, |x_i|)``).

    Parameters
    ----------
    fun : callable
        ``fun(x) -> y``, a vector function of the state.
    x : numpy.ndarray, shape (n,)
        Point of linearisation.
    eps : float
        Relative step.

    Returns
    -------
    numpy.ndarray, shape (m, n)
        The Jacobian, truncation error O(step²).
    """
    x = np.asarray(x, dtype=np.float64)
    f0 = np.atleast_1d(np.asarray(fun(x), dtype=np.float64))
    J = np.empty((f0.shape[0], x.shape[0]))
    for i in range(x.shape[0]):
        h = eps * max(1.0, abs(x[i]))
        xp = x.copy()
        xm = x.copy()
        xp[i] += h
        xm[i] -= h
        J[:, i] = (np.atleast_1d(fun(xp)) - np.atleast_1d(fun(xm))) / (2 * h)
    return J


class ExtendedKalmanFilter:
    """EKF with state ``x`` and covariance ``P`` (module docstring; Gelb 1974, §6.1).

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state.
    P0 : array_like, shape (n, n)
        Initial covariance.
    f : callable
        ``f(x, u) -> x_next`` process model (``u`` may be None).
    h : callable
        ``h(x) -> z_pred`` measurement model.
    F_jac, H_jac : callable, optional
        Jacobians ``F_jac(x, u)``, ``H_jac(x)``; numerical (:func:`numerical_jacobian`) when omitted.
    Q : array_like, shape (n, n), optional
        Default process-noise covariance of a step.
    R : array_like, shape (m, m), optional
        Default measurement-noise covariance.
    residual : callable, optional
        ``residual(z, z_pred) -> ν`` (e.g. wrapping angles); default ``z - z_pred``.
    """

    def __init__(
        self,
        x0: ArrayLike,
        P0: ArrayLike,
        f: Callable[..., ArrayLike],
        h: Callable[[Array], ArrayLike],
        Q: ArrayLike,
        R: ArrayLike,
        F_jac: Callable[..., ArrayLike] | None = None,
        H_jac: Callable[[Array], ArrayLike] | None = None,
        residual: Callable[[Array, Array], ArrayLike] | None = None,
    ) -> None:
        self.x = as_vector(x0, "x0")
        n = self.x.shape[0]
        self.P = as_covariance(P0, "P0", n)
        self.f, self.h, self.F_jac, self.H_jac, self.residual = f, h, F_jac, H_jac, residual
        self.Q = as_covariance(Q, "Q", n)
        self.R = as_covariance(R, "R")

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    def predict(self, u: ArrayLike | None = None, *, Q: ArrayLike | None = None) -> tuple[Array, Array]:
        """``x⁻ = f(x, u)``, ``P⁻ = F P Fᵀ + Q``.

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
        ShapeError
            If ``f`` returns a state of another size.
        """
        Qm = self.Q if Q is None else as_covariance(Q, "Q", self.n)
        x0 = self.x
        if self.F_jac is not None:
            F = as_matrix(self.F_jac(x0, u), "F_jac(x, u)", self.n, self.n)
        else:
            F = numerical_jacobian(lambda xx: self.f(xx, u), x0)
        xn = np.asarray(self.f(x0, u), dtype=np.float64).reshape(-1)
        if xn.shape[0] != self.n:
            raise ShapeError(f"f(x, u) returned {xn.shape[0]} values, the state has {self.n}")
        self.x = xn
        self.P = symmetrize(F @ self.P @ F.T + Qm)
        return self.x, self.P

    def update(self, z: ArrayLike, *, R: ArrayLike | None = None, h: Callable[[Array], ArrayLike] | None = None,
               H_jac: Callable[[Array], ArrayLike] | None = None) -> UpdateResult:
        """Measurement update with ``h`` (or an override, e.g. another sensor); Joseph-form covariance.

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement.
        R : array_like, shape (m, m), optional
            Measurement-noise covariance (default: the filter's ``R``).
        h : callable, optional
            Measurement model for this update (default: the filter's ``h``).
        H_jac : callable, optional
            Its Jacobian (numerical when omitted).

        Returns
        -------
        UpdateResult
            Innovation, its covariance, the gain, the normalised innovation and the NIS.

        Raises
        ------
        InvalidInputError
            If ``R`` does not match the size of the measurement.
        """
        hf = self.h if h is None else h
        Hj = self.H_jac if h is None else H_jac
        zp = np.atleast_1d(np.asarray(hf(self.x), dtype=np.float64))
        zv = as_vector(z, "z", zp.shape[0])
        Rm = self.R if R is None else as_covariance(R, "R")
        if Rm.shape[0] != zp.shape[0]:
            raise InvalidInputError(f"R is {Rm.shape} but the measurement has {zp.shape[0]} values")
        H = as_matrix(Hj(self.x), "H_jac(x)", zp.shape[0], self.n) if Hj is not None else numerical_jacobian(hf, self.x)
        nu = zv - zp if self.residual is None else np.asarray(self.residual(zv, zp), dtype=np.float64)
        S = symmetrize(H @ self.P @ H.T + Rm)
        K = np.linalg.solve(S, H @ self.P).T
        self.x = self.x + K @ nu
        self.P = joseph_update(self.P, K, H, Rm)
        m = nu.shape[0]
        return UpdateResult(nu, S, K, inv_sqrt_spd(S) @ nu, float(nu @ np.linalg.solve(S, nu)),
                            np.ones(m, dtype=bool), np.ones(m))
