"""Allocation-free numba kernels of the paper's gravity-vector filters (private).

Candan & Söken (UHUK-2020-173): Lee et al. 2012 (kind 0), Javed et al. 2020
("Javed-like" reconstruction, kind 1) and the proposed adaptive KF (kind 2).
Same equations, index convention and parameter vector ``gp`` as
:mod:`imunav.attitude.gravity_kf` documents (eqs. 11-14, 20-30 of the paper);
this module only removes the per-sample heap allocations: every 3×3 product is
written out on scalars or into a preallocated workspace, and the 3×3 SPD
inverse of eq. 27 is the closed-form adjugate / determinant.

Parameters ``gp`` (float64): the GravityKfConfig fields named in GRAVITY_PARAMS, read through the
G_* constants; state ``sv``: the SV_* layout below; 3×3 workspace ``W`` (N_WORK, 3, 3).  The 3×3 algebra
(adjugate inverse, products, Joseph covariance) is :mod:`imunav.filters._core`'s allocation-free 3×3 forms.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_exp_into
from imunav.filters._core import inv3, joseph_cov3, mm3, mmt3

#: parameter vector ``gp``: GravityKfConfig.vector() packs these fields in this order; G_* index it
GRAVITY_PARAMS = (
    "gyro_noise_std", "accel_noise_std", "c_a", "g", "accel_norm_threshold", "s_mode", "s_fixed", "hold_s",
    "normalize", "exact", "gyro_bias_random_walk", "bias_pseudo_noise_std", "bias_window",
)
(
    G_GYRO_NOISE_STD, G_ACCEL_NOISE_STD, G_C_A, G_G, G_ACCEL_NORM_THRESHOLD, G_S_MODE, G_S_FIXED, G_HOLD_S,
    G_NORMALIZE, G_EXACT, G_GYRO_BIAS_RANDOM_WALK, G_BIAS_PSEUDO_NOISE_STD, G_BIAS_WINDOW,
) = range(len(GRAVITY_PARAMS))

#: filter state ``sv``: a⁺_{t−1} (3), detector hold timer, Javed bias estimate (3), bias pseudo-measurement sum (3),
#: its count
SV_A_PLUS = 0
SV_HOLD = 3
SV_BIAS = 4
SV_BIAS_SUM = 7
SV_BIAS_COUNT = 10
N_SV = 11
#: workspace ``W`` (N_WORK, 3, 3): the 3 × 3 scratch matrices of one step
N_WORK = 6


@njit(cache=True)
def gravity_step(kind, x, P, sv, Pb, yg, ya, h, gp, S, W):
    """One step t−1 → t in place on x (3,), P (3, 3), sv (N_SV,), Pb (3, 3).

    ``yg`` is the gyro sample t−1, ``ya`` the accelerometer sample t in the
    paper's convention (y_a = −f), both (3,).  Writes the scale-factor diagonal into S (3,)
    and uses W (N_WORK, 3, 3) as workspace.  Returns the detector flag α_t.
    """
    F, T, Pp, K, A, Ai = W[0], W[1], W[2], W[3], W[4], W[5]
    yg0, yg1, yg2 = yg[0], yg[1], yg[2]
    ya0, ya1, ya2 = ya[0], ya[1], ya[2]
    sg2 = gp[G_GYRO_NOISE_STD] * gp[G_GYRO_NOISE_STD]
    sa2 = gp[G_ACCEL_NOISE_STD] * gp[G_ACCEL_NOISE_STD]
    g = gp[G_G]
    ap0, ap1, ap2 = sv[SV_A_PLUS], sv[SV_A_PLUS + 1], sv[SV_A_PLUS + 2]
    bh0, bh1, bh2 = sv[SV_BIAS], sv[SV_BIAS + 1], sv[SV_BIAS + 2]
    w0, w1, w2 = yg0 - bh0, yg1 - bh1, yg2 - bh2
    # F = I − h [y_g]× (eq. 11), or exp(−h [y_g]×) (Rodrigues) when exact
    if gp[G_EXACT] > 0.5:
        dcm_exp_into(F, -w0 * h, -w1 * h, -w2 * h)
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
    mm3(F, P, T)
    mmt3(T, F, Pp)
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
    det = abs(math.sqrt(ya0 * ya0 + ya1 * ya1 + ya2 * ya2) - g) > gp[G_ACCEL_NORM_THRESHOLD]
    if det:
        sv[SV_HOLD] = gp[G_HOLD_S]
    elif sv[SV_HOLD] > 0.0:
        sv[SV_HOLD] -= h
        det = True
    if kind == 0:
        ca = gp[G_C_A]
    elif kind == 1:
        ca = gp[G_C_A] if det else 0.5 * gp[G_C_A]
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
        if gp[G_S_MODE] < 0.5:
            s0 = gp[G_S_FIXED]
            s1 = gp[G_S_FIXED]
            s2 = gp[G_S_FIXED]
        elif gp[G_S_MODE] < 1.5:  # eq. 26, diagonal, floored at 1
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
    inv3(A, Ai)
    mm3(Pp, Ai, K)
    for i in range(3):
        for j in range(3):
            K[i, j] *= g
    xn0 = xp0 + K[0, 0] * nu0 + K[0, 1] * nu1 + K[0, 2] * nu2
    xn1 = xp1 + K[1, 0] * nu0 + K[1, 1] * nu1 + K[1, 2] * nu2
    xn2 = xp2 + K[2, 0] * nu0 + K[2, 1] * nu1 + K[2, 2] * nu2
    # Joseph form: P = (I − gK) P⁻ (I − gK)ᵀ + K (S M) Kᵀ  (K H = g K in F, free after the prediction)
    for i in range(3):
        for j in range(3):
            F[i, j] = g * K[i, j]
    joseph_cov3(Pp, F, K, sm0, sm1, sm2, P, A, T)
    if gp[G_NORMALIZE] > 0.5:
        nn = math.sqrt(xn0 * xn0 + xn1 * xn1 + xn2 * xn2)
        xn0 /= nn
        xn1 /= nn
        xn2 /= nn
    x[0], x[1], x[2] = xn0, xn1, xn2
    sv[SV_A_PLUS], sv[SV_A_PLUS + 1], sv[SV_A_PLUS + 2] = ya0 - g * xn0, ya1 - g * xn1, ya2 - g * xn2  # a⁺_t
    if kind == 1 and not det:
        _javed_bias(x, xq0, xq1, xq2, yg0, yg1, yg2, h, gp, sv, Pb, W)
    elif kind == 1:
        for i in range(SV_BIAS_SUM, SV_BIAS_COUNT + 1):
            sv[i] = 0.0
    return det


@njit(cache=True)
def _javed_bias(x, xq0, xq1, xq2, yg0, yg1, yg2, h, gp, sv, Pb, W):
    """Cascaded gyro-bias KF of the Javed-like filter (a standard design standing in for Javed et al. 2020's).

    Pseudo-measurement z_b = (x_t − x_{t−1})/Δt − [x_{t−1}]× y_g = −[x_{t−1}]× b,
    averaged over ``gp[G_BIAS_WINDOW]`` samples without detected acceleration.
    """
    Hb, T, Sb, Kb, A, Ai = W[0], W[1], W[2], W[3], W[4], W[5]
    # [x]× y = x × y
    c0 = xq1 * yg2 - xq2 * yg1
    c1 = xq2 * yg0 - xq0 * yg2
    c2 = xq0 * yg1 - xq1 * yg0
    sv[SV_BIAS_SUM] += (x[0] - xq0) / h - c0
    sv[SV_BIAS_SUM + 1] += (x[1] - xq1) / h - c1
    sv[SV_BIAS_SUM + 2] += (x[2] - xq2) / h - c2
    sv[SV_BIAS_COUNT] += 1.0
    nb = sv[SV_BIAS_COUNT]
    if nb < gp[G_BIAS_WINDOW]:
        return
    zb0, zb1, zb2 = sv[SV_BIAS_SUM] / nb, sv[SV_BIAS_SUM + 1] / nb, sv[SV_BIAS_SUM + 2] / nb
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
    qb = gp[G_GYRO_BIAS_RANDOM_WALK] * gp[G_GYRO_BIAS_RANDOM_WALK] * h * nb
    rb = gp[G_BIAS_PSEUDO_NOISE_STD] * gp[G_BIAS_PSEUDO_NOISE_STD] / nb
    for i in range(3):
        Pb[i, i] += qb
    # Sb = Hb Pb Hbᵀ + Rb ; Kb = Pb Hbᵀ Sb⁻¹
    mm3(Hb, Pb, T)
    mmt3(T, Hb, Sb)
    for i in range(3):
        Sb[i, i] += rb
    inv3(Sb, Ai)
    mmt3(Pb, Hb, T)
    mm3(T, Ai, Kb)
    bh0, bh1, bh2 = sv[SV_BIAS], sv[SV_BIAS + 1], sv[SV_BIAS + 2]
    r0 = zb0 - (Hb[0, 0] * bh0 + Hb[0, 1] * bh1 + Hb[0, 2] * bh2)
    r1 = zb1 - (Hb[1, 0] * bh0 + Hb[1, 1] * bh1 + Hb[1, 2] * bh2)
    r2 = zb2 - (Hb[2, 0] * bh0 + Hb[2, 1] * bh1 + Hb[2, 2] * bh2)
    sv[SV_BIAS] = bh0 + Kb[0, 0] * r0 + Kb[0, 1] * r1 + Kb[0, 2] * r2
    sv[SV_BIAS + 1] = bh1 + Kb[1, 0] * r0 + Kb[1, 1] * r1 + Kb[1, 2] * r2
    sv[SV_BIAS + 2] = bh2 + Kb[2, 0] * r0 + Kb[2, 1] * r1 + Kb[2, 2] * r2
    # Joseph form: Pb = (I − Kb Hb) Pb (I − Kb Hb)ᵀ + Kb Rb Kbᵀ, written out (not joseph_cov3): the Javed-like
    # cascade amplifies rounding (tests/attitude/test_gravity_kernels.py), so this keeps its published figures
    # bit-identical; rb (Kb Kbᵀ) is summed before scaling, and Pb is not symmetrised
    mm3(Kb, Hb, T)
    for i in range(3):
        for j in range(3):
            A[i, j] = (1.0 if i == j else 0.0) - T[i, j]
    mm3(A, Pb, T)
    mmt3(T, A, Sb)
    for i in range(3):
        for j in range(3):
            Pb[i, j] = Sb[i, j] + rb * (Kb[i, 0] * Kb[j, 0] + Kb[i, 1] * Kb[j, 1] + Kb[i, 2] * Kb[j, 2])
    for i in range(SV_BIAS_SUM, SV_BIAS_COUNT + 1):
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
    sv = np.zeros(N_SV)
    Pb = np.eye(3) * (1e-3) ** 2
    S = np.ones(3)
    W = np.empty((N_WORK, 3, 3))
    xs[0, 0], xs[0, 1], xs[0, 2] = x[0], x[1], x[2]
    for t in range(1, n):
        det = gravity_step(kind, x, P, sv, Pb, gyr[t - 1], ya[t], dt[t], gp, S, W)
        al[t] = 1.0 if det else 0.0
        for i in range(3):
            xs[t, i] = x[i]
            Sd[t, i] = S[i]
            ap[t, i] = sv[SV_A_PLUS + i]
            bb[t, i] = sv[SV_BIAS + i]
    return xs, al, Sd, ap, bb
