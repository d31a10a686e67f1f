"""GNSS velocity aid: a receiver's NED velocity at its own time stamp, with the antenna lever arm.

The antenna moves with ``v_ant = v + C (ω_eb × l)``, ``ω_eb = ω_ib − Cᵀ ω_ie`` (body rate relative to the Earth;
``ω_ib``: the compensated mean rate of the last covariance interval, context ``w_mean``).  With the global
attitude error and the gyro bias and scale errors (``δω = −δb_g − diag(ω) δs_g`` on the rate), the innovation and
rows are (Groves 2013, §14.3.1, eq. 14.125 in this sign convention)::

    a = Ĉ (ω̂_eb × l),   ν = v_f − v̂ − a
    H = [ 0  I  −[a×]  Ĉ[l×]  0  Ĉ[l×] diag(ω̂)  0 … ],   R = the fix's velocity covariance ((m/s)²).

Measurement ``z``: v_N, v_E, v_D (m/s); ``r``: 3×3 covariance.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.earth import OMEGA_E
from imunav.filters._core_gins import cross3, write_skew
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import CTX, LAY, NOM

NAME = "gnss_velocity"
ROWS = 3
WIDTH = 3
#: own parameters: the antenna lever arm, body FRD, m
PARAMS, N_PARAMS = named_layout("GnssVelocityParams", (("lever", 3),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``lever_arm``, m).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    p = np.zeros(N_PARAMS)
    p[PARAMS.lever:PARAMS.lever + 3] = config.lever_arm
    return p


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the innovation, Jacobian rows and covariance of one velocity fix into rows ``row .. row + 2``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``): ``w_mean`` is the body rate.
    z : (3,) NED velocity, m/s.
    r : (3, 3) its covariance, (m/s)².
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    C = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    lat = xs[NOM.lla]
    lever = p[PARAMS.lever:PARAMS.lever + 3]
    wb = ctx[CTX.w_mean:CTX.w_mean + 3]
    w_ie_b = C.T @ np.array([OMEGA_E * math.cos(lat), 0.0, -OMEGA_E * math.sin(lat)])
    a = C @ cross3(wb - w_ie_b, lever)
    iv = lay[LAY.vel]
    for j in range(3):
        nu[row + j] = z[j] - xs[NOM.vel + j] - a[j]
        H[row + j, iv + j] = 1.0
        for i in range(3):
            R[row + j, row + i] = r[j, i]
    write_skew(a, H, row, lay[LAY.att], -1.0)
    Lx = np.zeros((3, 3))
    write_skew(lever, Lx, np.int64(0), np.int64(0), 1.0)
    CL = C @ Lx
    ib = lay[LAY.gyro_bias]
    isg = lay[LAY.gyro_scale]
    for i in range(3):
        for j in range(3):
            H[row + i, ib + j] = CL[i, j]
            if isg >= 0:
                H[row + i, isg + j] = CL[i, j] * wb[j]
