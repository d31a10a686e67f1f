"""GNSS position aid: a receiver's geodetic fix at its own time stamp, with the antenna lever arm.

The antenna sits at ``l`` (body FRD, m) from the IMU: ``r_ant = r + C l``.  With the NED position error δr and
the global attitude error φ (``C = exp([φ×]) Ĉ``, so ``C l ≈ Ĉ l + φ × Ĉ l = Ĉ l − [Ĉl ×] φ``), the innovation in
metres along N, E, D is (Groves 2013, §14.3.1, eq. 14.124 in this sign convention)::

    ν = ( (φ_f − φ̂)(R_N + ĥ),  (λ_f − λ̂)(R_E + ĥ) cos φ̂,  −(h_f − ĥ) ) − Ĉ l + v̂ τ̂
    H = [ I  −τ̂ I  −[Ĉl ×]  0 …  −v̂ (on δτ) ],     R = the fix's NED position covariance (m²).

``b`` is the fixes' error correlated in time (multipath, atmosphere; Groves 2013, §9.4.2 and §14.3.1): a fix is
``r_ant + b + w`` with ``w`` white; with the ``gnss_bias`` block the innovation also takes out the estimate ``b̂``
and ``H`` has ``I`` on ``δb``.  ``R`` is the reported covariance times the adaptive factor the kernel keeps
(nominal ``gnss_r_scale``, 1 without adaptation).

``τ`` is the receiver's latency: a fix stamped ``t`` holds the position of ``t − τ``, ``r(t − τ) ≈ r(t) − v τ``
(first order in τ, the velocity of the antenna taken as the IMU's; nominal state ``gnss_delay``, a state when the
error state has the ``gnss_delay`` block).

Measurement ``z``: latitude (rad), longitude (rad), ellipsoidal height (m); ``r``: 3×3 covariance, m².
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.earth import radii_gravity_1
from imunav.filters._core_gins import write_skew
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "gnss_position"
#: rows of the update, and columns of ``z``
ROWS = 3
WIDTH = 3
#: own parameters: the antenna lever arm, body FRD, m
PARAMS, N_PARAMS = named_layout("GnssPositionParams", (("lever", 3),))


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
    """Write the innovation, Jacobian rows and covariance of one fix into rows ``row .. row + 2``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``; not used).
    z : (3,) fix: lat rad, lon rad, h m.
    r : (3, 3) its NED covariance, m².
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H : (m, nx) Jacobian, rows written (the other columns must be zero).
    R : (m, m) measurement covariance, block written.
    nu : (m,) innovation, written.
    row : int, first row.
    """
    lla = xs[NOM.lla:NOM.lla + 3]
    C = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    la = C @ p[PARAMS.lever:PARAMS.lever + 3]
    RN, RE, _ = radii_gravity_1(lla[0], lla[2])
    nu[row] = (z[0] - lla[0]) * (RN + lla[2]) - la[0]
    nu[row + 1] = (z[1] - lla[1]) * (RE + lla[2]) * math.cos(lla[0]) - la[1]
    nu[row + 2] = -(z[2] - lla[2]) - la[2]
    ib = lay[LAY.gnss_bias]
    if ib >= 0:
        for j in range(3):
            nu[row + j] -= xs[NOM.gnss_bias + j]
            H[row + j, ib + j] = 1.0
    sc = xs[NOM.gnss_r_scale]
    tau = xs[NOM.gnss_delay]
    idl = lay[LAY.gnss_delay]
    iv = lay[LAY.vel]
    if tau != 0.0 or idl >= 0:
        for j in range(3):
            nu[row + j] += xs[NOM.vel + j] * tau
            H[row + j, iv + j] = -tau
            if idl >= 0:
                H[row + j, idl] = -xs[NOM.vel + j]
    ip = lay[LAY.pos]
    for j in range(3):
        H[row + j, ip + j] = 1.0
        for i in range(3):
            R[row + j, row + i] = sc * r[j, i]
    write_skew(la, H, row, lay[LAY.att], -1.0)
