"""Numba kernels of the loosely coupled GNSS/INS error-state filter (private; public API in :mod:`imunav.ins.gins`).

Error state (named layout below): NED position error δr (m), velocity error δv (m/s), navigation-frame attitude
error φ with ``C_nb = exp([φ×]) Ĉ_nb`` (the global convention of :mod:`imunav.filters._core`), gyro and
accelerometer biases, and optionally gyro and accelerometer scale factors (first-order Gauss–Markov each).
Errors are ``true − estimate``.  The IMU model is ``ω̃ = (1 + s_g) ω + b_g + w_g``, ``f̃ = (1 + s_a) f + b_a + w_a``.

Continuous error dynamics (Groves 2013, §14.2.4, in this sign convention; small Earth-curvature terms of the
position rows dropped, the vertical gravity gradient kept)::

    δṙ = δv
    δv̇ = −[fⁿ×] φ − [(2ω_ie + ω_en)×] δv − Ĉ δb_a − Ĉ diag(f^b) δs_a + (0, 0, 2g/R δr_D) − Ĉ w_a
    φ̇  = −[ω_in×] φ − δω_en(δv) − Ĉ δb_g − Ĉ diag(ω^b) δs_g − Ĉ w_g
    δḃ = −δb / T + w_b  (σ² 2/T),   δṡ = −δs / T + w_s

The nominal state is integrated per IMU sample by :func:`imunav.filters._core.strapdown_step_ned`; the covariance
every ``cov_step`` samples (and at each GNSS epoch and each barometer or magnetometer sample) by
:func:`imunav.filters._core_gins.propagate_cov_series`.
GNSS epochs between two IMU samples split the increments at their own time stamps.  Updates use
:func:`imunav.filters._core.chi2_gate` and :func:`imunav.filters._core.joseph_update`; injection uses
:func:`imunav.filters._core.inject_additive`, :func:`~imunav.filters._core.inject_attitude_global` and
:func:`imunav.filters._core_gins.inject_position_lla`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.earth import radii_gravity_1
from imunav.filters._core import (
    ATT_START,
    chi2_gate,
    inject_additive,
    inject_attitude_global,
    joseph_update,
    joseph_update_rows,
    nis,
    strapdown_step_ned,
)
from imunav.filters._core_gins import earth_rate_rows, inject_position_lla, mag_heading, propagate_cov_series
from imunav.filters._core_models import height, zero_velocity

# error-state layout
I_POS = 0  # δr N E D, m
I_VEL = 3  # δv N E D, m/s
I_ATT = 6  # φ, rad (navigation frame)
I_BG = 9  # δb_g, rad/s
I_BA = 12  # δb_a, m/s²
I_SG = 15  # δs_g (21 states only)
I_SA = 18  # δs_a (21 states only)
NX15 = 15
NX21 = 21

# IMU-error vector of the nominal state (bg, ba, sg, sa)
E_BG = 0
E_BA = 3
E_SG = 6
E_SA = 9
E_ODO = 12  # odometer scale factor
NE = 13

# parameter vector layout (built by imunav.ins.gins._params)
K_OMEGA_E = 0
K_ARW = 1  # 3
K_VRW = 4  # 3
K_BG_Q = 7  # 3: 2 σ² / T
K_BA_Q = 10
K_SG_Q = 13
K_SA_Q = 16
K_BG_T = 19  # 3: correlation times, s
K_BA_T = 22
K_SG_T = 25
K_SA_T = 28
K_LEVER = 31  # 3: antenna lever arm, body FRD, m
K_GATE_POS = 34
K_GATE_VEL = 35
K_COV_STEP = 36  # samples between covariance propagations
K_USE_VEL = 37  # 1.0: use GNSS velocity when given
K_NB = 38  # 15 or 21: navigation + IMU-error states before the optional odometer scale state
K_I_ODO = 39  # index of the odometer scale state, -1 without odometer
K_ODO_Q = 40  # 2 σ² / T of the odometer scale
K_ODO_T = 41
K_ODO_LEVER = 42  # 3: wheel contact point (odometer and NHC), body FRD, m
K_NHC_R = 45  # NHC variance (m/s)², 0: no NHC
K_GATE_VEH = 46  # χ² gate of the vehicle update (3 rows; 2 and 1 rows scaled in the wrapper)
K_GATE_VEH2 = 47
K_GATE_VEH1 = 48
K_ZUPT_SD = 49  # ZUPT velocity σ, m/s
K_ZARU_SD = 50  # ZARU rate σ, rad/s
K_BARO_SD = 51  # barometric height σ, m
K_GATE_ZUPT = 52  # χ²(6)
K_GATE_BARO = 53  # χ²(1)
K_DECL = 54  # magnetic declination, rad (east positive)
K_MAG_SD = 55  # magnetometer heading σ, rad
K_GATE_MAG = 56  # χ²(1)
NK = 57

# aiding NIS record columns (per IMU sample, NaN when not applied)
A_ZUPT = 0  # ZUPT + ZARU together (6 dof), the statistic of their gate
A_BARO = 1
A_MAG = 2
A_ODO = 3  # odometer row alone (1 dof), from the joint innovation covariance of the vehicle update
A_NHC = 4  # NHC rows alone (2 dof)
A_ZUPT_V = 5  # ZUPT velocity rows alone (3 dof)
A_ZARU = 6  # ZARU rate rows alone (3 dof)
NA = 7

# NIS record columns
N_POS = 0
N_VEL = 1


@njit(cache=True)
def _skew(a, M, r0, c0, sign):
    """Write ``sign [a×]`` into M[r0:r0+3, c0:c0+3]."""
    M[r0, c0] = 0.0
    M[r0, c0 + 1] = -sign * a[2]
    M[r0, c0 + 2] = sign * a[1]
    M[r0 + 1, c0] = sign * a[2]
    M[r0 + 1, c0 + 1] = 0.0
    M[r0 + 1, c0 + 2] = -sign * a[0]
    M[r0 + 2, c0] = -sign * a[1]
    M[r0 + 2, c0 + 1] = sign * a[0]
    M[r0 + 2, c0 + 2] = 0.0


@njit(cache=True)
def _mat3(C, M, r0, c0, sign, d):
    """Write ``sign C diag(d)`` into M[r0:r0+3, c0:c0+3]."""
    for i in range(3):
        for j in range(3):
            M[r0 + i, c0 + j] = sign * C[i, j] * d[j]


@njit(cache=True)
def _system(q, v, lla, fb, wb, prm, nx, F, Q):
    """Fill F and Q (= G Q Gᵀ) of the error dynamics at the nominal state with mean ``f^b`` and ``ω^b``."""
    F[:, :] = 0.0
    Q[:, :] = 0.0
    C = dcm_from_quat_1(q)
    lat = lla[0]
    alt = lla[2]
    RN, RE, g = radii_gravity_1(lat, alt)
    om = prm[K_OMEGA_E]
    w_ie = np.array([om * math.cos(lat), 0.0, -om * math.sin(lat)])
    w_en = np.array([v[1] / (RE + alt), -v[0] / (RN + alt), -v[1] * math.tan(lat) / (RE + alt)])
    fn = C @ fb
    ones = np.ones(3)
    for j in range(3):
        F[I_POS + j, I_VEL + j] = 1.0
    F[I_VEL + 2, I_POS + 2] = 2.0 * g / (math.sqrt(RN * RE) + alt)
    _skew(fn, F, I_VEL, I_ATT, -1.0)
    _skew(2.0 * w_ie + w_en, F, I_VEL, I_VEL, -1.0)
    _mat3(C, F, I_VEL, I_BA, -1.0, ones)
    _skew(w_ie + w_en, F, I_ATT, I_ATT, -1.0)
    F[I_ATT, I_VEL + 1] = -1.0 / (RE + alt)
    F[I_ATT + 1, I_VEL] = 1.0 / (RN + alt)
    F[I_ATT + 2, I_VEL + 1] = math.tan(lat) / (RE + alt)
    _mat3(C, F, I_ATT, I_BG, -1.0, ones)
    for j in range(3):
        F[I_BG + j, I_BG + j] = -1.0 / prm[K_BG_T + j]
        F[I_BA + j, I_BA + j] = -1.0 / prm[K_BA_T + j]
        Q[I_BG + j, I_BG + j] = prm[K_BG_Q + j]
        Q[I_BA + j, I_BA + j] = prm[K_BA_Q + j]
    io = int(prm[K_I_ODO])
    if io >= 0:
        F[io, io] = -1.0 / prm[K_ODO_T]
        Q[io, io] = prm[K_ODO_Q]
    if prm[K_NB] == NX21:
        _mat3(C, F, I_VEL, I_SA, -1.0, fb)
        _mat3(C, F, I_ATT, I_SG, -1.0, wb)
        for j in range(3):
            F[I_SG + j, I_SG + j] = -1.0 / prm[K_SG_T + j]
            F[I_SA + j, I_SA + j] = -1.0 / prm[K_SA_T + j]
            Q[I_SG + j, I_SG + j] = prm[K_SG_Q + j]
            Q[I_SA + j, I_SA + j] = prm[K_SA_Q + j]
    # white noise through C: C diag(n²) Cᵀ
    for i in range(3):
        for j in range(3):
            a = 0.0
            b = 0.0
            for l in range(3):
                a += C[i, l] * prm[K_VRW + l] ** 2 * C[j, l]
                b += C[i, l] * prm[K_ARW + l] ** 2 * C[j, l]
            Q[I_VEL + i, I_VEL + j] = a
            Q[I_ATT + i, I_ATT + j] = b


@njit(cache=True)
def _inject(dx, q, v, lla, err, nx, prm, acc_dx):
    """Feed the error estimate back into the nominal state and zero it."""
    inject_position_lla(lla, dx, I_POS)
    inject_additive(v, dx, I_VEL, 3)
    qn = inject_attitude_global(q, dx, I_ATT)
    for j in range(4):
        q[j] = qn[j]
    bg = err[E_BG:E_BG + 3]
    ba = err[E_BA:E_BA + 3]
    inject_additive(bg, dx, I_BG, 3)
    inject_additive(ba, dx, I_BA, 3)
    io = int(prm[K_I_ODO])
    if io >= 0:
        err[E_ODO] += dx[io]
    if prm[K_NB] == NX21:
        sg = err[E_SG:E_SG + 3]
        sa = err[E_SA:E_SA + 3]
        inject_additive(sg, dx, I_SG, 3)
        inject_additive(sa, dx, I_SA, 3)
    for j in range(nx):
        acc_dx[j] += dx[j]
    dx[:] = 0.0


@njit(cache=True)
def _gated_update(P, dx, H, R, nu, innov, S, gate, q, v, lla, err, nx, prm, acc_dx):
    """Chi-square gate on ``S0 = H P Hᵀ + R``; when accepted, Joseph update (``innov``, ``S``: work arrays) and
    injection of ``dx``.  Returns (accepted, NIS)."""
    S0 = H @ P @ H.T + R
    ok, d = chi2_gate(nu, S0, gate)
    if ok:
        joseph_update(P, dx, H, R, nu, innov, S)
        _inject(dx, q, v, lla, err, nx, prm, acc_dx)
    return ok, d


@njit(cache=True)
def _gnss_update(P, dx, q, v, lla, err, wb, zp, rp, zv, rv, use_vel, prm, nx, nis_out, acc_out, acc_dx):
    """GNSS position (and velocity) update with the antenna lever arm; χ² gates; NIS recorded."""
    C = dcm_from_quat_1(q)
    lever = prm[K_LEVER:K_LEVER + 3]
    la = C @ lever
    RN, RE, _ = radii_gravity_1(lla[0], lla[2])
    H = np.zeros((3, nx))
    R = np.zeros((3, 3))
    nu = np.empty(3)
    innov = np.empty(3)
    S = np.empty((3, 3))
    nu[0] = (zp[0] - lla[0]) * (RN + lla[2]) - la[0]
    nu[1] = (zp[1] - lla[1]) * (RE + lla[2]) * math.cos(lla[0]) - la[1]
    nu[2] = -(zp[2] - lla[2]) - la[2]
    for j in range(3):
        H[j, I_POS + j] = 1.0
        R[j, j] = rp[j]
    _skew(la, H, 0, I_ATT, -1.0)
    ok, nis_out[N_POS] = _gated_update(P, dx, H, R, nu, innov, S, prm[K_GATE_POS], q, v, lla, err, nx, prm, acc_dx)
    acc_out[N_POS] = 1.0 if ok else 0.0
    if not use_vel:
        return
    C = dcm_from_quat_1(q)
    lat = lla[0]
    om = prm[K_OMEGA_E]
    w_ie_b = C.T @ np.array([om * math.cos(lat), 0.0, -om * math.sin(lat)])
    w_eb = wb - w_ie_b
    wxl = np.array([w_eb[1] * lever[2] - w_eb[2] * lever[1], w_eb[2] * lever[0] - w_eb[0] * lever[2],
                    w_eb[0] * lever[1] - w_eb[1] * lever[0]])
    a = C @ wxl
    H[:, :] = 0.0
    for j in range(3):
        nu[j] = zv[j] - v[j] - a[j]
        H[j, I_VEL + j] = 1.0
        R[j, j] = rv[j]
    _skew(a, H, 0, I_ATT, -1.0)
    Lx = np.zeros((3, 3))
    _skew(lever, Lx, 0, 0, 1.0)
    CL = C @ Lx
    for i in range(3):
        for j in range(3):
            H[i, I_BG + j] = CL[i, j]
            if prm[K_NB] == NX21:
                H[i, I_SG + j] = CL[i, j] * wb[j]
    ok, nis_out[N_VEL] = _gated_update(P, dx, H, R, nu, innov, S, prm[K_GATE_VEL], q, v, lla, err, nx, prm, acc_dx)
    acc_out[N_VEL] = 1.0 if ok else 0.0


@njit(cache=True)
def _vehicle_update(P, dx, q, v, lla, err, wb, z_odo, r_odo, prm, nx, out, acc_dx, aid, moving):
    """Odometer (forward wheel speed, scale-factor state) and non-holonomic constraint (zero lateral and vertical
    velocity of the wheel point) as one update of up to 3 rows; ``out`` receives (NIS, accepted, rows), ``aid``
    the NIS of the odometer row and of the NHC rows alone (``A_ODO``, ``A_NHC``: the marginals of the joint
    innovation, χ²(1) and χ²(2) for a consistent filter; record only, the update is the joint one).
    The NHC rows and the odometer are left out while the vehicle is declared static (``moving`` False): the ZUPT
    then constrains the same velocity with the rest σ (a wheel encoder reads 0 while the body idles), and using
    the one velocity twice, as if the two measurements had independent noises, would make the filter
    overconfident.

    Wheel-point body velocity ``v_w = Ĉᵀ v + ω × l``; with ``C = exp([φ×]) Ĉ``:
    ``∂v_w/∂δv = Ĉᵀ``, ``∂v_w/∂φ = Ĉᵀ [v×]``, ``∂v_w/∂δb_g = [l×]``, ``∂v_w/∂δs_g = [l×] diag(ω)``;
    the odometer reads ``(1 + k) v_w,x`` (Groves 2013, §16.3; Niu et al. 2007 for the NHC).
    """
    use_odo = not math.isnan(z_odo) and moving
    use_nhc = prm[K_NHC_R] > 0.0 and moving
    m = (1 if use_odo else 0) + (2 if use_nhc else 0)
    if m == 0:
        return
    C = dcm_from_quat_1(q)
    lever = prm[K_ODO_LEVER:K_ODO_LEVER + 3]
    vb = C.T @ v
    vw = vb + np.array([wb[1] * lever[2] - wb[2] * lever[1], wb[2] * lever[0] - wb[0] * lever[2],
                        wb[0] * lever[1] - wb[1] * lever[0]])
    Hv = np.zeros((3, nx))
    for i in range(3):
        for j in range(3):
            Hv[i, I_VEL + j] = C[j, i]
    Vx = np.zeros((3, 3))
    _skew(v, Vx, 0, 0, 1.0)
    CtV = C.T @ Vx
    Lx = np.zeros((3, 3))
    _skew(lever, Lx, 0, 0, 1.0)
    for i in range(3):
        for j in range(3):
            Hv[i, I_ATT + j] = CtV[i, j]
            Hv[i, I_BG + j] = Lx[i, j]
            if prm[K_NB] == NX21:
                Hv[i, I_SG + j] = Lx[i, j] * wb[j]
    H = np.zeros((m, nx))
    R = np.zeros((m, m))
    nu = np.empty(m)
    r = 0
    io = int(prm[K_I_ODO])
    if use_odo:
        k = err[E_ODO] if io >= 0 else 0.0
        for j in range(nx):
            H[r, j] = (1.0 + k) * Hv[0, j]
        if io >= 0:
            H[r, io] = vw[0]
        nu[r] = z_odo - (1.0 + k) * vw[0]
        R[r, r] = r_odo
        r += 1
    if use_nhc:
        for a in (1, 2):
            for j in range(nx):
                H[r, j] = Hv[a, j]
            nu[r] = -vw[a]
            R[r, r] = prm[K_NHC_R]
            r += 1
    S0 = H @ P @ H.T + R
    if use_odo:
        aid[A_ODO] = nu[0] * nu[0] / S0[0, 0]
    if use_nhc:
        aid[A_NHC] = nis(nu[m - 2:], S0[m - 2:, m - 2:])
    gate = prm[K_GATE_VEH] if m == 3 else (prm[K_GATE_VEH2] if m == 2 else prm[K_GATE_VEH1])
    ok, out[0] = _gated_update(P, dx, H, R, nu, np.empty(m), np.empty((m, m)), gate, q, v, lla, err, nx, prm, acc_dx)
    out[1] = 1.0 if ok else 0.0
    out[2] = m


@njit(cache=True)
def _rows_update(P, dx, idx, z, r, gate, q, v, lla, err, nx, prm, acc_dx):
    """Gated unit-row update (H selects ``idx``) with :func:`~imunav.filters._core.joseph_update_rows`; returns NIS."""
    m = idx.shape[0]
    S = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            S[i, j] = P[idx[i], idx[j]]
        S[i, i] += r[i]
    ok, d = chi2_gate(z, S, gate)
    if ok:
        innov = np.empty(m)
        s_out = np.empty(m)
        joseph_update_rows(P, dx, idx, z, r, innov, s_out)
        _inject(dx, q, v, lla, err, nx, prm, acc_dx)
    return d


@njit(cache=True)
def _rest_and_baro_update(P, dx, q, v, lla, err, gyr, dt_rate, static, h_baro, prm, nx, out, acc_dx):
    """ZUPT + ZARU while ``static`` and barometric height (``ν = −h_b + ĥ`` on δr_D, through
    :func:`~imunav.filters._core_models.height`).

    ZUPT: ``ν = −v̂`` on δv.  ZARU: at rest the gyros read the Earth rate (``gyr``: the raw mean rate over the
    last ``dt_rate`` seconds, the covariance step; white noise of density ARW gives it the variance
    ``ARW² / dt_rate`` per axis, added to ``zaru_noise²``, the rate disturbance at rest such as engine vibration),
    :func:`~imunav.filters._core_gins.earth_rate_rows`, whose attitude columns make a static
    alignment's heading and east gyro bias one observable combination (Groves 2013, §14.2.2): without them the
    filter would count the Earth rate as a direct measurement of the bias and report a heading σ it does not
    have.  The core's :func:`~imunav.filters._core_models.zero_rate` is the local-level model without Earth
    rate."""
    if static and prm[K_ZUPT_SD] > 0.0:
        nu3 = np.empty(3)
        r3 = np.empty(3)
        zero_velocity(v, prm[K_ZUPT_SD], nu3, r3)
        om = prm[K_OMEGA_E]
        w_ie_n = np.array([om * math.cos(lla[0]), 0.0, -om * math.sin(lla[0])])
        H = np.zeros((6, nx))
        R = np.zeros((6, 6))
        z = np.empty(6)
        full = prm[K_NB] == NX21
        sg = np.zeros(3)
        if full:
            sg[:] = err[E_SG:E_SG + 3]
        earth_rate_rows(dcm_from_quat_1(q), gyr, err[E_BG:E_BG + 3], sg, w_ie_n, z, H, 3, I_ATT, I_BG,
                        I_SG if full else -1)
        for j in range(3):
            H[j, I_VEL + j] = 1.0
            z[j] = nu3[j]
            R[j, j] = r3[j]
            R[3 + j, 3 + j] = prm[K_ZARU_SD] ** 2 + prm[K_ARW + j] ** 2 / dt_rate
        S0 = H @ P @ H.T + R
        # the marginal NIS of the ZUPT rows and of the ZARU rows (record only; the update is the joint one)
        out[A_ZUPT_V] = nis(z[0:3], S0[0:3, 0:3])
        out[A_ZARU] = nis(z[3:6], S0[3:6, 3:6])
        _, out[A_ZUPT] = _gated_update(P, dx, H, R, z, np.empty(6), np.empty((6, 6)), prm[K_GATE_ZUPT], q, v, lla,
                                       err, nx, prm, acc_dx)
    if not math.isnan(h_baro):
        nu1 = np.empty(1)
        r1 = np.empty(1)
        height(-lla[2], -h_baro, prm[K_BARO_SD], nu1, r1)
        idx1 = np.array([I_POS + 2], dtype=np.int64)
        out[A_BARO] = _rows_update(P, dx, idx1, nu1, r1, prm[K_GATE_BARO], q, v, lla, err, nx, prm, acc_dx)


@njit(cache=True)
def _mag_update(P, dx, q, v, lla, err, mb, prm, nx, out, acc_dx):
    """Gated magnetometer-heading update (:func:`imunav.filters._core_gins.mag_heading`); NIS into ``out[A_MAG]``."""
    H = np.zeros((1, nx))
    nu = np.empty(1)
    R = np.empty((1, 1))
    nu[0], R[0, 0] = mag_heading(dcm_from_quat_1(q), mb, prm[K_DECL], prm[K_MAG_SD], H[0], I_ATT)
    _, out[A_MAG] = _gated_update(P, dx, H, R, nu, np.empty(1), np.empty((1, 1)), prm[K_GATE_MAG], q, v, lla, err,
                                  nx, prm, acc_dx)


@njit(cache=True)
def _step(q, v, lla, dth, dv, h, err, nx, om, qn, vn, llan, wb, fb):
    """Compensate the increments for the estimated IMU errors and run one NED strapdown step in place;
    ``wb``, ``fb`` receive the compensated mean rate and specific force."""
    dthc = np.empty(3)
    dvc = np.empty(3)
    for j in range(3):
        sg = err[E_SG + j] if nx >= NX21 else 0.0
        sa = err[E_SA + j] if nx >= NX21 else 0.0
        dthc[j] = (dth[j] - err[E_BG + j] * h) / (1.0 + sg)
        dvc[j] = (dv[j] - err[E_BA + j] * h) / (1.0 + sa)
        wb[j] = dthc[j] / h
        fb[j] = dvc[j] / h
    strapdown_step_ned(q, v, lla, dthc, dvc, h, om, ATT_START, qn, vn, llan)
    q[:] = qn
    v[:] = vn
    lla[:] = llan


@njit(cache=True)
def _rec_post(r, tr, P, q, v, lla, acc_dx, rec_t, rec_ppost, rec_inj, rec_state):
    """Smoother record of epoch r after its updates: time, posterior P, injected error (added), nominal state."""
    rec_t[r] = tr
    rec_ppost[r] = P
    for j in range(acc_dx.shape[0]):
        rec_inj[r, j] += acc_dx[j]
        acc_dx[j] = 0.0
    for j in range(3):
        rec_state[r, j] = lla[j]
        rec_state[r, 3 + j] = v[j]
    for j in range(4):
        rec_state[r, 6 + j] = q[j]


# carried filter state between calls of gins_run (GinsFilter.step): covariance clock and mean-rate accumulators
C_T_COV = 0  # time of the last covariance propagation, s
C_N_COV = 1  # samples since then
C_SW = 2  # 3: Σ ω^b h since then, rad
C_SF = 5  # 3: Σ f^b h since then, m/s
C_RAW = 8  # 3: Σ raw gyro increments since the last covariance step, rad (the ZARU's mean rate)
C_T_RAW = 11  # time of that step, s
NC = 12


@njit(cache=True)
def _record_cov(m, tk, P, cov_t, cov_diag, cov_nav):
    """Write covariance record m (time, diagonal, navigation block) when there is room; returns the new count."""
    if m < cov_t.shape[0]:
        for j in range(P.shape[0]):
            cov_diag[m, j] = P[j, j]
        for a in range(9):
            for b in range(9):
                cov_nav[m, a, b] = P[a, b]
        cov_t[m] = tk
        return m + 1
    return m


@njit(cache=True)
def gins_run(t, dth, dv, g_t, g_lla, g_rp, g_vel, g_rv, odo, odo_r, q, v, lla, err, P, carry, prm,
             q_out, v_out, lla_out, err_out, cov_t, cov_diag, cov_nav, nis, acc, veh,
             rec_t, rec_phi, rec_ppri, rec_ppost, rec_inj, rec_state, static, baro, mag, aid, first, final):
    """Filter over the IMU samples 1..N-1 (row k: increments over [t[k-1], t[k]]), from the state at t[0].

    ``q, v, lla, err, P`` (nominal state, IMU errors, covariance) and ``carry`` (covariance clock, layout
    ``C_*``) are the state at t[0] and are updated in place, so that consecutive calls continue one filter
    (:class:`imunav.ins.gins.GinsFilter`.step calls it with N = 2).  ``first``: write the records of t[0]
    (covariance, smoother); ``final``: propagate the covariance at the last sample whatever the clock says.

    With ``rec_*`` of length R > 0 it also records, per covariance epoch r, what the RTS smoother needs: the
    transition Φ_r into r, the prior and posterior covariances, the error injected at r and the posterior nominal
    state (lat, lon, h, v, q).

    Returns the number of covariance records written and the number of smoother epochs recorded.
    """
    n = t.shape[0]
    nx = P.shape[0]
    dx = np.zeros(nx)
    qn = np.empty(4)
    vn = np.empty(3)
    llan = np.empty(3)
    wb = np.zeros(3)
    fb = np.zeros(3)
    sw = carry[C_SW:C_SW + 3]
    sf = carry[C_SF:C_SF + 3]
    raw = carry[C_RAW:C_RAW + 3]
    F = np.zeros((nx, nx))
    Q = np.zeros((nx, nx))
    rem_th = np.empty(3)
    rem_v = np.empty(3)
    pth = np.empty(3)
    pv = np.empty(3)
    om = prm[K_OMEGA_E]
    use_vel = prm[K_USE_VEL] > 0.5
    cov_step = int(prm[K_COV_STEP])
    q_out[0] = q
    v_out[0] = v
    lla_out[0] = lla
    err_out[0] = err
    gi = 0
    ng = g_t.shape[0]
    while gi < ng and g_t[gi] <= t[0]:
        gi += 1  # epochs before the first sample have no state to update (the wrapper trims them)
    t_cov = carry[C_T_COV]
    n_cov = int(carry[C_N_COV])
    m = 0
    if first:
        m = _record_cov(m, t[0], P, cov_t, cov_diag, cov_nav)
    acc_dx = np.zeros(nx)
    rec = rec_t.shape[0] > 0
    r = 0
    if rec and first:
        _rec_post(r, t[0], P, q, v, lla, acc_dx, rec_t, rec_ppost, rec_inj, rec_state)
    for k in range(1, n):
        t_cur = t[k - 1]
        for j in range(3):
            rem_th[j] = dth[k, j]
            rem_v[j] = dv[k, j]
        # GNSS epochs inside (t[k-1], t[k]]: integrate to their time stamp, propagate P, update
        while gi < ng and g_t[gi] <= t[k]:
            frac = (g_t[gi] - t_cur) / (t[k] - t_cur)
            hh = g_t[gi] - t_cur
            if hh > 0.0:
                for j in range(3):
                    pth[j] = frac * rem_th[j]
                    pv[j] = frac * rem_v[j]
                    rem_th[j] -= pth[j]
                    rem_v[j] -= pv[j]
                _step(q, v, lla, pth, pv, hh, err, nx, om, qn, vn, llan, wb, fb)
                for j in range(3):
                    sw[j] += wb[j] * hh
                    sf[j] += fb[j] * hh
                t_cur = g_t[gi]
            dtc = t_cur - t_cov
            if dtc > 0.0:
                for j in range(3):
                    wb[j] = sw[j] / dtc
                    fb[j] = sf[j] / dtc
                _system(q, v, lla, fb, wb, prm, nx, F, Q)
                Phi = propagate_cov_series(P, F, Q, dtc)
                t_cov = t_cur
                sw[:] = 0.0
                sf[:] = 0.0
                n_cov = 0
                if rec and r + 1 < rec_t.shape[0]:
                    r += 1
                    rec_phi[r] = Phi
                    rec_ppri[r] = P
            _gnss_update(P, dx, q, v, lla, err, wb, g_lla[gi], g_rp[gi], g_vel[gi], g_rv[gi], use_vel, prm, nx,
                         nis[gi], acc[gi], acc_dx)
            if rec:
                _rec_post(r, t_cur, P, q, v, lla, acc_dx, rec_t, rec_ppost, rec_inj, rec_state)
            gi += 1
        hh = t[k] - t_cur
        if hh > 0.0:
            _step(q, v, lla, rem_th, rem_v, hh, err, nx, om, qn, vn, llan, wb, fb)
            for j in range(3):
                sw[j] += wb[j] * hh
                sf[j] += fb[j] * hh
        n_cov += 1
        for j in range(3):
            raw[j] += dth[k, j]
        if n_cov >= cov_step or (final and k == n - 1) or not math.isnan(baro[k]) or not math.isnan(mag[k, 0]):
            dtc = t[k] - t_cov
            if dtc > 0.0:
                for j in range(3):
                    wb[j] = sw[j] / dtc
                    fb[j] = sf[j] / dtc
                _system(q, v, lla, fb, wb, prm, nx, F, Q)
                Phi = propagate_cov_series(P, F, Q, dtc)
                if rec and r + 1 < rec_t.shape[0]:
                    r += 1
                    rec_phi[r] = Phi
                    rec_ppri[r] = P
            t_cov = t[k]
            sw[:] = 0.0
            sf[:] = 0.0
            n_cov = 0
            if not math.isnan(odo[k]) or prm[K_NHC_R] > 0.0:
                for j in range(3):
                    wb[j] = dth[k, j] / (t[k] - t[k - 1]) - err[E_BG + j]
                _vehicle_update(P, dx, q, v, lla, err, wb, odo[k], odo_r[k], prm, nx, veh[k], acc_dx, aid[k],
                                static[k] <= 0.5)
            if static[k] > 0.5 or not math.isnan(baro[k]):
                dt_rate = t[k] - carry[C_T_RAW]
                for j in range(3):
                    wb[j] = raw[j] / dt_rate
                _rest_and_baro_update(P, dx, q, v, lla, err, wb, dt_rate, static[k] > 0.5, baro[k], prm, nx, aid[k],
                                      acc_dx)
            raw[:] = 0.0
            carry[C_T_RAW] = t[k]
            if not math.isnan(mag[k, 0]):
                _mag_update(P, dx, q, v, lla, err, mag[k], prm, nx, aid[k], acc_dx)
            if rec:
                _rec_post(r, t[k], P, q, v, lla, acc_dx, rec_t, rec_ppost, rec_inj, rec_state)
            m = _record_cov(m, t[k], P, cov_t, cov_diag, cov_nav)
        q_out[k] = q
        v_out[k] = v
        lla_out[k] = lla
        err_out[k] = err
    carry[C_T_COV] = t_cov
    carry[C_N_COV] = n_cov
    return m, (r + 1 if rec else 0)
