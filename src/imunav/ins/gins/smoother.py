"""Rauch–Tung–Striebel smoothing of the GNSS/INS feedback filter (from the records of
:func:`imunav.ins.gins.kernels.gins_run`), and the forward–backward separation that measures, without a truth,
whether the forward filter's σ held (:func:`forward_backward_separation`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.earth import dlla_to_ned, ned_to_dlla
from imunav.errors import InvalidInputError
from imunav.ins.gins.result import GinsResult, SmoothedTrack
from imunav.results import Result
from imunav.rotation import quat_from_rotvec, quat_multiply, quat_normalize

Array = NDArray[np.float64]

#: Epochs whose smoother gains are solved in one stacked call (:func:`rts_smooth`).
_GAIN_BLOCK = 256


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
    # the gains A_r need no recursion: a block of epochs at a time, one stacked product and one stacked solve (the
    # same BLAS / LAPACK call per epoch as one by one, so the same numbers; numpy's overhead once per block: 1.5 s
    # of a one-hour log's 34,000 epochs)
    for hi in range(M - 1, 0, -_GAIN_BLOCK):
        lo = max(hi - _GAIN_BLOCK, 0)  # epochs lo .. hi - 1
        rhs = (ppost[lo:hi] @ phi[lo + 1:hi + 1].transpose(0, 2, 1)).transpose(0, 2, 1)
        gains = np.linalg.solve(ppri[lo + 1:hi + 1].transpose(0, 2, 1), rhs).transpose(0, 2, 1)
        for r in range(hi - 1, lo - 1, -1):
            A = gains[r - lo]
            ds[r] = A @ (ds[r + 1] + inj[r + 1])
            Pn = ppost[r] + A @ (Pn - ppri[r + 1]) @ A.T
            Ps[r] = Pn[:9, :9]
    # only the navigation block (position, velocity, attitude: the error state's first 9 entries) is applied to the
    # trajectory: interpolating it alone writes 9 of the n columns per IMU sample (a one-hour log at 200 Hz with 37
    # states: 0.2 GB of temporaries instead of 1 GB), each element the same sum as over all of them
    nav = ds[:, :9]
    before = nav + inj[:, :9]  # relative to the prior nominal at each epoch (before its injection)
    i = np.clip(np.searchsorted(rec_t, t, side="right") - 1, 0, M - 1)
    j = np.minimum(i + 1, M - 1)
    span = rec_t[j] - rec_t[i]
    w = np.where(span > 0, (t - rec_t[i]) / np.where(span > 0, span, 1.0), 0.0)[:, None]
    corr = (1 - w) * nav[i] + w * before[j]
    out_lla = lla + ned_to_dlla(corr[:, 0:3], lla)
    out_q = quat_multiply(quat_from_rotvec(corr[:, 6:9]), q)
    return SmoothedTrack(t, out_lla, vel + corr[:, 3:6], quat_normalize(out_q), rec_t.copy(), Ps)


@dataclass(frozen=True)
class Separation(Result):
    """How far the forward filter and the RTS smoother part, epoch by epoch: a quality figure that needs no truth.

    For the RTS smoother the smoothed error is uncorrelated with everything the data determine, so the difference
    between the forward and the smoothed estimates has the covariance ``P_f − P_s`` (Rauch, Tung & Striebel
    1965; Gelb 1974, §5.4): the normalised separation ``d² = Δᵀ (P_f − P_s)⁻¹ Δ`` of the horizontal position is
    χ²(2) at each epoch when the filter's model holds, larger when the forward filter was confident and wrong.

    Attributes
    ----------
    t : numpy.ndarray, shape (M,)
        The covariance epochs, s.
    horizontal_m : numpy.ndarray, shape (M,)
        Horizontal distance between the forward and the smoothed positions, m.
    d2 : numpy.ndarray, shape (M,)
        The normalised separation of the horizontal position (2 dof); NaN where ``P_f − P_s`` is not positive
        definite (the epochs where the smoother adds nothing: the last one, rounding).
    sigma_m : numpy.ndarray, shape (M,)
        ``√tr(P_f − P_s)`` of the horizontal position: the separation's expected size, m.
    """

    t: Array
    horizontal_m: Array
    d2: Array
    sigma_m: Array

    def summary(self) -> dict[str, Any]:
        """RMS and largest separation, m, and the mean of ``d²`` with its χ² band.

        Returns
        -------
        dict
            ``rms_m``, ``max_m``, ``mean_d2`` (2 for a consistent filter; null without a usable epoch), ``dof``
            (2) and ``epochs``.
        """
        ok = np.isfinite(self.d2)
        return {"rms_m": float(np.sqrt(np.mean(self.horizontal_m**2))) if self.t.size else None,
                "max_m": float(np.max(self.horizontal_m)) if self.t.size else None,
                "mean_d2": float(np.mean(self.d2[ok])) if ok.any() else None, "dof": 2, "epochs": int(ok.sum())}


def common_epochs(a: Array, b: Array) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Indices ``(i, j)`` with ``a[i] == b[j]`` (to 1 ns): the covariance epochs that the forward filter's records
    ``a`` and the smoother's ``b`` share.

    Parameters
    ----------
    a, b : numpy.ndarray, shape (M,) and (L,)
        Increasing epoch times, s.

    Returns
    -------
    i, j : numpy.ndarray of int
        The matching indices into ``a`` and ``b``.
    """
    i = np.clip(np.searchsorted(a, b), 0, a.size - 1)
    same = np.abs(a[i] - b) < 1e-9
    return i[same], np.flatnonzero(same)


def forward_backward_separation(res: GinsResult) -> Separation:
    """The separation of a run's forward filter and its smoother (:class:`Separation`) at the covariance epochs.

    Parameters
    ----------
    res : GinsResult
        A run with ``smoothed`` (``GinsFilter.run(..., smoother=True)``).

    Returns
    -------
    Separation
        At the epochs common to the forward covariance records and the smoother's.

    Raises
    ------
    InvalidInputError
        If the run has no smoothed track.
    """
    s = res.smoothed
    if s is None:
        raise InvalidInputError("forward_backward_separation needs a run with the smoother (smoother=True)")
    k, js = common_epochs(res.cov_t, s.cov_t)
    i = np.clip(np.searchsorted(res.t, s.cov_t[js]), 0, res.t.size - 1)
    ref = res.lla[i]
    delta = dlla_to_ned(s.lla[i] - ref, ref)[:, :2]  # smoothed − forward, N E m
    D = res.cov_nav[k, :2, :2] - s.cov_nav[js, :2, :2]
    det = D[:, 0, 0] * D[:, 1, 1] - D[:, 0, 1] * D[:, 1, 0]
    pos = (D[:, 0, 0] > 0) & (det > 1e-12 * np.maximum(D[:, 0, 0] * D[:, 1, 1], 1e-30))
    d2 = np.full(js.size, np.nan)
    a, b, c = D[pos, 0, 0], D[pos, 0, 1], D[pos, 1, 1]
    x, y = delta[pos, 0], delta[pos, 1]
    d2[pos] = (c * x * x - 2 * b * x * y + a * y * y) / det[pos]
    return Separation(s.cov_t[js], np.hypot(delta[:, 0], delta[:, 1]), d2,
                      np.sqrt(np.maximum(D[:, 0, 0] + D[:, 1, 1], 0.0)))
