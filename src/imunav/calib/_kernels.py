"""numba kernels of the calibration estimators (internal)."""

from __future__ import annotations

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1, qexp_1, qmul_1


@njit(cache=True)
def rotate_between_poses(raw, offsets, M, dt, u_from):
    """Rotate gravity directions through calibrated gyro segments.

    For segment m (rows ``offsets[m]:offsets[m+1]`` of ``raw``, bias removed),
    integrate ``ω = M raw`` with the rotation vector of each step for a rate
    varying linearly between the samples (``q ← q ⊗ exp(φ)``,
    ``φ = (ω_k + ω_{k+1}) dt/2 + (ω_k × ω_{k+1}) dt²/12``, the second-order
    solution of the Bortz equation: the coning term) and return ``Cᵀ u_from[m]``:
    a direction fixed in the start frame, seen from the end frame.
    """
    P = offsets.shape[0] - 1
    out = np.empty((P, 3))
    phi = np.empty(3)
    w0 = np.empty(3)
    w1 = np.empty(3)
    c = dt * dt / 12.0
    for m in range(P):
        q = np.array([1.0, 0.0, 0.0, 0.0])
        a, b = offsets[m], offsets[m + 1]
        for i in range(3):
            s = 0.0
            for j in range(3):
                s += M[i, j] * raw[a, j]
            w1[i] = s
        for k in range(a, b - 1):
            for i in range(3):
                w0[i] = w1[i]
                s = 0.0
                for j in range(3):
                    s += M[i, j] * raw[k + 1, j]
                w1[i] = s
            phi[0] = 0.5 * (w0[0] + w1[0]) * dt + c * (w0[1] * w1[2] - w0[2] * w1[1])
            phi[1] = 0.5 * (w0[1] + w1[1]) * dt + c * (w0[2] * w1[0] - w0[0] * w1[2])
            phi[2] = 0.5 * (w0[2] + w1[2]) * dt + c * (w0[0] * w1[1] - w0[1] * w1[0])
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
            a = max(a, 0)
            b = min(b, N)
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
            out[i, j] = max(0.0, v)
    return out
