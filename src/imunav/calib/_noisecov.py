"""Covariance of per-segment means under white noise + Gauss-Markov bias drift (internal).

For a first-order Gauss-Markov process (variance σ², correlation time τ,
``R(Δ) = σ² e^{−|Δ|/τ}``) the means over windows ``[a_k, b_k]`` of lengths
``L_k`` have (integrating R over both windows)::

    Var(x̄_k)        = 2 σ² τ² / L² · (L/τ − 1 + e^{−L/τ})
    Cov(x̄_k, x̄_l)   = σ² τ² / (L_k L_l) · (1 − e^{−L_k/τ}) (1 − e^{−L_l/τ}) e^{−(a_l − b_k)/τ},  b_k ≤ a_l

and white noise of per-sample standard deviation s adds ``s² / n_k`` on the
diagonal.  Flicker-like bias instability given as a sum of GM components
(``components()`` of :mod:`imunav.sim` error models) adds one term per component.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def gm_mean_covariance(t0: Array, t1: Array, sigma: float, tau: float) -> Array:
    """Covariance (K, K) of the means of a GM process over time-ordered, disjoint windows."""
    L = np.maximum(t1 - t0, 1e-12)
    x = L / tau
    var = 2.0 * sigma**2 * tau**2 / L**2 * (x - 1.0 + np.exp(-x))
    g = (1.0 - np.exp(-x)) / L  # (1 - e^{-L/τ}) / L
    gap = t0[None, :] - t1[:, None]  # a_l - b_k
    C = sigma**2 * tau**2 * np.outer(g, g) * np.exp(-np.abs(np.where(gap >= 0, gap, gap.T)) / tau)
    C = np.triu(C, 1)
    C = C + C.T
    C[np.diag_indices_from(C)] = var
    return C


def segment_mean_covariances(
    triad: Any, t0: Array, t1: Array, n: Array, fs: float
) -> list[Array] | None:
    """Per-axis covariance of segment means for a triad error model (None if it has no noise terms).

    ``triad`` needs ``noise_density`` (3,) and ``bias_instability`` (None or an
    object with ``components() -> (sigmas (m, 3), taus (m, 3))``).
    """
    nd = np.broadcast_to(np.asarray(getattr(triad, "noise_density", 0.0), float), (3,))
    bi = getattr(triad, "bias_instability", None)
    out = []
    for i in range(3):
        C = np.diag((nd[i] ** 2 * fs) / np.maximum(n, 1))
        if bi is not None:
            sig, tau = bi.components()
            for s, tt in zip(np.atleast_2d(sig)[:, i], np.atleast_2d(tau)[:, i]):
                if s > 0:
                    C = C + gm_mean_covariance(t0, t1, float(s), float(tt))
        if not np.any(C):
            return None
        out.append(C)
    return out
