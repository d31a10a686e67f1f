"""Allocation-free numba kernels of the paper's gravity-vector filters (private).

Candan & Söken (UHUK-2020-173): Lee et al. 2012 (kind 0), Javed et al. 2020
("Javed-like" reconstruction, kind 1) and the proposed adaptive KF (kind 2).
Same equations, index convention and parameter vector ``gp`` as
:mod:`imunav.attitude.gravity_kf` documents (eqs. 11-14, 20-30 of the paper);
this module only removes the per-sample heap allocations: every 3×3 product is
written out on scalars or into a preallocated workspace, and the 3×3 SPD
inverse of eq. 27 is the closed-form adjugate / determinant.

gp (float64 array):
 0 sigma_g, 1 sigma_a, 2 c_a, 3 g, 4 tau (detector D1), 5 s_mode (0 A, 1 B, 2 C),
 6 s_fixed, 7 hold [s], 8 normalize, 9 exact F, 10 sigma_b, 11 r_b, 12 bias window.

State vector ``sv``: [0:3] a⁺_{t−1}, [3] detector hold timer, [4:7] Javed bias
estimate, [7:10] bias pseudo-measurement sum, [10] its count.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _inv3(A, out):
    """out = A⁻¹ for a 3×3 matrix by the adjugate (A = adj(A) / det A)."""
    a00, a01, a02 = A[0, 0], A[0, 1], A[0, 2]
    a10, a11, a12 = A[1, 0], A[1, 1], A[1, 2]
    a20, a21, a22 = A[2, 0], A[2, 1], A[2, 2]
    c00 = a11 * a22 - a12 * a21
    c01 = a02 * a21 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c10 = a12 * a20 - a10 * a22
    c11 = a00 * a22 - a02 * a20
    c12 = a02 * a10 - a00 * a12
    c20 = a10 * a21 - a11 * a20
    c21 = a01 * a20 - a00 * a21
    c22 = a00 * a11 - a01 * a10
    d = 1.0 / (a00 * c00 + a01 * c10 + a02 * c20)
    out[0, 0], out[0, 1], out[0, 2] = c00 * d, c01 * d, c02 * d
    out[1, 0], out[1, 1], out[1, 2] = c10 * d, c11 * d, c12 * d
    out[2, 0], out[2, 1], out[2, 2] = c20 * d, c21 * d, c22 * d


@njit(cache=True)
def _mm(A, B, C):
    """C = A B (3×3, C distinct from A and B)."""
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True)
def _mmt(A, B, C):
    """C = A Bᵀ (3×3, C distinct from A and B)."""
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[j, 0] + A[i, 1] * B[j, 1] + A[i, 2] * B[j, 2]


@njit(cache=True)
def gravity_step(kind, x, P, sv, Pb, yg0, yg1, yg2, ya0, ya1, ya2, h, gp, S, F, T, Pp, K, A, Ai):
    """One step t−1 → t in place on x (3,), P (3, 3), sv (11,), Pb (3, 3).

    ``yg*`` is the gyro sample t−1, ``ya*`` the accelerometer sample t in the
    paper's convention (y_a = −f).  Writes the scale-factor diagonal into S (3,)
    and uses the 3×3 arrays F … Ai as workspace.  Returns the detector flag α_t.
    """
    sg2 = gp[0] * gp[0]
    sa2 = gp[1] * gp[1]
    g = gp[3]
    ap0, ap1, ap2 = sv[0], sv[1], sv[2]
    bh0, bh1, bh2 = sv[4], sv[5], sv[6]
    w0, w1, w2 = yg0 - bh0, yg1 - bh1, yg2 - bh2
    # F = I − h [y_g]× (eq. 11), or exp(−h [y_g]×) (Rodrigues) when exact
    if gp[9] > 0.5:
        r0, r1, r2 = -w0 * h, -w1 * h, -w2 * h
        th2 = r0 * r0 + r1 * r1 + r2 * r2
        th = math.sqrt(th2)
        if th < 1e-8:
            a = 1.0
            b = 0.5
        else:
            a = math.sin(th) / th
            b = (1.0 - math.cos(th)) / th2
        # I + a [r]× + b ([r]×)², ([r]×)² = r rᵀ − |r|² I
        F[0, 0] = 1.0 + b * (r0 * r0 - th2)
        F[1, 1] = 1.0 + b * (r1 * r1 - th2)
        F[2, 2] = 1.0 + b * (r2 * r2 - th2)
        F[0, 1] = -a * r2 + b * r0 * r1
        F[1, 0] = a * r2 + b * r0 * r1
        F[0, 2] = a * r1 + b * r0 * r2
        F[2, 0] = -a * r1 + b * r0 * r2
        F[1, 2] = -a * r0 + b * r1 * r2
        F[2, 1] = a * r0 + b * r1 * r2
    else:
        F[0, 0] = 1.0
        F[0, 1] = h * w2
        F[0, 2] = -h * w1
        F[1, 0] = -h * w2
        F[1, 1] = 1.0
        F[1, 2] = h * w0
        F[2, 0] = h * w1
        F[2, 1] = -h * w0
        F[2, 2] = 1.0
    xq0, xq1, xq2 = x[0], x[1], x[2]  # x_{t−1}
    # x⁻ = F x ; P⁻ = F P Fᵀ + Q, Q = −h² σ_g² [x]×[x]× = h² σ_g² (|x|² I − x xᵀ) (eq. 14)
    xp0 = F[0, 0] * xq0 + F[0, 1] * xq1 + F[0, 2] * xq2
    xp1 = F[1, 0] * xq0 + F[1, 1] * xq1 + F[1, 2] * xq2
    xp2 = F[2, 0] * xq0 + F[2, 1] * xq1 + F[2, 2] * xq2
    q = h * h * sg2
    xx = xq0 * xq0 + xq1 * xq1 + xq2 * xq2
    _mm(F, P, T)
    _mmt(T, F, Pp)
    Pp[0, 0] += q * (xx - xq0 * xq0)
    Pp[1, 1] += q * (xx - xq1 * xq1)
    Pp[2, 2] += q * (xx - xq2 * xq2)
    Pp[0, 1] -= q * xq0 * xq1
    Pp[1, 0] -= q * xq1 * xq0
    Pp[0, 2] -= q * xq0 * xq2
    Pp[2, 0] -= q * xq2 * xq0
    Pp[1, 2] -= q * xq1 * xq2
    Pp[2, 1] -= q * xq2 * xq1
    # detector D1 with hold time
    det = abs(math.sqrt(ya0 * ya0 + ya1 * ya1 + ya2 * ya2) - g) > gp[4]
    if det:
        sv[3] = gp[7]
    elif sv[3] > 0.0:
        sv[3] -= h
        det = True
    if kind == 0:
        ca = gp[2]
    elif kind == 1:
        ca = gp[2] if det else 0.5 * gp[2]
    else:
        ca = 1.0 if det else 0.0
    z0, z1, z2 = ya0 - ca * ap0, ya1 - ca * ap1, ya2 - ca * ap2  # eq. 22
    apap = ap0 * ap0 + ap1 * ap1 + ap2 * ap2
    if kind == 1:
        # eqs. 29-30 (reconstruction): (c² |a⁺|² + | |y|² − g² |) W
        aa0, aa1, aa2 = abs(ap0), abs(ap1), abs(ap2)
        sw = aa0 + aa1 + aa2
        mag2 = ca * ca * apap + abs(ya0 * ya0 + ya1 * ya1 + ya2 * ya2 - g * g)
        if sw > 1e-12:
            m0 = mag2 * (aa0 / sw) + sa2
            m1 = mag2 * (aa1 / sw) + sa2
            m2 = mag2 * (aa2 / sw) + sa2
        else:
            m0 = mag2 * (1.0 / 3.0) + sa2
            m1 = m0
            m2 = m0
    else:
        m0 = ca * ca * apap / 3.0 + sa2  # eq. 25
        m1 = m0
        m2 = m0
    nu0, nu1, nu2 = z0 - g * xp0, z1 - g * xp1, z2 - g * xp2
    gg = g * g
    s0 = 1.0
    s1 = 1.0
    s2 = 1.0
    if kind == 2 and det:
        if gp[5] < 0.5:
            s0 = gp[6]
            s1 = gp[6]
            s2 = gp[6]
        elif gp[5] < 1.5:  # eq. 26, diagonal, floored at 1
            s0 = max(1.0, (nu0 * nu0 - gg * Pp[0, 0]) / m0)
            s1 = max(1.0, (nu1 * nu1 - gg * Pp[1, 1]) / m1)
            s2 = max(1.0, (nu2 * nu2 - gg * Pp[2, 2]) / m2)
    S[0], S[1], S[2] = s0, s1, s2
    sm0, sm1, sm2 = s0 * m0, s1 * m1, s2 * m2
    # K = P⁻Hᵀ (H P⁻ Hᵀ + S M)⁻¹ with H = g I (eq. 27)
    for i in range(3):
        for j in range(3):
            A[i, j] = gg * Pp[i, j]
    A[0, 0] += sm0
    A[1, 1] += sm1
    A[2, 2] += sm2
    _inv3(A, Ai)
    _mm(Pp, Ai, K)
    for i in range(3):
        for j in range(3):
            K[i, j] *= g
    xn0 = xp0 + K[0, 0] * nu0 + K[0, 1] * nu1 + K[0, 2] * nu2
    xn1 = xp1 + K[1, 0] * nu0 + K[1, 1] * nu1 + K[1, 2] * nu2
    xn2 = xp2 + K[2, 0] * nu0 + K[2, 1] * nu1 + K[2, 2] * nu2
    # Joseph form: P = (I − gK) P⁻ (I − gK)ᵀ + K (S M) Kᵀ
    for i in range(3):
        for j in range(3):
            A[i, j] = (1.0 if i == j else 0.0) - g * K[i, j]
    _mm(A, Pp, T)
    _mmt(T, A, Ai)
    for i in range(3):
        for j in range(3):
            P[i, j] = Ai[i, j] + K[i, 0] * sm0 * K[j, 0] + K[i, 1] * sm1 * K[j, 1] + K[i, 2] * sm2 * K[j, 2]
    for i in range(3):
        for j in range(i + 1, 3):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v
    if gp[8] > 0.5:
        nn = math.sqrt(xn0 * xn0 + xn1 * xn1 + xn2 * xn2)
        xn0 /= nn
        xn1 /= nn
        xn2 /= nn
    x[0], x[1], x[2] = xn0, xn1, xn2
    sv[0], sv[1], sv[2] = ya0 - g * xn0, ya1 - g * xn1, ya2 - g * xn2  # a⁺_t
    if kind == 1 and not det:
        _javed_bias(x, xq0, xq1, xq2, yg0, yg1, yg2, h, gp, sv, Pb, F, T, Pp, K, A, Ai)
    elif kind == 1:
        for i in range(7, 11):
            sv[i] = 0.0
    return det


@njit(cache=True)
def _javed_bias(x, xq0, xq1, xq2, yg0, yg1, yg2, h, gp, sv, Pb, Hb, T, Sb, Kb, A, Ai):
    """Cascaded gyro-bias KF of the Javed-like filter (a standard design standing in for Javed et al. 2020's).

    Pseudo-measurement z_b = (x_t − x_{t−1})/Δt − [x_{t−1}]× y_g = −[x_{t−1}]× b,
    averaged over ``gp[12]`` samples without detected acceleration.
    """
    # [x]× y = x × y
    c0 = xq1 * yg2 - xq2 * yg1
    c1 = xq2 * yg0 - xq0 * yg2
    c2 = xq0 * yg1 - xq1 * yg0
    sv[7] += (x[0] - xq0) / h - c0
    sv[8] += (x[1] - xq1) / h - c1
    sv[9] += (x[2] - xq2) / h - c2
    sv[10] += 1.0
    nb = sv[10]
    if nb < gp[12]:
        return
    zb0, zb1, zb2 = sv[7] / nb, sv[8] / nb, sv[9] / nb
    # Hb = −[x_{t−1}]×
    Hb[0, 0] = 0.0
    Hb[0, 1] = xq2
    Hb[0, 2] = -xq1
    Hb[1, 0] = -xq2
    Hb[1, 1] = 0.0
    Hb[1, 2] = xq0
    Hb[2, 0] = xq1
    Hb[2, 1] = -xq0
    Hb[2, 2] = 0.0
    qb = gp[10] * gp[10] * h * nb
    rb = gp[11] * gp[11] / nb
    for i in range(3):
        Pb[i, i] += qb
    # Sb = Hb Pb Hbᵀ + Rb ; Kb = Pb Hbᵀ Sb⁻¹
    _mm(Hb, Pb, T)
    _mmt(T, Hb, Sb)
    for i in range(3):
        Sb[i, i] += rb
    _inv3(Sb, Ai)
    _mmt(Pb, Hb, T)
    _mm(T, Ai, Kb)
    bh0, bh1, bh2 = sv[4], sv[5], sv[6]
    r0 = zb0 - (Hb[0, 0] * bh0 + Hb[0, 1] * bh1 + Hb[0, 2] * bh2)
    r1 = zb1 - (Hb[1, 0] * bh0 + Hb[1, 1] * bh1 + Hb[1, 2] * bh2)
    r2 = zb2 - (Hb[2, 0] * bh0 + Hb[2, 1] * bh1 + Hb[2, 2] * bh2)
    sv[4] = bh0 + Kb[0, 0] * r0 + Kb[0, 1] * r1 + Kb[0, 2] * r2
    sv[5] = bh1 + Kb[1, 0] * r0 + Kb[1, 1] * r1 + Kb[1, 2] * r2
    sv[6] = bh2 + Kb[2, 0] * r0 + Kb[2, 1] * r1 + Kb[2, 2] * r2
    # Joseph form: Pb = (I − Kb Hb) Pb (I − Kb Hb)ᵀ + Kb Rb Kbᵀ
    _mm(Kb, Hb, T)
    for i in range(3):
        for j in range(3):
            A[i, j] = (1.0 if i == j else 0.0) - T[i, j]
    _mm(A, Pb, T)
    _mmt(T, A, Sb)
    for i in range(3):
        for j in range(3):
            Pb[i, j] = Sb[i, j] + rb * (Kb[i, 0] * Kb[j, 0] + Kb[i, 1] * Kb[j, 1] + Kb[i, 2] * Kb[j, 2])
    for i in range(7, 11):
        sv[i] = 0.0


@njit(cache=True)
def gravity_run(kind, x0, P0, gyr, ya, dt, gp):
    """Whole-recording run; returns x (N,3), α (N,), S diag (N,3), a⁺ (N,3), bias (N,3).

    Index convention: F_{t−1} from y_g[t−1] (paper eqs. 11-12); row 0 is the
    initial state.
    """
    n = gyr.shape[0]
    xs = np.empty((n, 3))
    al = np.zeros(n)
    Sd = np.ones((n, 3))
    ap = np.zeros((n, 3))
    bb = np.zeros((n, 3))
    x = x0.copy()
    P = P0.copy()
    sv = np.zeros(11)
    Pb = np.eye(3) * (1e-3) ** 2
    S = np.ones(3)
    F = np.empty((3, 3))
    T = np.empty((3, 3))
    Pp = np.empty((3, 3))
    K = np.empty((3, 3))
    A = np.empty((3, 3))
    Ai = np.empty((3, 3))
    xs[0, 0], xs[0, 1], xs[0, 2] = x[0], x[1], x[2]
    for t in range(1, n):
        det = gravity_step(kind, x, P, sv, Pb, gyr[t - 1, 0], gyr[t - 1, 1], gyr[t - 1, 2],
                           ya[t, 0], ya[t, 1], ya[t, 2], dt[t], gp, S, F, T, Pp, K, A, Ai)
        al[t] = 1.0 if det else 0.0
        for i in range(3):
            xs[t, i] = x[i]
            Sd[t, i] = S[i]
            ap[t, i] = sv[i]
            bb[t, i] = sv[4 + i]
    return xs, al, Sd, ap, bb
