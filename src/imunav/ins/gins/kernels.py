"""Numba kernel of the loosely coupled GNSS/INS error-state filter (private; public API in
:mod:`imunav.ins.gins.filter`).

Error state (blocks of :data:`imunav.ins.gins.layout.STATE_BLOCKS`): NED position error δr (m), velocity error δv
(m/s), navigation-frame attitude error φ with ``C_nb = exp([φ×]) Ĉ_nb`` (the global convention of
:mod:`imunav.filters._core`), gyro and accelerometer biases, and optionally gyro and accelerometer scale factors
and the odometer scale factor (first-order Gauss–Markov each).  Errors are ``true − estimate``.  The IMU model is
``ω̃ = (1 + s_g) ω + b_g + w_g``, ``f̃ = (1 + s_a) f + b_a + w_a``.

Continuous error dynamics (Groves 2013, §14.2.4, in this sign convention; small Earth-curvature terms of the
position rows dropped, the vertical gravity gradient kept)::

    δṙ = δv
    δv̇ = −[fⁿ×] φ − [(2ω_ie + ω_en)×] δv − Ĉ δb_a − Ĉ diag(f^b) δs_a + (0, 0, 2g/R δr_D) − Ĉ w_a
    φ̇  = −[ω_in×] φ − δω_en(δv) − Ĉ δb_g − Ĉ diag(ω^b) δs_g − Ĉ w_g
    δḃ = −δb / T + w_b  (σ² 2/T),   δṡ = −δs / T + w_s

With a bias made of a random constant and a Gauss–Markov part (``bias_model="constant_and_gauss_markov"``) the
bias blocks hold the whole bias and two more blocks its Gauss–Markov part ``δg`` (Maybeck 1979, §4.11)::

    δḃ = δġ = −δg / T + w_b,   cov(w_b into δb, δg) = the same σ² 2/T

The nominal state is integrated per IMU sample by :func:`imunav.filters._core.strapdown_step_ned`; the covariance
every ``cov_step`` samples, at each timed aid's stamp and at each sample that carries a forcing sampled aid
(barometer, magnetometer) by :func:`imunav.filters._core_gins.propagate_cov_series`.  Timed measurements between
two IMU samples split the increments at their own stamps.  Every update is one call of the aid models of
:mod:`imunav.ins.gins.aids` (through :func:`~imunav.ins.gins.aids.evaluate_used`, which compiles the models of the
aids a run uses only), then
:func:`imunav.filters._core.chi2_gate` on the stacked innovation, :func:`imunav.filters._core.joseph_update_consider` and
the injection of the error estimate into the nominal state.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.earth import radii_gravity_1
from imunav.filters._core import (
    ATT_START,
    chi2_gate,
    cholesky_small,
    inject_additive,
    inject_attitude_global,
    joseph_update_consider,
    nis,
    strapdown_step_ned,
)
from imunav.filters._core_gins import inject_position_lla, propagate_cov_series, write_mat3, write_skew
from imunav.ins.gins.aids import AID, N_AIDS, ROWS, WIDTH, evaluate_used
from imunav.ins.gins.layout import (
    CARRY,
    CARRY_N,
    CTX,
    LAY,
    MAX_GROUP,
    MAX_WIDTH,
    N_CTX,
    N_LAY,
    NOM,
    PRM,
    STATE_BLOCKS,
)

#: IMU increments: times (N,), Δθ (N, 3) rad, Δv (N, 3) m/s; row k covers [t[k-1], t[k]].
ImuInput = namedtuple("ImuInput", ("t", "dtheta", "dvel"))
#: Timed aid measurements in time order: stamp (E,), aid kind (E,) int64, z (E, 3), covariance r (E, 3, 3).  A kind
#: ``−1 − k`` marks a withheld measurement of aid ``k``: its innovation is computed and logged (NIS, ln det S), the
#: state is not updated (a cross-validation's predictive check, :func:`_withheld`).
TimedInput = namedtuple("TimedInput", ("t", "kind", "z", "r"))
#: Sampled aids: columns z (N, W) on the IMU grid (NaN: no measurement), force (N,) bool (a covariance epoch at that
#: sample), and per slot s: aid kind, first column, joint-update group (slots of one group are consecutive).
SampledInput = namedtuple("SampledInput", ("z", "force", "kind", "col", "group"))
#: Outputs: per-sample nominal state ``xs`` (N, N_NOM); covariance records (time, diagonal, 9×9 navigation block);
#: the update log (time, IMU sample, source: timed index >= 0 or −1 − group, rows, accepted, NIS, each model's NIS
#: alone; ``log_lds``: ln det S of a withheld measurement's innovation covariance, NaN for the others); the smoother
#: records (time, Φ into the epoch, prior and posterior P, injected error, posterior nominal state lat, lon, h, v, q).
KernelOutput = namedtuple("KernelOutput", (
    "xs", "cov_t", "cov_diag", "cov_nav", "log_t", "log_k", "log_src", "log_rows", "log_ok", "log_nis", "log_blk",
    "log_lds", "rec_t", "rec_phi", "rec_ppri", "rec_ppost", "rec_inj", "rec_state"))


@njit(cache=True)
def _system(xs, fb, wb, prm, lay, F, Q):
    """Fill F and Q (= G Q Gᵀ) of the error dynamics at the nominal state with mean ``f^b`` and ``ω^b``."""
    F[:, :] = 0.0
    Q[:, :] = 0.0
    C = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    lat = xs[NOM.lla]
    alt = xs[NOM.lla + 2]
    v = xs[NOM.vel:NOM.vel + 3]
    RN, RE, g = radii_gravity_1(lat, alt)
    om = prm[PRM.omega_e]
    w_ie = np.array([om * math.cos(lat), 0.0, -om * math.sin(lat)])
    w_en = np.array([v[1] / (RE + alt), -v[0] / (RN + alt), -v[1] * math.tan(lat) / (RE + alt)])
    fn = C @ fb
    ones = np.ones(3)
    ip, iv, ia = lay[LAY.pos], lay[LAY.vel], lay[LAY.att]
    ibg, iba = lay[LAY.gyro_bias], lay[LAY.accel_bias]
    for j in range(3):
        F[ip + j, iv + j] = 1.0
    F[iv + 2, ip + 2] = 2.0 * g / (math.sqrt(RN * RE) + alt)
    # 2 ω_ie + ω_en and ω_in = ω_ie + ω_en element by element (array expressions compile broadcasting loops into every
    # caller's machine code: issue 35, a first run)
    w2 = np.empty(3)
    w_in = np.empty(3)
    for j in range(3):
        w2[j] = 2.0 * w_ie[j] + w_en[j]
        w_in[j] = w_ie[j] + w_en[j]
    write_skew(fn, F, iv, ia, -1.0)
    write_skew(w2, F, iv, iv, -1.0)
    write_mat3(C, F, iv, iba, -1.0, ones)
    write_skew(w_in, F, ia, ia, -1.0)
    F[ia, iv + 1] = -1.0 / (RE + alt)
    F[ia + 1, iv] = 1.0 / (RN + alt)
    F[ia + 2, iv + 1] = math.tan(lat) / (RE + alt)
    write_mat3(C, F, ia, ibg, -1.0, ones)
    for ib, ig, t0, q0 in ((ibg, lay[LAY.gyro_bias_gm], PRM.gyro_bias_t, PRM.gyro_bias_q),
                           (iba, lay[LAY.accel_bias_gm], PRM.accel_bias_t, PRM.accel_bias_q)):
        for j in range(3):
            a = -1.0 / prm[t0 + j]
            q = prm[q0 + j]
            Q[ib + j, ib + j] = q
            if ig < 0:  # the bias a Gauss–Markov process: δḃ = −δb / T + w
                F[ib + j, ib + j] = a
            else:  # a constant c plus a Gauss–Markov g, the whole b = c + g: δḃ = δġ = −δg / T + w
                F[ib + j, ig + j] = a
                F[ig + j, ig + j] = a
                Q[ig + j, ig + j] = q
                Q[ib + j, ig + j] = q
                Q[ig + j, ib + j] = q
    ig = lay[LAY.gnss_bias]
    if ig >= 0:  # the fixes' correlated error: δḃ = −δb / T + w
        for j in range(3):
            F[ig + j, ig + j] = -1.0 / prm[PRM.gnss_bias_t]
            Q[ig + j, ig + j] = prm[PRM.gnss_bias_q + j]
    io = lay[LAY.odo_scale]
    if io >= 0:
        F[io, io] = -1.0 / prm[PRM.odo_scale_t]
        Q[io, io] = prm[PRM.odo_scale_q]
    isg, isa = lay[LAY.gyro_scale], lay[LAY.accel_scale]
    if isa >= 0:
        write_mat3(C, F, iv, isa, -1.0, fb)
    if isg >= 0:
        write_mat3(C, F, ia, isg, -1.0, wb)
    for j in range(3):
        if isg >= 0:
            F[isg + j, isg + j] = -1.0 / prm[PRM.gyro_scale_t + j]
            Q[isg + j, isg + j] = prm[PRM.gyro_scale_q + j]
        if isa >= 0:
            F[isa + j, isa + j] = -1.0 / prm[PRM.accel_scale_t + j]
            Q[isa + j, isa + j] = prm[PRM.accel_scale_q + j]
    # white noise through C: C diag(n²) Cᵀ
    for i in range(3):
        for j in range(3):
            a = 0.0
            b = 0.0
            for l in range(3):
                a += C[i, l] * prm[PRM.accel_noise_density + l] ** 2 * C[j, l]
                b += C[i, l] * prm[PRM.gyro_noise_density + l] ** 2 * C[j, l]
            Q[iv + i, iv + j] = a
            Q[ia + i, ia + j] = b


# (state block, nominal offset) of the additive sensor-error blocks
_ADDITIVE = ((LAY.gyro_bias, NOM.gyro_bias, 3), (LAY.accel_bias, NOM.accel_bias, 3),
             (LAY.gyro_scale, NOM.gyro_scale, 3), (LAY.accel_scale, NOM.accel_scale, 3),
             (LAY.odo_scale, NOM.odo_scale, 1), (LAY.odo_lever, NOM.odo_lever, 3), (LAY.gnss_delay, NOM.gnss_delay, 1),
             (LAY.gnss_bias, NOM.gnss_bias, 3), (LAY.odo_turn, NOM.odo_turn, 1),
             (LAY.side_slip, NOM.side_slip, 1))


@njit(cache=True)
def _inject(dx, xs, lay, acc_dx):
    """Feed the error estimate back into the nominal state, add it to ``acc_dx`` and zero it."""
    lla = xs[NOM.lla:NOM.lla + 3]
    inject_position_lla(lla, dx, lay[LAY.pos])
    v = xs[NOM.vel:NOM.vel + 3]
    inject_additive(v, dx, lay[LAY.vel], np.int64(3))
    qn = inject_attitude_global(xs[NOM.q:NOM.q + 4], dx, lay[LAY.att])
    for j in range(4):
        xs[NOM.q + j] = qn[j]
    for blk, off, n in _ADDITIVE:
        i0 = lay[blk]
        if i0 >= 0:
            e = xs[off:off + n]
            inject_additive(e, dx, i0, n)
    im = lay[LAY.mount]
    if im >= 0:  # C_vb = exp([μ×]) Ĉ_vb
        qm = inject_attitude_global(xs[NOM.q_vb:NOM.q_vb + 4], dx, im)
        for j in range(4):
            xs[NOM.q_vb + j] = qm[j]
    for j in range(dx.shape[0]):
        acc_dx[j] += dx[j]
    dx[:] = 0.0


@njit(cache=True)
def _update(kinds, n_models, zs, rs, xs, ctx, P, prm, lay, acc_dx, blk, force, use):
    """One (joint) update of ``n_models`` aid models: stack their rows, gate the whole, Joseph update, inject.

    ``kinds[i]``, ``zs[i]``, ``rs[i]``: kind, measurement and covariance of model i.  ``blk[i]`` receives the NIS of
    model i's rows alone (the marginal of the joint innovation, χ²(rows) for a consistent filter; record only;
    NaN past ``n_models``).  ``force``: apply the update whatever the gate says (after too many rejections in a
    row).  ``use``: the aid set of the run (:func:`imunav.ins.gins.aids.used`).  Returns (rows, accepted by the
    gate, NIS).
    """
    nx = P.shape[0]
    m = np.int64(0)
    for i in range(n_models):
        m += ROWS[kinds[i]]
    H = np.zeros((m, nx))
    R = np.zeros((m, m))
    nu = np.empty(m)
    row = np.int64(0)
    for i in range(n_models):
        k = kinds[i]
        # zs[i], rs[i]: the padded measurement and covariance buffers of model i
        evaluate_used(use, k, xs, ctx, zs[i], rs[i], prm[lay[N_LAY + k]:], lay, H, R, nu, row)
        row += ROWS[k]
    S0 = H @ P @ H.T
    for i in range(m):  # + R element by element (no array expression: issue 35)
        for j in range(m):
            S0[i, j] += R[i, j]
    blk[:] = np.nan
    row = np.int64(0)
    for i in range(n_models):
        w = ROWS[kinds[i]]
        # a C-contiguous copy of the block: the one compilation of nis (C layout) that chi2_gate below uses
        blk[i] = nis(nu[row:row + w], S0[row:row + w, row:row + w].copy())
        row += w
    ok, d = chi2_gate(nu, S0, prm[PRM.gate + m - 1])
    if ok or force:
        if kinds[0] == _GNSS_POS and prm[PRM.gnss_adapt] > 0.0:
            _adapt_noise(xs, nu, S0, R, prm, NOM.gnss_r_scale, PRM.gnss_adapt)
        elif prm[PRM.wheel_adapt] > 0.0:
            row = np.int64(0)
            for i in range(n_models):  # each wheel aid's factor from its own rows
                w = ROWS[kinds[i]]
                if kinds[i] == _ODO or kinds[i] == _NHC:
                    _adapt_noise(xs, nu[row:row + w], S0[row:row + w, row:row + w], R[row:row + w, row:row + w], prm,
                                 NOM.odo_r_scale if kinds[i] == _ODO else NOM.nhc_r_scale, PRM.wheel_adapt)
                row += w
        if not ok and kinds[0] != _GNSS_POS:
            # forced after a run of rejections: the innovation's covariance scaled by λ = d / threshold, so that it
            # sits on the gate (R̃ = R + (λ − 1) S, S̃ = λ S; Chang 2014, "Robust Kalman filtering based on Mahalanobis
            # distance as outlier judging criterion", J. Geodesy 88): the filter moves towards the measurement by
            # what its own P allows, not onto it (a wheel spinning for 3 s, forced in at its σ, took the velocity
            # 1.4 m/s off with a σ of 0.04 m/s).  A forced fix keeps its σ: the fixes' adaptive factor learns a
            # receiver's understated σ from it (at S̃ = λ S the filter's own P dominates S and the factor never moves)
            lam = d / prm[PRM.gate + m - 1]
            for i in range(m):
                for j in range(m):
                    R[i, j] += (lam - 1.0) * S0[i, j]
        dx = np.zeros(nx)
        # one update kernel for both cases (an empty mask zeroes no gain row: joseph_update's arithmetic), so that a
        # first run compiles one Joseph update, not two
        joseph_update_consider(P, dx, H, R, nu, np.empty(m), np.empty((m, m)), np.empty((nx, m)),
                               _consider_mask(lay, nx))
        _inject(dx, xs, lay, acc_dx)
    return m, ok, d


@njit(cache=True)
def _withheld(kinds, zs, rs, xs, ctx, P, prm, lay, use):
    """A withheld measurement of aid ``kinds[0]`` (``zs[0]``, ``rs[0]``): its innovation ``ν`` and covariance
    ``S = H P Hᵀ + R`` as :func:`_update` computes them, the state and covariance untouched.  Returns (rows, NIS
    ``νᵀ S⁻¹ ν``, ``ln det S``): the measurement's predictive density is ``N(ν; 0, S)`` (Bar-Shalom et al. 2001,
    §5.2.3), which a cross-validation scores (:func:`imunav.ins.gins.identify.withheld_score`)."""
    k = kinds[0]
    m = ROWS[k]
    H = np.zeros((m, P.shape[0]))
    R = np.zeros((m, m))
    nu = np.empty(m)
    evaluate_used(use, k, xs, ctx, zs[0], rs[0], prm[lay[N_LAY + k]:], lay, H, R, nu, np.int64(0))
    S = H @ P @ H.T
    for i in range(m):
        for j in range(m):
            S[i, j] += R[i, j]
    Lc = cholesky_small(S)
    lds = 0.0
    for i in range(m):
        lds += 2.0 * math.log(Lc[i, i])
    return m, nis(nu, S), lds


@njit(cache=True, inline="always")
def _consider_mask(lay, nx):
    """The states of the consider blocks (bit mask ``lay[LAY.consider]`` over :data:`STATE_BLOCKS`)."""
    mask = np.zeros(nx, dtype=np.bool_)
    for b in range(len(_BLOCK_LAY)):
        if (lay[LAY.consider] >> b) & 1 and lay[_BLOCK_LAY[b]] >= 0:
            for j in range(_BLOCK_SIZE[b]):
                mask[lay[_BLOCK_LAY[b]] + j] = True
    return mask


# the LAY field and the size of each block of STATE_BLOCKS, in order (compile-time constants)
_BLOCK_LAY = tuple(getattr(LAY, name) for name, _ in STATE_BLOCKS)
_BLOCK_SIZE = tuple(n for _, n in STATE_BLOCKS)


_GNSS_POS = AID.gnss_position
_ODO = AID.odometer
_NHC = AID.nhc


@njit(cache=True, inline="always")
def _adapt_noise(xs, nu, S0, R, prm, nom, pa):
    """Covariance matching of an aid's white noise (Mehra 1972; Mohamed & Schwarz 1999, "Adaptive Kalman
    filtering for INS/GPS", J. Geodesy 73): ``E[ν νᵀ] = H P⁻ Hᵀ + s R_rep``, so one update's estimate of the factor
    is ``ŝ = (νᵀν − tr(H P⁻ Hᵀ)) / tr(R_rep)``, of variance ``v = 2 Σ S_jj² / tr(R_rep)²`` (Gaussian ν, diagonal
    terms): large while the filter's own uncertainty ``H P⁻ Hᵀ`` dominates, as at the start.  The kernel keeps the
    inverse-variance weighted mean with forgetting,

        ``W ← (1 − w₀) W + 1/v``,   ``s ← s + (1/v) / W · (ŝ − s)``,

    the reported σ counting as a number of prior updates of variance ``2 / m`` (``W₀``, ``s₀ = 1``), bounded to
    ``[s_min, s_max]``.  ``nom``: the offset in ``xs`` of the factor applied, the estimate and its information (the
    GNSS fixes' ``NOM.gnss_r_scale``, the odometer's ``NOM.odo_r_scale``, the NHC's ``NOM.nhc_r_scale``); ``pa``:
    the offset in ``prm`` of ``(w₀, s_min, s_max)``.

    The factor applied to the next update's ``R`` is the estimate when it departs from 1 by more than two standard
    errors ``2 / √W``, else 1: an aid whose σ is right keeps it exactly.  A noisy factor about 1, or one driven by
    the first innovations (which hold the initial position's error), made the robot drives' GNSS NIS
    1.013 -> 1.036.
    """
    tr_r = 0.0
    v = 0.0
    vv = 0.0
    tr_hph = 0.0
    s_used = xs[nom]
    for j in range(nu.shape[0]):
        tr_r += R[j, j] / s_used
        tr_hph += S0[j, j] - R[j, j]
        vv += nu[j] * nu[j]
        v += 2.0 * S0[j, j] * S0[j, j]
    v /= tr_r * tr_r
    W = (1.0 - prm[pa]) * xs[nom + 2] + 1.0 / v
    xs[nom + 2] = W
    est = xs[nom + 1] + (1.0 / v) / W * ((vv - tr_hph) / tr_r - xs[nom + 1])
    est = min(max(est, prm[pa + 1]), prm[pa + 2])
    xs[nom + 1] = est
    xs[nom] = est if abs(est - 1.0) > 2.0 / math.sqrt(W) else 1.0


@njit(cache=True, inline="always")
def _forced(carry_n, lay, src):
    """After ``lay[LAY.max_rejections]`` (> 0) gate rejections in a row of one source (a timed aid kind, or
    ``N_AIDS + group``), its next update is applied whatever the gate says: a filter that has drifted off would
    otherwise reject every later measurement of a continuous aid (odometer, NHC, ZUPT) and never come back."""
    mx = lay[LAY.max_rejections]
    return mx > 0 and carry_n[CARRY_N.rejections + src] >= mx


@njit(cache=True, inline="always")
def _count(carry_n, src, ok):
    """Count the gate rejections in a row of a source (reset by an acceptance)."""
    carry_n[CARRY_N.rejections + src] = 0 if ok else carry_n[CARRY_N.rejections + src] + 1


@njit(cache=True, inline="always")
def _log(out, L, t, k, src, m, ok, d, blk):
    """Append one row to the update log when there is room; returns the new count."""
    if L < out.log_t.shape[0]:
        out.log_t[L] = t
        out.log_k[L] = k
        out.log_src[L] = src
        out.log_rows[L] = m
        out.log_ok[L] = ok
        out.log_nis[L] = d
        for i in range(blk.shape[0]):
            out.log_blk[L, i] = blk[i]
        return L + 1
    return L


@njit(cache=True)
def _step(xs, dth, dv, h, lay, om, wb, fb, work):
    """Compensate the increments for the estimated IMU errors and run one NED strapdown step in place;
    ``wb``, ``fb`` receive the compensated mean rate and specific force; ``work``: 16 floats of scratch (allocated
    once per kernel call: a heap allocation per sample would cost a tenth of the step)."""
    dthc = work[0:3]
    dvc = work[3:6]
    scale_g = lay[LAY.gyro_scale] >= 0
    scale_a = lay[LAY.accel_scale] >= 0
    for j in range(3):
        sg = xs[NOM.gyro_scale + j] if scale_g else 0.0
        sa = xs[NOM.accel_scale + j] if scale_a else 0.0
        dthc[j] = (dth[j] - xs[NOM.gyro_bias + j] * h) / (1.0 + sg)
        dvc[j] = (dv[j] - xs[NOM.accel_bias + j] * h) / (1.0 + sa)
        wb[j] = dthc[j] / h
        fb[j] = dvc[j] / h
    q = xs[NOM.q:NOM.q + 4]
    v = xs[NOM.vel:NOM.vel + 3]
    lla = xs[NOM.lla:NOM.lla + 3]
    qn = work[6:10]
    vn = work[10:13]
    llan = work[13:16]
    strapdown_step_ned(q, v, lla, dthc, dvc, h, om, ATT_START, qn, vn, llan)
    for j in range(4):  # element by element here and below: a row assignment compiles numba's shape-error message
        q[j] = qn[j]
    for j in range(3):
        v[j] = vn[j]
        lla[j] = llan[j]


@njit(cache=True, inline="always")
def _copy1(dst, src):
    """``dst[:] = src`` element by element (a slice assignment compiles numba's shape-error message: seconds of a
    first run; issue 35)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, inline="always")
def _copy2(dst, src):
    """``dst[:, :] = src`` element by element (:func:`_copy1`)."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True)
def _rec_post(out, r, tr, P, xs, acc_dx):
    """Smoother record of epoch r after its updates: time, posterior P, injected error (added), nominal state."""
    out.rec_t[r] = tr
    _copy2(out.rec_ppost[r], P)
    for j in range(acc_dx.shape[0]):
        out.rec_inj[r, j] += acc_dx[j]
        acc_dx[j] = 0.0
    for j in range(3):
        out.rec_state[r, j] = xs[NOM.lla + j]
        out.rec_state[r, 3 + j] = xs[NOM.vel + j]
    for j in range(4):
        out.rec_state[r, 6 + j] = xs[NOM.q + j]


@njit(cache=True, inline="always")
def _record_cov(out, m, tk, P):
    """Write covariance record m (time, diagonal, navigation block) when there is room; returns the new count."""
    if m < out.cov_t.shape[0]:
        for j in range(P.shape[0]):
            out.cov_diag[m, j] = P[j, j]
        for a in range(9):
            for b in range(9):
                out.cov_nav[m, a, b] = P[a, b]
        out.cov_t[m] = tk
        return m + 1
    return m


@njit(cache=True)
def _propagate(xs, carry, t_now, P, prm, lay, F, Q, wb, fb, out, r):
    """Covariance propagation over ``(t_cov, t_now]`` with the mean rate and specific force of that span; returns
    the new smoother epoch count (Φ and the prior recorded) — nothing when the span is empty."""
    dtc = t_now - carry[CARRY.t_cov]
    if dtc > 0.0:
        for j in range(3):
            wb[j] = carry[CARRY.sum_w + j] / dtc
            fb[j] = carry[CARRY.sum_f + j] / dtc
        _system(xs, fb, wb, prm, lay, F, Q)
        Phi = propagate_cov_series(P, F, Q, dtc)
        if lay[LAY.gnss_bias] >= 0:  # the fixes' correlated error is predicted to decay as its model says
            a = math.exp(-dtc / prm[PRM.gnss_bias_t])
            for j in range(3):
                xs[NOM.gnss_bias + j] *= a
        if out.rec_t.shape[0] > 0 and r + 1 < out.rec_t.shape[0]:
            r += 1
            _copy2(out.rec_phi[r], Phi)
            _copy2(out.rec_ppri[r], P)
    return r


@njit(cache=True)
def gins_run(imu, timed, sampled, xs, P, carry, carry_n, prm, lay, out, first, final, use):
    """Filter over the IMU samples 1..N-1 (row k: increments over [t[k-1], t[k]]), from the state at t[0].

    ``xs`` (nominal state, layout ``NOM``), ``P`` and ``carry`` / ``carry_n`` (covariance clock) are the state at
    t[0] and are updated in place, so that consecutive calls continue one filter
    (:meth:`imunav.ins.gins.GinsFilter.step` calls it with N = 2).  ``first``: write the records of t[0]
    (covariance, smoother); ``final``: propagate the covariance at the last sample whatever the clock says.
    Inputs and outputs: :data:`ImuInput`, :data:`TimedInput` (or None: no timed aid, whose updates numba then does
    not compile), :data:`SampledInput`, :data:`KernelOutput` (smoother
    records of length R > 0 ask for them: per covariance epoch r the transition Φ_r into r, the prior and
    posterior covariances, the error injected at r and the posterior nominal state).  ``use``: the aids the call may
    apply (:func:`imunav.ins.gins.aids.used`; its type is the set, and the kernel compiles the rows of those aids only).

    Returns the numbers of covariance records, smoother epochs and update-log rows written.
    """
    t = imu.t
    n = t.shape[0]
    nx = P.shape[0]
    wb = np.zeros(3)
    fb = np.zeros(3)
    F = np.zeros((nx, nx))
    Q = np.zeros((nx, nx))
    rem_th = np.empty(3)
    rem_v = np.empty(3)
    work = np.empty(16)
    pth = np.empty(3)
    pv = np.empty(3)
    ctx = np.zeros(N_CTX)
    blk = np.full(MAX_GROUP, np.nan)
    blk_slot = np.full(MAX_GROUP, np.nan)
    kinds = np.empty(MAX_GROUP, dtype=np.int64)
    slot = np.empty(MAX_GROUP, dtype=np.int64)
    zs = np.zeros((MAX_GROUP, MAX_WIDTH))
    rs = np.zeros((MAX_GROUP, 3, 3))
    om = prm[PRM.omega_e]
    cov_step = lay[LAY.cov_step]
    n_slots = sampled.kind.shape[0]
    _copy1(out.xs[0], xs)
    ei = np.int64(0)
    ne = np.int64(0)
    if timed is not None:  # None (no timed aid): numba drops the timed updates from what it compiles
        ne = timed.t.shape[0]
        while ei < ne and timed.t[ei] <= t[0]:
            ei += 1  # measurements before the first sample have no state to update (the wrapper trims them)
    # counters start as int64, not as the literal 0: numba would otherwise compile every kernel they are passed to
    # once more, for the literal (issue 35: a first run compiles each kernel once)
    m = np.int64(0)
    L = np.int64(0)
    if first:
        m = _record_cov(out, m, t[0], P)
    acc_dx = np.zeros(nx)
    rec = out.rec_t.shape[0] > 0
    r = np.int64(0)
    if rec and first:
        _rec_post(out, r, t[0], P, xs, acc_dx)
    for k in range(1, n):
        t_cur = t[k - 1]
        for j in range(3):
            rem_th[j] = imu.dtheta[k, j]
            rem_v[j] = imu.dvel[k, j]
        # timed measurements inside (t[k-1], t[k]]: integrate to their stamp, propagate P, update
        if timed is not None:
            while ei < ne and timed.t[ei] <= t[k]:
                te = timed.t[ei]
                hh = te - t_cur
                if hh > 0.0:
                    frac = hh / (t[k] - t_cur)
                    for j in range(3):
                        pth[j] = frac * rem_th[j]
                        pv[j] = frac * rem_v[j]
                        rem_th[j] -= pth[j]
                        rem_v[j] -= pv[j]
                    _step(xs, pth, pv, hh, lay, om, wb, fb, work)
                    for j in range(3):
                        carry[CARRY.sum_w + j] += wb[j] * hh
                        carry[CARRY.sum_f + j] += fb[j] * hh
                    t_cur = te
                if t_cur - carry[CARRY.t_cov] > 0.0:
                    r = _propagate(xs, carry, t_cur, P, prm, lay, F, Q, wb, fb, out, r)
                    carry[CARRY.t_cov] = t_cur
                    for j in range(3):
                        carry[CARRY.sum_w + j] = 0.0
                        carry[CARRY.sum_f + j] = 0.0
                    carry_n[CARRY_N.n_cov] = 0
                for j in range(3):
                    ctx[CTX.w_mean + j] = wb[j]
                src = timed.kind[ei]
                kinds[0] = src if src >= 0 else -1 - src  # −1 − kind: withheld, scored and not applied
                for i in range(3):
                    zs[0, i] = timed.z[ei, i]
                    for j in range(3):
                        rs[0, i, j] = timed.r[ei, i, j]
                if src < 0:
                    mm, d, lds = _withheld(kinds, zs, rs, xs, ctx, P, prm, lay, use)
                    blk[:] = np.nan
                    blk[0] = d
                    L0 = L
                    L = _log(out, L, te, k, ei, mm, d <= prm[PRM.gate + mm - 1], d, blk)
                    if L > L0:
                        out.log_lds[L0] = lds
                else:
                    mm, ok, d = _update(kinds, np.int64(1), zs, rs, xs, ctx, P, prm, lay, acc_dx, blk,
                                        _forced(carry_n, lay, src), use)
                    _count(carry_n, src, ok)
                    L = _log(out, L, te, k, ei, mm, ok, d, blk)
                if rec:
                    _rec_post(out, r, t_cur, P, xs, acc_dx)
                ei += 1
        hh = t[k] - t_cur
        if hh > 0.0:
            _step(xs, rem_th, rem_v, hh, lay, om, wb, fb, work)
            for j in range(3):
                carry[CARRY.sum_w + j] += wb[j] * hh
                carry[CARRY.sum_f + j] += fb[j] * hh
        carry_n[CARRY_N.n_cov] += 1
        for j in range(3):
            carry[CARRY.sum_raw + j] += imu.dtheta[k, j]
        if carry_n[CARRY_N.n_cov] >= cov_step or (final and k == n - 1) or sampled.force[k]:
            r = _propagate(xs, carry, t[k], P, prm, lay, F, Q, wb, fb, out, r)
            carry[CARRY.t_cov] = t[k]
            for j in range(3):
                carry[CARRY.sum_w + j] = 0.0
                carry[CARRY.sum_f + j] = 0.0
            carry_n[CARRY_N.n_cov] = 0
            # the context of the sampled aids: this sample's rate, the raw mean rate since the last epoch
            dt_raw = t[k] - carry[CARRY.t_raw]
            for j in range(3):
                ctx[CTX.w_sample + j] = imu.dtheta[k, j] / (t[k] - t[k - 1]) - xs[NOM.gyro_bias + j]
                ctx[CTX.w_raw + j] = carry[CARRY.sum_raw + j] / dt_raw
            ctx[CTX.dt_raw] = dt_raw
            s = 0
            while s < n_slots:
                g = sampled.group[s]
                s0 = s
                nm = 0
                while s < n_slots and sampled.group[s] == g:
                    c0 = sampled.col[s]
                    if not math.isnan(sampled.z[k, c0]):
                        kinds[nm] = sampled.kind[s]
                        slot[nm] = s - s0
                        for i in range(WIDTH[kinds[nm]]):
                            zs[nm, i] = sampled.z[k, c0 + i]
                        nm += 1
                    s += 1
                if nm > 0:
                    src = N_AIDS + g
                    mm, ok, d = _update(kinds, nm, zs, rs, xs, ctx, P, prm, lay, acc_dx, blk,
                                        _forced(carry_n, lay, src), use)
                    _count(carry_n, src, ok)
                    # each model's own NIS at its slot position in the group
                    blk_slot[:] = np.nan
                    for i in range(nm):
                        blk_slot[slot[i]] = blk[i]
                    L = _log(out, L, t[k], k, -1 - g, mm, ok, d, blk_slot)
            for j in range(3):
                carry[CARRY.sum_raw + j] = 0.0
            carry[CARRY.t_raw] = t[k]
            if rec:
                _rec_post(out, r, t[k], P, xs, acc_dx)
            m = _record_cov(out, m, t[k], P)
        _copy1(out.xs[k], xs)
    return m, (r + 1 if rec else 0), L
