"""Power spectral density of IMU noise, IEEE-952 frequency averaging, and the
PSD estimates of the noise terms.

After the PSD method of E. Atasoy, *Estimation and analysis of error parameters of attitude-heading
reference system sensors* (in Turkish), MSc thesis, Başkent University, §5.4.1, and IEEE Std 952-1997,
Annex C.  Normalisation (the thesis's eqs. 5.10-5.11 are wrong): :func:`psd` returns the **one-sided**
density S1(f), which integrates to the variance over [0, fs/2]; white noise of per-sample standard
deviation sigma at rate fs has S1 = 2 sigma^2 / fs.  The IEEE-952 term formulas use the
two-sided level S2 = S1 / 2 (:attr:`PsdResult.two_sided`):

==================  ========================  ============================
term                S2(f)                     read-off
==================  ========================  ============================
quantization Q      (2 pi f)^2 tau0 Q^2       Q = sqrt(S2)/(2 pi f sqrt(tau0))
white rate N        N^2                       N = sqrt(S2)
bias instab. B      B^2 / (2 pi f)            B = sqrt(2 pi f S2)
rate random walk K  K^2 / (2 pi f)^2          K = 2 pi f sqrt(S2)
==================  ========================  ============================

so that N from the PSD equals N from the Allan variance (N^2/tau).  Power
slopes are +2, 0, -1, -2 (the thesis's "+1" for quantization is the slope of
the amplitude spectrum).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal
from scipy.optimize import nnls

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.noise.allan import check_rows_are_samples
from imunav.results import Result

__all__ = ["PsdResult", "PsdFit", "psd", "frequency_average", "log_average", "fit_psd", "psd_readout",
           "compare_psd_allan"]


@dataclass(frozen=True)
class PsdResult(Result):
    """One-sided PSD, unit^2/Hz.

    Attributes
    ----------
    f : numpy.ndarray, shape (F,)
        Frequencies, Hz (DC dropped).
    psd : numpy.ndarray, shape (F,) or (F, C)
        One-sided density S1(f) of each channel, (unit of ``units``)²/Hz, like the input.
    counts : numpy.ndarray, shape (F,)
        Number of raw periodogram bins (times Welch segments) averaged into each point, which sets its
        relative variance 1/count.
    fs : float
        Sample rate, Hz.
    method : str
        ``"periodogram"`` or ``"welch"``, with the averaging applied appended (``"welch+log-average"``).
    units : str
        Unit of the input samples (e.g. ``"rad/s"``).
    channels : tuple of str
        Channel names.
    """

    f: NDArray[np.float64]
    psd: NDArray[np.float64]
    counts: NDArray[np.float64]
    fs: float
    method: str
    units: str = ""
    channels: tuple[str, ...] = ()

    @property
    def two_sided(self) -> NDArray[np.float64]:
        """Two-sided level S2 = S1/2 used by the IEEE-952 formulas."""
        return self.psd / 2.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the PSD.

        Returns
        -------
        dict
            ``f``, ``psd``, ``counts`` as lists, ``fs``, ``method``, ``units``, ``channels`` and ``sides: "one"``.
        """
        return {"f": self.f.tolist(), "psd": self.psd.tolist(), "counts": self.counts.tolist(), "fs": self.fs,
                "method": self.method, "units": self.units, "channels": list(self.channels), "sides": "one"}


def _as2d(x: ArrayLike) -> tuple[np.ndarray, bool]:
    a = np.asarray(x, dtype=float)
    if a.ndim not in (1, 2):
        raise ShapeError(f"x must be (N,) or (N, C), got shape {a.shape}")
    one = a.ndim == 1
    a2 = a[:, None] if one else a

    check_rows_are_samples(a2.shape, "x")
    if not np.all(np.isfinite(a2)):
        r, c = np.argwhere(~np.isfinite(a2))[0]
        raise NonFiniteError(f"non-finite value in row {r}, column {c}; the PSD needs a gap-free record")
    return a2, one


def psd(x: ArrayLike, fs: float, method: Literal["periodogram", "welch"] = "periodogram", *,
        nperseg: int | None = None, window: str | None = None, detrend: str = "constant", units: str = "",
        channels: Sequence[str] | None = None) -> PsdResult:
    """One-sided PSD of each channel.

    ``"periodogram"``: one DFT of the whole record (rectangular window by
    default, as in the thesis); ``"welch"``: averaged segments (Hann window,
    ``nperseg`` default N/16 rounded to a power of 2, 50 % overlap; P. D. Welch, IEEE Trans. Audio
    Electroacoustics 15(2), 1967).  DC is dropped.

    Parameters
    ----------
    x : array_like, shape (N,) or (N, C)
        Samples (rates in rad/s, specific force in m/s², ...), rows are samples, finite.
    fs : float
        Sample rate, Hz, > 0.
    method : {"periodogram", "welch"}
        Estimator.
    nperseg : int, optional
        Welch segment length, samples.
    window : str, optional
        A :func:`scipy.signal.get_window` name (default: ``"boxcar"`` for the periodogram, ``"hann"`` for
        Welch).
    detrend : str
        Detrending of each segment (``"constant"``, ``"linear"`` or ``"none"``).
    units : str
        Unit of ``x``, recorded in the result.
    channels : sequence of str, optional
        Channel names.

    Returns
    -------
    PsdResult
        The one-sided density, (unit of ``units``)²/Hz.

    Raises
    ------
    ShapeError
        If ``x`` is not (N,) / (N, C), or looks transposed.
    NonFiniteError
        If ``x`` has NaN or infinite values.
    InvalidInputError
        If ``fs`` is not positive, ``method`` is unknown or ``nperseg`` is outside 8..N.
    InsufficientDataError
        With fewer than 8 samples.
    """
    a2, one = _as2d(x)
    if not (np.isfinite(fs) and fs > 0):
        raise InvalidInputError(f"fs must be positive, got {fs!r}")
    n = a2.shape[0]
    if n < 8:
        raise InsufficientDataError(f"{n} samples are too few for a PSD (need >= 8)")
    if method == "periodogram":
        f, p = signal.periodogram(a2, fs=fs, window=window or "boxcar", detrend=detrend, scaling="density",
                                  axis=0)
        counts = np.ones(f.size)
    elif method == "welch":
        if nperseg is None:
            nperseg = int(2 ** max(3, int(np.floor(np.log2(max(8, n // 16))))))
        if not 8 <= nperseg <= n:
            raise InvalidInputError(f"nperseg={nperseg} must be between 8 and the record length {n}")
        f, p = signal.welch(a2, fs=fs, window=window or "hann", nperseg=nperseg, detrend=detrend,
                            scaling="density", axis=0)
        nseg = 1 + (n - nperseg) // (nperseg // 2)
        # 50 % overlapped Hann segments: effective independent averages ~ nseg / 1.06 (Welch 1967)
        counts = np.full(f.size, max(1.0, nseg / 1.055))
    else:
        raise InvalidInputError(f"method={method!r}; use 'periodogram' or 'welch'")
    f, p, counts = f[1:], p[1:], counts[1:]
    names = tuple(channels) if channels is not None else tuple(f"ch{i}" for i in range(a2.shape[1]))
    return PsdResult(f=f, psd=p[:, 0] if one else p, counts=counts, fs=float(fs), method=method, units=units,
                     channels=names)


def _group(res: PsdResult, groups: list[np.ndarray], geometric: bool, method: str) -> PsdResult:
    p2 = res.psd if res.psd.ndim == 2 else res.psd[:, None]
    f_out = np.array([np.exp(np.mean(np.log(res.f[g]))) if geometric else res.f[g].mean() for g in groups])
    p_out = np.array([p2[g].mean(axis=0) for g in groups])
    c_out = np.array([res.counts[g].sum() for g in groups])
    return PsdResult(f=f_out, psd=p_out[:, 0] if res.psd.ndim == 1 else p_out, counts=c_out, fs=res.fs,
                     method=f"{res.method}+{method}", units=res.units, channels=res.channels)


def frequency_average(res: PsdResult, first: int = 32, per_octave: int = 16, geometric: bool = False) -> PsdResult:
    """IEEE Std 952 frequency averaging (Atasoy, Table 5.1), for any number of bins.

    The first ``first`` bins are kept; every following octave of bins
    [2^k + 1, 2^(k+1)] (k >= log2(first)) is split into ``per_octave`` equal
    groups of consecutive bins, each averaged.  A last, incomplete octave is
    split into groups of the same size (the final group may be shorter).
    For 32768 bins this gives the table's 32 + 10 x 16 = 192 points.

    Parameters
    ----------
    res : PsdResult
        A one-sided PSD (raw or averaged).
    first : int
        Number of leading bins kept as they are, a power of 2.
    per_octave : int
        Groups per octave, >= 1.
    geometric : bool
        Frequency of a group: geometric mean (True) or arithmetic mean (False).

    Returns
    -------
    PsdResult
        The averaged PSD, with ``counts`` summed over each group.

    Raises
    ------
    InvalidInputError
        If ``first`` is not a power of 2 or ``per_octave < 1``.
    """
    nb = res.f.size
    if first < 1 or per_octave < 1 or first & (first - 1):
        raise InvalidInputError("first must be a power of 2 and per_octave >= 1")
    groups = [np.array([i]) for i in range(min(first, nb))]
    lo = first  # zero-based index of bin first+1
    width = first
    while lo < nb:
        size = max(1, width // per_octave)
        hi = min(lo + width, nb)
        for g0 in range(lo, hi, size):
            groups.append(np.arange(g0, min(g0 + size, hi)))
        lo += width
        width *= 2
    return _group(res, groups, geometric, "ieee952-average")


def log_average(res: PsdResult, per_decade: int = 20) -> PsdResult:
    """Average into logarithmically spaced frequency bins (empty bins skipped).

    Parameters
    ----------
    res : PsdResult
        A one-sided PSD (raw or averaged).
    per_decade : int
        Bins per decade of frequency.

    Returns
    -------
    PsdResult
        The averaged PSD (geometric-mean frequencies), ``"+log-average"`` appended to ``method``.
    """
    edges = np.logspace(np.log10(res.f[0]), np.log10(res.f[-1]) + 1e-12,
                        max(2, int(np.ceil(per_decade * np.log10(res.f[-1] / res.f[0]))) + 1))
    idx = np.clip(np.searchsorted(edges, res.f, side="right") - 1, 0, edges.size - 2)
    groups = [np.flatnonzero(idx == k) for k in range(edges.size - 1)]
    return _group(res, [g for g in groups if g.size], True, "log-average")


@dataclass(frozen=True)
class PsdFit(Result):
    """Noise terms from the PSD (SI, same meaning as :class:`imunav.noise.fit.NoiseFit`).

    Attributes
    ----------
    names : tuple of str
        Terms fitted, from ``"Q", "N", "B", "K"``.
    value : numpy.ndarray, shape (P, C)
        Estimate of each term and channel, SI (N in rad/s/√Hz for a gyro, ...).
    se : numpy.ndarray, shape (P, C)
        Standard errors.
    channels : tuple of str
        Channel names.
    f_range : tuple of (float, float)
        Frequency band fitted for each channel, Hz.
    """

    names: tuple[str, ...]
    value: NDArray[np.float64]  # (P, C)
    se: NDArray[np.float64]
    channels: tuple[str, ...]
    f_range: tuple[tuple[float, float], ...]  # per channel

    def get(self, name: str, channel: int = 0) -> float:
        """One fitted value, SI.

        Parameters
        ----------
        name : str
            Term name, one of :attr:`names`.
        channel : int
            Channel index.

        Returns
        -------
        float
            The estimate.
        """
        return float(self.value[self.names.index(name), channel])

    def model(self, f: ArrayLike, channel: int = 0, tau0: float = 0.0) -> NDArray[np.float64]:
        """Fitted one-sided PSD, ``2 [N² + B²/(2πf) + K²/(2πf)² + (2πf)² τ0 Q²]``.

        Parameters
        ----------
        f : array_like
            Frequencies, Hz.
        channel : int
            Channel index.
        tau0 : float
            Sample interval, s (only for the quantization term).

        Returns
        -------
        numpy.ndarray
            S1(f), in the square of the channel's unit per Hz.
        """
        f = np.asarray(f, dtype=float)
        v = dict(zip(self.names, self.value[:, channel]))
        w = 2 * np.pi * f
        s2 = v.get("N", 0) ** 2 + v.get("B", 0) ** 2 / w + v.get("K", 0) ** 2 / w**2 + w**2 * tau0 * v.get("Q", 0) ** 2
        return 2.0 * s2

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the fit.

        Returns
        -------
        dict
            ``names``, ``value``, ``se``, ``channels``, ``f_range``.
        """
        return {"names": list(self.names), "value": self.value.tolist(), "se": self.se.tolist(),
                "channels": list(self.channels), "f_range": list(self.f_range)}


def fit_psd(res: PsdResult, terms: Sequence[str] = ("N", "B", "K"), f_range: Any = None) -> PsdFit:
    """Weighted NNLS fit of the two-sided PSD model to an (averaged) PSD.

    The model is the sum of the terms' shapes (table in the module docstring); each point's relative
    variance is 1/count, and the residuals are weighted by the model (iterated), like the Allan fit.

    Parameters
    ----------
    res : PsdResult
        A one-sided PSD (raw or averaged).
    terms : sequence of str
        Terms to fit, a non-empty subset of ``("Q", "N", "B", "K")``.
    f_range : tuple of float or list of tuple, optional
        Band ``(lo, hi)``, Hz; default [f_min, 0.4 fs] to stay clear of anti-alias filtering near Nyquist.
        A list of ``(lo, hi)``, one per channel, sets each channel's band.

    Returns
    -------
    PsdFit
        The terms, SI, with standard errors.

    Raises
    ------
    InvalidInputError
        If ``terms`` is empty or holds an unknown term.
    InsufficientDataError
        If a band holds too few points.
    """
    allowed = ("Q", "N", "B", "K")
    if any(t not in allowed for t in terms) or not terms:
        raise InvalidInputError(f"terms must be a non-empty subset of {allowed}")
    p_all = (res.psd if res.psd.ndim == 2 else res.psd[:, None]) / 2.0
    n_ch = p_all.shape[1]
    if f_range is None:
        ranges = [(res.f[0], 0.4 * res.fs)] * n_ch
    elif np.ndim(f_range) == 1:
        ranges = [tuple(f_range)] * n_ch
    else:
        ranges = [tuple(r) for r in f_range]
        if len(ranges) != n_ch:
            raise InvalidInputError(f"{len(ranges)} f_range entries for {n_ch} channels")
    val = np.zeros((len(terms), n_ch))
    se = np.full((len(terms), n_ch), np.nan)
    tau0 = 1.0 / res.fs
    for c in range(n_ch):
        lo, hi = ranges[c]
        ok = (res.f >= lo) & (res.f <= hi)
        if ok.sum() < len(terms) + 1:
            raise InsufficientDataError(f"only {int(ok.sum())} PSD points in f_range=({lo:g}, {hi:g}) Hz")
        f = res.f[ok]
        w = 2 * np.pi * f
        shapes = {"Q": w**2 * tau0, "N": np.ones_like(f), "B": 1.0 / w, "K": 1.0 / w**2}
        G = np.column_stack([shapes[t] for t in terms])
        cnt = res.counts[ok]
        y = p_all[ok, c]
        model = y.copy()
        for _ in range(4):
            sw = np.sqrt(cnt) / np.maximum(model, 1e-300)
            scale = np.sqrt(np.sum((G * sw[:, None]) ** 2, axis=0))
            scale[scale == 0] = 1
            th, _ = nnls(G * sw[:, None] / scale, y * sw)
            th = th / scale
            model = np.maximum(G @ th, 1e-300)
        sw = np.sqrt(cnt) / model
        Gw = G * sw[:, None]
        keep = th > 0
        if keep.any():
            cov = np.linalg.pinv(Gw[:, keep].T @ Gw[:, keep])
            se[keep, c] = np.sqrt(np.diag(cov)) / (2 * np.sqrt(th[keep]))
        val[:, c] = np.sqrt(th)
    return PsdFit(names=tuple(terms), value=val, se=se, channels=res.channels,
                  f_range=tuple((float(a), float(b)) for a, b in ranges))


def psd_readout(res: PsdResult, term: str, f_band: tuple[float, float]) -> NDArray[np.float64]:
    """Fixed-slope read-out of one term over a frequency band (per channel).

    The band's PSD points are averaged after removing the term's slope, i.e. the line of slope
    (+2, 0, -1, -2) through them, and the coefficient read with the formulas of the module docstring.

    Parameters
    ----------
    res : PsdResult
        A one-sided PSD (raw or averaged).
    term : {"Q", "N", "B", "K"}
        The term read.
    f_band : tuple of float
        ``(lo, hi)``, Hz.

    Returns
    -------
    numpy.ndarray, shape (C,)
        The coefficient of each channel, SI.

    Raises
    ------
    InsufficientDataError
        If no PSD point lies in the band.
    InvalidInputError
        If the term is unknown.
    """
    ok = (res.f >= f_band[0]) & (res.f <= f_band[1])
    if not ok.any():
        raise InsufficientDataError(f"no PSD points in f_band={f_band}")
    w = 2 * np.pi * res.f[ok]
    p2 = (res.psd if res.psd.ndim == 2 else res.psd[:, None])[ok] / 2.0
    tau0 = 1.0 / res.fs
    if term == "N":
        v = np.sqrt(np.mean(p2, axis=0))
    elif term == "B":
        v = np.sqrt(np.mean(p2 * w[:, None], axis=0))
    elif term == "K":
        v = np.sqrt(np.mean(p2 * w[:, None] ** 2, axis=0))
    elif term == "Q":
        v = np.sqrt(np.mean(p2 / (w[:, None] ** 2 * tau0), axis=0))
    else:
        raise InvalidInputError(f"term={term!r}; use 'Q', 'N', 'B' or 'K'")
    return v if res.psd.ndim == 2 else v[:1]


def compare_psd_allan(psd_fit: PsdFit, noise_fit: Any, terms: Sequence[str] = ("N",)) -> dict[str, list[float]]:
    """Relative difference PSD / Allan - 1 of the terms both fits have, per channel.

    Parameters
    ----------
    psd_fit : PsdFit
        Terms from the PSD.
    noise_fit : NoiseFit
        Terms from the Allan variance (:func:`imunav.noise.fit_noise`).
    terms : sequence of str
        Terms compared.

    Returns
    -------
    dict of str to list of float
        Per term present in both fits, ``psd / allan - 1`` of each channel.
    """
    out = {}
    for t in terms:
        if t in psd_fit.names and t in noise_fit.names:
            a = noise_fit.value[noise_fit.names.index(t)]
            p = psd_fit.value[psd_fit.names.index(t)]
            with np.errstate(divide="ignore", invalid="ignore"):
                out[t] = (p / a - 1.0).tolist()
    return out
