"""numba kernels of the calibration estimators (internal)."""

from __future__ import annotations

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1, qexp_1, qmul_1


@njit(cache=True)
def rotate_between_poses(raw, offsets, M, dt, u_from):
    """Rotate gravity directions through calibrated gyro segments.

    For segment m (rows ``offsets[m]:offsets[m+1]`` of ``raw``, bias removed),
    integrate ``ω = M raw`` with the mean rate over each step
    (``q ← q ⊗ exp((ω_k + ω_{k+1}) dt / 2)``) and return ``Cᵀ u_from[m]``:
    a direction fixed in the start frame, seen from the end frame.
    """
    P = offsets.shape[0] - 1
    out = np.empty((P, 3))
    phi = np.empty(3)
    for m in range(P):
        q = np.array([1.0, 0.0, 0.0, 0.0])
        a, b = offsets[m], offsets[m + 1]
        for k in range(a, b - 1):
            for i in range(3):
                s = 0.0
                for j in range(3):
                    s += M[i, j] * (raw[k, j] + raw[k + 1, j])
                phi[i] = 0.5 * s * dt
            q = qmul_1(q, qexp_1(phi))
        C = dcm_from_quat_1(q)
        for i in range(3):
            out[m, i] = C[0, i] * u_from[m, 0] + C[1, i] * u_from[m, 1] + C[2, i] * u_from[m, 2]
    return out


@njit(cache=True)
def moving_variance_kernel(x, n):
    """Centred moving variance of each column over ``n`` samples (shorter windows at the edges).

    Sliding sums of ``x - c`` (``c`` the column's first value) updated in O(1)
    per sample and recomputed exactly every ``64 n`` samples to bound rounding drift.
    """
    N, m = x.shape
    out = np.empty((N, m))
    h = n // 2
    for j in range(m):
        c = x[0, j]
        s1 = 0.0
        s2 = 0.0
        lo, hi = 0, 0  # current window [lo, hi)
        since = 0
        for i in range(N):
            a = i - h
            b = i - h + n
            if a < 0:
                a = 0
            if b > N:
                b = N
            if since >= 64 * n:
                s1 = 0.0
                s2 = 0.0
                for k in range(a, b):
                    d = x[k, j] - c
                    s1 += d
                    s2 += d * d
                lo, hi = a, b
                since = 0
            while hi < b:
                d = x[hi, j] - c
                s1 += d
                s2 += d * d
                hi += 1
            while lo < a:
                d = x[lo, j] - c
                s1 -= d
                s2 -= d * d
                lo += 1
            since += 1
            cnt = hi - lo
            mu = s1 / cnt
            v = s2 / cnt - mu * mu
            out[i, j] = v if v > 0.0 else 0.0
    return out
