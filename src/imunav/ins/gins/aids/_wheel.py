"""The wheel contact point's body velocity and its Jacobian, shared by the odometer and the NHC (private).

``v_w = Ĉᵀ v + ω × l`` (``l``: wheel contact point from the IMU, body FRD, m; ``ω``: the compensated rate of the
current IMU sample, context ``w_sample``).  With ``C = exp([φ×]) Ĉ``: ``∂v_w/∂δv = Ĉᵀ``, ``∂v_w/∂φ = Ĉᵀ [v×]``,
``∂v_w/∂δb_g = [l×]``, ``∂v_w/∂δs_g = [l×] diag(ω)`` (Groves 2013, §16.3).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._core_gins import cross3, write_skew
from imunav.ins.gins.layout import CTX, LAY, NOM


@njit(cache=True)
def wheel_velocity(xs, ctx, lever, lay, Hv):
    """Wheel-point body velocity (m/s) and its rows on the error state.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``; ``w_sample``).
    lever : (3,) wheel contact point, body FRD, m.
    lay : int state layout (``LAY``).
    Hv : (3, nx) receives ``∂v_w/∂δx`` (must be zero on entry).

    Returns
    -------
    (3,) array, the wheel-point velocity in body axes, m/s.
    """
    C = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    v = xs[NOM.vel:NOM.vel + 3]
    wb = ctx[CTX.w_sample:CTX.w_sample + 3]
    vw = C.T @ v + cross3(wb, lever)
    iv = lay[LAY.vel]
    for i in range(3):
        for j in range(3):
            Hv[i, iv + j] = C[j, i]
    Vx = np.zeros((3, 3))
    write_skew(v, Vx, 0, 0, 1.0)
    CtV = C.T @ Vx
    Lx = np.zeros((3, 3))
    write_skew(lever, Lx, 0, 0, 1.0)
    ia = lay[LAY.att]
    ib = lay[LAY.gyro_bias]
    isg = lay[LAY.gyro_scale]
    for i in range(3):
        for j in range(3):
            Hv[i, ia + j] = CtV[i, j]
            Hv[i, ib + j] = Lx[i, j]
            if isg >= 0:
                Hv[i, isg + j] = Lx[i, j] * wb[j]
    return vw
