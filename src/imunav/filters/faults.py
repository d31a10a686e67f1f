"""Innovation-based fault detection, isolation and fault injection.

For a consistent filter the normalised innovations ``ν̃(k) = S^{-1/2} ν(k)``
are white N(0, I) (Mehra & Peschon 1971).  Faults (bias, drift, noise
increase, stuck output, outliers) change their mean or covariance.  The
detectors here run over a whole sequence ``ν̃`` of shape (N, s):

* **Alg. 1 / Alg. 2** of Akgün (2002, eq. 4.22; Hajiyev 1994): sliding window
  of length M, ``A = Σ (ν̃ − ν̄)(ν̃ − ν̄)ᵀ`` (mean removed, so A ~ W_s(I, M−1)),
  ``λ = Lᵀ P⁻¹ L / Lᵀ A⁻¹ L``.  Alg. 1 maximises over L (λ = largest
  eigenvalue of ``A P⁻¹``), Alg. 2 uses the all-ones L.
* **Alg. 3**: windowed ``Σ ν̃ᵀ ν̃`` ~ χ²(M s).
* **NIS**: ``ν̃ᵀ ν̃`` ~ χ²(s) each step.
* **CUSUM** (Page 1954): variance CUSUM with the log-likelihood ratio of
  N(0, ρI) against N(0, I) and a two-sided per-channel mean CUSUM.
* **Low variance** (stuck output, not in the thesis): the smallest
  per-channel windowed sum of squared first differences
  ``Σ (ν̃_{i,j} − ν̃_{i,j−1})²`` over a short window (5 differences) falls
  below its lower quantile.  A frozen sensor removes its own noise from the
  innovation, which the variance-increase tests cannot see; differencing
  removes the constant offset the frozen noise sample leaves behind.

Thresholds (those of Akgün 2002, §4.4, 5.3.3 and 6.2d, are wrong; the table says why):

=========  =============================  =======================================
detector   thesis threshold (α = 0.05)    calibrated (per-step false-alarm rate p)
=========  =============================  =======================================
Alg. 1     χ²_{0.95}(M − s + 1) = 28.87   (1−p) quantile of the largest eigenvalue of
                                          W_s(I, M − 1) (Roy's largest root, seeded
                                          Monte Carlo); the χ² law holds only for a
                                          fixed L, and 28.87 gives ≈ 43 % alarms
Alg. 2     χ²_{0.95}(M − s + 1) = 28.87   χ²_{1−p}(M − s) exactly (mean removed)
Alg. 3     χ²_{0.95}(M s) = 79.08         χ²_{1−p}(M s)
NIS        —                              χ²_{1−p}(s)
CUSUM      —                              (1−p) quantile of the stationary H0
                                          distribution (seeded Monte Carlo)
low var.   —                              p quantile (lower tail) of the min over s
                                          channels, seeded Monte Carlo under H0
=========  =============================  =======================================

Because the windows overlap, the per-step false-alarm rate of a detector at
its (1−p) threshold is p, but a run of many steps almost surely has some
alarm; the rates are reported per step and per run by :func:`false_alarm_rates`.
Once a detector fires its alarm is latched (a bias is absorbed by the filter
within ~100 steps and the statistics fall back under the threshold).
Channel isolation uses per-channel windowed χ²(M) sums and mean tests.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._quantiles import chi2_isf, chi2_ppf, norm_isf
from imunav.errors import InvalidInputError, ShapeError
from imunav.filters._batch import window_stats_batch
from imunav.filters._kernels import cusum_stats
from imunav.results import Result

__all__ = [
    "DETECTORS",
    "window_chi2_thresholds",
    "calibrated_thresholds",
    "wishart_largest_root_quantile",
    "window_statistics",
    "cusum_statistics",
    "FaultDetectorResult",
    "FaultDetectionResult",
    "detect_faults",
    "latch",
    "first_alarm",
    "detector_statistics",
    "alarms",
    "LOWER_TAIL",
    "isolate_faulty_channels",
    "Fault",
    "inject_faults",
    "false_alarm_rates",
    "detection_delays",
]

Array = NDArray[np.float64]
DETECTORS = ("alg1", "alg2", "alg3", "nis", "cusum_var", "cusum_mean", "low_variance")
LOWER_TAIL = frozenset({"low_variance"})  # detectors that alarm when the statistic falls *below* the threshold


def _check_nv(normalized: ArrayLike, batch: bool = False) -> Array:
    nv = np.asarray(normalized, dtype=np.float64)
    if nv.ndim == 1:
        nv = nv[:, None]
    if nv.ndim != 2 and not (batch and nv.ndim == 3):
        raise ShapeError(f"normalised innovations must be (N, s), got {np.shape(normalized)}")
    bad = ~np.isfinite(nv)
    if bad.any():
        r, c = np.argwhere(bad)[0][-2:]
        raise InvalidInputError(f"normalised innovations have NaN/inf at row {r}, column {c}; "
                                "pass only steps with a measurement")
    return np.ascontiguousarray(nv)


def _check_window(M: int, s: int, N: int | None = None) -> None:
    if M <= s:
        raise InvalidInputError(f"window M = {M} must exceed the measurement size s = {s} (A must be invertible)")
    if N is not None and N < M:
        raise InvalidInputError(f"need at least M = {M} innovations, got {N}")


def _check_level(name: str, value: float, upper: float, M: int, s: int) -> None:
    """``0 < value < upper`` (a quantile or false-alarm rate) and a window ``M > s``."""
    if not 0 < value < upper:
        raise InvalidInputError(f"{name} must be in (0, {upper:g}), got {value}")
    _check_window(M, s)


def window_chi2_thresholds(M: int = 20, s: int = 3, confidence: float = 0.95) -> dict[str, float]:
    """Nominal χ² thresholds of the window tests: χ²(M−s+1) for Alg. 1/2, χ²(Ms) for Alg. 3.

    The degrees of freedom a window of ``M`` steps of size-``s`` measurements suggests, as the source of the
    algorithms sets them; kept for comparison: the module docstring says why they are wrong.

    Parameters
    ----------
    M : int, optional
        Window length in steps.
    s : int, optional
        Measurement size.
    confidence : float, optional
        Confidence level of the χ² points (default 0.95).

    Returns
    -------
    dict of str to float
        Thresholds of ``"alg1"``, ``"alg2"`` and ``"alg3"``.

    References
    ----------
    O. Akgün, *Integration of an air data system and a Doppler radar via Kalman filtering*, MSc thesis, Istanbul
    Technical University, 2002, §4.4.
    """
    return {
        "alg1": float(chi2_ppf(confidence, M - s + 1)),
        "alg2": float(chi2_ppf(confidence, M - s + 1)),
        "alg3": float(chi2_ppf(confidence, M * s)),
    }


@lru_cache(maxsize=32)
def _largest_root_samples(M: int, s: int, n_mc: int, seed: int) -> Array:
    rng = np.random.default_rng(seed)
    out = np.empty(n_mc)
    chunk = 50_000
    for i in range(0, n_mc, chunk):
        k = min(chunk, n_mc - i)
        X = rng.standard_normal((k, M, s))
        X -= X.mean(axis=1, keepdims=True)
        A = np.einsum("kji,kjl->kil", X, X)
        out[i:i + k] = np.linalg.eigvalsh(A)[:, -1]
    out.sort()
    return out


def wishart_largest_root_quantile(q: float, M: int = 20, s: int = 3, n_mc: int = 100_000, seed: int = 0) -> float:
    """q-quantile of the largest eigenvalue of ``Σ (ν̃ − ν̄)(ν̃ − ν̄)ᵀ`` over M white N(0, I_s).

    Seeded Monte Carlo (Roy's largest-root law of W_s(I, M−1)); with the
    defaults the 0.95 / 0.99 quantiles are ≈ 39.6 / 45.5 for M = 20, s = 3 (Roy 1953,
    Ann. Math. Stat. 24(2); Johnstone 2001, Ann. Stat. 29(2)).

    Parameters
    ----------
    q : float
        Quantile, in (0, 1).
    M : int, optional
        Window length, > s.
    s : int, optional
        Dimension.
    n_mc : int, optional
        Number of Monte Carlo samples.
    seed : int, optional
        Seed (same seed, same value).

    Returns
    -------
    float
        The q-quantile.

    Raises
    ------
    InvalidInputError
        If ``q`` is not in (0, 1) or ``M <= s``.
    """
    _check_level("q", q, 1, M, s)
    return float(np.quantile(_largest_root_samples(M, s, n_mc, seed), q))


@lru_cache(maxsize=32)
def _cusum_quantiles(s: int, rho: float, k_mean: float, p: float, n_runs: int, n_steps: int, seed: int
                     ) -> tuple[float, float]:
    # one long H0 sequence (the CUSUMs are ergodic Markov chains), burn-in dropped
    rng = np.random.default_rng(seed)
    burn = 2000
    gv, gm = cusum_stats(rng.standard_normal((n_runs * n_steps + burn, s)), rho, k_mean)
    return float(np.quantile(gv[burn:], 1 - p)), float(np.quantile(gm[burn:], 1 - p))


def calibrated_thresholds(M: int = 20, s: int = 3, p_false_alarm: float = 0.01, *, cusum_rho: float = 4.0,
                          cusum_k: float = 0.5, n_mc: int = 100_000, seed: int = 0, low_window: int = 5
                          ) -> dict[str, float]:
    """Thresholds giving a per-step false-alarm rate ``p_false_alarm`` under H0.

    Alg. 2, Alg. 3 and NIS are exact χ² points; Alg. 1 and the CUSUMs are
    seeded Monte Carlo quantiles (same seed, same thresholds).

    Parameters
    ----------
    M : int, optional
        Window length in steps, > s.
    s : int, optional
        Measurement size.
    p_false_alarm : float, optional
        Per-step false-alarm rate, in (0, 0.5).
    cusum_rho : float, optional
        Variance ratio the variance CUSUM is tuned to.
    cusum_k : float, optional
        Reference value of the mean CUSUM, standard deviations.
    n_mc : int, optional
        Monte Carlo samples for Alg. 1.
    seed : int, optional
        Seed of the Monte Carlo quantiles.
    low_window : int, optional
        Number of differences of the low-variance statistic.

    Returns
    -------
    dict of str to float
        Threshold per name of :data:`DETECTORS`.

    Raises
    ------
    InvalidInputError
        If ``p_false_alarm`` is not in (0, 0.5) or ``M <= s``.
    """
    _check_level("p_false_alarm", p_false_alarm, 0.5, M, s)
    cv, cm = _cusum_quantiles(s, float(cusum_rho), float(cusum_k), float(p_false_alarm), 50, 4000, seed)
    return {
        "alg1": wishart_largest_root_quantile(1 - p_false_alarm, M, s, n_mc, seed),
        "alg2": float(chi2_isf(p_false_alarm, M - s)),
        "alg3": float(chi2_isf(p_false_alarm, M * s)),
        "nis": float(chi2_isf(p_false_alarm, s)),
        "cusum_var": cv,
        "cusum_mean": cm,
        "low_variance": _low_variance_quantile(s, low_window, float(p_false_alarm), 200_000, seed),
    }


def _low_variance_stat(b: Array, w: int) -> Array:
    """min over channels of the windowed sum of w squared first differences; b (R, N, s) → (R, N)."""
    d2 = np.zeros_like(b)
    d2[:, 1:] = np.diff(b, axis=1) ** 2
    c = np.concatenate([np.zeros((b.shape[0], 1, b.shape[2])), np.cumsum(d2, axis=1)], axis=1)
    out = np.full(b.shape[:2], np.nan)
    out[:, w:] = (c[:, w + 1:] - c[:, 1:-w]).min(axis=2)
    return out


@lru_cache(maxsize=32)
def _low_variance_quantile(s: int, w: int, p: float, n: int, seed: int) -> float:
    rng = np.random.default_rng(seed)
    st = _low_variance_stat(rng.standard_normal((1, n, s)), w)[0, w:]
    return float(np.quantile(st, p))


def alarms(name: str, statistic: ArrayLike, threshold: float) -> NDArray[np.bool_]:
    """Raw alarms of detector ``name``: statistic above (below, for :data:`LOWER_TAIL`) the threshold; NaN → no alarm.

    Parameters
    ----------
    name : str
        Detector name (one of :data:`DETECTORS`).
    statistic : array_like
        Its statistic.
    threshold : float
        Its threshold.

    Returns
    -------
    numpy.ndarray of bool, same shape as ``statistic``
        True where the detector alarms.
    """
    st = np.asarray(statistic, dtype=np.float64)
    if name in LOWER_TAIL:
        return np.nan_to_num(st, nan=np.inf) < threshold
    return np.nan_to_num(st, nan=-np.inf) > threshold


def window_statistics(normalized: ArrayLike, M: int = 20, P: ArrayLike | None = None, L: ArrayLike | None = None
                      ) -> tuple[Array, Array, Array]:
    """Sliding-window statistics (λ Alg. 1, λ Alg. 2, Alg. 3 sum) per step.

    ``normalized`` is (N, s) or a batch of runs (R, N, s).  Values before the window is full (k < M−1, 0-based) are NaN.
    ``P`` is the covariance of ν̃ under H0 (identity); ``L`` the fixed
    direction of Alg. 2 (all ones).

    Parameters
    ----------
    normalized : array_like, shape (N, s) or (R, N, s)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` of one run or a batch of runs, finite.
    M : int, optional
        Window length in steps, > s (default 20).
    P : array_like, shape (s, s), optional
        Covariance of ν̃ under H0 (default identity).
    L : array_like, shape (s,), optional
        Direction of Alg. 2 (default all ones).

    Returns
    -------
    lambda1 : numpy.ndarray, shape (..., N)
        Alg. 1: largest eigenvalue of ``A P⁻¹``.
    lambda2 : numpy.ndarray, shape (..., N)
        Alg. 2: ``Lᵀ P⁻¹ L / Lᵀ A⁻¹ L``.
    sum3 : numpy.ndarray, shape (..., N)
        Alg. 3: windowed ``Σ ν̃ᵀ ν̃``.

    Raises
    ------
    ShapeError
        If ``P`` or ``L`` has the wrong shape.
    """

    nv = _check_nv(normalized, batch=True)
    N, s = nv.shape[-2:]
    _check_window(M, s, N)
    Pm = np.eye(s) if P is None else np.asarray(P, dtype=np.float64)
    Lv = np.ones(s) if L is None else np.asarray(L, dtype=np.float64).reshape(-1)
    if Pm.shape != (s, s) or Lv.shape != (s,):
        raise ShapeError(f"P must be ({s}, {s}) and L ({s},); got {Pm.shape}, {Lv.shape}")
    return window_stats_batch(nv, int(M), np.linalg.inv(Pm), Lv)


def cusum_statistics(normalized: ArrayLike, rho: float = 4.0, k: float = 0.5) -> tuple[Array, Array]:
    """Variance CUSUM (tuned to a variance ratio ρ) and two-sided mean CUSUM (reference k).

    Page (1954, Biometrika 41): ``g_k = max(0, g_(k−1) + ℓ_k)`` with the log-likelihood ratio of
    N(0, ρI) against N(0, I), ``ℓ = ½(1 − 1/ρ)|ν̃|² − (s/2) ln ρ``, for the variance, and
    ``g±_i = max(0, g±_i ± ν̃_i − k)`` per channel for the mean (statistic: max over channels and sides).

    Parameters
    ----------
    normalized : array_like, shape (N, s)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` (a 1-D array is one channel), finite.
    rho : float, optional
        Variance ratio to detect, > 1.
    k : float, optional
        Reference value of the mean CUSUM, standard deviations, >= 0.

    Returns
    -------
    variance : numpy.ndarray, shape (N,)
        Variance CUSUM.
    mean : numpy.ndarray, shape (N,)
        Largest two-sided per-channel mean CUSUM.

    Raises
    ------
    InvalidInputError
        If ``rho <= 1`` or ``k < 0``.
    """

    if not rho > 1:
        raise InvalidInputError(f"cusum rho (variance ratio to detect) must be > 1, got {rho}")
    if not k >= 0:
        raise InvalidInputError(f"cusum reference k must be >= 0, got {k}")
    return cusum_stats(_check_nv(normalized), float(rho), float(k))


def detector_statistics(normalized: ArrayLike, M: int = 20, *, cusum_rho: float = 4.0, cusum_k: float = 0.5,
                        low_window: int = 5) -> dict[str, Array]:
    """All detector statistics for one run (N, s) or a batch of runs (R, N, s).

    Returns {name: (…, N)} for the names in :data:`DETECTORS` (window ones NaN
    before the window is full).  Compare with the thresholds of
    :func:`calibrated_thresholds` / :func:`window_chi2_thresholds`.

    Parameters
    ----------
    normalized : array_like, shape (N, s) or (R, N, s)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` of one run or a batch of runs, finite.
    M : int, optional
        Window length in steps, > s (default 20).
    cusum_rho : float, optional
        Variance ratio of the variance CUSUM, > 1.
    cusum_k : float, optional
        Reference value of the mean CUSUM, >= 0.
    low_window : int, optional
        Number of differences of the low-variance statistic.

    Returns
    -------
    dict of str to numpy.ndarray
        Statistic per detector name, shape (N,) or (R, N).

    Raises
    ------
    InvalidInputError
        If ``cusum_rho <= 1`` or ``cusum_k < 0``.
    """

    nv = _check_nv(normalized, batch=True)
    single = nv.ndim == 2
    b = nv[None] if single else nv
    if not cusum_rho > 1 or not cusum_k >= 0:
        raise InvalidInputError(f"cusum_rho must be > 1 and cusum_k >= 0, got {cusum_rho}, {cusum_k}")
    l1, l2, a3 = window_statistics(b, M)
    gv = np.empty(b.shape[:2])
    gm = np.empty(b.shape[:2])
    for r in range(b.shape[0]):
        gv[r], gm[r] = cusum_stats(np.ascontiguousarray(b[r]), float(cusum_rho), float(cusum_k))
    low = _low_variance_stat(b, low_window)  # stuck output; NaN until the short window is full
    out = {"alg1": l1, "alg2": l2, "alg3": a3, "nis": np.einsum("...i,...i->...", b, b), "cusum_var": gv,
           "cusum_mean": gm, "low_variance": low}
    return {k: v[0] for k, v in out.items()} if single else out


def latch(alarm: ArrayLike) -> NDArray[np.bool_]:
    """Latched alarm: true from the first alarm on (cumulative OR along the last axis).

    Parameters
    ----------
    alarm : array_like of bool
        Raw alarms, steps along the last axis.

    Returns
    -------
    numpy.ndarray of bool, same shape
        Latched alarms.
    """
    a = np.asarray(alarm, dtype=bool)
    return np.logical_or.accumulate(a, axis=-1)


def first_alarm(alarm: ArrayLike, start: int = 0) -> int:
    """Index of the first alarm at or after ``start``; -1 if none.

    Parameters
    ----------
    alarm : array_like of bool, shape (N,)
        Alarms.
    start : int, optional
        First step considered.

    Returns
    -------
    int
        Step index, or -1.
    """
    a = np.asarray(alarm, dtype=bool)[start:]
    idx = np.flatnonzero(a)
    return int(idx[0] + start) if idx.size else -1


def isolate_faulty_channels(normalized: ArrayLike, M: int = 20, p_false_alarm: float = 1e-3, start: int = 0,
                            during: ArrayLike | None = None, min_count: int = 3
                            ) -> tuple[NDArray[np.bool_], Array]:
    """Channels whose own windowed statistics show a fault.

    Per channel i: ``Σ ν̃_i²`` over the window (χ²(M) under H0) and the window
    mean test ``|Σ ν̃_i| / √M`` (N(0, 1)); both at level p / (2s) (Bonferroni).
    A channel is isolated when it is flagged on at least ``min_count`` steps
    at or after ``start`` on which ``during`` (e.g. the system alarm) is True
    (all steps if None): a persistent fault keeps flagging its channel, a
    chance flag does not repeat.

    Parameters
    ----------
    normalized : array_like, shape (N, s)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` (a 1-D array is one channel), finite.
    M : int, optional
        Window length in steps, > s (default 20).
    p_false_alarm : float, optional
        Per-step level of the two tests together (split by Bonferroni).
    start : int, optional
        Flags before this step are ignored.
    during : array_like of bool, shape (N,), optional
        Steps on which flags count (default all).
    min_count : int, optional
        Least number of flagged steps to isolate a channel.

    Returns
    -------
    isolated : numpy.ndarray of bool, shape (s,)
        True for the faulty channels.
    first_flag : numpy.ndarray, shape (s,)
        First flagged step per channel (as float), -1 if none.
    """
    nv = _check_nv(normalized)
    N, s = nv.shape
    _check_window(M, 0, N)
    a = p_false_alarm / (2 * s)
    thr_sq = chi2_isf(a, M)
    thr_mu = norm_isf(a / 2)
    c2 = np.concatenate([np.zeros((1, s)), np.cumsum(nv**2, axis=0)])
    c1 = np.concatenate([np.zeros((1, s)), np.cumsum(nv, axis=0)])
    sq = np.full((N, s), np.nan)
    mu = np.full((N, s), np.nan)
    sq[M - 1:] = c2[M:] - c2[:-M]
    mu[M - 1:] = np.abs(c1[M:] - c1[:-M]) / np.sqrt(M)
    flag = (sq > thr_sq) | (mu > thr_mu)
    flag[:start] = False
    if during is not None:
        flag &= np.asarray(during, dtype=bool).reshape(N, 1)
    first = np.array([first_alarm(flag[:, i]) for i in range(s)], dtype=np.int64)
    return flag.sum(axis=0) >= min_count, first.astype(np.float64)


@dataclass(frozen=True)
class FaultDetectorResult(Result):
    """One fault detector over an innovation sequence (not :class:`imunav.ins.DetectorResult`, the
    zero-velocity detector's flags).

    Attributes
    ----------
    name : str
        Detector name (one of :data:`DETECTORS`).
    statistic : numpy.ndarray, shape (N,)
        The statistic (NaN before the window is full).
    threshold : float
        Threshold used.
    thesis_threshold : float
        Akgün's (2002) threshold (NaN where the thesis has none).
    alarm : numpy.ndarray of bool, shape (N,)
        Raw per-step decisions.
    latched : numpy.ndarray of bool, shape (N,)
        Alarms latched from the first on.
    first_alarm : int
        Step of the first alarm, or -1.
    """

    name: str
    statistic: Array
    threshold: float
    thesis_threshold: float
    alarm: NDArray[np.bool_]
    latched: NDArray[np.bool_]
    first_alarm: int


@dataclass(frozen=True)
class FaultDetectionResult(Result):
    """All detectors on one sequence, plus channel isolation after the first alarm.

    Attributes
    ----------
    detectors : dict of str to FaultDetectorResult
        One result per detector name.
    isolated_channels : numpy.ndarray of bool, shape (s,)
        Channels isolated as faulty (none without an alarm).
    channel_first_flag : numpy.ndarray, shape (s,)
        First flagged step per channel, -1 if none.
    window : int
        Window length M, steps.
    p_false_alarm : float
        Per-step false-alarm rate of the calibrated thresholds.
    threshold_mode : str
        ``"calibrated"`` or ``"thesis"``.
    extra : dict
        Further information.
    """

    detectors: dict[str, FaultDetectorResult]
    isolated_channels: NDArray[np.bool_]
    channel_first_flag: Array
    window: int
    p_false_alarm: float
    threshold_mode: str
    extra: dict = field(default_factory=dict)


def detect_faults(
    normalized: ArrayLike,
    M: int = 20,
    *,
    p_false_alarm: float = 0.01,
    threshold_mode: str = "calibrated",
    start: int = 0,
    cusum_rho: float = 4.0,
    cusum_k: float = 0.5,
    thresholds: dict[str, float] | None = None,
    p_isolation: float = 1e-3,
) -> FaultDetectionResult:
    """Run Alg. 1-3, NIS and both CUSUMs on normalised innovations (N, s).

    Parameters
    ----------
    normalized : array_like, shape (N, s)
        Normalised innovations ``ν̃ = S^{-1/2} ν`` (a 1-D array is one channel), finite.
    M : int, optional
        Window length in steps, > s (default 20).
    p_false_alarm : float, optional
        Per-step false-alarm rate of the calibrated thresholds, in (0, 0.5).
    threshold_mode : str
        ``"calibrated"`` (per-step false-alarm rate ``p_false_alarm``) or ``"thesis"`` (χ² points of the
        thesis for Alg. 1-3; calibrated for the others).  ``thresholds`` overrides.
    start : int
        Alarms before this step are ignored (e.g. filter transient).
    cusum_rho : float, optional
        Variance ratio of the variance CUSUM.
    cusum_k : float, optional
        Reference value of the mean CUSUM.
    thresholds : dict of str to float, optional
        Thresholds overriding those of ``threshold_mode``, by detector name.
    p_isolation : float
        Per-step level of the per-channel isolation tests (a channel is isolated when flagged on >= 3 steps
        with a system alarm).

    Returns
    -------
    FaultDetectionResult
        Every detector's statistic and alarms, and the isolated channels.

    Raises
    ------
    InvalidInputError
        If ``threshold_mode`` or a name in ``thresholds`` is unknown.
    """
    nv = _check_nv(normalized)
    N, s = nv.shape
    _check_window(M, s, N)
    if threshold_mode not in ("calibrated", "thesis"):
        raise InvalidInputError(f"threshold_mode must be 'calibrated' or 'thesis', got {threshold_mode!r}")
    thr = calibrated_thresholds(M, s, p_false_alarm, cusum_rho=cusum_rho, cusum_k=cusum_k)
    th = window_chi2_thresholds(M, s)
    if threshold_mode == "thesis":
        thr.update(th)
    if thresholds:
        unknown = set(thresholds) - set(DETECTORS)
        if unknown:
            raise InvalidInputError(f"unknown detector(s) {sorted(unknown)}; known: {DETECTORS}")
        thr.update({k: float(v) for k, v in thresholds.items()})
    stats = detector_statistics(nv, M, cusum_rho=cusum_rho, cusum_k=cusum_k)
    dets = {}
    earliest = -1
    for name in DETECTORS:
        st = stats[name]
        alarm = alarms(name, st, thr[name])
        alarm[:start] = False
        fa = first_alarm(alarm)
        dets[name] = FaultDetectorResult(name, st, thr[name], th.get(name, np.nan), alarm, latch(alarm), fa)
        if fa >= 0 and (earliest < 0 or fa < earliest):
            earliest = fa
    if earliest >= 0:
        any_alarm = np.zeros(N, dtype=bool)
        for d in dets.values():
            any_alarm |= d.alarm
        iso, cf = isolate_faulty_channels(nv, M, p_isolation, start=start, during=any_alarm)
    else:
        iso, cf = np.zeros(s, dtype=bool), np.full(s, -1.0)
    return FaultDetectionResult(dets, iso, cf, int(M), float(p_false_alarm), threshold_mode)


@dataclass(frozen=True)
class Fault:
    """A fault to inject into a measurement sequence.

    Attributes
    ----------
    kind : str
        ``"bias"`` (add ``magnitude``), ``"drift"`` (add ``magnitude`` per second from onset, needs ``dt``),
        ``"noise"`` (noise × ``magnitude``), ``"stuck"`` (output frozen at its onset value), ``"outlier"``
        (noise × ``magnitude`` at the single steps ``steps``).
    onset, end : int
        Step range [onset, end) (end None = to the last step).
    magnitude : float
        Bias (measurement units), drift (units/s) or noise factor (>= 1).
    channels : tuple of int or None
        Channel indices (None = all).
    steps : tuple of int
        Steps of an ``"outlier"`` fault.

    Raises
    ------
    InvalidInputError
        If the kind is unknown, ``onset`` negative or a noise factor below 1.
    """

    kind: str
    onset: int = 0
    magnitude: float = 0.0
    channels: tuple[int, ...] | None = None
    end: int | None = None
    steps: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in ("bias", "drift", "noise", "stuck", "outlier"):
            raise InvalidInputError(f"fault kind must be bias, drift, noise, stuck or outlier, got {self.kind!r}")
        if self.onset < 0:
            raise InvalidInputError(f"fault onset must be >= 0, got {self.onset}")
        if self.kind in ("noise", "outlier") and not self.magnitude >= 1:
            raise InvalidInputError(f"{self.kind} fault magnitude is a noise factor >= 1, got {self.magnitude}")

    def to_dict(self) -> dict:
        """The fault as plain JSON types.

        Returns
        -------
        dict
            Keys ``kind``, ``onset``, ``magnitude``, ``channels``, ``end``, ``steps``.
        """
        return {"kind": self.kind, "onset": self.onset, "magnitude": self.magnitude,
                "channels": None if self.channels is None else list(self.channels),
                "end": self.end, "steps": list(self.steps)}


def inject_faults(
    z: ArrayLike,
    faults: list[Fault] | tuple[Fault, ...],
    *,
    noise: ArrayLike | None = None,
    sigma: ArrayLike | None = None,
    dt: float = 1.0,
    rng: np.random.Generator | int | None = None,
) -> Array:
    """Return a copy of measurements ``z`` (N, m) with the faults applied.

    Noise-type faults scale the known noise realisation ``noise`` (so
    ``z + (f − 1)·noise`` has exactly f × the nominal noise) or, without it,
    add independent noise of std ``σ √(f² − 1)``.

    Parameters
    ----------
    z : array_like, shape (N, m)
        Measurements (a 1-D array is one channel).
    faults : list or tuple of Fault
        Faults to apply, in order.
    noise : array_like, shape (N, m), optional
        Noise realisation contained in ``z``.
    sigma : array_like, shape (m,) or scalar, optional
        Nominal noise std per channel (used without ``noise``).
    dt : float, optional
        Step, s (drift faults).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    numpy.ndarray, shape (N, m)
        The faulty measurements (a copy).

    Raises
    ------
    InvalidInputError
        If a fault's channels, onset or steps are out of range, or a noise fault has neither
        ``noise`` nor ``sigma``.
    """
    zz = np.array(z, dtype=np.float64)
    if zz.ndim == 1:
        zz = zz[:, None]
    N, m = zz.shape
    out = zz.copy()
    gen = np.random.default_rng(rng)
    nz = None if noise is None else np.asarray(noise, dtype=np.float64).reshape(N, m)
    sg = None if sigma is None else np.broadcast_to(np.asarray(sigma, dtype=np.float64), (m,))
    for f in faults:
        ch = np.arange(m) if f.channels is None else np.asarray(f.channels, dtype=int)
        if ch.size and (ch.min() < 0 or ch.max() >= m):
            raise InvalidInputError(f"fault channels {list(ch)} out of range for {m} channels")
        if f.onset >= N:
            raise InvalidInputError(f"fault onset {f.onset} is past the last step {N - 1}")
        end = N if f.end is None else min(f.end, N)
        rows = np.arange(f.onset, end)
        if f.kind == "bias":
            out[np.ix_(rows, ch)] += f.magnitude
        elif f.kind == "drift":
            out[np.ix_(rows, ch)] += (f.magnitude * (rows - f.onset) * dt)[:, None]
        elif f.kind == "stuck":
            out[np.ix_(rows, ch)] = out[f.onset, ch]
        else:
            if f.kind == "outlier":
                rows = np.asarray(f.steps, dtype=int)
                if rows.size and (rows.min() < 0 or rows.max() >= N):
                    raise InvalidInputError(f"outlier steps {list(rows)} out of range 0..{N - 1}")
            if nz is not None:
                out[np.ix_(rows, ch)] += (f.magnitude - 1.0) * nz[np.ix_(rows, ch)]
            elif sg is not None:
                out[np.ix_(rows, ch)] += (np.sqrt(f.magnitude**2 - 1.0) * sg[ch]
                                         * gen.standard_normal((rows.size, ch.size)))
            else:
                raise InvalidInputError(f"a {f.kind} fault needs the noise realisation (noise=) or its std (sigma=)")
    return out


def false_alarm_rates(alarm: ArrayLike, valid: ArrayLike | None = None) -> tuple[float, float]:
    """(per-step rate, share of runs with any alarm) for alarms (runs, steps) under H0.

    Parameters
    ----------
    alarm : array_like of bool, shape (runs, steps) or (steps,)
        Alarms of fault-free runs.
    valid : array_like of bool, optional
        Steps counted (broadcast to ``alarm``; default all).

    Returns
    -------
    per_step : float
        Share of valid steps with an alarm.
    per_run : float
        Share of runs with any alarm on a valid step.

    Raises
    ------
    InvalidInputError
        If no step is valid.
    """
    a = np.asarray(alarm, dtype=bool)
    if a.ndim == 1:
        a = a[None]
    v = np.ones_like(a) if valid is None else np.broadcast_to(np.asarray(valid, dtype=bool), a.shape)
    if not v.any():
        raise InvalidInputError("no valid steps to count false alarms on")
    per_step = float(a[v].mean())
    per_run = float(np.mean((a & v).any(axis=1)))
    return per_step, per_run


def detection_delays(alarm: ArrayLike, onset: int, horizon: int | None = None) -> tuple[Array, float]:
    """Delays (first alarm at or after onset minus onset + 1; the onset sample is delay 1).

    Parameters
    ----------
    alarm : array_like of bool, shape (runs, steps) or (steps,)
        Alarms.
    onset : int
        Step at which the fault starts.
    horizon : int, optional
        Steps after the onset within which a detection counts (default to the end).

    Returns
    -------
    delays : numpy.ndarray, shape (runs,)
        Delay in steps (NaN for a missed detection).
    missed : float
        Missed-detection rate within the horizon.
    """
    a = np.asarray(alarm, dtype=bool)
    if a.ndim == 1:
        a = a[None]
    end = a.shape[1] if horizon is None else min(a.shape[1], onset + horizon)
    seg = a[:, onset:end]
    hit = seg.any(axis=1)
    d = np.where(hit, np.argmax(seg, axis=1) + 1.0, np.nan)
    return d, float(1.0 - hit.mean())
