"""Numba kernels of the strapdown mechanization (private): angle / velocity increments with coning and sculling,
and the local-level and NED integrations.  Public, validated wrappers: :mod:`imunav.ins.strapdown`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from imunav._timeseries_kernels import interval_integrals
from imunav.filters._core import ATT_MID, ATT_START, strapdown_step_local, strapdown_step_ned

# --------------------------------------------------------------------------
# Small helpers
# --------------------------------------------------------------------------


@njit(cache=True)
def cross(a, b):
    """a × b of two 3-vectors."""
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True)
def increments(t, gyr, acc, corrected):
    """Angle and velocity increments over [t_{k-1}, t_k] for k = 1..N-1.

    Without ``corrected`` the rate of sample k is held over interval k (first
    order, the thesis / pyshoe convention); with ``corrected`` the point
    samples are integrated by the cubic through the interval's samples and one more on each side
    (:func:`imunav._timeseries_kernels.interval_integrals`: fourth order; the trapezoid's second order shrinks a
    2.6 Hz sinusoid sampled at 30 Hz by 2.5 %) and the two-sample coning and sculling corrections (Savage,
    *Strapdown Analytics* §7; Groves 2013 §5.5.4) use the previous interval:
    dth_k += dth_{k-1} x dth_k / 12,
    dv_k  += dth_k x dv_k / 2 + (dth_{k-1} x dv_k + dv_{k-1} x dth_k) / 12.
    Row 0 is zero.
    """
    n = t.shape[0]
    if corrected:
        dth = interval_integrals(t, gyr)
        dv = interval_integrals(t, acc)
    else:
        dth = np.zeros((n, 3))
        dv = np.zeros((n, 3))
        for k in range(1, n):
            h = t[k] - t[k - 1]
            for j in range(3):
                dth[k, j] = gyr[k, j] * h
                dv[k, j] = acc[k, j] * h
    if not corrected:
        return dth, dv
    out_th = dth.copy()
    out_v = dv.copy()
    for k in range(1, n):
        rot = cross(dth[k], dv[k])
        for j in range(3):
            out_v[k, j] += 0.5 * rot[j]
        if k >= 2:
            con = cross(dth[k - 1], dth[k])
            s1 = cross(dth[k - 1], dv[k])
            s2 = cross(dv[k - 1], dth[k])
            for j in range(3):
                out_th[k, j] += con[j] / 12.0
                out_v[k, j] += (s1[j] + s2[j]) / 12.0
    return out_th, out_v


# --------------------------------------------------------------------------
# Strapdown: local level (no Earth rate) and NED with Earth / transport rate, both on the core's step
# --------------------------------------------------------------------------


@njit(cache=True)
def strapdown_local_kernel(dth, dv, dt, q0, v0, p0, g, compensated):
    """Integrate increments in a fixed local-level NED frame (gravity (0,0,g)).

    Each row is :func:`imunav.filters._core.strapdown_step_local` with the velocity increment resolved at the
    start of the interval when ``dv`` already carries the rotation compensation (``compensated``), else at mid
    interval.
    """
    n = dth.shape[0]
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    p = np.empty((n, 3))
    q[0] = q0
    v[0] = v0
    p[0] = p0
    att = ATT_START if compensated else ATT_MID
    for k in range(1, n):
        strapdown_step_local(q[k - 1], v[k - 1], p[k - 1], dth[k], dv[k], dt[k], g, att, q[k], v[k], p[k])
    return q, v, p


@njit(cache=True)
def strapdown_ned_kernel(dth, dv, dt, q0, v0, lat0, lon0, h0, omega_e, compensated):
    """NED mechanization with Earth rate, transport rate and Coriolis: each row is
    :func:`imunav.filters._core.strapdown_step_ned` (Groves 2013 eq. 5.44 form)."""
    n = dth.shape[0]
    q = np.empty((n, 4))
    v = np.empty((n, 3))
    lla = np.empty((n, 3))
    q[0] = q0
    v[0] = v0
    lla[0, 0] = lat0
    lla[0, 1] = lon0
    lla[0, 2] = h0
    att = ATT_START if compensated else ATT_MID
    for k in range(1, n):
        strapdown_step_ned(q[k - 1], v[k - 1], lla[k - 1], dth[k], dv[k], dt[k], omega_e, att, q[k], v[k], lla[k])
    return q, v, lla
