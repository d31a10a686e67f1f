"""numba kernels of :mod:`imunav.filters` (private; public wrappers validate input)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def cusum_stats(nv, rho, k_mean):
    """CUSUM statistics on normalised innovations nv (N, s).

    Variance CUSUM (Page 1954) with the log-likelihood ratio of N(0, ρI)
    against N(0, I): ``ℓ = ½(1 − 1/ρ)|ν̃|² − (s/2) ln ρ``, ``g = max(0, g + ℓ)``.
    Mean CUSUM: two-sided per channel with reference k: ``g± = max(0, g± ± ν̃ − k)``,
    statistic = max over channels and sides.
    """
    N, s = nv.shape
    gv = np.empty(N)
    gm = np.empty(N)
    g = 0.0
    gp = np.zeros(s)
    gn = np.zeros(s)
    c1 = 0.5 * (1.0 - 1.0 / rho)
    c0 = 0.5 * s * np.log(rho)
    for k in range(N):
        q = 0.0
        for i in range(s):
            q += nv[k, i] * nv[k, i]
        g = max(0.0, g + c1 * q - c0)
        gv[k] = g
        mx = 0.0
        for i in range(s):
            gp[i] = max(0.0, gp[i] + nv[k, i] - k_mean)
            gn[i] = max(0.0, gn[i] - nv[k, i] - k_mean)
            mx = max(mx, gp[i], gn[i])
        gm[k] = mx
    return gv, gm
