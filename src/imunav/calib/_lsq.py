"""Linear least squares with parameter covariance (internal).

All calibration designs here are multi-output linear regressions
``Y = X Θ + E`` with ``Y`` (K, m) per-position (or per-step) means, ``X``
(K, p) the known inputs and ``Θ`` (p, m) the unknowns; imu-error-calibration
§5.4, eqs. (12)-(17): ``Θ = (XᵀX)⁻¹ XᵀY``.

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
from numpy.typing import NDArray

from imunav.errors import DegenerateGeometryError, InsufficientDataError

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


def design_condition(X: Array) -> float:
    """Condition number of ``X`` after scaling each column to unit norm.

    Column scaling removes the trivial dependence on units (e.g. a column of
    9.8 m/s² next to a column of ones), so the number measures geometry only.
    """
    n = np.linalg.norm(X, axis=0)
    n[n == 0] = 1.0
    s = np.linalg.svd(X / n, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def linear_fit(X: Array, Y: Array, *, what: str, max_cond: float = 1e8) -> LinearFit:
    """Least-squares fit of ``Y ≈ X Θ`` with residual-based covariance.

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
    stderr = np.sqrt(np.einsum("mii->im", cov))
    return LinearFit(theta, stderr, cov, res, np.sqrt(s2), cond, dof)
