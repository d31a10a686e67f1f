"""Frozen reference of the MEKF kernel as it was at 8c8bfc6 (before issue 34's allocation-free rewrite).

The oracle of ``test_mekf_speed_rewrite.py``: the fast kernel of :mod:`imunav.attitude._kernels` must reproduce
these outputs (same algorithm, different arithmetic order) to rounding.  Do not edit: it is the record of the
slow path, kept only to test against.  Parameters and state layout are the live module's (``P_*``, ``S_*``).
"""
# ruff: noqa: E501

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_exp_into, dcm_from_quat_1, qexp_t, qmul_t, qnormalize_t, qrot_t
from imunav.attitude._kernels import (  # the live P_* / S_* layout
    I_ATT,
    N_STATE,
    NX,
    P_ACCEL_DIRECTION_NOISE_STD,
    P_ACCEL_LPF_TIME_CONSTANT,
    P_ACCEL_REJECT_THRESHOLD,
    P_G,
    P_GYRO_BIAS_RANDOM_WALK,
    P_GYRO_NOISE_DENSITY,
    P_HEADING_NOISE_STD,
    P_HEADING_TIME_CONSTANT,
    P_K_ACCEL,
    P_K_GYRO_RATE,
    P_K_MAG,
    P_K_RATE,
    P_LPF_GYRO_THRESHOLD,
    P_MAG_BIAS,
    P_MAG_DIP_THRESHOLD,
    P_MAG_LPF_TIME_CONSTANT,
    P_MAG_MIN_UNDISTURBED,
    P_MAG_NORM_THRESHOLD,
    P_MAG_REF_TIME,
    P_MAG_REF_TIME_CONSTANT,
    P_REST_ACCEL_THRESHOLD,
    P_REST_GYRO_THRESHOLD,
    P_REST_LPF_TIME_CONSTANT,
    P_REST_TIME,
    P_TILT_TIME_CONSTANT,
    P_USE_MAG,
    P_ZARU_NOISE_STD,
    S_ACC_LP,
    S_ATT_Q,
    S_DISTURBED_TIMER,
    S_DOF,
    S_F_LP,
    S_F_LP_INIT,
    S_FLAGS,
    S_GYR_LP,
    S_MAG_DIP_LP,
    S_MAG_LP_INIT,
    S_MAG_NORM_LP,
    S_MAG_REF_DIP,
    S_MAG_REF_NORM,
    S_MAG_REF_VALID,
    S_NIS,
    S_REST_LP_INIT,
    S_REST_TIMER,
    S_UNDISTURBED,
    _lowpass,
)
from imunav.filters._core import reset_attitude_cov, scalar_update
from imunav.filters._core_models import gravity_direction_row, gyro_rest_row


@njit(cache=True)
def _heading_update_frozen(P, dx, qw, qx, qy, qz, tan_dip, r, psi, PH, with_bias):
    """Heading-only magnetometer update with the tilt as consider states (in place).

    The field yaw ψ_m = atan2(n_E, n_N) of n = C_nb(q̂) m_b is computed with the
    estimated tilt, so its error is, to first order in the navigation-frame
    attitude error φ = C_nb δθ and for a reference field of yaw 0 and dip δ,
        δψ_m = −φ_D + tan(δ) φ_N,
    i.e. a tilt error leaks into the measured heading by tan(dip) (the reason a
    compass is tilt-sensitive; Groves 2013, §6.1.1).  The update uses this H in
    the frame y = [φ_D, δb, φ_N, φ_E], with φ_N and φ_E as consider states
    (Schmidt-Kalman: zero gain, Simon 2006, §7.5): the field never tilts the
    estimate, and the reported covariance carries the tilt uncertainty of the
    measured heading.  ``tan_dip`` comes from the reference field, not from the
    current sample: a Jacobian built from the noisy sample is correlated with
    the innovation's noise and makes the bias covariance over-confident
    (measured: z RMS 1.46 on a static sensor).  With ``with_bias`` False the
    bias is a consider state as well.  Returns the NIS term.
    """
    # rows of T: C_nb row 3 (down), identity on the bias, C_nb rows 1 and 2
    qa = np.empty(4)
    qa[0], qa[1], qa[2], qa[3] = qw, qx, qy, qz
    C = dcm_from_quat_1(qa)
    T = np.zeros((6, 6))
    T[0, 0:3] = C[2]
    T[4, 0:3] = C[0]
    T[5, 0:3] = C[1]
    for i in range(3):
        T[1 + i, 3 + i] = 1.0
    Py = T @ P @ T.T
    dy = T @ dx
    Hy = np.zeros(6)
    Hy[0] = -1.0
    Hy[4] = tan_dip
    nu, s = scalar_update(Py, dy, Hy, r, psi, PH, 4 if with_bias else 1)
    nis = nu * nu / s
    P[:, :] = T.T @ Py @ T
    dx[:] = T.T @ dy
    return nis


@njit(cache=True)
def _mekf_predict_frozen(P, R, dt, sg2, sb2, W):
    """P ← Φ P Φᵀ + Q with Φ = [[R, −dt I], [0, I]] (block form, in place; W 6x6 scratch)."""
    # W[0:3, :] = Φ[0:3, :] P  (rows of the attitude block)
    for i in range(3):
        for j in range(6):
            acc = -dt * P[3 + i, j]
            for k in range(3):
                acc += R[i, k] * P[k, j]
            W[i, j] = acc
    # new A = W[0:3,:] Φ[0:3,:]ᵀ ; new B = W[0:3, 3:6]
    for i in range(3):
        for j in range(3):
            acc = -dt * W[i, 3 + j]
            for k in range(3):
                acc += W[i, k] * R[j, k]
            W[3 + i, j] = acc  # temporarily store new A in W rows 3..5
    for i in range(3):
        for j in range(3):
            P[i, j] = 0.5 * (W[3 + i, j] + W[3 + j, i])
            P[i, 3 + j] = W[i, 3 + j]
            P[3 + j, i] = W[i, 3 + j]
        P[i, i] += sg2
        P[3 + i, 3 + i] += sb2


@njit(cache=True)
def mekf_step_frozen(q, b, P, st, gyr, acc, mag, dt, p, out_phi):
    """One MEKF step.  ``st`` (float64 array, len N_STATE) is the adaptive state, laid out as MEKF_STATE
    (S_* constants); ``p`` the parameters (P_* constants).  The measurement updates are the models of
    :mod:`imunav.filters._core_models` fed to :func:`imunav.filters._core.scalar_update`, one scalar row at a time.
    Returns (q, b).  ``out_phi`` receives the 6x6 transition matrix.
    """
    g = p[P_G]
    use_mag = p[P_USE_MAG] > 0.5
    W = np.empty((6, 6))
    dx = np.zeros(6)
    H = np.zeros(6)
    PH = np.empty(6)
    # ---- predict
    w0 = gyr[0] - b[0]
    w1 = gyr[1] - b[1]
    w2 = gyr[2] - b[2]
    dcm_exp_into(W, -w0 * dt, -w1 * dt, -w2 * dt)  # δθ_k+1 = exp(-[ω]dt) δθ_k - dt δb
    R = W[0:3, 0:3].copy()
    for i in range(3):
        for j in range(3):
            out_phi[i, j] = R[i, j]
            out_phi[i, 3 + j] = -dt if i == j else 0.0
            out_phi[3 + i, j] = 0.0
            out_phi[3 + i, 3 + j] = 1.0 if i == j else 0.0
    e0, e1, e2, e3 = qexp_t(w0 * dt, w1 * dt, w2 * dt)
    t0, t1, t2, t3 = qmul_t(q[0], q[1], q[2], q[3], e0, e1, e2, e3)
    qw, qx, qy, qz = qnormalize_t(t0, t1, t2, t3)
    # gyro noise grows with the rate (scale-factor and misalignment errors of an
    # uncalibrated gyro act in proportion to |ω|): σ² = σ_g² + (k_ω |ω̄|)²
    wn2 = w0 * w0 + w1 * w1 + w2 * w2
    sg2 = (p[P_GYRO_NOISE_DENSITY] * p[P_GYRO_NOISE_DENSITY] + p[P_K_GYRO_RATE] * p[P_K_GYRO_RATE] * wn2) * dt
    st[S_ATT_Q] = sg2
    _mekf_predict_frozen(P, R, dt, sg2, p[P_GYRO_BIAS_RANDOM_WALK] * p[P_GYRO_BIAS_RANDOM_WALK] * dt, W)
    flags = 0
    nis = 0.0
    ndof = 0.0
    qbw, qbx, qby, qbz = qw, qx, qy, qz
    # ---- accelerometer (direction only)
    a0, a1, a2 = acc[0], acc[1], acc[2]
    an = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    wn = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if p[P_REST_LPF_TIME_CONSTANT] > 0.0:
        # rest from the deviation of gyro and accelerometer from their low-pass
        # (time constant p[P_REST_LPF_TIME_CONSTANT]) plus a bias-size bound on the low-passed rate
        # (Laidig & Seel 2023, §4.2): independent of the accelerometer's
        # scale and of the current bias estimate, robust to per-sample noise
        first = st[S_REST_LP_INIT] < 0.5
        st[S_REST_LP_INIT] = 1.0
        c = 1.0 - math.exp(-dt / p[P_REST_LPF_TIME_CONSTANT])
        dg = 0.0
        da = 0.0
        big = False
        for i in range(3):
            _lowpass(st, S_GYR_LP + i, gyr[i], c, first)
            _lowpass(st, S_ACC_LP + i, acc[i], c, first)
            dg += (gyr[i] - st[S_GYR_LP + i]) ** 2
            da += (acc[i] - st[S_ACC_LP + i]) ** 2
            if abs(st[S_GYR_LP + i]) > p[P_LPF_GYRO_THRESHOLD]:
                big = True
        if p[P_REST_GYRO_THRESHOLD] > 0.0 and dg < p[P_REST_GYRO_THRESHOLD] * p[P_REST_GYRO_THRESHOLD] and da < p[P_REST_ACCEL_THRESHOLD] * p[P_REST_ACCEL_THRESHOLD] and not big:
            st[S_REST_TIMER] += dt
        else:
            st[S_REST_TIMER] = 0.0
    elif p[P_REST_GYRO_THRESHOLD] > 0.0 and wn < p[P_REST_GYRO_THRESHOLD] and abs(an - g) < p[P_REST_ACCEL_THRESHOLD]:
        st[S_REST_TIMER] += dt
    else:
        st[S_REST_TIMER] = 0.0
    if p[P_ACCEL_LPF_TIME_CONSTANT] > 0.0:
        # low-pass of the specific force in the nav frame; the stored vector is
        # rotated with every correction below, so this is the low-pass in the
        # gyro-integrated frame: translational accelerations average out
        # because velocity stays bounded (cf. Laidig & Seel 2023, §4.1)
        f0, f1, f2 = qrot_t(qw, qx, qy, qz, a0, a1, a2)
        first = st[S_F_LP_INIT] < 0.5
        st[S_F_LP_INIT] = 1.0
        c = 1.0 - math.exp(-dt / p[P_ACCEL_LPF_TIME_CONSTANT])
        _lowpass(st, S_F_LP, f0, c, first)
        _lowpass(st, S_F_LP + 1, f1, c, first)
        _lowpass(st, S_F_LP + 2, f2, c, first)
        a0, a1, a2 = qrot_t(qw, -qx, -qy, -qz, st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2])
        an = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    dev = abs(an - g) / g
    if an > 0.0 and dev < p[P_ACCEL_REJECT_THRESHOLD]:
        # per-sample variance: σ_a², or from the time constant τ_a of the tilt
        # correction, (τ_a σ_g)² / Δt (steady state of a random walk of density
        # σ_g seen through white noise of density τ_a σ_g: gain 1/τ_a)
        sa2 = (p[P_TILT_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]) ** 2 / dt if p[P_TILT_TIME_CONSTANT] > 0.0 else p[P_ACCEL_DIRECTION_NOISE_STD] * p[P_ACCEL_DIRECTION_NOISE_STD]
        r = sa2 * (1.0 + p[P_K_ACCEL] * (dev / 0.01) ** 2) + (p[P_K_RATE] * wn) ** 2
        # gravity-direction model, one scalar row at a time (H = [ĥ]x rows for the body error)
        for i in range(3):
            a_i = a0 if i == 0 else (a1 if i == 1 else a2)
            nu = gravity_direction_row(qw, qx, qy, qz, a_i / an, i, H)
            nu, s = scalar_update(P, dx, H, r, nu, PH, NX)
            nis += nu * nu / s
            ndof += 1.0
    else:
        flags |= 1
    # ---- rest: zero-rate pseudo measurement ω_meas - b = 0 (+ noise)
    if p[P_REST_GYRO_THRESHOLD] > 0.0 and st[S_REST_TIMER] >= p[P_REST_TIME]:
        flags |= 4
        r = p[P_ZARU_NOISE_STD] * p[P_ZARU_NOISE_STD]
        for i in range(3):
            nu = gyro_rest_row(gyr[i], b[i], i, H)
            nu, s = scalar_update(P, dx, H, r, nu, PH, NX)
            nis += nu * nu / s
            ndof += 1.0
    # apply the tilt / bias correction before the heading update
    reset_attitude_cov(P, dx, I_ATT)
    e0, e1, e2, e3 = qexp_t(dx[0], dx[1], dx[2])
    t0, t1, t2, t3 = qmul_t(qw, qx, qy, qz, e0, e1, e2, e3)
    qw, qx, qy, qz = qnormalize_t(t0, t1, t2, t3)
    bo = np.empty(3)
    bo[0] = b[0] + dx[3]
    bo[1] = b[1] + dx[4]
    bo[2] = b[2] + dx[5]
    # ---- magnetometer: heading only
    if use_mag:
        mn = math.sqrt(mag[0] * mag[0] + mag[1] * mag[1] + mag[2] * mag[2])
        if mn > 0.0:
            n0, n1, n2 = qrot_t(qw, qx, qy, qz, mag[0], mag[1], mag[2])
            hh = math.sqrt(n0 * n0 + n1 * n1)
            dip = math.atan2(n2, hh)
            if p[P_MAG_LPF_TIME_CONSTANT] > 0.0:
                # norm and dip low-passed (time constant p[P_MAG_LPF_TIME_CONSTANT]) before the disturbance test
                first = st[S_MAG_LP_INIT] < 0.5
                st[S_MAG_LP_INIT] = 1.0
                c = 1.0 - math.exp(-dt / p[P_MAG_LPF_TIME_CONSTANT])
                _lowpass(st, S_MAG_NORM_LP, mn, c, first)
                _lowpass(st, S_MAG_DIP_LP, dip, c, first)
                mn_t = st[S_MAG_NORM_LP]
                dip_t = st[S_MAG_DIP_LP]
            else:
                mn_t = mn
                dip_t = dip
            if st[S_MAG_REF_VALID] < 0.5:
                st[S_MAG_REF_NORM] = mn_t
                st[S_MAG_REF_DIP] = dip_t
                st[S_MAG_REF_VALID] = 1.0
            dn = (mn_t - st[S_MAG_REF_NORM]) / st[S_MAG_REF_NORM]
            dd = dip_t - st[S_MAG_REF_DIP]
            disturbed = abs(dn) > p[P_MAG_NORM_THRESHOLD] or abs(dd) > p[P_MAG_DIP_THRESHOLD]
            if disturbed:
                st[S_UNDISTURBED] = 0.0
            else:
                st[S_UNDISTURBED] += dt
            if disturbed:
                st[S_DISTURBED_TIMER] += dt
                flags |= 2
                if p[P_MAG_REF_TIME] > 0.0 and st[S_DISTURBED_TIMER] > p[P_MAG_REF_TIME]:
                    st[S_MAG_REF_NORM] = mn_t
                    st[S_MAG_REF_DIP] = dip_t
                    st[S_DISTURBED_TIMER] = 0.0
            else:
                st[S_DISTURBED_TIMER] = 0.0
                if p[P_MAG_REF_TIME_CONSTANT] > 0.0:
                    c = dt / p[P_MAG_REF_TIME_CONSTANT]
                    st[S_MAG_REF_NORM] += c * (mn_t - st[S_MAG_REF_NORM])
                    st[S_MAG_REF_DIP] += c * (dip_t - st[S_MAG_REF_DIP])
            # used only after p[P_MAG_MIN_UNDISTURBED] s of continuous undisturbed field: the few
            # samples of a disturbance that happen to pass the test are not used
            if not disturbed and st[S_UNDISTURBED] >= p[P_MAG_MIN_UNDISTURBED] and hh > 1e-9 * mn:
                psi = math.atan2(n1, n0)
                # σ_mag is field-vector noise, so the heading noise is σ_mag |m| / |m_h|;
                # τ_mag is the time constant of the heading itself (whatever the dip)
                sm2 = (p[P_HEADING_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]) ** 2 / dt if p[P_HEADING_TIME_CONSTANT] > 0.0 else (p[P_HEADING_NOISE_STD] * mn / hh) ** 2
                r = sm2 * (1.0 + p[P_K_MAG] * ((dn / p[P_MAG_NORM_THRESHOLD]) ** 2 + (dd / p[P_MAG_DIP_THRESHOLD]) ** 2))
                for j in range(6):
                    dx[j] = 0.0
                nis += _heading_update_frozen(P, dx, qw, qx, qy, qz, math.tan(st[S_MAG_REF_DIP]), r, psi, PH, p[P_MAG_BIAS] > 0.5)
                ndof += 1.0
                reset_attitude_cov(P, dx, I_ATT)
                e0, e1, e2, e3 = qexp_t(dx[0], dx[1], dx[2])
                t0, t1, t2, t3 = qmul_t(qw, qx, qy, qz, e0, e1, e2, e3)
                qw, qx, qy, qz = qnormalize_t(t0, t1, t2, t3)
                bo[0] += dx[3]
                bo[1] += dx[4]
                bo[2] += dx[5]
    if p[P_ACCEL_LPF_TIME_CONSTANT] > 0.0:
        # rotate the low-passed nav-frame vector with the total correction q ⊗ q_before*
        d0, d1, d2, d3 = qmul_t(qw, qx, qy, qz, qbw, -qbx, -qby, -qbz)
        st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2] = qrot_t(d0, d1, d2, d3, st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2])
    st[S_FLAGS] = flags
    st[S_NIS] = nis
    st[S_DOF] = ndof
    qo = np.empty(4)
    qo[0] = qw
    qo[1] = qx
    qo[2] = qy
    qo[3] = qz
    return qo, bo


@njit(cache=True)
def mekf_run_frozen(q0, b0, P0, gyr, acc, mag, dt, p, store):
    """Run the MEKF over a recording.

    Returns q (N,4), b (N,3), Pdiag (N,6), flags (N,), nis (N,), dof (N,), and
    when ``store``: P after update (N,6,6), P predicted (N,6,6), Φ (N,6,6).
    """
    n = gyr.shape[0]
    qs = np.empty((n, 4))
    bs = np.empty((n, 3))
    pd = np.empty((n, 6))
    flags = np.zeros(n, np.int64)
    nis = np.zeros(n)
    dof = np.zeros(n)
    m = n if store else 1
    Pu = np.empty((m, 6, 6))
    Pp = np.empty((m, 6, 6))
    Ph = np.empty((m, 6, 6))
    q = q0.copy()
    b = b0.copy()
    P = P0.copy()
    st = np.zeros(N_STATE)
    phi = np.empty((6, 6))
    for k in range(n):
        q, b = mekf_step_frozen(q, b, P, st, gyr[k], acc[k], mag[k], dt[k], p, phi)
        if store:
            Ph[k] = phi
            # P predicted = Φ P_{k-1} Φ^T + Q (recompute cheaply)
            Pprev = P0 if k == 0 else Pu[k - 1]
            Q = np.zeros((6, 6))
            for i in range(3):
                Q[i, i] = st[S_ATT_Q]
                Q[3 + i, 3 + i] = p[P_GYRO_BIAS_RANDOM_WALK] * p[P_GYRO_BIAS_RANDOM_WALK] * dt[k]
            Pp[k] = phi @ Pprev @ phi.T + Q
            Pu[k] = P
        qs[k] = q
        bs[k] = b
        for i in range(6):
            pd[k, i] = P[i, i]
        flags[k] = int(st[S_FLAGS])
        nis[k] = st[S_NIS]
        dof[k] = st[S_DOF]
    return qs, bs, pd, flags, nis, dof, Pu, Pp, Ph

