"""The wheel contact point's velocity in the vehicle frame and its Jacobian, shared by the odometer and the NHC
(private).

In the IMU body frame the wheel contact point moves with ``u = Ĉ_nbᵀ v + ω × l`` (``l``: the contact point from the
IMU, body FRD, m, nominal state ``odo_lever``; ``ω``: the compensated rate of the current IMU sample, context
``w_sample``); in the vehicle frame with ``w = C_vb u`` (``C_vb``: the IMU's mounting, nominal ``q_vb``).  With the
global attitude error ``C_nb = exp([φ×]) Ĉ_nb``, the mounting error ``C_vb = exp([μ×]) Ĉ_vb`` and the lever-arm
error ``δl`` (Groves 2013, §16.3; Niu et al. 2007 and Chen et al. 2020 for the mounting)::

    ∂u/∂δv = Ĉ_nbᵀ,   ∂u/∂φ = Ĉ_nbᵀ [v×],   ∂u/∂δb_g = [l×],   ∂u/∂δs_g = [l×] diag(ω),   ∂u/∂δl = [ω×]
    ∂w/∂(·) = Ĉ_vb ∂u/∂(·),                  ∂w/∂μ = −[ŵ×]
"""

from __future__ import annotations

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._core_gins import cross3, write_skew
from imunav.ins.gins.layout import CTX, LAY, NOM


@njit(cache=True)
def wheel_velocity(xs, ctx, lay, Hw):
    """Wheel-point velocity in the vehicle frame (m/s) and its rows on the error state.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``; ``w_sample``).
    lay : int state layout (``LAY``).
    Hw : (3, nx) receives ``∂w/∂δx`` (must be zero on entry).

    Returns
    -------
    (3,) array, the wheel-point velocity in vehicle axes, m/s.
    """
    nx = Hw.shape[1]
    C = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    v = xs[NOM.vel:NOM.vel + 3]
    lever = xs[NOM.odo_lever:NOM.odo_lever + 3]
    wb = ctx[CTX.w_sample:CTX.w_sample + 3]
    u = C.T @ v
    cw = cross3(wb, lever)
    for i in range(3):  # + element by element (no array expression: issue 35, a first run)
        u[i] += cw[i]
    Hv = np.zeros((3, nx))
    iv = lay[LAY.vel]
    for i in range(3):
        for j in range(3):
            Hv[i, iv + j] = C[j, i]
    Vx = np.zeros((3, 3))
    write_skew(v, Vx, np.int64(0), np.int64(0), 1.0)
    CtV = C.T @ Vx
    Lx = np.zeros((3, 3))
    write_skew(lever, Lx, np.int64(0), np.int64(0), 1.0)
    ia = lay[LAY.att]
    ib = lay[LAY.gyro_bias]
    isg = lay[LAY.gyro_scale]
    il = lay[LAY.odo_lever]
    for i in range(3):
        for j in range(3):
            Hv[i, ia + j] = CtV[i, j]
            Hv[i, ib + j] = Lx[i, j]
            if isg >= 0:
                Hv[i, isg + j] = Lx[i, j] * wb[j]
    if il >= 0:
        write_skew(wb, Hv, np.int64(0), il, 1.0)
    Cvb = dcm_from_quat_1(xs[NOM.q_vb:NOM.q_vb + 4])
    w = Cvb @ u
    CH = Cvb @ Hv
    for i in range(Hw.shape[0]):  # element by element: a slice assignment compiles numba's shape-error message
        for j in range(Hw.shape[1]):
            Hw[i, j] = CH[i, j]
    im = lay[LAY.mount]
    if im >= 0:
        write_skew(w, Hw, np.int64(0), im, -1.0)
    return w


@njit(cache=True)
def vehicle_rate(xs, ctx):
    """The compensated rate of the current IMU sample in the vehicle frame ``C_vb ω`` (rad/s; its z: the vehicle's
    yaw rate) and ``Ĉ_vb``."""
    Cvb = dcm_from_quat_1(xs[NOM.q_vb:NOM.q_vb + 4])
    wv = np.zeros(3)
    for i in range(3):
        for j in range(3):
            wv[i] += Cvb[i, j] * ctx[CTX.w_sample + j]
    return wv, Cvb


@njit(cache=True)
def add_yaw_rate_rows(a, wv, Cvb, ctx, lay, H, row):
    """``H[row] += a ∂ω_z/∂δx`` for the vehicle's yaw rate ``ω_z = (C_vb ω)_z`` (``wv``, ``Cvb``: from
    :func:`vehicle_rate`): through the gyro's bias and scale (``∂ω/∂δb_g = −1``, ``∂ω/∂δs_g = −diag ω``) and the
    mounting (``∂(C_vb ω)/∂μ = −[(Ĉ_vb ω)×]``)."""
    ib, isg, im = lay[LAY.gyro_bias], lay[LAY.gyro_scale], lay[LAY.mount]
    for j in range(3):
        H[row, ib + j] -= a * Cvb[2, j]
        if isg >= 0:
            H[row, isg + j] -= a * Cvb[2, j] * ctx[CTX.w_sample + j]
    if im >= 0:
        H[row, im] += a * wv[1]
        H[row, im + 1] -= a * wv[0]
