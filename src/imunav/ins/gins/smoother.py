"""Rauch–Tung–Striebel smoothing of the GNSS/INS feedback filter (from the records of
:func:`imunav.ins.gins.kernels.gins_run`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imunav.earth import ned_to_dlla
from imunav.ins.gins.result import SmoothedTrack
from imunav.rotation import quat_from_rotvec, quat_multiply, quat_normalize

Array = NDArray[np.float64]


def rts_smooth(t: Array, lla: Array, vel: Array, q: Array, rec_t: Array, phi: Array, ppri: Array, ppost: Array,
         inj: Array, state: Array) -> SmoothedTrack:
    """Rauch–Tung–Striebel backward pass over the error state of the feedback filter (Rauch, Tung & Striebel
    1965; Groves 2013, §3.4.2), then the smoothed corrections applied to the nominal trajectory.

    With the posterior error at every epoch reset to zero by the feedback, the smoothed error ``δs_r`` (true minus
    posterior nominal at r) obeys ``δs_r = A_r (δs_{r+1} + δx_inj,{r+1})``, ``A_r = P_r⁺ Φ_{r+1}ᵀ (P_{r+1}⁻)⁻¹``,
    ``P_r^s = P_r⁺ + A_r (P_{r+1}^s − P_{r+1}⁻) A_rᵀ``; between epochs the correction is interpolated in time
    from ``δs_r`` (after r) to ``δs_{r+1} + δx_inj,{r+1}`` (before the injection at r+1).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        IMU times, s.
    lla, vel, q : numpy.ndarray, shapes (N, 3), (N, 3), (N, 4)
        The forward filter's nominal trajectory (lat rad, lon rad, h m; NED m/s; ``q_nb``).
    rec_t : numpy.ndarray, shape (M,)
        Times of the covariance epochs, s.
    phi : numpy.ndarray, shape (M, n, n)
        Transition matrix into each epoch.
    ppri, ppost : numpy.ndarray, shape (M, n, n)
        Prior and posterior error covariance at each epoch.
    inj : numpy.ndarray, shape (M, n)
        Error state injected into the nominal state at each epoch.
    state : numpy.ndarray, shape (M, 10)
        Posterior nominal state at each epoch (lat, lon, h, v, q).

    Returns
    -------
    SmoothedTrack
        The smoothed trajectory and the navigation block of its covariance.
    """
    M, n = inj.shape
    ds = np.zeros((M, n))
    Ps = np.empty((M, 9, 9))
    Pn = ppost[M - 1].copy()
    Ps[M - 1] = Pn[:9, :9]
    for r in range(M - 2, -1, -1):
        A = np.linalg.solve(ppri[r + 1].T, (ppost[r] @ phi[r + 1].T).T).T
        ds[r] = A @ (ds[r + 1] + inj[r + 1])
        Pn = ppost[r] + A @ (Pn - ppri[r + 1]) @ A.T
        Ps[r] = Pn[:9, :9]
    before = ds + inj  # relative to the prior nominal at each epoch (before its injection)
    i = np.clip(np.searchsorted(rec_t, t, side="right") - 1, 0, M - 1)
    j = np.minimum(i + 1, M - 1)
    span = rec_t[j] - rec_t[i]
    w = np.where(span > 0, (t - rec_t[i]) / np.where(span > 0, span, 1.0), 0.0)[:, None]
    corr = (1 - w) * ds[i] + w * before[j]
    out_lla = lla + ned_to_dlla(corr[:, 0:3], lla)
    out_q = quat_multiply(quat_from_rotvec(corr[:, 6:9]), q)
    return SmoothedTrack(t, out_lla, vel + corr[:, 3:6], quat_normalize(out_q), rec_t.copy(), Ps)
