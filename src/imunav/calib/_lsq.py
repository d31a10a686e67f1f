"""Linear least squares with parameter covariance (internal).

All calibration designs here are multi-output linear regressions
``Y = X Θ + E`` with ``Y`` (K, m) per-position (or per-step) means, ``X``
(K, p) the known inputs and ``Θ`` (p, m) the unknowns; Günhan 2014, §4.1.3,
eqs. (12)-(17): ``Θ = (XᵀX)⁻¹ XᵀY``.

Uncertainty: each output column j gets ``cov(θ_j) = s_j² (XᵀX)⁻¹`` with
``s_j² = r_jᵀ r_j / (K − p)`` the scatter of the per-position residuals.  This
is deliberately *not* the white-noise value ``σ²/n_samples``: when the bias
drifts (Gauss–Markov bias instability with a correlation time comparable to
the dwell), the per-position means scatter far more than white-noise theory
says and only their observed scatter gives an honest standard error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import DegenerateGeometryError, InsufficientDataError, ShapeError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LinearFit:
    theta: Array  # (p, m)
    stderr: Array  # (p, m)
    cov: Array  # (m, p, p)
    residuals: Array  # (K, m)
    sigma: Array  # (m,) residual standard deviation per output
    cond: float  # condition number of the column-scaled design
    dof: int
    rho: Array | None = None  # lag-1 residual autocorrelation used (serial fits)


def paired_means(x: ArrayLike, x_name: str, y: ArrayLike, y_name: str) -> tuple[Array, Array]:
    """The known inputs and the means of a fit as float arrays, both checked to be (K, 3) with the same K.

    Parameters
    ----------
    x, y : array_like, shape (K, 3)
        Known input per position / step (reference force, table rate) and the mean sensor output.
    x_name, y_name : str
        Their argument names, for the message.

    Returns
    -------
    x, y : numpy.ndarray, shape (K, 3)
        The two arrays as float.

    Raises
    ------
    ShapeError
        If they are not both (K, 3) with the same K.
    """
    xa = np.asarray(x, float)
    ya = np.asarray(y, float)
    if xa.shape != ya.shape or xa.ndim != 2 or xa.shape[1] != 3:
        raise ShapeError(f"{x_name} {xa.shape} and {y_name} {ya.shape} must both be (K, 3)")
    return xa, ya


def design_condition(X: Array) -> float:
    """Condition number of ``X`` after scaling each column to unit norm.

    Column scaling removes the trivial dependence on units (e.g. a column of
    9.8 m/s² next to a column of ones), so the number measures geometry only.
    """
    n = np.linalg.norm(X, axis=0)
    n[n == 0] = 1.0
    s = np.linalg.svd(X / n, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def linear_fit(
    X: Array, Y: Array, *, what: str, max_cond: float = 1e8, serial: bool = False, covs: list[Array] | None = None
) -> LinearFit:
    """Least-squares fit of ``Y ≈ X Θ`` with residual-based covariance.

    ``serial=True`` (rows in time order) accounts for the correlation that a
    slowly drifting bias leaves between consecutive positions: the lag-1
    autocorrelation ρ of the OLS residuals is estimated per output and, when
    positive, the fit is repeated as feasible GLS with an AR(1) error model
    (Prais & Winsten 1954: ``y*_1 = √(1−ρ²) y_1``, ``y*_k = y_k − ρ y_{k−1}``,
    same for ``X``); its covariance ``s*² (X*ᵀX*)⁻¹`` then includes the
    correlation instead of treating the positions as independent.

    ``covs`` (one (K, K) matrix per output, e.g. from a characterised noise
    model, see ``_noisecov``) gives generalised least squares with that error
    covariance: ``cov(θ) = (XᵀΣ⁻¹X)⁻¹ · max(1, χ²/dof)`` (never smaller than
    the model says, inflated when the residuals scatter more).

    Raises
    ------
    InsufficientDataError
        Fewer rows than unknowns (+1, so that a residual scatter exists).
    DegenerateGeometryError
        The design does not excite every unknown (condition > ``max_cond``).
    """
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if Y.ndim == 1:
        Y = Y[:, None]
    k, p = X.shape
    if k <= p:
        raise InsufficientDataError(
            f"{what}: {k} positions/steps for {p} unknowns per axis; at least {p + 1} are needed "
            "(add positions with both signs on every axis)"
        )
    cond = design_condition(X)
    if not np.isfinite(cond) or cond > max_cond:
        raise DegenerateGeometryError(
            f"{what}: the design matrix is singular or ill-conditioned (condition {cond:.3g}); "
            "the positions/rates do not excite every parameter - use inputs with both signs on all three axes"
        )
    theta, *_ = np.linalg.lstsq(X, Y, rcond=None)
    res = Y - X @ theta
    dof = k - p
    s2 = np.sum(res**2, axis=0) / dof
    xtx_inv = np.linalg.inv(X.T @ X)
    cov = s2[:, None, None] * xtx_inv[None]
    rho = np.zeros(Y.shape[1])
    if covs is not None:
        for j in range(Y.shape[1]):
            Lc = np.linalg.cholesky(covs[j])
            Xw = np.linalg.solve(Lc, X)
            yw = np.linalg.solve(Lc, Y[:, j])
            th, *_ = np.linalg.lstsq(Xw, yw, rcond=None)
            rw = yw - Xw @ th
            theta[:, j] = th
            res[:, j] = Y[:, j] - X @ th
            chi2 = float(rw @ rw) / dof
            cov[j] = np.linalg.inv(Xw.T @ Xw) * max(1.0, chi2)
            s2[j] = float(res[:, j] @ res[:, j]) / dof
        serial = False
    if serial and k >= 3 * p + 10:
        for j in range(Y.shape[1]):
            r = res[:, j]
            den = float(r @ r)
            rj = float(r[1:] @ r[:-1]) / den if den > 0 else 0.0
            rj = min(max(rj, 0.0), 0.95)
            if rj <= 0.0:
                continue
            rho[j] = rj
            Xs = np.vstack([np.sqrt(1 - rj**2) * X[:1], X[1:] - rj * X[:-1]])
            ys = np.concatenate([np.sqrt(1 - rj**2) * Y[:1, j], Y[1:, j] - rj * Y[:-1, j]])
            th, *_ = np.linalg.lstsq(Xs, ys, rcond=None)
            rs = ys - Xs @ th
            theta[:, j] = th
            res[:, j] = Y[:, j] - X @ th
            s2[j] = float(rs @ rs) / dof
            cov[j] = s2[j] * np.linalg.inv(Xs.T @ Xs)
    stderr = np.sqrt(np.einsum("mii->im", cov))
    return LinearFit(theta, stderr, cov, res, np.sqrt(s2), cond, dof, rho)
