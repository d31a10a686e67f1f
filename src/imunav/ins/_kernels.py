"""Numba kernels of :mod:`imunav.ins` (private).

Zero-velocity detector statistics, the strapdown steps (local level and NED)
and the error-state ZUPT Kalman filter loop.  Public, validated wrappers live
in :mod:`imunav.ins.detectors`, :mod:`imunav.ins.strapdown` and
:mod:`imunav.ins.zupt`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1, qexp_1, qlog_1, qmul_1, qrot_1
from imunav.earth import radii_gravity_1

# --------------------------------------------------------------------------
# Zero-velocity detector statistics
# --------------------------------------------------------------------------


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
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        for s in range(k, k + W):
            m0 += acc[s, 0]
            m1 += acc[s, 1]
            m2 += acc[s, 2]
        m0 /= W
        m1 /= W
        m2 /= W
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
        T /= W
        for s in range(k, k + W):
            out[s] = T
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
        T /= W
        for s in range(k, k + W):
            out[s] = T
        k += W
    return out


@njit(cache=True)
def amvd_blocks(acc, W):
    """AMVD statistic 1/W sum |y_a,k - ybar_a|^2 on non-overlapping blocks."""
    n = acc.shape[0]
    out = np.zeros(n)
    k = 0
    while k + W <= n:
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        for s in range(k, k + W):
            m0 += acc[s, 0]
            m1 += acc[s, 1]
            m2 += acc[s, 2]
        m0 /= W
        m1 /= W
        m2 /= W
        T = 0.0
        for s in range(k, k + W):
            T += (acc[s, 0] - m0) ** 2 + (acc[s, 1] - m1) ** 2 + (acc[s, 2] - m2) ** 2
        T /= W
        for s in range(k, k + W):
            out[s] = T
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


@njit(cache=True)
def moving_average(x, L):
    """Centred moving average of length L (shrinking at the edges)."""
    n = x.shape[0]
    c = np.zeros(n + 1)
    for i in range(n):
        c[i + 1] = c[i] + x[i]
    out = np.empty(n)
    h0 = L // 2
    h1 = L - h0
    for i in range(n):
        a = max(0, i - h0)
        b = min(n, i + h1)
        out[i] = (c[b] - c[a]) / (b - a)
    return out


# --------------------------------------------------------------------------
# Small helpers
# --------------------------------------------------------------------------


@njit(cache=True)
def _cross(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True)
def _normalize4(q):
    nn = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return q / nn


@njit(cache=True)
def increments(t, gyr, acc, corrected):
    """Angle and velocity increments over [t_{k-1}, t_k] for k = 1..N-1.

    Without ``corrected`` the rate of sample k is held over interval k (first
    order, the thesis / pyshoe convention); with ``corrected`` the point
    samples are integrated by the trapezoid rule and the two-sample coning and sculling corrections (Savage,
    *Strapdown Analytics* §7; Groves 2013 §5.5.4) use the previous interval:
    dth_k += dth_{k-1} x dth_k / 12,
    dv_k  += dth_k x dv_k / 2 + (dth_{k-1} x dv_k + dv_{k-1} x dth_k) / 12.
    Row 0 is zero.
    """
    n = t.shape[0]
    dth = np.zeros((n, 3))
    dv = np.zeros((n, 3))
    for k in range(1, n):
        h = t[k] - t[k - 1]
        for j in range(3):
            if corrected:
                # point samples: trapezoid over the interval (second order)
                dth[k, j] = 0.5 * (gyr[k - 1, j] + gyr[k, j]) * h
                dv[k, j] = 0.5 * (acc[k - 1, j] + acc[k, j]) * h
            else:
                dth[k, j] = gyr[k, j] * h
                dv[k, j] = acc[k, j] * h
    if not corrected:
        return dth, dv
    out_th = dth.copy()
    out_v = dv.copy()
    for k in range(1, n):
        rot = _cross(dth[k], dv[k])
        for j in range(3):
            out_v[k, j] += 0.5 * rot[j]
        if k >= 2:
            con = _cross(dth[k - 1], dth[k])
            s1 = _cross(dth[k - 1], dv[k])
            s2 = _cross(dv[k - 1], dth[k])
            for j in range(3):
                out_th[k, j] += con[j] / 12.0
                out_v[k, j] += (s1[j] + s2[j]) / 12.0
    return out_th, out_v


# --------------------------------------------------------------------------
# Strapdown: local level (no Earth rate) and NED with Earth / transport rate
# --------------------------------------------------------------------------


@njit(cache=True)
def strapdown_local_kernel(dth, dv, dt, q0, v0, p0, g, compensated):
    """Integrate increments in a fixed local-level NED frame (gravity (0,0,g)).

    q_k = q_{k-1} ⊗ exp(dth_k); v_k = v_{k-1} + C dv_k + g dt_k with C the
    attitude at the start of the interval when ``dv`` already carries the
    rotation compensation (``compensated``), else at mid interval;
    p_k = p_{k-1} + (v_{k-1} + v_k) dt_k / 2.
    """
    n = dth.shape[0]
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    p = np.empty((n, 3))
    q[0] = q0
    v[0] = v0
    p[0] = p0
    half = np.empty(3)
    for k in range(1, n):
        for j in range(3):
            half[j] = 0.0 if compensated else 0.5 * dth[k, j]
        qm = qmul_1(q[k - 1], qexp_1(half))
        dvn = qrot_1(qm, dv[k])
        q[k] = _normalize4(qmul_1(q[k - 1], qexp_1(dth[k])))
        h = dt[k]
        for j in range(3):
            v[k, j] = v[k - 1, j] + dvn[j]
        v[k, 2] += g * h
        for j in range(3):
            p[k, j] = p[k - 1, j] + 0.5 * (v[k - 1, j] + v[k, j]) * h
    return q, v, p


@njit(cache=True)
def strapdown_ned_kernel(dth, dv, dt, q0, v0, lat0, lon0, h0, omega_e, compensated):
    """NED mechanization with Earth rate, transport rate and Coriolis.

    q_k = exp(-w_in^n dt) ⊗ q_{k-1} ⊗ exp(dth_k)  (Groves 2013 eq. 5.44 form);
    v_k = v_{k-1} + [C_mid dv_k + (g^n - (2 w_ie^n + w_en^n) x v) dt];
    lat, lon, h from the mean velocity with the WGS84 radii.
    """
    n = dth.shape[0]
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    lla = np.empty((n, 3))
    q[0] = q0
    v[0] = v0
    lla[0, 0] = lat0
    lla[0, 1] = lon0
    lla[0, 2] = h0
    w_in = np.empty(3)
    half = np.empty(3)
    for k in range(1, n):
        h = dt[k]
        lat = lla[k - 1, 0]
        alt = lla[k - 1, 2]
        RN, RE, g = radii_gravity_1(lat, alt)
        vn = v[k - 1]
        w_ie0 = omega_e * math.cos(lat)
        w_ie2 = -omega_e * math.sin(lat)
        w_en0 = vn[1] / (RE + alt)
        w_en1 = -vn[0] / (RN + alt)
        w_en2 = -vn[1] * math.tan(lat) / (RE + alt)
        w_in[0] = w_ie0 + w_en0
        w_in[1] = w_en1
        w_in[2] = w_ie2 + w_en2
        # attitude for the velocity increment: start (compensated dv) or mid interval
        for j in range(3):
            half[j] = 0.0 if compensated else 0.5 * dth[k, j]
        qm = qmul_1(q[k - 1], qexp_1(half))
        for j in range(3):
            half[j] = -0.5 * w_in[j] * h
        qm = qmul_1(qexp_1(half), qm)
        dvn = qrot_1(qm, dv[k])
        # Coriolis and gravity
        c0 = 2.0 * w_ie0 + w_en0
        c1 = w_en1
        c2 = 2.0 * w_ie2 + w_en2
        cx = c1 * vn[2] - c2 * vn[1]
        cy = c2 * vn[0] - c0 * vn[2]
        cz = c0 * vn[1] - c1 * vn[0]
        v[k, 0] = vn[0] + dvn[0] - cx * h
        v[k, 1] = vn[1] + dvn[1] - cy * h
        v[k, 2] = vn[2] + dvn[2] + (g - cz) * h
        for j in range(3):
            half[j] = -w_in[j] * h
        q[k] = _normalize4(qmul_1(qexp_1(half), qmul_1(q[k - 1], qexp_1(dth[k]))))
        vm0 = 0.5 * (vn[0] + v[k, 0])
        vm1 = 0.5 * (vn[1] + v[k, 1])
        vm2 = 0.5 * (vn[2] + v[k, 2])
        lla[k, 2] = alt - vm2 * h
        lla[k, 0] = lat + vm0 / (RN + alt) * h
        lla[k, 1] = lla[k - 1, 1] + vm1 / ((RE + alt) * math.cos(lat)) * h
    return q, v, lla


# --------------------------------------------------------------------------
# Error-state ZUPT EKF
# --------------------------------------------------------------------------
# Error state dx = [dp, dv, dphi, (dba, dbg)] with
#   p = p_hat + dp, v = v_hat + dv, C_nb = exp([dphi x]) C_hat,
#   b_a = ba_hat + dba, b_g = bg_hat + dbg.
# Continuous error dynamics (local level, no Earth rate):
#   dp' = dv,  dv' = -[f^n x] dphi - C_hat dba + C_hat n_a,
#   dphi' = -C_hat dbg - C_hat n_g,  dba' = w_ba, dbg' = w_bg.


@njit(cache=True)
def _inv_small(S, Si):
    """Inverse of a small SPD matrix by Gauss-Jordan (m <= 6)."""
    m = S.shape[0]
    A = S.copy()
    for i in range(m):
        for j in range(m):
            Si[i, j] = 1.0 if i == j else 0.0
    for c in range(m):
        piv = A[c, c]
        for j in range(m):
            A[c, j] /= piv
            Si[c, j] /= piv
        for r in range(m):
            if r != c:
                fct = A[r, c]
                if fct != 0.0:
                    for j in range(m):
                        A[r, j] -= fct * A[c, j]
                        Si[r, j] -= fct * Si[c, j]


@njit(cache=True)
def _joseph_update(P, dx, idx, z, r, innov_out, s_out):
    """Update for unit-row H (measured states ``idx``), Joseph form.

    S = H P H^T + R; K = P H^T S^-1; dx = K z;
    P <- (I-KH) P (I-KH)^T + K R K^T, evaluated in O(nx^2 m) using that H
    only selects states.  Writes the innovation z and the diagonal of S.
    """
    nx = P.shape[0]
    m = idx.shape[0]
    S = np.empty((m, m))
    Si = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            S[i, j] = P[idx[i], idx[j]]
        S[i, i] += r[i]
    _inv_small(S, Si)
    K = np.empty((nx, m))
    for i in range(nx):
        for j in range(m):
            acc = 0.0
            for l in range(m):
                acc += P[i, idx[l]] * Si[l, j]
            K[i, j] = acc
    for i in range(nx):
        acc = 0.0
        for j in range(m):
            acc += K[i, j] * z[j]
        dx[i] = acc
    # X = (I - K H) P = P - K P[idx, :]
    X = np.empty((nx, nx))
    for i in range(nx):
        for j in range(nx):
            acc = P[i, j]
            for l in range(m):
                acc -= K[i, l] * P[idx[l], j]
            X[i, j] = acc
    # P = X (I - K H)^T + K R K^T = X - X[:, idx] K^T + K R K^T
    for i in range(nx):
        for j in range(i, nx):
            acc = X[i, j]
            for l in range(m):
                acc += -X[i, idx[l]] * K[j, l] + K[i, l] * r[l] * K[j, l]
            acc2 = X[j, i]
            for l in range(m):
                acc2 += -X[j, idx[l]] * K[i, l] + K[j, l] * r[l] * K[i, l]
            P[i, j] = 0.5 * (acc + acc2)
            P[j, i] = P[i, j]
    for j in range(m):
        innov_out[j] = z[j]
        s_out[j] = S[j, j]


@njit(cache=True)
def _sandwich(Phi, P, Qd, M, nzc, nzn):
    """P <- sym(Phi P Phi^T + Qd), skipping the zeros of the sparse Phi."""
    nx = P.shape[0]
    for i in range(nx):
        c = 0
        for l in range(nx):
            if Phi[i, l] != 0.0:
                nzc[i, c] = l
                c += 1
        nzn[i] = c
    for i in range(nx):
        for j in range(nx):
            acc = 0.0
            for c in range(nzn[i]):
                l = nzc[i, c]
                acc += Phi[i, l] * P[l, j]
            M[i, j] = acc
    for i in range(nx):
        for j in range(i, nx):
            acc = 0.0
            for c in range(nzn[j]):
                l = nzc[j, c]
                acc += M[i, l] * Phi[j, l]
            acc += 0.5 * (Qd[i, j] + Qd[j, i])
            P[i, j] = acc
            P[j, i] = acc


@njit(cache=True)
def _heading_change(q, q_ref):
    """Vertical (nav z) component of the rotation vector of ``C(q) C(q_ref)^T``.

    This is the rotation about the local vertical since ``q_ref``, whatever
    the sensor's mounting.  (The difference of ZYX yaw angles is not: the yaw
    of a tilted sensor changes when the foot only pitches, heel to toe.)
    """
    qc = np.empty(4)
    qc[0] = q_ref[0]
    for j in range(3):
        qc[1 + j] = -q_ref[1 + j]
    return qlog_1(qmul_1(q, qc))[2]


@njit(cache=True)
def zupt_ekf_kernel(
    t, acc, gyr, zv, q0, p0, v0, ba0, bg0, P0, nx, g,
    sig_a, sig_g, sig_ba, sig_bg, sig_v, zaru, sig_zaru, heading, sig_psi, coning,
    floor, sig_floor,
):
    """Run the error-state ZUPT EKF over a whole recording.

    Sample 0 carries the initial state; for k >= 1 the nominal state is
    propagated with sample k over t_k - t_{k-1}, the covariance with
    Phi = I + F dt, Q_d = G diag(sig_a^2, sig_g^2) G^T dt^2 (per-sample noise
    std, as in OpenShoe / pyshoe) plus bias random walks sig_b^2 dt; then, if
    zv[k], the ZUPT (and optionally heading-hold) updates apply, and the ZARU
    where the boolean mask zaru[k] is set (a subset of zv).

    Heading hold: from the second sample of a stance on, the rotation about
    the nav vertical since its first sample is measured as 0 (std sig_psi).
    Level floor (``floor``): each stance sample measures the height as the
    initial height p0[2] (std sig_floor).
    """
    n = t.shape[0]
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
    Phi = np.eye(nx)
    Qd = np.zeros((nx, nx))
    M = np.empty((nx, nx))
    nzc = np.empty((nx, nx), dtype=np.int64)
    nzn = np.empty(nx, dtype=np.int64)
    dx = np.zeros(nx)
    w = np.empty(3)
    f = np.empty(3)
    idx_v = np.array([3, 4, 5])
    idx_b = np.array([12, 13, 14])
    idx_psi = np.array([8])
    idx_z = np.array([2])
    rz = np.full(1, sig_floor * sig_floor)
    rv = np.full(3, sig_v * sig_v)
    rb = np.full(3, sig_zaru * sig_zaru)
    rpsi = np.full(1, sig_psi * sig_psi)
    z3 = np.empty(3)
    z1 = np.empty(1)
    tmp3 = np.empty(3)
    tmp1 = np.empty(1)
    s3 = np.empty(3)
    s1_ = np.empty(1)
    dth_prev = np.zeros(3)
    dv_prev = np.zeros(3)
    dth = np.empty(3)
    dvb = np.empty(3)
    in_stance = False
    q_ref = q0.copy()
    for k in range(1, n):
        h = t[k] - t[k - 1]
        for j in range(3):
            w[j] = gyr[k, j] - bg[k - 1, j]
            f[j] = acc[k, j] - ba[k - 1, j]
            if coning:
                dth[j] = (0.5 * (gyr[k, j] + gyr[k - 1, j]) - bg[k - 1, j]) * h
                dvb[j] = (0.5 * (acc[k, j] + acc[k - 1, j]) - ba[k - 1, j]) * h
            else:
                dth[j] = w[j] * h
                dvb[j] = f[j] * h
        qprev = q[k - 1]
        if coning:
            rot = _cross(dth, dvb)
            s1 = _cross(dth_prev, dvb)
            s2 = _cross(dv_prev, dth)
            con = _cross(dth_prev, dth)
            for j in range(3):
                dv_prev[j] = dvb[j]
                dvb[j] = dvb[j] + 0.5 * rot[j] + (s1[j] + s2[j]) / 12.0
            for j in range(3):
                dth_prev[j] = dth[j]
                dth[j] = dth[j] + con[j] / 12.0
            qk = _normalize4(qmul_1(qprev, qexp_1(dth)))
            dvn = qrot_1(qprev, dvb)
        else:
            # first-order: rotate first, then the specific force with the new attitude
            qk = _normalize4(qmul_1(qprev, qexp_1(dth)))
            dvn = qrot_1(qk, dvb)
        q[k] = qk
        for j in range(3):
            v[k, j] = v[k - 1, j] + dvn[j]
        v[k, 2] += g * h
        for j in range(3):
            p[k, j] = p[k - 1, j] + 0.5 * (v[k - 1, j] + v[k, j]) * h
            ba[k, j] = ba[k - 1, j]
            bg[k, j] = bg[k - 1, j]
        # ---- covariance propagation
        C = dcm_from_quat_1(qprev)
        for i in range(nx):
            for j in range(nx):
                Phi[i, j] = 1.0 if i == j else 0.0
                Qd[i, j] = 0.0
        for i in range(3):
            Phi[i, 3 + i] = h
        # -[dv^n x]: the Jacobian of v_k = v_{k-1} + dv^n + g h w.r.t. the nav-frame attitude error
        # (C = exp([dphi x]) C_hat  =>  d(dv^n) = dphi x dv^n) uses the very increment dv^n that the
        # nominal integration added, so that over a swing sum(dv^n) is the estimated velocity change
        # (~0 horizontally) and the yaw stays unobservable, as it is.
        Phi[3, 7] = dvn[2]
        Phi[3, 8] = -dvn[1]
        Phi[4, 6] = -dvn[2]
        Phi[4, 8] = dvn[0]
        Phi[5, 6] = dvn[1]
        Phi[5, 7] = -dvn[0]
        if nx == 15:
            for i in range(3):
                for j in range(3):
                    Phi[3 + i, 9 + j] = -C[i, j] * h
                    Phi[6 + i, 12 + j] = -C[i, j] * h
        # G Q G^T with G = dt C blocks: C diag(s^2) C^T = s^2 I for isotropic s
        qa = sig_a * sig_a * h * h
        qg = sig_g * sig_g * h * h
        for i in range(3):
            Qd[3 + i, 3 + i] = qa
            Qd[6 + i, 6 + i] = qg
        if nx == 15:
            for i in range(3):
                Qd[9 + i, 9 + i] = sig_ba * sig_ba * h
                Qd[12 + i, 12 + i] = sig_bg * sig_bg * h
        _sandwich(Phi, P, Qd, M, nzc, nzn)
        # ---- updates
        if zv[k]:
            # ZUPT: z = 0 - v_hat = dv + noise
            for j in range(3):
                z3[j] = -v[k, j]
            _joseph_update(P, dx, idx_v, z3, rv, tmp3, s3)
            for j in range(3):
                innov[k, j] = tmp3[j]
                svar[k, j] = s3[j]
            _inject(dx, k, p, v, q, ba, bg, nx)
            if zaru[k] and nx == 15:
                for j in range(3):
                    z3[j] = gyr[k, j] - bg[k, j]
                _joseph_update(P, dx, idx_b, z3, rb, tmp3, s3)
                _inject(dx, k, p, v, q, ba, bg, nx)
            if heading:
                if not in_stance:
                    for j in range(4):
                        q_ref[j] = q[k, j]
                else:
                    # C = exp([dphi x]) C_hat  =>  measured change 0 = change_hat + dphi_z
                    z1[0] = -_heading_change(q[k], q_ref)
                    _joseph_update(P, dx, idx_psi, z1, rpsi, tmp1, s1_)
                    _inject(dx, k, p, v, q, ba, bg, nx)
            if floor:
                z1[0] = p0[2] - p[k, 2]
                _joseph_update(P, dx, idx_z, z1, rz, tmp1, s1_)
                _inject(dx, k, p, v, q, ba, bg, nx)
            in_stance = True
        else:
            in_stance = False
        for i in range(nx):
            Pd[k, i] = P[i, i]
    return q, v, p, ba, bg, Pd, innov, svar, P


@njit(cache=True)
def _inject(dx, k, p, v, q, ba, bg, nx):
    """Fold the error estimate into the nominal state (then dx is reset)."""
    for j in range(3):
        p[k, j] += dx[j]
        v[k, j] += dx[3 + j]
    r = np.empty(3)
    for j in range(3):
        r[j] = dx[6 + j]
    q[k] = _normalize4(qmul_1(qexp_1(r), q[k]))
    if nx == 15:
        for j in range(3):
            ba[k, j] += dx[9 + j]
            bg[k, j] += dx[12 + j]
    for j in range(nx):
        dx[j] = 0.0
