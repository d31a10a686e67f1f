"""Numba kernels of the pedestrian ZUPT INS: the zero-velocity detector statistics and the error-state ZUPT
Kalman filter loop.  Public, validated wrappers live in :mod:`imunav.ins.zupt.statistics` and
:mod:`imunav.ins.zupt.filter`.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._core import (
    ATT_END,
    ATT_START,
    inject_additive,
    inject_attitude_global,
    joseph_update_rows,
    propagate_cov_sparse,
    strapdown_step_local,
)
from imunav.filters._core_models import heading_hold, height, zero_rate, zero_velocity
from imunav.ins._strapdown_kernels import cross

# --------------------------------------------------------------------------
# Zero-velocity detector statistics
# --------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _block_mean(acc, k, W):
    """Mean of acc[k:k+W] per axis (summed in sample order, then divided by W)."""
    m0 = 0.0
    m1 = 0.0
    m2 = 0.0
    for s in range(k, k + W):
        m0 += acc[s, 0]
        m1 += acc[s, 1]
        m2 += acc[s, 2]
    return m0 / W, m1 / W, m2 / W


@njit(cache=True, inline="always")
def _hold_block(out, k, W, T):
    """out[k:k+W] = T / W (a block statistic held over its samples)."""
    T /= W
    for s in range(k, k + W):
        out[s] = T


@njit(cache=True)
def shoe_blocks(acc, gyr, W, sigma_a, sigma_w, g):
    """SHOE statistic on non-overlapping blocks of W samples (Skog et al. 2010).

    T = 1/W sum_k [ |y_a,k - g ybar_a/|ybar_a||^2 / sigma_a^2 + |y_w,k|^2 / sigma_w^2 ],
    held constant over each block; samples after the last full block get 0.
    """
    n = acc.shape[0]
    out = np.zeros(n)
    ia = 1.0 / (sigma_a * sigma_a)
    iw = 1.0 / (sigma_w * sigma_w)
    k = 0
    while k + W <= n:
        m0, m1, m2 = _block_mean(acc, k, W)
        nm = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
        u0 = g * m0 / nm
        u1 = g * m1 / nm
        u2 = g * m2 / nm
        T = 0.0
        for s in range(k, k + W):
            d0 = acc[s, 0] - u0
            d1 = acc[s, 1] - u1
            d2 = acc[s, 2] - u2
            T += ia * (d0 * d0 + d1 * d1 + d2 * d2)
            T += iw * (gyr[s, 0] ** 2 + gyr[s, 1] ** 2 + gyr[s, 2] ** 2)
        _hold_block(out, k, W, T)
        k += W
    return out


@njit(cache=True)
def ared_blocks(gyr, W):
    """ARED statistic 1/W sum |y_w,k|^2 on non-overlapping blocks."""
    n = gyr.shape[0]
    out = np.zeros(n)
    k = 0
    while k + W <= n:
        T = 0.0
        for s in range(k, k + W):
            T += gyr[s, 0] ** 2 + gyr[s, 1] ** 2 + gyr[s, 2] ** 2
        _hold_block(out, k, W, T)
        k += W
    return out


@njit(cache=True)
def amvd_blocks(acc, W):
    """AMVD statistic 1/W sum |y_a,k - ybar_a|^2 on non-overlapping blocks."""
    n = acc.shape[0]
    out = np.zeros(n)
    k = 0
    while k + W <= n:
        m0, m1, m2 = _block_mean(acc, k, W)
        T = 0.0
        for s in range(k, k + W):
            T += (acc[s, 0] - m0) ** 2 + (acc[s, 1] - m1) ** 2 + (acc[s, 2] - m2) ** 2
        _hold_block(out, k, W, T)
        k += W
    return out


@njit(cache=True)
def mbgtd_sliding(acc, W, tail):
    """MBGTD statistic on a window sliding per sample (Olivares et al. 2012).

    For the window acc[k:k+W] and every pair of split indices a < b, the
    summed distance between samples 0..a and b..W-1 is normalised by
    (b - a)(W - b + 1) (the published convention); T[k] is the maximum.  The
    last W - 1 samples have no full window and get ``tail``.
    """
    n = acc.shape[0]
    out = np.full(n, tail)
    D = np.empty((W, W))
    for k in range(0, n - W + 1):
        # pairwise distances inside the window
        for i in range(W):
            for j in range(W):
                d0 = acc[k + i, 0] - acc[k + j, 0]
                d1 = acc[k + i, 1] - acc[k + j, 1]
                d2 = acc[k + i, 2] - acc[k + j, 2]
                D[i, j] = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        best = 0.0
        for a in range(W - 1):
            for b in range(a + 1, W):
                s = 0.0
                for i in range(a + 1):
                    for j in range(b, W):
                        s += D[i, j]
                s /= (b - a) * (W - b + 1)
                if s > best:
                    best = s
        out[k] = best
    return out


# --------------------------------------------------------------------------
# Error-state ZUPT EKF
# --------------------------------------------------------------------------
# Error state dx = [dp, dv, dphi, (dba, dbg)] (layout: the I_* constants) with
#   p = p_hat + dp, v = v_hat + dv, C_nb = exp([dphi x]) C_hat,
#   b_a = ba_hat + dba, b_g = bg_hat + dbg.
# Continuous error dynamics (local level, no Earth rate):
#   dp' = dv,  dv' = -[f^n x] dphi - C_hat dba + C_hat n_a,
#   dphi' = -C_hat dbg - C_hat n_g,  dba' = w_ba, dbg' = w_bg.

I_POS = 0  # δp, m (3)
I_VEL = 3  # δv, m/s (3)
I_ATT = 6  # δφ, rad, navigation-frame attitude error (3)
I_BA = 9  # δb_a, m/s² (3; 15-state filter only)
I_BG = 12  # δb_g, rad/s (3; 15-state filter only)
NX_NAV = 9
NX_BIAS = 15

#: Parameters of :func:`zupt_ekf_kernel` (from :class:`imunav.ins.zupt.ZuptConfig`; numba passes a named tuple
#: by value, its fields are compile-time typed).
ZuptKernelParams = namedtuple(
    "ZuptKernelParams",
    ["nx", "g", "accel_noise_std", "gyro_noise_std", "accel_bias_random_walk", "gyro_bias_random_walk", "zupt_noise_std", "zaru_noise_std",
     "heading_hold", "heading_noise_std", "coning", "level_floor", "floor_noise_std"],
)

#: The recording a ZUPT EKF window runs over: times ``t`` (N,), specific force ``acc`` and rate ``gyr`` (N, 3),
#: the stance flags ``zv`` and the ZARU mask ``zaru`` (N,) bool.
ZuptInput = namedtuple("ZuptInput", ["t", "acc", "gyr", "zv", "zaru"])

#: Per-sample outputs of a ZUPT EKF window (row 0 holds the state the window starts from): ``q`` (N, 4),
#: ``v``, ``p``, ``ba``, ``bg`` (N, 3), the covariance diagonal ``Pd`` (N, nx), the ZUPT innovation ``innov`` and
#: its variance ``svar`` (N, 3; NaN off stance).
ZuptRows = namedtuple("ZuptRows", ["q", "v", "p", "ba", "bg", "Pd", "innov", "svar"])

#: The state carried from one sample to the next (updated in place): the covariance ``P`` (nx, nx), the previous
#: compensated increments ``dth_prev``, ``dv_prev`` (3,) (coning), the heading-hold reference ``q_ref`` (4,),
#: ``stance`` (1,) bool (the previous sample was a stance) and the level-floor height ``floor_height`` (float).
ZuptCarry = namedtuple("ZuptCarry", ["P", "dth_prev", "dv_prev", "q_ref", "stance", "floor_height"])


@njit(cache=True)
def _zupt_transition(Phi, Qd, C, dvn, h, prm):
    """Φ = I + F h and Q_d = G Q Gᵀ h² (+ bias random walks σ² h) of the ZUPT error state (in place)."""
    nx = prm.nx
    for i in range(nx):
        for j in range(nx):
            Phi[i, j] = 1.0 if i == j else 0.0
            Qd[i, j] = 0.0
    for i in range(3):
        Phi[I_POS + i, I_VEL + i] = h
    # -[dv^n x]: the Jacobian of v_k = v_{k-1} + dv^n + g h w.r.t. the nav-frame attitude error
    # (C = exp([dphi x]) C_hat  =>  d(dv^n) = dphi x dv^n) uses the very increment dv^n that the
    # nominal integration added, so that over a swing sum(dv^n) is the estimated velocity change
    # (~0 horizontally) and the yaw stays unobservable, as it is.
    Phi[I_VEL + 0, I_ATT + 1] = dvn[2]
    Phi[I_VEL + 0, I_ATT + 2] = -dvn[1]
    Phi[I_VEL + 1, I_ATT + 0] = -dvn[2]
    Phi[I_VEL + 1, I_ATT + 2] = dvn[0]
    Phi[I_VEL + 2, I_ATT + 0] = dvn[1]
    Phi[I_VEL + 2, I_ATT + 1] = -dvn[0]
    if nx == NX_BIAS:
        for i in range(3):
            for j in range(3):
                Phi[I_VEL + i, I_BA + j] = -C[i, j] * h
                Phi[I_ATT + i, I_BG + j] = -C[i, j] * h
    # G Q G^T with G = dt C blocks: C diag(s^2) C^T = s^2 I for isotropic s
    qa = prm.accel_noise_std * prm.accel_noise_std * h * h
    qg = prm.gyro_noise_std * prm.gyro_noise_std * h * h
    for i in range(3):
        Qd[I_VEL + i, I_VEL + i] = qa
        Qd[I_ATT + i, I_ATT + i] = qg
    if nx == NX_BIAS:
        for i in range(3):
            Qd[I_BA + i, I_BA + i] = prm.accel_bias_random_walk * prm.accel_bias_random_walk * h
            Qd[I_BG + i, I_BG + i] = prm.gyro_bias_random_walk * prm.gyro_bias_random_walk * h


@njit(cache=True)
def zupt_ekf_kernel(inp, q0, p0, v0, ba0, bg0, P0, prm):
    """Run the error-state ZUPT EKF over a whole recording ``inp`` (:data:`ZuptInput`; ``prm``:
    :data:`ZuptKernelParams`).

    Sample 0 carries the initial state; for k >= 1 the nominal state is
    propagated with sample k over t_k - t_{k-1} (:func:`imunav.filters._core.strapdown_step_local`), the
    covariance with Phi = I + F dt, Q_d = G diag(sig_a^2, sig_g^2) G^T dt^2 (per-sample noise
    std, as in OpenShoe / pyshoe) plus bias random walks sig_b^2 dt; then, if
    zv[k], the ZUPT (and optionally heading-hold) updates apply, and the ZARU
    where the boolean mask zaru[k] is set (a subset of zv).  Each update is a measurement model of
    :mod:`imunav.filters._core_models` followed by :func:`imunav.filters._core.joseph_update_rows` and the
    injection of the error estimate.

    Heading hold: from the second sample of a stance on, the rotation about
    the nav vertical since its first sample is measured as 0 (std heading_noise_std).
    Level floor (``level_floor``): each stance sample measures the height as the
    initial height p0[2] (std floor_noise_std).

    The loop is :func:`zupt_ekf_window`; this wrapper allocates the outputs (:data:`ZuptRows`) and the state
    carried from sample to sample (:data:`ZuptCarry`), which it returns after the outputs so that
    :meth:`imunav.ins.ZuptFilter.step` can go on from the last sample.
    """
    n = inp.t.shape[0]
    nx = prm.nx
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    p = np.empty((n, 3))
    ba = np.zeros((n, 3))
    bg = np.zeros((n, 3))
    Pd = np.empty((n, nx))
    innov = np.full((n, 3), np.nan)
    svar = np.full((n, 3), np.nan)
    q[0] = q0
    v[0] = v0
    p[0] = p0
    ba[0] = ba0
    bg[0] = bg0
    P = P0.copy()
    for i in range(nx):
        Pd[0, i] = P[i, i]
    dth_prev = np.zeros(3)
    dv_prev = np.zeros(3)
    q_ref = q0.copy()
    stance = np.zeros(1, dtype=np.bool_)
    rows = ZuptRows(q, v, p, ba, bg, Pd, innov, svar)
    carry = ZuptCarry(P, dth_prev, dv_prev, q_ref, stance, p0[2])
    zupt_ekf_window(inp, rows, carry, prm)
    return rows, carry


@njit(cache=True, inline="always")  # inlined into zupt_ekf_kernel: its arrays stay local there (speed)
def zupt_ekf_window(inp, rows, carry, prm):
    """The loop of :func:`zupt_ekf_kernel` over rows 1..n-1 of a window ``inp`` (:data:`ZuptInput`) whose row 0
    holds the state.

    Writes rows 1..n-1 of the arrays of ``rows`` (:data:`ZuptRows`: ``q, v, p, ba, bg``, ``Pd``, ``innov``,
    ``svar``); updates in place the state ``carry`` (:data:`ZuptCarry`) carried from one sample to the next:
    the covariance ``P``, the previous compensated increments ``dth_prev``, ``dv_prev`` (coning), the
    heading-hold reference ``q_ref`` and ``stance[0]`` (the previous sample was a stance); its
    ``floor_height`` is the level-floor height.  A window of 2 rows is one sample
    (:meth:`imunav.ins.ZuptFilter.step`).
    """
    t, acc, gyr, zv, zaru = inp.t, inp.acc, inp.gyr, inp.zv, inp.zaru
    q, v, p, ba, bg, Pd, innov, svar = rows.q, rows.v, rows.p, rows.ba, rows.bg, rows.Pd, rows.innov, rows.svar
    P, dth_prev, dv_prev, q_ref, stance = carry.P, carry.dth_prev, carry.dv_prev, carry.q_ref, carry.stance
    floor_height = carry.floor_height
    n = t.shape[0]
    nx = prm.nx
    Phi = np.eye(nx)
    Qd = np.zeros((nx, nx))
    M = np.empty((nx, nx))
    nzc = np.empty((nx, nx), dtype=np.int64)
    nzn = np.empty(nx, dtype=np.int64)
    dx = np.zeros(nx)
    idx_v = np.arange(I_VEL, I_VEL + 3)
    idx_b = np.arange(I_BG, I_BG + 3)
    idx_psi = np.array([I_ATT + 2])
    idx_z = np.array([I_POS + 2])
    r3 = np.empty(3)
    r1 = np.empty(1)
    z3 = np.empty(3)
    z1 = np.empty(1)
    tmp3 = np.empty(3)
    tmp1 = np.empty(1)
    s3 = np.empty(3)
    s1_ = np.empty(1)
    dth = np.empty(3)
    dvb = np.empty(3)
    in_stance = stance[0]
    for k in range(1, n):
        h = t[k] - t[k - 1]
        for j in range(3):
            if prm.coning:
                dth[j] = (0.5 * (gyr[k, j] + gyr[k - 1, j]) - bg[k - 1, j]) * h
                dvb[j] = (0.5 * (acc[k, j] + acc[k - 1, j]) - ba[k - 1, j]) * h
            else:
                dth[j] = (gyr[k, j] - bg[k - 1, j]) * h
                dvb[j] = (acc[k, j] - ba[k - 1, j]) * h
        if prm.coning:
            rot = cross(dth, dvb)
            s1 = cross(dth_prev, dvb)
            s2 = cross(dv_prev, dth)
            con = cross(dth_prev, dth)
            for j in range(3):
                dv_prev[j] = dvb[j]
                dvb[j] = dvb[j] + 0.5 * rot[j] + (s1[j] + s2[j]) / 12.0
            for j in range(3):
                dth_prev[j] = dth[j]
                dth[j] = dth[j] + con[j] / 12.0
            # compensated increments: the velocity increment is resolved with the start attitude
            att = ATT_START
        else:
            # first-order: rotate first, then the specific force with the new attitude
            att = ATT_END
        dvn = strapdown_step_local(q[k - 1], v[k - 1], p[k - 1], dth, dvb, h, prm.g, att, q[k], v[k], p[k])
        for j in range(3):
            ba[k, j] = ba[k - 1, j]
            bg[k, j] = bg[k - 1, j]
        # ---- covariance propagation
        _zupt_transition(Phi, Qd, dcm_from_quat_1(q[k - 1]), dvn, h, prm)
        propagate_cov_sparse(Phi, P, Qd, M, nzc, nzn)
        # ---- updates
        if zv[k]:
            zero_velocity(v[k], prm.zupt_noise_std, z3, r3)
            joseph_update_rows(P, dx, idx_v, z3, r3, tmp3, s3)
            for j in range(3):
                innov[k, j] = tmp3[j]
                svar[k, j] = s3[j]
            _inject(dx, k, p, v, q, ba, bg, nx)
            if zaru[k] and nx == NX_BIAS:
                zero_rate(gyr[k], bg[k], prm.zaru_noise_std, z3, r3)
                joseph_update_rows(P, dx, idx_b, z3, r3, tmp3, s3)
                _inject(dx, k, p, v, q, ba, bg, nx)
            if prm.heading_hold:
                if not in_stance:
                    for j in range(4):
                        q_ref[j] = q[k, j]
                else:
                    heading_hold(q[k], q_ref, prm.heading_noise_std, z1, r1)
                    joseph_update_rows(P, dx, idx_psi, z1, r1, tmp1, s1_)
                    _inject(dx, k, p, v, q, ba, bg, nx)
            if prm.level_floor:
                height(p[k, 2], floor_height, prm.floor_noise_std, z1, r1)
                joseph_update_rows(P, dx, idx_z, z1, r1, tmp1, s1_)
                _inject(dx, k, p, v, q, ba, bg, nx)
            in_stance = True
        else:
            in_stance = False
        for i in range(nx):
            Pd[k, i] = P[i, i]
    stance[0] = in_stance


@njit(cache=True)
def _inject(dx, k, p, v, q, ba, bg, nx):
    """Fold the error estimate into the nominal state of row k (then dx is reset)."""
    inject_additive(p[k], dx, I_POS, 3)
    inject_additive(v[k], dx, I_VEL, 3)
    q[k] = inject_attitude_global(q[k], dx, I_ATT)
    if nx == NX_BIAS:
        inject_additive(ba[k], dx, I_BA, 3)
        inject_additive(bg[k], dx, I_BG, 3)
    for j in range(nx):
        dx[j] = 0.0
