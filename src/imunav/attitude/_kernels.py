"""Numba kernels of the attitude filters (private).

Conventions: ``q`` is ``q_nb`` (body -> NED), Hamilton, scalar first; the
accelerometer gives specific force ``f_b`` (level at rest: ``(0, 0, -g)``);
the body frame is any right-handed sensor frame.  Sample ``k`` moves the state
from ``t_{k-1}`` to ``t_k`` with the gyro sample ``k`` held over ``dt[k]`` and
then applies the aiding measurements of sample ``k``; output row ``k`` is the
state after sample ``k``.

Error-state filters use a body-frame attitude error ``q = q̂ ⊗ exp(δθ)``
(Solà 2017, §7, "local" error) and a gyro-bias error ``b = b̂ + δb``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import (
    dcm_from_quat_t,
    qconj_1,
    qexp_1,
    qlog_1,
    qmul_1,
    qmul_t,
    qnormalize_t,
    qrot_1,
    qrot_t,
)
from imunav.filters._core import (
    inject_attitude_local,
    inv_spd_cholesky,
    quat_normalize,
    sigma_offsets,
    unscented_cov,
    unscented_mean,
    unscented_update,
    unscented_weights,
)
from imunav.filters._core_models import gravity_direction_row, gyro_rest_row

# ---------------------------------------------------------------------------
# small helpers (quaternion, DCM and SPD helpers: imunav._rotation_kernels and imunav.filters._core)


@njit(cache=True)
def _norm3(v):
    """Euclidean norm of a 3-vector."""
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


@njit(cache=True)
def first_rate_over(gyr, max_rate):
    """First sample whose rate exceeds ``max_rate``: ``(k, |ω_k|)``, or ``(-1, 0.0)`` when none does.

    A row whose largest component exceeds ``max_rate`` reports that component (its norm could overflow);
    otherwise the row's Euclidean norm is compared.  One pass, no temporary arrays.
    """
    for k in range(gyr.shape[0]):
        x = abs(gyr[k, 0])
        y = abs(gyr[k, 1])
        z = abs(gyr[k, 2])
        big = max(x, max(y, z))
        if big > max_rate:
            return k, big
        nrm = math.sqrt(x * x + y * y + z * z)
        if nrm > max_rate:
            return k, nrm
    return -1, 0.0


# ---------------------------------------------------------------------------
# Madgwick gradient-descent filter


@njit(cache=True)
def _grad_term(q, d, s):
    """Gradient of 0.5 |q* ⊗ d ⊗ q - s|^2 w.r.t. the 4 quaternion components.

    With e = q* d q - s (pure): grad = -2 d ⊗ q ⊗ e  (d, e pure quaternions).
    Equivalent to Madgwick's J^T f (Madgwick 2010, eqs. 20-34) for any
    reference direction d.
    """
    v = qrot_1(qconj_1(q), d)
    e = np.empty(4)
    e[0] = 0.0
    e[1] = v[0] - s[0]
    e[2] = v[1] - s[1]
    e[3] = v[2] - s[2]
    dq = np.empty(4)
    dq[0] = 0.0
    dq[1] = d[0]
    dq[2] = d[1]
    dq[3] = d[2]
    return -2.0 * qmul_1(qmul_1(dq, q), e)


@njit(cache=True)
def madgwick_step(q, gyr, acc, mag, dt, beta, use_mag, mag_scale):
    """One Madgwick update.  ``q`` is body -> NWU here (Madgwick's Earth frame:
    x magnetic north, z up); the public wrappers convert from/to NED.

    Residuals and Jacobians are those of Madgwick (2010), eqs. 25-34, with the
    field reference b = [b_x, 0, b_z] = mag_scale [|h_xy|, 0, h_z] and
    h = q ⊗ m ⊗ q*.  ``mag_scale = 1`` is the derivation; ``0.5`` reproduces the
    C code, whose ``_2bx = sqrt(hx² + hy²)`` should be ``2 sqrt(...)``
    (Laidig et al. 2021, BROAD).  The 6D branch uses the same residual without the field.
    """
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    gx, gy, gz = gyr[0], gyr[1], gyr[2]
    qd0 = 0.5 * (-q1 * gx - q2 * gy - q3 * gz)
    qd1 = 0.5 * (q0 * gx + q2 * gz - q3 * gy)
    qd2 = 0.5 * (q0 * gy - q1 * gz + q3 * gx)
    qd3 = 0.5 * (q0 * gz + q1 * gy - q2 * gx)
    an = _norm3(acc)
    if an > 0.0:
        ax, ay, az = acc[0] / an, acc[1] / an, acc[2] / an
        # gravity residual f_g (eq. 25) and J_g^T f_g
        f1 = 2.0 * (q1 * q3 - q0 * q2) - ax
        f2 = 2.0 * (q0 * q1 + q2 * q3) - ay
        f3 = 2.0 * (0.5 - q1 * q1 - q2 * q2) - az
        s0 = -2.0 * q2 * f1 + 2.0 * q1 * f2
        s1 = 2.0 * q3 * f1 + 2.0 * q0 * f2 - 4.0 * q1 * f3
        s2 = -2.0 * q0 * f1 + 2.0 * q3 * f2 - 4.0 * q2 * f3
        s3 = 2.0 * q1 * f1 + 2.0 * q2 * f2
        mn = _norm3(mag)
        if use_mag and mn > 0.0:
            mx, my, mz = mag[0] / mn, mag[1] / mn, mag[2] / mn
            hx = (mx * (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3) + 2.0 * my * (q1 * q2 - q0 * q3)
                  + 2.0 * mz * (q0 * q2 + q1 * q3))
            hy = (2.0 * mx * (q0 * q3 + q1 * q2) + my * (q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3)
                  + 2.0 * mz * (q2 * q3 - q0 * q1))
            hz = (2.0 * mx * (q1 * q3 - q0 * q2) + 2.0 * my * (q0 * q1 + q2 * q3)
                  + mz * (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3))
            bx = mag_scale * math.sqrt(hx * hx + hy * hy)
            bz = mag_scale * hz
            # field residual f_b (eq. 29) and J_b^T f_b (eq. 30)
            e1 = 2.0 * bx * (0.5 - q2 * q2 - q3 * q3) + 2.0 * bz * (q1 * q3 - q0 * q2) - mx
            e2 = 2.0 * bx * (q1 * q2 - q0 * q3) + 2.0 * bz * (q0 * q1 + q2 * q3) - my
            e3 = 2.0 * bx * (q0 * q2 + q1 * q3) + 2.0 * bz * (0.5 - q1 * q1 - q2 * q2) - mz
            s0 += -2.0 * bz * q2 * e1 + (-2.0 * bx * q3 + 2.0 * bz * q1) * e2 + 2.0 * bx * q2 * e3
            s1 += 2.0 * bz * q3 * e1 + (2.0 * bx * q2 + 2.0 * bz * q0) * e2 + (2.0 * bx * q3 - 4.0 * bz * q1) * e3
            s2 += ((-4.0 * bx * q2 - 2.0 * bz * q0) * e1 + (2.0 * bx * q1 + 2.0 * bz * q3) * e2
                   + (2.0 * bx * q0 - 4.0 * bz * q2) * e3)
            s3 += (-4.0 * bx * q3 + 2.0 * bz * q1) * e1 + (-2.0 * bx * q0 + 2.0 * bz * q2) * e2 + 2.0 * bx * q1 * e3
        sn = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2 + s3 * s3)
        if sn > 0.0:
            qd0 -= beta * s0 / sn
            qd1 -= beta * s1 / sn
            qd2 -= beta * s2 / sn
            qd3 -= beta * s3 / sn
    out = np.empty(4)
    out[0] = q0 + qd0 * dt
    out[1] = q1 + qd1 * dt
    out[2] = q2 + qd2 * dt
    out[3] = q3 + qd3 * dt
    return quat_normalize(out)


@njit(cache=True)
def _ned_nwu(q):
    """X ⊗ q with X = [0, 1, 0, 0] (π about north): NED <-> NWU, sign-normalised."""
    out = np.empty(4)
    out[0] = -q[1]
    out[1] = q[0]
    out[2] = -q[3]
    out[3] = q[2]
    if out[0] < 0.0:
        out = -out
    return out


@njit(cache=True)
def madgwick_run(q0, gyr, acc, mag, dt, beta, use_mag, mag_scale):
    """q0 and the output are body -> NED."""
    n = gyr.shape[0]
    out = np.empty((n, 4))
    q = _ned_nwu(q0)
    for k in range(n):
        q = madgwick_step(q, gyr[k], acc[k], mag[k], dt[k], beta, use_mag, mag_scale)
        out[k] = _ned_nwu(q)
    return out


# ---------------------------------------------------------------------------
# Mahony explicit complementary filter


@njit(cache=True)
def mahony_step(q, bint, gyr, acc, mag, dt, kp, ki, use_mag):
    """One Mahony update; returns (q, integral term).

    e = a_meas × v̂ + m_meas × ŵ (unit vectors, body frame), ω' = ω + kp e + ∫ ki e dt
    (Mahony, Hamel, Pflimlin 2008, eq. 32; magnetometer term with the
    horizontal/vertical reference of the measured field).
    """
    qw, qx, qy, qz = q[0], q[1], q[2], q[3]
    ex = 0.0
    ey = 0.0
    ez = 0.0
    bo = bint.copy()
    an = math.sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2])
    if an > 0.0:
        ax, ay, az = acc[0] / an, acc[1] / an, acc[2] / an
        # predicted up direction in body: -(row 3 of C_nb)
        vx = -2.0 * (qx * qz - qw * qy)
        vy = -2.0 * (qy * qz + qw * qx)
        vz = -(1.0 - 2.0 * (qx * qx + qy * qy))
        ex += ay * vz - az * vy
        ey += az * vx - ax * vz
        ez += ax * vy - ay * vx
        mn = math.sqrt(mag[0] * mag[0] + mag[1] * mag[1] + mag[2] * mag[2])
        if use_mag and mn > 0.0:
            mx, my, mz = mag[0] / mn, mag[1] / mn, mag[2] / mn
            h0, h1, h2 = qrot_t(qw, qx, qy, qz, mx, my, mz)
            bx = math.sqrt(h0 * h0 + h1 * h1)
            wx, wy, wz = qrot_t(qw, -qx, -qy, -qz, bx, 0.0, h2)
            ex += my * wz - mz * wy
            ey += mz * wx - mx * wz
            ez += mx * wy - my * wx
        if ki > 0.0:
            bo[0] += ki * ex * dt
            bo[1] += ki * ey * dt
            bo[2] += ki * ez * dt
        else:
            bo[:] = 0.0
    gx = gyr[0] + kp * ex + bo[0]
    gy = gyr[1] + kp * ey + bo[1]
    gz = gyr[2] + kp * ez + bo[2]
    d0, d1, d2, d3 = qmul_t(qw, qx, qy, qz, 0.0, gx, gy, gz)
    h = 0.5 * dt
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = qnormalize_t(qw + h * d0, qx + h * d1, qy + h * d2, qz + h * d3)
    return out, bo


@njit(cache=True)
def mahony_run(q0, b0, gyr, acc, mag, dt, kp, ki, use_mag):
    n = gyr.shape[0]
    out = np.empty((n, 4))
    bias = np.empty((n, 3))
    q = q0.copy()
    bint = b0.copy()
    for k in range(n):
        q, bint = mahony_step(q, bint, gyr[k], acc[k], mag[k], dt[k], kp, ki, use_mag)
        out[k] = q
        bias[k] = -bint  # the integral term compensates the bias: b̂ = -∫
    return out, bias


# ---------------------------------------------------------------------------
# Basic complementary filter (gyro strapdown + first-order tilt / heading pull)


@njit(cache=True)
def complementary_step(q, gyr, acc, mag, dt, k_accel, k_mag, use_mag):
    """q ⊗ exp(ω dt), then rotate the estimate by a fraction of the tilt error
    (accelerometer in nav frame vs. up) and of the heading error (horizontal
    field vs. north).  Gains are first-order time constants: fraction = k dt.
    """
    q = quat_normalize(qmul_1(q, qexp_1(gyr * dt)))
    an = _norm3(acc)
    if an > 0.0 and k_accel > 0.0:
        fn = qrot_1(q, acc / an)  # should be (0, 0, -1)
        # rotation that takes fn to -e3: axis fn × (-e3), angle acos(-fn_z)
        ax = np.empty(3)
        ax[0] = -fn[1]
        ax[1] = fn[0]
        ax[2] = 0.0
        s = _norm3(ax)
        if s > 1e-12:
            ang = math.atan2(s, -fn[2])
            frac = min(k_accel * dt, 1.0)
            q = quat_normalize(qmul_1(qexp_1(ax / s * ang * frac), q))
    if use_mag and k_mag > 0.0:
        mn = _norm3(mag)
        if mn > 0.0:
            h = qrot_1(q, mag / mn)
            psi = math.atan2(h[1], h[0])  # should be 0 (magnetic north)
            r = np.zeros(3)
            r[2] = -psi * min(k_mag * dt, 1.0)
            q = quat_normalize(qmul_1(qexp_1(r), q))
    return q


@njit(cache=True)
def complementary_run(q0, gyr, acc, mag, dt, k_accel, k_mag, use_mag):
    n = gyr.shape[0]
    out = np.empty((n, 4))
    q = q0.copy()
    for k in range(n):
        q = complementary_step(q, gyr[k], acc[k], mag[k], dt[k], k_accel, k_mag, use_mag)
        out[k] = q
    return out


# ---------------------------------------------------------------------------
# Multiplicative EKF with gyro-bias states, adaptive R, disturbance rejection
#
# Parameter vector ``p`` (float64): one entry per name of MEKF_PARAMS, in that order; the kernels read it through
# the P_* constants generated from the tuple (numba freezes module-level integers at compile time).  The names are
# the fields of :class:`imunav.attitude.mekf.MekfConfig` (``vector()`` packs them in this order):
#   gyro_noise_density        gyro white noise [rad/s/sqrt(Hz)]
#   gyro_bias_random_walk     gyro bias random walk [rad/s/sqrt(s)]
#   accel_direction_noise_std accelerometer direction noise [unitless, per sample]
#   k_accel                   R_acc inflation per (| |f| - g | / g)^2   (adaptive R)
#   accel_reject_threshold    reject accelerometer when | |f| - g | / g > accel_reject_threshold
#   heading_noise_std         heading noise from the magnetometer [rad, per sample]
#   mag_norm_threshold        relative field-norm tolerance for disturbance detection
#   mag_dip_threshold         dip-angle tolerance [rad]
#   k_mag                     R_mag inflation per normalised (norm, dip) deviation^2
#   rest_gyro_threshold       rest detection: max |ω - b̂| [rad/s] (<= 0 disables)
#   rest_accel_threshold      rest detection: max | |f| - g | [m/s^2]
#   rest_time                 rest detection: minimum duration [s]
#   zaru_noise_std            zero-rate pseudo-measurement noise [rad/s]
#   g                         gravity magnitude [m/s^2]
#   mag_ref_time              after this long continuously disturbed [s], accept the
#                             current field as the new reference (<= 0: never)
#   k_rate                    extra accelerometer noise per rad/s of |ω| (centripetal)
#   mag_ref_time_constant     time constant [s] of the slow field-reference update
#   use_mag                   (> 0.5) use the magnetometer
#   accel_lpf_time_constant   [s] low-pass of the nav-frame specific force (0: off)
#   rest_lpf_time_constant    [s] > 0: rest test on deviations from low-passes (the
#                             rest thresholds are then deviation bounds)
#   mag_lpf_time_constant     [s] low-pass of field norm and dip before the disturbance test (0: off)
#   mag_min_undisturbed       [s] continuous undisturbed field required before the field is used
#   mag_bias                  (> 0.5) heading update also corrects the bias (else consider states)
#   lpf_gyro_threshold        [rad/s] no rest while a low-passed gyro axis exceeds it
#   k_gyro_rate               [sqrt(s)] gyro noise density grows as sqrt(gyro_noise_density^2 + (k |ω|)^2)
#   tilt_time_constant        [s] > 0: tilt-correction time constant, replaces
#                             accel_direction_noise_std (variance (T gyro_noise_density)^2 / dt)
#   heading_time_constant     [s] > 0: heading-correction time constant, replaces heading_noise_std (whatever the dip)

MEKF_PARAMS = (
    "gyro_noise_density", "gyro_bias_random_walk", "accel_direction_noise_std", "k_accel", "accel_reject_threshold",
    "heading_noise_std", "mag_norm_threshold", "mag_dip_threshold", "k_mag", "rest_gyro_threshold",
    "rest_accel_threshold", "rest_time", "zaru_noise_std", "g", "mag_ref_time", "k_rate", "mag_ref_time_constant",
    "use_mag", "accel_lpf_time_constant", "rest_lpf_time_constant", "mag_lpf_time_constant", "mag_min_undisturbed",
    "mag_bias", "lpf_gyro_threshold", "k_gyro_rate", "tilt_time_constant", "heading_time_constant",
)
(
    P_GYRO_NOISE_DENSITY, P_GYRO_BIAS_RANDOM_WALK, P_ACCEL_DIRECTION_NOISE_STD, P_K_ACCEL, P_ACCEL_REJECT_THRESHOLD,
    P_HEADING_NOISE_STD, P_MAG_NORM_THRESHOLD, P_MAG_DIP_THRESHOLD, P_K_MAG, P_REST_GYRO_THRESHOLD,
    P_REST_ACCEL_THRESHOLD, P_REST_TIME, P_ZARU_NOISE_STD, P_G, P_MAG_REF_TIME, P_K_RATE, P_MAG_REF_TIME_CONSTANT,
    P_USE_MAG, P_ACCEL_LPF_TIME_CONSTANT, P_REST_LPF_TIME_CONSTANT, P_MAG_LPF_TIME_CONSTANT, P_MAG_MIN_UNDISTURBED,
    P_MAG_BIAS, P_LPF_GYRO_THRESHOLD, P_K_GYRO_RATE, P_TILT_TIME_CONSTANT, P_HEADING_TIME_CONSTANT,
) = range(len(MEKF_PARAMS))
N_PARAMS = len(MEKF_PARAMS)

# Adaptive state ``st`` (float64, N_STATE) of mekf_step: (name, length) in order; S_* is the first index of each.
MEKF_STATE = (
    ("rest_timer", 1),  # s at rest so far
    ("mag_ref_norm", 1),  # reference field norm
    ("mag_ref_dip", 1),  # reference dip, rad
    ("disturbed_timer", 1),  # s continuously disturbed
    ("mag_ref_valid", 1),  # > 0.5 once the reference is set
    ("f_lp", 3),  # low-passed nav-frame specific force
    ("flags", 1),  # flag bits of the step (FLAG_NAMES of mekf.py)
    ("nis", 1),  # NIS sum of the step
    ("dof", 1),  # its degrees of freedom
    ("f_lp_init", 1),  # f_lp initialised
    ("gyr_lp", 3),  # low-passed gyro of the rest test
    ("acc_lp", 3),  # low-passed accelerometer of the rest test
    ("rest_lp_init", 1),  # their init flag
    ("mag_norm_lp", 1),  # low-passed field norm
    ("mag_dip_lp", 1),  # low-passed dip
    ("mag_lp_init", 1),  # their init flag
    ("undisturbed", 1),  # s since the field was last disturbed
    ("att_q", 1),  # attitude process variance of the step
    ("lp_rest_c", 2),  # (Δt, 1 − exp(−Δt/τ)) of the rest low-pass, cached while Δt repeats
    ("lp_acc_c", 2),  # the same for the accelerometer low-pass
    ("lp_mag_c", 2),  # the same for the field norm / dip low-pass
    ("tan_dip", 2),  # (δ₀, tan δ₀): the tangent of the reference dip, kept while the reference moves little
)
(
    S_REST_TIMER, S_MAG_REF_NORM, S_MAG_REF_DIP, S_DISTURBED_TIMER, S_MAG_REF_VALID, S_F_LP, S_FLAGS, S_NIS, S_DOF,
    S_F_LP_INIT, S_GYR_LP, S_ACC_LP, S_REST_LP_INIT, S_MAG_NORM_LP, S_MAG_DIP_LP, S_MAG_LP_INIT, S_UNDISTURBED,
    S_ATT_Q, S_LP_REST_C, S_LP_ACC_C, S_LP_MAG_C, S_TAN_DIP,
) = (sum(n for _, n in MEKF_STATE[:i]) for i in range(len(MEKF_STATE)))
N_STATE = sum(n for _, n in MEKF_STATE)

# error state [δθ (body), δb_g]
I_ATT = 0
I_BIAS = 3
NX = 6


# Inlining (issue 35, a first run): ``inline="always"`` inlines at numba's level, copying the helper's IR into every
# call site, where it is type-checked and lowered once per site; ``forceinline=True`` (a numba target option: LLVM's
# alwaysinline) compiles the helper once and lets LLVM inline that copy, to the same machine code.  The helpers called
# from several places use the latter (_qexp_fast, _gain6, _inject: 40 % less compilation of the MEKF kernel with the
# Python-side allocation of mekf_run, the same results bit for bit and the same speed, measured).  It changes
# rounding where a helper's arithmetic fuses with its caller's (fused multiply-adds across the call: _qnormalize_fast,
# _att_row_update and the quaternion helpers of imunav._rotation_kernels, measured), which stay inline="always";
# _lp_factor too (its index argument is a literal: one compiled copy per call site).

#: Taylor coefficients of cos(θ/2) and sin(θ/2)/θ in powers of θ² (to θ¹⁰: below θ = 0.05 the first term left out is
#: under 1e-27, far below the rounding of a double)
_C1, _C2, _C3, _C4, _C5 = -1.0 / 8.0, 1.0 / 384.0, -1.0 / 46080.0, 1.0 / 10321920.0, -1.0 / 3715891200.0
_S1, _S2, _S3, _S4, _S5 = -1.0 / 48.0, 1.0 / 3840.0, -1.0 / 645120.0, 1.0 / 185794560.0, -1.0 / 81749606400.0
_SERIES_TH2 = 0.05 * 0.05


@njit(cache=True, error_model="numpy", fastmath={"contract"}, forceinline=True)
def _qexp_fast(r0, r1, r2):
    """:func:`imunav._rotation_kernels.qexp_t` (``[cos(θ/2), sin(θ/2) r/θ]``, θ = |r|) to rounding, cheaper.

    Below θ = 0.05 rad (every gyro increment of a sensor sampled at 100 Hz or faster turning under 5 rad/s, and every
    correction) the sine and cosine are their Taylor polynomials in θ², exact to rounding: no square root, no division,
    no call to the maths library.
    """
    th2 = r0 * r0 + r1 * r1 + r2 * r2
    if th2 < _SERIES_TH2:
        c = 1.0 + th2 * (_C1 + th2 * (_C2 + th2 * (_C3 + th2 * (_C4 + th2 * _C5))))
        s = 0.5 + th2 * (_S1 + th2 * (_S2 + th2 * (_S3 + th2 * (_S4 + th2 * _S5))))
    else:
        th = math.sqrt(th2)
        c = math.cos(0.5 * th)
        s = math.sin(0.5 * th) / th
    return c, s * r0, s * r1, s * r2


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _qnormalize_fast(a0, a1, a2, a3):
    """:func:`imunav._rotation_kernels.qnormalize_t` to rounding: near unit norm (|n² − 1| < 1e-9, the product of two
    unit quaternions) ``1/√n² = 1.5 − n²/2`` to within 4e-19 (the next term, 3 (n² − 1)² / 8), without the square root
    and the division."""
    n2 = a0 * a0 + a1 * a1 + a2 * a2 + a3 * a3
    if abs(n2 - 1.0) < 1e-9:
        f = 1.5 - 0.5 * n2
    else:
        f = 1.0 / math.sqrt(n2)
    return a0 * f, a1 * f, a2 * f, a3 * f


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _tan_cached(st, k, x):
    """``math.tan(x)`` to rounding, with ``st[k:k+2] = (x₀, tan x₀)`` kept while |x − x₀| < 1e-5.

    Near x₀ (the reference dip of the heading update, which the slow tracking moves by a few 1e-7 rad a sample)
    ``tan(x₀ + d) = T + d u (1 + d T + d² (1 + 3T²) / 3)``, T = tan x₀, u = 1 + T²: the first term left out is
    below 1e-18 for |d| < 1e-5 and |x₀| < 1.4 rad (dip under 80°).  A zeroed state is a valid start (tan 0 = 0).
    """
    d = x - st[k]
    if abs(d) < 1e-5 and abs(x) < 1.4:
        T = st[k + 1]
        u = 1.0 + T * T
        return T + d * u * (1.0 + d * (T + d * (1.0 + 3.0 * T * T) * (1.0 / 3.0)))
    t = math.tan(x)
    st[k] = x
    st[k + 1] = t
    return t


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _atan2_small(y, x):
    """``math.atan2(y, x)`` to rounding; for x > 0 and |y| < 0.05 x (a heading innovation once the filter has
    converged) the series ``atan z = z − z³/3 + … + z¹⁷/17``, z = y / x (the first term left out is under 1e-22 z)."""
    if x > 0.0 and abs(y) < 0.05 * x:
        z = y / x
        u = z * z
        return z * (1.0 + u * (-1.0 / 3.0 + u * (0.2 + u * (-1.0 / 7.0 + u * (1.0 / 9.0 + u * (-1.0 / 11.0 + u * (
            1.0 / 13.0 + u * (-1.0 / 15.0 + u * (1.0 / 17.0)))))))))
    return math.atan2(y, x)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _lowpass(st, k, x, c, first):
    """First-order low-pass of ``x`` held in ``st[k]`` with factor c = 1 − exp(−Δt/τ); ``first`` starts it at x."""
    st[k] = x if first else st[k] + c * (x - st[k])


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _lp_factor(st, k, dt, tau, inv_tau):
    """The low-pass factor ``c = 1 − exp(−Δt/τ)``, cached as ``st[k:k+2] = (Δt₀, c₀)`` while Δt repeats.

    A uniformly sampled recording computes the exponential once instead of once per sample.  Time steps taken from
    rounded time stamps differ from the cached one by a few ulp of the time (ε, |ε| < 1e-9 Δt₀): then
    ``c = c₀ + ε (1 − c₀) / τ``, exact to rounding (the term left out, ε² / (2τ²), is below 1e-20 c).
    """
    eps = dt - st[k]
    if eps == 0.0:
        return st[k + 1]
    if abs(eps) < 1e-9 * st[k]:
        return st[k + 1] + eps * (1.0 - st[k + 1]) * inv_tau
    st[k] = dt
    st[k + 1] = 1.0 - math.exp(-dt / tau)
    return st[k + 1]


@njit(cache=True, error_model="numpy", fastmath={"contract"}, forceinline=True)
def _gain6(P, dx, PH, nu, s):
    """Tail of a scalar update on the six estimated states: ``dx += PH ν / s``, ``P −= PH PHᵀ / s``.

    The six-state, fully estimated case of :func:`imunav.filters._core.scalar_update` (``n_est = 6``), on the
    upper triangle mirrored (P stays bit-symmetric), without the generic loop bounds and branches.
    """
    si = 1.0 / s
    k = nu * si
    for i in range(6):
        dx[i] += PH[i] * k
    for i in range(6):
        f = PH[i] * si
        for j in range(i, 6):
            v = P[i, j] - f * PH[j]
            P[i, j] = v
            P[j, i] = v
    return si


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _att_row_update(P, dx, h0, h1, h2, r, nu, PH):
    """Scalar update with the row ``h = [h0, h1, h2, 0, 0, 0]`` (a measurement of the attitude error only).

    Same equations as :func:`imunav.filters._core.scalar_update` (``s = h P hᵀ + r``, ``ν' = ν − h dx``,
    ``dx += K ν'``, ``P −= P hᵀ h P / s``) with the zero entries of h skipped.  Returns ``(ν', 1/s)``.
    """
    for i in range(6):
        PH[i] = P[i, 0] * h0 + P[i, 1] * h1 + P[i, 2] * h2
    s = r + h0 * PH[0] + h1 * PH[1] + h2 * PH[2]
    nu = nu - (h0 * dx[0] + h1 * dx[1] + h2 * dx[2])
    return nu, _gain6(P, dx, PH, nu, s)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _reset6(P, d0, d1, d2):
    """``P ← G P Gᵀ``, ``G = blockdiag(I − [a×], I₃)``, ``a = ½ δθ̂`` (Markley 2003; Solà 2017, §6.3), in place.

    The closed form of :func:`imunav.filters._core.reset_attitude_cov` for the six-state MEKF: only the attitude
    block ``A ← G₃ A G₃ᵀ`` and the cross block ``B ← G₃ B`` change.
    """
    a0 = 0.5 * d0
    a1 = 0.5 * d1
    a2 = 0.5 * d2
    # G₃ = I − [a×] = [[1, a2, −a1], [−a2, 1, a0], [a1, −a0, 1]]
    for j in range(3, 6):
        p0 = P[0, j]
        p1 = P[1, j]
        p2 = P[2, j]
        v0 = p0 + a2 * p1 - a1 * p2
        v1 = p1 - a2 * p0 + a0 * p2
        v2 = p2 + a1 * p0 - a0 * p1
        P[0, j] = v0
        P[j, 0] = v0
        P[1, j] = v1
        P[j, 1] = v1
        P[2, j] = v2
        P[j, 2] = v2
    # M = G₃ A (columns), then A' = M G₃ᵀ (upper triangle, mirrored)
    m00 = P[0, 0] + a2 * P[1, 0] - a1 * P[2, 0]
    m01 = P[0, 1] + a2 * P[1, 1] - a1 * P[2, 1]
    m02 = P[0, 2] + a2 * P[1, 2] - a1 * P[2, 2]
    m10 = P[1, 0] - a2 * P[0, 0] + a0 * P[2, 0]
    m11 = P[1, 1] - a2 * P[0, 1] + a0 * P[2, 1]
    m12 = P[1, 2] - a2 * P[0, 2] + a0 * P[2, 2]
    m20 = P[2, 0] + a1 * P[0, 0] - a0 * P[1, 0]
    m21 = P[2, 1] + a1 * P[0, 1] - a0 * P[1, 1]
    m22 = P[2, 2] + a1 * P[0, 2] - a0 * P[1, 2]
    P[0, 0] = m00 + a2 * m01 - a1 * m02
    v = m10 + a2 * m11 - a1 * m12
    P[0, 1] = v
    P[1, 0] = v
    v = m20 + a2 * m21 - a1 * m22
    P[0, 2] = v
    P[2, 0] = v
    P[1, 1] = m11 - a2 * m10 + a0 * m12
    v = m21 - a2 * m20 + a0 * m22
    P[1, 2] = v
    P[2, 1] = v
    P[2, 2] = m22 + a1 * m20 - a0 * m21


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _heading_update(P, dx, qw, qx, qy, qz, tan_dip, r, psi, PH, V, with_bias):
    """Heading-only magnetometer update with the tilt as consider states (in place).

    The field yaw ψ_m = atan2(n_E, n_N) of n = C_nb(q̂) m_b is computed with the
    estimated tilt, so its error is, to first order in the navigation-frame
    attitude error φ = C_nb δθ and for a reference field of yaw 0 and dip δ,
        δψ_m = −φ_D + tan(δ) φ_N,
    i.e. a tilt error leaks into the measured heading by tan(dip) (the reason a
    compass is tilt-sensitive; Groves 2013, §6.1.1).  The update uses this H,
    h = (−C_D + tan δ C_N, 0) on the body error (C_N, C_E, C_D the rows of C_nb),
    with φ_N and φ_E as consider states (Schmidt-Kalman: zero gain, Simon 2006,
    §7.5): the field never tilts the estimate, and the reported covariance
    carries the tilt uncertainty of the measured heading.  ``tan_dip`` comes from
    the reference field, not from the current sample: a Jacobian built from the
    noisy sample is correlated with the innovation's noise and makes the bias
    covariance over-confident (measured: z RMS 1.46 on a static sensor).  With
    ``with_bias`` False the bias is a consider state as well.

    In the frame y = T δx = (φ_D, δb, φ_N, φ_E) (T orthogonal) the consider update is
    ``P_y −= (PHᵧ PHᵧᵀ − c cᵀ) / s`` with ``c`` the consider part of ``PHᵧ = T P hᵀ``; back in the body frame
    ``P −= (u uᵀ − v vᵀ) / s`` with ``u = P hᵀ``, ``v = Tᵀ c``: a rank-two update, and ``dx = (u − v) ψ / s``.
    ``PH`` and ``V`` (6) are scratch.  Returns the NIS term.
    """
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = dcm_from_quat_t(qw, qx, qy, qz)
    h0 = -c20 + tan_dip * c00
    h1 = -c21 + tan_dip * c01
    h2 = -c22 + tan_dip * c02
    for i in range(6):
        PH[i] = P[i, 0] * h0 + P[i, 1] * h1 + P[i, 2] * h2
    s = r + h0 * PH[0] + h1 * PH[1] + h2 * PH[2]
    yd = c20 * PH[0] + c21 * PH[1] + c22 * PH[2]
    yn = c00 * PH[0] + c01 * PH[1] + c02 * PH[2]
    ye = c10 * PH[0] + c11 * PH[1] + c12 * PH[2]
    # v: the consider part mapped back (tilt rows; the bias too when it is a consider state)
    v0 = c00 * yn + c10 * ye
    v1 = c01 * yn + c11 * ye
    v2 = c02 * yn + c12 * ye
    si = 1.0 / s
    k = psi * si
    dx[0] = c20 * yd * k
    dx[1] = c21 * yd * k
    dx[2] = c22 * yd * k
    # with_bias 1.0 / 0.0, without a branch: the bias rows estimated (gain PH k, nothing in v) or considered (no
    # gain, the whole of PH in v); x·1 and x·0 are exact, so both give what the two branches gave
    kb = k * with_bias
    cb = 1.0 - with_bias
    V[0] = v0
    V[1] = v1
    V[2] = v2
    for i in range(3, 6):
        dx[i] = PH[i] * kb
        V[i] = PH[i] * cb
    for i in range(6):
        ui = PH[i] * si
        wi = V[i] * si
        for j in range(i, 6):
            val = P[i, j] - (ui * PH[j] - wi * V[j])
            P[i, j] = val
            P[j, i] = val
    return psi * k


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _mekf_predict(P, R, dt, sg2, sb2, W):
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


@njit(cache=True, inline="always")
def _phi_fill(phi, dt):
    """The constant blocks of the MEKF transition ``Φ = [[R, −dt I], [0, I]]`` (R written by :func:`mekf_core`)."""
    for i in range(3):
        for j in range(3):
            phi[i, 3 + j] = -dt if i == j else 0.0
            phi[3 + i, j] = 0.0
            phi[3 + i, 3 + j] = 1.0 if i == j else 0.0


@njit(cache=True)
def mekf_step(q, b, P, st, gyr, acc, mag, dt, p, out_phi):
    """One MEKF step on single samples (the per-sample API): :func:`mekf_core` on copies of ``q`` and ``b``.

    Returns the new (q, b); ``P`` and ``st`` are updated in place, ``out_phi`` receives the 6x6 transition matrix.
    """
    qn = q.copy()
    bn = b.copy()
    mekf_core(qn, bn, P, st, gyr.reshape(1, 3), acc.reshape(1, 3), mag.reshape(1, 3), np.full(1, dt), 0, 1, p, out_phi,
              (np.empty((6, 6)), np.zeros(6), np.empty(6), np.empty(6)),
              (np.empty((1, 4)), np.empty((1, 3)), np.empty((1, 6)), np.empty(1, np.int64), np.empty(1), np.empty(1)))
    _phi_fill(out_phi, dt)
    return qn, bn


@njit(cache=True, error_model="numpy", fastmath={"contract"}, forceinline=True)
def _inject(P, dx, b, qw, qx, qy, qz):
    """Apply the error-state correction ``dx`` (tilt, bias): the covariance reset (:func:`_reset6`), ``q ⊗ exp(δθ)``
    normalised and ``b += δb``; returns the new quaternion's components."""
    _reset6(P, dx[0], dx[1], dx[2])
    e0, e1, e2, e3 = _qexp_fast(dx[0], dx[1], dx[2])
    t0, t1, t2, t3 = qmul_t(qw, qx, qy, qz, e0, e1, e2, e3)
    b[0] += dx[3]
    b[1] += dx[4]
    b[2] += dx[5]
    return _qnormalize_fast(t0, t1, t2, t3)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def mekf_core(q, b, P, st, gyr, acc, mag, dts, k0, k1, p, out_phi, scratch, out):
    """MEKF steps on samples ``k0 … k1 − 1`` of the (N, 3) arrays, in place on ``q``, ``b``, ``P`` and ``st``; row k of
    the outputs ``out = (qs, bs, pd, flg, nis_o, dof_o)`` receives the state after sample k; ``scratch = (W, dx, H,
    PH)`` (tuples: 15 arguments at most, ``tests/test_kernel_signatures.py``).

    ``dts`` holds the time steps (Δt of sample k is ``dts[k]``).  ``st`` (float64 array, len N_STATE) is the adaptive
    state, laid out as MEKF_STATE (S_* constants); ``p`` the parameters (P_* constants).  The measurement updates are
    the models of :mod:`imunav.filters._core_models` (gravity direction, zero rate) and the heading, one scalar row at a
    time (:func:`_att_row_update`, :func:`_heading_update`).  ``out_phi`` receives the 6x6 transition matrix; ``W``
    (6x6), ``dx``, ``H`` and ``PH`` (6) are scratch: nothing is allocated, so a whole recording runs without touching
    the heap.  The loop over the samples is here, not in the caller, so that the arrays are bound once (an inlined
    call per sample took and dropped a reference to each of them, atomic operations that cost as much as the
    filter's arithmetic), and what the parameters fix is computed once.
    """
    W, dx, H, PH = scratch
    qs, bs, pd, flg, nis_o, dof_o = out
    qw, qx, qy, qz = q[0], q[1], q[2], q[3]
    # constants of the recording, out of the loop
    g = p[P_G]
    inv_g = 1.0 / g
    use_mag = p[P_USE_MAG] > 0.5
    sg2_0 = p[P_GYRO_NOISE_DENSITY] * p[P_GYRO_NOISE_DENSITY]
    kg2 = p[P_K_GYRO_RATE] * p[P_K_GYRO_RATE]
    sb2_0 = p[P_GYRO_BIAS_RANDOM_WALK] * p[P_GYRO_BIAS_RANDOM_WALK]
    rest_on = p[P_REST_GYRO_THRESHOLD] > 0.0
    rest_lpf = p[P_REST_LPF_TIME_CONSTANT] > 0.0
    rest_g2 = p[P_REST_GYRO_THRESHOLD] * p[P_REST_GYRO_THRESHOLD]
    rest_a2 = p[P_REST_ACCEL_THRESHOLD] * p[P_REST_ACCEL_THRESHOLD]
    acc_lpf = p[P_ACCEL_LPF_TIME_CONSTANT] > 0.0
    tilt_tc = p[P_TILT_TIME_CONSTANT] > 0.0
    sa_tc = p[P_TILT_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]
    sa_tc2 = sa_tc * sa_tc
    sa_fix2 = p[P_ACCEL_DIRECTION_NOISE_STD] * p[P_ACCEL_DIRECTION_NOISE_STD]
    k_rate_on = p[P_K_RATE] > 0.0
    head_tc = p[P_HEADING_TIME_CONSTANT] > 0.0
    sm_tc = p[P_HEADING_TIME_CONSTANT] * p[P_GYRO_NOISE_DENSITY]
    sm_tc2 = sm_tc * sm_tc
    zaru2 = p[P_ZARU_NOISE_STD] * p[P_ZARU_NOISE_STD]
    mag_bias = 1.0 if p[P_MAG_BIAS] > 0.5 else 0.0
    inv_tau_rest = 1.0 / p[P_REST_LPF_TIME_CONSTANT] if rest_lpf else 0.0
    inv_tau_acc = 1.0 / p[P_ACCEL_LPF_TIME_CONSTANT] if acc_lpf else 0.0
    inv_tau_mag = 1.0 / p[P_MAG_LPF_TIME_CONSTANT] if p[P_MAG_LPF_TIME_CONSTANT] > 0.0 else 0.0
    inv_tau_ref = 1.0 / p[P_MAG_REF_TIME_CONSTANT] if p[P_MAG_REF_TIME_CONSTANT] > 0.0 else 0.0
    dt_prev = -1.0
    inv_dt = 0.0
    for k in range(k0, k1):
        dt = dts[k]
        if dt != dt_prev:  # 1/Δt once while Δt repeats
            dt_prev = dt
            inv_dt = 1.0 / dt
        gx = gyr[k, 0]
        gy = gyr[k, 1]
        gz = gyr[k, 2]
        # ---- predict
        w0 = gx - b[0]
        w1 = gy - b[1]
        w2 = gz - b[2]
        e0, e1, e2, e3 = _qexp_fast(w0 * dt, w1 * dt, w2 * dt)
        # δθ_k+1 = exp(-[ω]dt) δθ_k - dt δb, with exp(-[ω]dt) = C(e)ᵀ, the transposed DCM of the increment e
        # (the same rotation as Rodrigues' formula, from the quaternion's sine and cosine)
        (out_phi[0, 0], out_phi[1, 0], out_phi[2, 0], out_phi[0, 1], out_phi[1, 1], out_phi[2, 1],
         out_phi[0, 2], out_phi[1, 2], out_phi[2, 2]) = dcm_from_quat_t(e0, e1, e2, e3)  # fmt: skip
        t0, t1, t2, t3 = qmul_t(qw, qx, qy, qz, e0, e1, e2, e3)
        qw, qx, qy, qz = _qnormalize_fast(t0, t1, t2, t3)
        # gyro noise grows with the rate (scale-factor and misalignment errors of an
        # uncalibrated gyro act in proportion to |ω|): σ² = σ_g² + (k_ω |ω̄|)²
        wn2 = w0 * w0 + w1 * w1 + w2 * w2
        sg2 = (sg2_0 + kg2 * wn2) * dt
        st[S_ATT_Q] = sg2
        _mekf_predict(P, out_phi, dt, sg2, sb2_0 * dt, W)
        for i in range(6):
            dx[i] = 0.0
        flags = 0
        nis = 0.0
        ndof = 0.0
        qbw, qbx, qby, qbz = qw, qx, qy, qz
        # ---- accelerometer (direction only)
        a0, a1, a2 = acc[k, 0], acc[k, 1], acc[k, 2]
        an = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if rest_lpf:
            # rest from the deviation of gyro and accelerometer from their low-pass
            # (time constant p[P_REST_LPF_TIME_CONSTANT]) plus a bias-size bound on the low-passed rate
            # (Laidig & Seel 2023, §4.2): independent of the accelerometer's
            # scale and of the current bias estimate, robust to per-sample noise
            first = st[S_REST_LP_INIT] < 0.5
            st[S_REST_LP_INIT] = 1.0
            c = _lp_factor(st, S_LP_REST_C, dt, p[P_REST_LPF_TIME_CONSTANT], inv_tau_rest)
            dg = 0.0
            da = 0.0
            big = False
            for i in range(3):
                _lowpass(st, S_GYR_LP + i, gyr[k, i], c, first)
                _lowpass(st, S_ACC_LP + i, acc[k, i], c, first)
                eg = gyr[k, i] - st[S_GYR_LP + i]
                ea = acc[k, i] - st[S_ACC_LP + i]
                dg += eg * eg
                da += ea * ea
                if abs(st[S_GYR_LP + i]) > p[P_LPF_GYRO_THRESHOLD]:
                    big = True
            if rest_on and dg < rest_g2 and da < rest_a2 and not big:
                st[S_REST_TIMER] += dt
            else:
                st[S_REST_TIMER] = 0.0
        elif rest_on and math.sqrt(wn2) < p[P_REST_GYRO_THRESHOLD] and abs(an - g) < p[P_REST_ACCEL_THRESHOLD]:
            st[S_REST_TIMER] += dt
        else:
            st[S_REST_TIMER] = 0.0
        if acc_lpf:
            # low-pass of the specific force in the nav frame; the stored vector is
            # rotated with every correction below, so this is the low-pass in the
            # gyro-integrated frame: translational accelerations average out
            # because velocity stays bounded (cf. Laidig & Seel 2023, §4.1)
            f0, f1, f2 = qrot_t(qw, qx, qy, qz, a0, a1, a2)
            first = st[S_F_LP_INIT] < 0.5
            st[S_F_LP_INIT] = 1.0
            c = _lp_factor(st, S_LP_ACC_C, dt, p[P_ACCEL_LPF_TIME_CONSTANT], inv_tau_acc)
            _lowpass(st, S_F_LP, f0, c, first)
            _lowpass(st, S_F_LP + 1, f1, c, first)
            _lowpass(st, S_F_LP + 2, f2, c, first)
            a0, a1, a2 = qrot_t(qw, -qx, -qy, -qz, st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2])
            an = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        dev = abs(an - g) * inv_g
        if an > 0.0 and dev < p[P_ACCEL_REJECT_THRESHOLD]:
            # per-sample variance: σ_a², or from the time constant τ_a of the tilt
            # correction, (τ_a σ_g)² / Δt (steady state of a random walk of density
            # σ_g seen through white noise of density τ_a σ_g: gain 1/τ_a)
            sa2 = sa_tc2 * inv_dt if tilt_tc else sa_fix2
            dv = dev * 100.0  # in units of 0.01 g
            kr = p[P_K_RATE] * math.sqrt(wn2) if k_rate_on else 0.0
            r = sa2 * (1.0 + p[P_K_ACCEL] * (dv * dv)) + kr * kr
            # gravity-direction model, one scalar row at a time (H = [ĥ]x rows for the body error)
            inv = 1.0 / an
            for i in range(3):
                a_i = a0 if i == 0 else (a1 if i == 1 else a2)
                nu = gravity_direction_row(qw, qx, qy, qz, a_i * inv, i, H)
                nu, si = _att_row_update(P, dx, H[0], H[1], H[2], r, nu, PH)
                nis += nu * nu * si
            ndof += 3.0
        else:
            flags |= 1
        # ---- rest: zero-rate pseudo measurement ω_meas - b = 0 (+ noise)
        if rest_on and st[S_REST_TIMER] >= p[P_REST_TIME]:
            flags |= 4
            r = zaru2
            for i in range(3):
                j = 3 + i
                nu = gyro_rest_row(gyr[k, i], b[i], i, H) - dx[j]  # H = e_j: ν' = ν − δb_i, P hᵀ = P[:, j]
                for l in range(6):
                    PH[l] = P[l, j]
                s = r + PH[j]
                si = _gain6(P, dx, PH, nu, s)
                nis += nu * nu * si
                ndof += 1.0
        # apply the tilt / bias correction before the heading update
        qw, qx, qy, qz = _inject(P, dx, b, qw, qx, qy, qz)
        # ---- magnetometer: heading only
        if use_mag:
            m0, m1, m2 = mag[k, 0], mag[k, 1], mag[k, 2]
            mn = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
            if mn > 0.0:
                n0, n1, n2 = qrot_t(qw, qx, qy, qz, m0, m1, m2)
                hh = math.sqrt(n0 * n0 + n1 * n1)
                dip = math.atan2(n2, hh)
                if p[P_MAG_LPF_TIME_CONSTANT] > 0.0:
                    # norm and dip low-passed (time constant p[P_MAG_LPF_TIME_CONSTANT]) before the disturbance test
                    first = st[S_MAG_LP_INIT] < 0.5
                    st[S_MAG_LP_INIT] = 1.0
                    c = _lp_factor(st, S_LP_MAG_C, dt, p[P_MAG_LPF_TIME_CONSTANT], inv_tau_mag)
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
                        c = dt * inv_tau_ref
                        st[S_MAG_REF_NORM] += c * (mn_t - st[S_MAG_REF_NORM])
                        st[S_MAG_REF_DIP] += c * (dip_t - st[S_MAG_REF_DIP])
                # used only after p[P_MAG_MIN_UNDISTURBED] s of continuous undisturbed field: the few
                # samples of a disturbance that happen to pass the test are not used
                if not disturbed and st[S_UNDISTURBED] >= p[P_MAG_MIN_UNDISTURBED] and hh > 1e-9 * mn:
                    psi = _atan2_small(n1, n0)
                    # σ_mag is field-vector noise, so the heading noise is σ_mag |m| / |m_h|;
                    # τ_mag is the time constant of the heading itself (whatever the dip)
                    if head_tc:
                        sm2 = sm_tc2 * inv_dt
                    else:
                        sm = p[P_HEADING_NOISE_STD] * mn / hh
                        sm2 = sm * sm
                    r = sm2
                    if p[P_K_MAG] > 0.0:
                        xn = dn / p[P_MAG_NORM_THRESHOLD]
                        xd = dd / p[P_MAG_DIP_THRESHOLD]
                        r = sm2 * (1.0 + p[P_K_MAG] * (xn * xn + xd * xd))
                    nis += _heading_update(P, dx, qw, qx, qy, qz, _tan_cached(st, S_TAN_DIP, st[S_MAG_REF_DIP]), r, psi, PH, H,
                                           mag_bias)
                    ndof += 1.0
                    qw, qx, qy, qz = _inject(P, dx, b, qw, qx, qy, qz)
        if acc_lpf:
            # rotate the low-passed nav-frame vector with the total correction q ⊗ q_before*
            d0, d1, d2, d3 = qmul_t(qw, qx, qy, qz, qbw, -qbx, -qby, -qbz)
            st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2] = qrot_t(d0, d1, d2, d3, st[S_F_LP], st[S_F_LP + 1], st[S_F_LP + 2])
        st[S_FLAGS] = flags
        st[S_NIS] = nis
        st[S_DOF] = ndof
        q[0] = qw
        q[1] = qx
        q[2] = qy
        q[3] = qz
        for i in range(4):
            qs[k, i] = q[i]
        for i in range(3):
            bs[k, i] = b[i]
        for i in range(6):
            pd[k, i] = P[i, i]
        flg[k] = flags
        nis_o[k] = nis
        dof_o[k] = ndof


@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def _mekf_loop_store(q, b, P, P0, gyr, acc, mag, dt, p, out, scratch, stored):
    """The MEKF over a recording that also stores P after update, P predicted and Φ of every sample (for the
    smoother): the rows of ``out = (qs, bs, pd, flags, nis, dof)`` written in place, ``scratch = (st, phi, W, dx, H,
    PH)`` (the adaptive state and :func:`mekf_core`'s buffers), ``stored = (Pu, Pp, Ph)``, each (N, 6, 6)."""
    Pu, Pp, Ph = stored
    st, phi, W, dx, H, PH = scratch
    Q = np.zeros((6, 6))
    for k in range(gyr.shape[0]):
        mekf_core(q, b, P, st, gyr, acc, mag, dt, k, k + 1, p, phi, (W, dx, H, PH), out)
        _phi_fill(phi, dt[k])
        Ph[k] = phi
        # P predicted = Φ P_{k-1} Φ^T + Q (recompute cheaply)
        Pprev = P0 if k == 0 else Pu[k - 1]
        for i in range(3):
            Q[i, i] = st[S_ATT_Q]
            Q[3 + i, 3 + i] = p[P_GYRO_BIAS_RANDOM_WALK] * p[P_GYRO_BIAS_RANDOM_WALK] * dt[k]
        Pp[k] = phi @ Pprev @ phi.T + Q
        Pu[k] = P


def _readonly(x):
    """``x`` as a read-only C-contiguous float64 array (a view where it already is one).

    The kernels' inputs pass through here so that one compiled specialization serves every caller: numba compiles a
    kernel again for each combination of writable / read-only, C / non-contiguous arrays it is given (a ULog's
    read-only columns, a writable array of ``imunav warmup``'s recording), and the MEKF's compilation is the first
    run's largest cost (issue 35).
    """
    v = np.ascontiguousarray(x, dtype=np.float64).view()
    v.flags.writeable = False
    return v


def mekf_run(q0, b0, P0, gyr, acc, mag, dt, p, store):
    """Run the MEKF over a recording (releases the GIL: recordings can run on threads side by side).

    Returns q (N,4), b (N,3), Pdiag (N,6), flags (N,), nis (N,), dof (N,), and
    when ``store``: P after update (N,6,6), P predicted (N,6,6), Φ (N,6,6) (else three (1,6,6) placeholders).

    Without ``store`` the outputs and buffers are allocated here and :func:`mekf_core` is the only kernel compiled (a
    kernel around it compiled the machine code of ``mekf_core`` again, issue 35, a first run); with ``store``,
    :func:`_mekf_run_store`.  The inputs pass through :func:`_readonly`: one specialization of each kernel.
    """
    gyr, acc, mag, dt, p = (_readonly(x) for x in (gyr, acc, mag, dt, p))
    if store:
        return _mekf_run_store(q0, b0, P0, gyr, acc, mag, dt, p)
    n = gyr.shape[0]
    out = (np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 6)), np.zeros(n, np.int64), np.zeros(n), np.zeros(n))
    # the state: writable copies (the caller's q0, b0, P0 stay as given)
    q, b, P = (np.array(x, dtype=np.float64, order="C") for x in (q0, b0, P0))
    mekf_core(q, b, P, np.zeros(N_STATE), gyr, acc, mag, dt, 0, n, p, np.empty((6, 6)),
              (np.empty((6, 6)), np.zeros(6), np.empty(6), np.empty(6)), out)
    return (*out, np.empty((1, 6, 6)), np.empty((1, 6, 6)), np.empty((1, 6, 6)))


@njit(cache=True, nogil=True, inline="always")
def _mekf_outputs(n, m):
    """The outputs of :func:`mekf_run` for ``n`` samples (``m`` stored covariances: n or 1)."""
    return (np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 6)), np.zeros(n, np.int64), np.zeros(n), np.zeros(n),
            np.empty((m, 6, 6)), np.empty((m, 6, 6)), np.empty((m, 6, 6)))


@njit(cache=True, nogil=True, inline="always")
def _mekf_scratch():
    """The adaptive state and :func:`mekf_core`'s buffers, ``(st, phi, W, dx, H, PH)``."""
    return np.zeros(N_STATE), np.empty((6, 6)), np.empty((6, 6)), np.zeros(6), np.empty(6), np.empty(6)


@njit(cache=True, nogil=True)
def _mekf_run_store(q0, b0, P0, gyr, acc, mag, dt, p):
    """:func:`mekf_run` with the covariances stored for the smoother."""
    qs, bs, pd, flags, nis, dof, Pu, Pp, Ph = _mekf_outputs(gyr.shape[0], gyr.shape[0])
    q = q0.copy()
    b = b0.copy()
    P = P0.copy()
    _mekf_loop_store(q, b, P, P0, gyr, acc, mag, dt, p, (qs, bs, pd, flags, nis, dof), _mekf_scratch(),
                     (Pu, Pp, Ph))
    return qs, bs, pd, flags, nis, dof, Pu, Pp, Ph


@njit(cache=True)
def rts_smooth(qf, bf, Pu, Pp, Ph, gyr, dt, P0, q0, b0):
    """Rauch-Tung-Striebel smoother on the error state of the MEKF.

    Backward recursion (Rauch, Tung, Striebel 1965) with the nominal state
    re-linearised at the filtered estimate:
        C_k = P_k Φ_{k+1}^T (P⁻_{k+1})^-1
        δx^s_k = C_k (x^s_{k+1} ⊟ x̂⁻_{k+1}),   x^s_k = x̂_k ⊞ δx^s_k
        P^s_k = P_k + C_k (P^s_{k+1} - P⁻_{k+1}) C_k^T
    where x̂⁻_{k+1} = f(x̂_k, ω_{k+1}) is the filter's prediction.
    """
    n = qf.shape[0]
    qs = np.empty((n, 4))
    bs = np.empty((n, 3))
    pd = np.empty((n, 6))
    qs[n - 1] = qf[n - 1]
    bs[n - 1] = bf[n - 1]
    Ps = Pu[n - 1].copy()
    for i in range(6):
        pd[n - 1, i] = Ps[i, i]
    for k in range(n - 2, -1, -1):
        # prediction from the filtered state at k to k+1
        w = gyr[k + 1] - bf[k]
        qp = quat_normalize(qmul_1(qf[k], qexp_1(w * dt[k + 1])))
        e = np.empty(6)
        e[0:3] = qlog_1(qmul_1(qconj_1(qp), qs[k + 1]))
        e[3:6] = bs[k + 1] - bf[k]
        C = Pu[k] @ Ph[k + 1].T @ inv_spd_cholesky(Pp[k + 1])
        dx = C @ e
        qs[k] = inject_attitude_local(qf[k], dx, I_ATT)
        bs[k] = bf[k] + dx[3:6]
        Ps = Pu[k] + C @ (Ps - Pp[k + 1]) @ C.T
        for i in range(6):
            pd[k, i] = Ps[i, i]
    return qs, bs, pd


# ---------------------------------------------------------------------------
# Unscented (error-state, USQUE-like) filter, 6 error states, same aiding as
# the MEKF without the adaptive parts (fixed R, accelerometer gate only).


@njit(cache=True)
def ukf_step(q, b, P, gyr, acc, mag, dt, p, alpha, beta_u, kappa, mag_ref):
    """One error-state UKF step (Crassidis & Markley 2003, USQUE, with the Hamilton body-error convention).

    The sigma points, their moments and the sigma-point update are the core's unscented transform
    (:func:`imunav.filters._core.sigma_offsets`, ``unscented_mean``, ``unscented_cov``, ``unscented_update``),
    the same primitives as :class:`imunav.filters.UnscentedKalmanFilter`.  Returns (q, b, P, nis, dof).
    """
    nx = 6
    lam, wm0, wc0, wi = unscented_weights(nx, alpha, beta_u, kappa)
    g = p[P_G]
    # ---- predict: sigma points of the error around (q, b)
    ns = 2 * nx + 1
    X = np.empty((ns, nx))
    sigma_offsets(P, lam, X)
    qp0 = quat_normalize(qmul_1(q, qexp_1((gyr - b) * dt)))
    Y = np.zeros((ns, nx))
    for s in range(ns):
        qs_ = qmul_1(q, qexp_1(X[s, 0:3]))
        bs_ = b + X[s, 3:6]
        qps = qmul_1(qs_, qexp_1((gyr - bs_) * dt))
        Y[s, 0:3] = qlog_1(qmul_1(qconj_1(qp0), qps))
        Y[s, 3:6] = bs_ - b
    ym = unscented_mean(Y, wm0, wi)
    D = Y - ym
    Pn = unscented_cov(D, D, wc0, wi)
    for i in range(3):
        Pn[i, i] += p[P_GYRO_NOISE_DENSITY] * p[P_GYRO_NOISE_DENSITY] * dt
        Pn[3 + i, 3 + i] += p[P_GYRO_BIAS_RANDOM_WALK] * p[P_GYRO_BIAS_RANDOM_WALK] * dt
    q = quat_normalize(qmul_1(qp0, qexp_1(ym[0:3])))
    b = b + ym[3:6]
    P = Pn
    nis = 0.0
    dof = 0.0
    # ---- update: stacked accelerometer direction (+ field direction)
    an = _norm3(acc)
    use_acc = an > 0.0 and abs(an - g) / g < p[P_ACCEL_REJECT_THRESHOLD]
    use_mag = p[P_USE_MAG] > 0.5 and _norm3(mag) > 0.0
    nz = (3 if use_acc else 0) + (3 if use_mag else 0)
    if nz > 0:
        sigma_offsets(P, lam, X)
        Z = np.zeros((ns, nz))
        dg = np.zeros(3)
        dg[2] = -1.0
        for s in range(ns):
            qsc = qconj_1(qmul_1(q, qexp_1(X[s, 0:3])))
            j = 0
            if use_acc:
                Z[s, 0:3] = qrot_1(qsc, dg)
                j = 3
            if use_mag:
                Z[s, j:j + 3] = qrot_1(qsc, mag_ref)
        zm = unscented_mean(Z, wm0, wi)
        Dz = Z - zm
        Pzz = unscented_cov(Dz, Dz, wc0, wi)
        Pxz = unscented_cov(X, Dz, wc0, wi)
        z = np.zeros(nz)
        j = 0
        if use_acc:
            z[0:3] = acc / an
            for i in range(3):
                Pzz[i, i] += p[P_ACCEL_DIRECTION_NOISE_STD] * p[P_ACCEL_DIRECTION_NOISE_STD]
            j = 3
        if use_mag:
            z[j:j + 3] = mag / _norm3(mag)
            for i in range(3):
                # the UKF keeps its field-direction σ (UkfConfig.mag_direction_noise_std) in this slot
                Pzz[j + i, j + i] += p[P_HEADING_NOISE_STD] * p[P_HEADING_NOISE_STD]
        dx = np.empty(nx)
        K = np.empty((nx, nz))
        nis = unscented_update(P, Pxz, Pzz, z - zm, dx, K)
        dof = nz
        q = inject_attitude_local(q, dx, I_ATT)
        b = b + dx[3:6]
    return q, b, P, nis, dof


@njit(cache=True)
def ukf_run(q0, b0, P0, gyr, acc, mag, dt, p, alpha, beta_u, kappa, mag_ref):
    n = gyr.shape[0]
    qs = np.empty((n, 4))
    bs = np.empty((n, 3))
    pd = np.empty((n, 6))
    Pa = np.empty((n, 6, 6))
    nis = np.zeros(n)
    dof = np.zeros(n)
    q = q0.copy()
    b = b0.copy()
    P = P0.copy()
    for k in range(n):
        q, b, P, nis[k], dof[k] = ukf_step(q, b, P, gyr[k], acc[k], mag[k], dt[k], p, alpha, beta_u, kappa, mag_ref)
        qs[k] = q
        bs[k] = b
        Pa[k] = P
        for i in range(6):
            pd[k, i] = P[i, i]
    return qs, bs, pd, Pa, nis, dof
