"""What a first pass of the filter tells of the aids' own errors: the memory of their residuals.

A filter that takes an aid's errors as white trusts each measurement as new information.  Real aids remember:
a receiver's multipath and atmosphere move its fixes by metres over tens of seconds, and a wheel's effective
radius changes with the ground, the tyre's warmth and the slip.  A first pass of the filter with those errors
taken as white leaves residuals that keep their memory; their autocovariance at a lag beyond the white part's
gives the correlated part's variance (Brown & Hwang 2012, §2.9; the covariance matching of Mehra 1972 on the
residuals rather than the innovations).  :func:`imunav.ins.gins.logrun.run_log` runs that first pass on every
log with GNSS and gives the second its findings:

* :func:`gnss_correlated_std`: the σ of the fixes' Gauss–Markov error (``GinsConfig.gnss_bias_std``);
* :func:`withheld_score`: how well a run predicts fixes withheld from it (a cross-validation of a process model
  on the log's own fixes, where the residuals cannot show it: a wandering odometer scale, which the fixes follow).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.earth import lla_to_ned
from imunav.ins.gins.result import GinsResult
from imunav.rotation import dcm_from_quat

__all__ = ["GNSS_BIAS_MIN_STD", "GNSS_BIAS_SCATTER_FACTOR", "GNSS_BIAS_TAU", "GNSS_CORR_LAG_S", "MEAN_KEPT_MIN", "SCORE_CLIP", "WITHHELD_GAP_S",
           "WITHHELD_S", "fix_residuals", "gnss_correlated_std",
           "withheld_score", "withheld_windows"]

Array = NDArray[np.float64]

#: Correlation time of the fixes' correlated error (s; multipath and atmosphere: 10-100 s, Groves 2013 §9.4.2) and
#: the smallest σ its identification gives (m).
GNSS_BIAS_TAU = 60.0
GNSS_BIAS_MIN_STD = 0.1
#: Lag of the residuals' autocovariance (s) and the factor on the σ it gives, for what of the correlated error the
#: first pass followed (:func:`gnss_correlated_std`; chosen on the hard robot and car drives 100-107).
GNSS_CORR_LAG_S = 2.0
GNSS_BIAS_SCATTER_FACTOR = 2.0
#: Smallest share of the correlated error's variance that :func:`gnss_correlated_std` takes its residuals about
#: their mean to keep (a log of a few correlation times or less keeps almost none of it).
MEAN_KEPT_MIN = 0.1
#: Cross-validation of a process model on the fixes (:func:`withheld_windows`): each window withholds the fixes
#: of this many seconds, then this many seconds of fixes follow.
WITHHELD_S = 30.0
WITHHELD_GAP_S = 60.0
#: Largest squared normalised error one withheld fix adds to the score (a 5σ error per axis).
SCORE_CLIP = 25.0


def _significant(c: Array, c0: Array, n: int) -> Array:
    """``c`` where it exceeds two standard errors of an autocovariance of white residuals (``2 c0 / √n``), else 0."""
    return np.where(c > 2.0 * c0 / math.sqrt(max(n, 1)), c, 0.0)


def _lag_pairs(t: Array, lag: float) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Index pairs ``(k, j)`` with ``t[j] − t[k]`` within half a lag of ``lag`` (``t`` increasing)."""
    j = np.searchsorted(t, t + lag)
    pair = j < t.size
    k, j = np.flatnonzero(pair), j[pair]
    near = np.abs(t[j] - t[k] - lag) < 0.5 * lag
    return k[near], j[near]


def fix_residuals(res: GinsResult, gnss: Any, mask: Any, lever_arm: Any) -> Array:
    """The fixes less the run's antenna position when each was taken: ``z_k − (r̂(t_k − τ̂) + Ĉ_nb(t_k − τ̂) l)``,
    NED about the first fix, m (``τ̂`` the run's last latency estimate; Groves 2013, §14.3.1).

    Parameters
    ----------
    res : GinsResult
        The run.
    gnss : GnssData
        The fixes.
    mask : array_like of bool, shape (G,)
        Which fixes.
    lever_arm : array_like, shape (3,)
        The antenna from the IMU, body FRD, m.

    Returns
    -------
    numpy.ndarray, shape (K, 3)
        The residuals of the selected fixes, north, east, down, m.
    """
    ok = np.asarray(mask, dtype=bool)
    tau = float(res.gnss_delay[-1]) if res.gnss_delay is not None else 0.0
    i = np.clip(np.searchsorted(res.t, gnss.t[ok] - tau), 0, res.t.size - 1)
    ant = np.einsum("nij,j->ni", dcm_from_quat(res.q_nb[i]), np.asarray(lever_arm, dtype=float))
    return lla_to_ned(gnss.lla[ok], gnss.lla[0]) - lla_to_ned(res.lla[i], gnss.lla[0]) - ant


def withheld_windows(t: Array, start: float, length: float = WITHHELD_S, gap: float = WITHHELD_GAP_S) -> NDArray[np.bool_]:
    """Which fixes a cross-validation withholds: windows of ``length`` s from ``start`` on, ``gap`` s of fixes
    between them.

    Parameters
    ----------
    t : numpy.ndarray, shape (G,)
        Times of the fixes, s.
    start : float
        Start of the first window, s.
    length, gap : float
        Window length and the fixes kept between windows, s.

    Returns
    -------
    numpy.ndarray of bool, shape (G,)
        True for a withheld fix.
    """
    u = (np.asarray(t, dtype=float) - start) % (length + gap)
    return (t >= start) & (u < length)


def withheld_score(res: GinsResult) -> float:
    """The log score of a run at the fixes it predicted without using them (``GinsFilter.run(gnss_withheld=…)``):
    the mean over them of ``ln det S + νᵀ S⁻¹ ν``, with ``ν`` the position innovation and ``S = H P Hᵀ + R`` its
    covariance as the filter computes them for a fix it applies (its estimate of the fixes' correlated error, the
    latency and the adaptive factor of ``R`` included).  That is twice the negative log predictive density up to a
    constant, a proper scoring rule (Gneiting & Raftery 2007): smaller is better, and it punishes a σ too small as
    much as an error too large.  The filter's own ``S`` carries the covariance between its position and its
    correlated-error estimate that the last fixes before a window leave, which a score adding the fixes'
    correlated variance to the position's would ignore.  Each NIS is cut at
    :data:`SCORE_CLIP` per degree of freedom (a fix that jumped tens of metres, which the gate would have
    rejected, must not decide the choice: the cut is Huber's robust loss in its simplest form).

    Parameters
    ----------
    res : GinsResult
        A run with withheld fixes (its ``aids['gnss_position_withheld']``).

    Returns
    -------
    float
        The mean score (NaN without withheld fixes inside the run).
    """
    rec = res.aids.get("gnss_position_withheld")
    if rec is None or rec.t.size == 0 or rec.logdet is None:
        return float("nan")
    return float(np.mean(rec.logdet + np.minimum(rec.nis, SCORE_CLIP * rec.dof)))


def gnss_correlated_std(first: GinsResult, gnss: Any, lever_arm: Any) -> Array:
    """σ north, east, down of the fixes' correlated error, from the residuals of a first pass that treats them as
    white: ``k √(max(0, C(L)) / (e^{−L/T} − v(W)))`` per axis, where ``C(L)`` is the residuals' autocovariance at
    the lag ``L`` (:data:`GNSS_CORR_LAG_S`, at least two fix intervals) about their mean over the ``W`` seconds
    they span, ``T`` = :data:`GNSS_BIAS_TAU`, ``v(W) = 2 (T/W) (1 − (T/W)(1 − e^{−W/T}))`` the variance of that
    mean over σ_c² (the mean taken out holds part of the slow error: without it a 4-minute drive reads its
    correlated error 20 % low, a one-minute one 50 %; the denominator is kept above :data:`MEAN_KEPT_MIN`) and
    ``k`` = :data:`GNSS_BIAS_SCATTER_FACTOR`; an autocorrelation within two standard errors of zero (``2 / √n``)
    counts as none; at least :data:`GNSS_BIAS_MIN_STD`.  The fixes before the first pass settles (its horizontal position σ
    within twice its median over the drive) are left out: their residuals hold the initial error.

    White fixes leave residuals without memory: a first-order Gauss–Markov error of σ_c and correlation time T
    leaves ``C(L) ≈ σ_c² e^{−L/T}`` (Brown & Hwang 2012, §2.9), less the variance of the mean taken out (the
    bias of a sample autocovariance, Priestley 1981, §5.3.2) and less what the first pass followed (hence
    ``k``).  The residual of fix k is ``z_k − (r̂(t_k − τ̂) + Ĉ l)`` on the accepted fixes, those beyond five
    median absolute deviations of their axis left out.

    Parameters
    ----------
    first : GinsResult
        The first pass (adaptive GNSS noise on, no ``gnss_bias`` state).
    gnss : GnssData
        The fixes it used.
    lever_arm : array_like, shape (3,)
        The antenna from the IMU, body FRD, m (the first pass's ``lever_arm``).

    Returns
    -------
    numpy.ndarray, shape (3,)
        σ north, east, down, m.
    """
    rec = first.aids.get("gnss_position")
    ok = np.ones(gnss.n, dtype=bool)
    if rec is not None and rec.t.size == gnss.n:
        ok = np.asarray(rec.accepted, dtype=bool)
    # the first pass's start (its position σ above twice the drive's median) holds its own transient, not the fixes'
    sd = np.sqrt(first.cov_diag[:, 0] + first.cov_diag[:, 1])
    settled = first.cov_t[int(np.argmax(sd <= 2.0 * np.median(sd)))]
    ok &= gnss.t >= settled
    t = gnss.t[ok]
    r = fix_residuals(first, gnss, ok, lever_arm)
    dev = np.abs(r - np.median(r, axis=0))
    keep = np.all(dev <= 5.0 * 1.4826 * np.maximum(np.median(dev, axis=0), 1e-6), axis=1)
    t, r = t[keep], r[keep] - r[keep].mean(axis=0)
    if t.size < 10:
        return np.full(3, GNSS_BIAS_MIN_STD)
    lag = max(GNSS_CORR_LAG_S, 2.0 * float(np.median(np.diff(t))))
    k, j = _lag_pairs(t, lag)
    if k.size < 10:
        return np.full(3, GNSS_BIAS_MIN_STD)
    c0 = np.mean(r**2, axis=0)
    c = _significant(np.mean(r[k] * r[j], axis=0), c0, k.size)
    # the residuals' own mean, taken out over the W seconds they span, holds part of the slow error: the sample
    # autocovariance lacks the variance of that mean, 2 σ_c² (T/W) (1 − (T/W)(1 − e^{−W/T}))
    w = max(float(t[-1] - t[0]), lag) / GNSS_BIAS_TAU
    kept = max(math.exp(-lag / GNSS_BIAS_TAU) - 2.0 / w * (1.0 - (1.0 - math.exp(-w)) / w), MEAN_KEPT_MIN)
    return np.maximum(GNSS_BIAS_SCATTER_FACTOR * np.sqrt(c / kept), GNSS_BIAS_MIN_STD)
