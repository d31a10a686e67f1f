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
