"""Allan family of stability statistics for IMU rate / increment records.

Definitions (NIST SP 1065, W. J. Riley 2008; IEEE Std 952-1997 Annex C) with
the phase ``x`` (integrated rate: angle for a gyro, velocity for an
accelerometer), ``tau = m tau0``, ``n`` phase points:

* ``"standard"`` (non-overlapping Allan), SP 1065 eq. (7):
  ``AVAR = sum_{i=0,m,2m..} (x[i+2m] - 2x[i+m] + x[i])^2 / (2 tau^2 K)``,
  K = floor((n-1)/m) - 1 terms.
* ``"overlapping"`` (default), eq. (11): the same with every i, K = n - 2m.
* ``"modified"``, eq. (15): ``MVAR = sum_j (sum_{i=j}^{j+m-1} d_i)^2 / (2 m^2 tau^2 (n-3m+1))``.
* ``"time"`` (TDEV), eq. (16): ``TVAR = tau^2 MVAR / 3`` (unit: phase unit).
* ``"hadamard"`` / ``"overlapping_hadamard"``, eqs. (17)-(19):
  ``HVAR = sum (x[i+3m] - 3x[i+2m] + 3x[i+m] - x[i])^2 / (6 tau^2 K)``.
* ``"total"``, eq. (25): overlapping Allan over the phase extended by odd
  reflection about both ends, ``/ (2 tau^2 (n-2))``.

Inputs are rates (``input="rate"``: rad/s, m/s^2 ...; the NIST "fractional
frequency"), per-sample increments (``"increment"``: delta-angle / delta-
velocity, phase = cumulative sum) or integrated values (``"phase"``).

Gaps and NaN (``nan_policy``): ``"raise"`` (default) raises
:class:`~imunav.errors.NonFiniteError` naming the first bad row and column;
``"segments"`` computes the sums of squared differences and their term counts
on every contiguous finite segment (and between time gaps when ``t`` is
given) and pools them, ``AVAR = sum of segment sums / sum of term counts``,
so no difference ever straddles a gap; the segments used are reported in the
result.  Nothing is dropped silently.

Speed: the phase of each channel is built once by a compensated running sum
(records are read in chunks, so a memory-mapped ``(1e8, 6)`` array needs one
float64 phase of one channel in memory at a time), and each statistic for
all tau is one parallel numba pass (:mod:`imunav.noise._allan_kernels`).

Confidence intervals: chi-squared with the equivalent degrees of freedom of
Greenhall & Riley (2003) for the noise type identified at each tau by the
lag-1 autocorrelation method (:mod:`imunav.noise.edf`).
"""

from __future__ import annotations

import mmap as _mmap
from dataclasses import dataclass, field
from typing import Any, Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.noise import _allan_kernels as _k
from imunav.noise.edf import ONE_SIGMA, chi2_interval, edf_greenhall, edf_totdev, noise_id_lag1
from imunav.results import Result

__all__ = ["AllanResult", "allan_deviation", "allan_variance", "tau_grid", "KINDS", "cluster_sizes"]

Kind = Literal["overlapping", "standard", "modified", "time", "hadamard", "overlapping_hadamard", "total"]
KINDS: tuple[str, ...] = ("overlapping", "standard", "modified", "time", "hadamard", "overlapping_hadamard", "total")
_ALIASES = {
    "oadev": "overlapping", "adev": "standard", "non-overlapping": "standard", "nonoverlapping": "standard",
    "mdev": "modified", "tdev": "time", "hdev": "hadamard", "ohdev": "overlapping_hadamard",
    "totdev": "total",
}
_CHUNK = 1 << 20


@dataclass(frozen=True)
class AllanResult(Result):
    """Result of :func:`allan_deviation`.

    Attributes
    ----------
    tau : numpy.ndarray
        (T,) cluster times, s.
    m : numpy.ndarray
        (T,) cluster sizes in samples (tau = m / fs).
    adev : numpy.ndarray
        (T,) or (T, C) deviation of the requested ``kind`` (same
        dimensionality as the input; unit ``units``, or the phase unit for
        ``kind="time"``).
    adev_lo, adev_hi : numpy.ndarray
        Confidence bounds at level ``ci`` (chi-squared, EDF).
    edf : numpy.ndarray
        Equivalent degrees of freedom used for the bounds.
    alpha : numpy.ndarray
        Rate-PSD noise exponent used for the EDF at each tau (integer).
    n_terms : numpy.ndarray
        (T,) or (T, C) number of squared differences averaged.
    n_samples : int
        Number of rate samples per channel.
    fs : float
        Sample rate, Hz.
    kind : str
        The statistic (see :data:`KINDS`).
    input : str
        ``"rate"``, ``"increment"`` or ``"phase"``.
    units : str
        Unit of the input samples.
    channels : tuple of str
        Channel names.
    ci : float
        Confidence level of ``adev_lo`` / ``adev_hi``.
    segments : tuple
        Per channel, (S, 2) half-open rate-sample ranges that were used.
    """

    tau: NDArray[np.float64]
    m: NDArray[np.int64]
    adev: NDArray[np.float64]
    adev_lo: NDArray[np.float64]
    adev_hi: NDArray[np.float64]
    edf: NDArray[np.float64]
    alpha: NDArray[np.float64]
    n_terms: NDArray[np.int64]
    n_samples: int
    fs: float
    kind: str = "overlapping"
    input: str = "rate"
    units: str = ""
    channels: tuple[str, ...] = ()
    ci: float = ONE_SIGMA
    segments: tuple[NDArray[np.int64], ...] = field(default_factory=tuple)

    @property
    def avar(self) -> NDArray[np.float64]:
        """Variance (deviation squared)."""
        return self.adev**2

    @property
    def n_channels(self) -> int:
        return 1 if self.adev.ndim == 1 else self.adev.shape[1]

    def channel(self, c: int | str) -> "AllanResult":
        """One channel as a 1-D result (by index or name).

        Parameters
        ----------
        c : int or str
            Channel index (0-based) or name (one of :attr:`channels`).

        Returns
        -------
        AllanResult
            The same statistics for that channel only (1-D arrays); ``self`` for a single-channel result.

        Raises
        ------
        InvalidInputError
            If the name is unknown or the index out of range.
        """
        if isinstance(c, str):
            if c not in self.channels:
                raise InvalidInputError(f"unknown channel {c!r}; channels are {self.channels}")
            c = self.channels.index(c)
        if self.adev.ndim == 1:
            if c != 0:
                raise InvalidInputError(f"channel index {c} out of range for a single-channel result")
            return self
        if not 0 <= c < self.adev.shape[1]:
            raise InvalidInputError(f"channel index {c} out of range 0..{self.adev.shape[1] - 1}")
        pick = lambda a: np.ascontiguousarray(a[:, c])  # noqa: E731
        return AllanResult(
            tau=self.tau, m=self.m, adev=pick(self.adev), adev_lo=pick(self.adev_lo), adev_hi=pick(self.adev_hi),
            edf=pick(self.edf), alpha=pick(self.alpha), n_terms=pick(self.n_terms), n_samples=self.n_samples,
            fs=self.fs, kind=self.kind, input=self.input, units=self.units,
            channels=(self.channels[c],) if self.channels else (), ci=self.ci,
            segments=(self.segments[c],) if self.segments else (),
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (lists of floats).

        Returns
        -------
        dict
            ``kind``, ``input``, ``units``, ``fs`` (Hz), ``n_samples``, ``ci``, ``channels``, the arrays ``tau`` (s),
            ``m``, ``adev``, ``adev_lo``, ``adev_hi`` (in ``units``), ``edf``, ``alpha``, ``n_terms`` as lists,
            and ``segments``.
        """
        return {
            "kind": self.kind, "input": self.input, "units": self.units, "fs": self.fs,
            "n_samples": self.n_samples, "ci": self.ci, "channels": list(self.channels),
            "tau": self.tau.tolist(), "m": self.m.tolist(), "adev": self.adev.tolist(),
            "adev_lo": self.adev_lo.tolist(), "adev_hi": self.adev_hi.tolist(), "edf": self.edf.tolist(),
            "alpha": self.alpha.tolist(), "n_terms": self.n_terms.tolist(),
            "segments": [s.tolist() for s in self.segments],
        }


# ---------------------------------------------------------------------------
def _max_m(kind: str, n_phase: int) -> int:
    if kind in ("overlapping", "standard", "total"):
        return (n_phase - 1) // 2
    return (n_phase - 1) // 3  # modified, time, hadamard family


def _log_grid(n: int, mmax: int, m0: int = 64) -> np.ndarray:
    """About n log-spaced cluster sizes in [1, mmax].

    Below m0 the log-spaced values are rounded; from m0 on, one octave of
    log-spaced integers is repeated by exact doubling, so the lag 2m of one
    tau is the lag m of another and the kernel reads each far stream once
    (about 30 % faster on long records)."""
    if mmax < 2 * m0 or n < 2:
        return np.unique(np.round(np.logspace(0, np.log10(mmax), max(n, 1))))
    per_oct = max(1, int(round(n / np.log2(mmax))))
    small = np.unique(np.round(np.logspace(0, np.log10(m0), int(per_oct * np.log2(m0)) + 1)))
    small = small[small < m0]
    base = np.unique(np.round(m0 * 2.0 ** (np.arange(per_oct) / per_oct)))
    parts = [small]
    b = base
    while b[0] <= mmax:
        parts.append(b[b <= mmax])
        b = b * 2
    return np.unique(np.concatenate(parts))


def cluster_sizes(taus: Any, fs: float, n_phase: int, kind: str = "overlapping") -> NDArray[np.int64]:
    """Cluster sizes m for a tau specification (see :func:`tau_grid`).

    Parameters
    ----------
    taus : str, tuple or array_like
        ``"octave"``, ``"decade"``, ``"all"``, ``"log"``, ``("log", n)`` or explicit cluster times, s.
    fs : float
        Sample rate, Hz.
    n_phase : int
        Number of phase points (rate samples + 1).
    kind : str
        Statistic (one of :data:`KINDS`): it sets the largest usable m, (n_phase - 1) // 2 for the Allan
        family, // 3 for the modified and Hadamard family.

    Returns
    -------
    numpy.ndarray of int64
        The cluster sizes m, increasing and unique (tau = m / fs).

    Raises
    ------
    InsufficientDataError
        If the record is too short for ``kind``, or an explicit tau exceeds the largest usable one.
    InvalidInputError
        If ``taus`` is not understood, or an explicit tau is not positive and finite or is below 1 / fs.
    """
    mmax = _max_m(kind, n_phase)
    if mmax < 1 or n_phase - 1 < _min_samples(kind):
        raise InsufficientDataError(
            f"{n_phase - 1} samples are too few for kind={kind!r}: need at least {_min_samples(kind)} samples"
        )
    if isinstance(taus, str):
        spec = taus.lower()
        if spec == "octave":
            ms = 2 ** np.arange(int(np.floor(np.log2(mmax))) + 1)
        elif spec == "decade":
            ms = np.array([k * 10**e for e in range(int(np.log10(mmax)) + 1) for k in (1, 2, 4)])
        elif spec == "all":
            ms = np.arange(1, mmax + 1)
        elif spec == "log":
            ms = _log_grid(100, mmax)
        else:
            raise InvalidInputError(
                f"taus={taus!r} not understood; use 'octave', 'decade', 'all', ('log', n) or an array of tau in s"
            )
    elif isinstance(taus, tuple) and len(taus) == 2 and isinstance(taus[0], str):
        if taus[0] != "log" or int(taus[1]) < 1:
            raise InvalidInputError(f"taus={taus!r}: the tuple form is ('log', n) with n >= 1 points")
        ms = _log_grid(int(taus[1]), mmax)
    else:
        t = np.atleast_1d(np.asarray(taus, dtype=float))
        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise InvalidInputError("taus must be positive finite cluster times in seconds (1-D)")
        ms = np.round(t * fs)
        if np.any(ms < 1):
            raise InvalidInputError(f"taus below one sample interval (1/fs = {1 / fs:g} s) are not possible")
        if np.any(ms > mmax):
            raise InsufficientDataError(
                f"tau up to {t.max():g} s requested but kind={kind!r} allows at most {mmax / fs:g} s "
                f"({mmax} samples) for this record; shorten taus or use a longer record"
            )
        ms = np.unique(ms)
    ms = ms[(ms >= 1) & (ms <= mmax)]
    return ms.astype(np.int64)


def _min_samples(kind: str) -> int:
    """Rate samples a statistic needs: two differences at tau0 (3 for the Allan family, 4 for the modified and
    Hadamard family, whose differences span one more sample)."""
    return 3 if kind in ("overlapping", "standard", "total") else 4


def tau_grid(n_samples: int, fs: float, taus: Any = "octave", kind: str = "overlapping") -> NDArray[np.float64]:
    """The tau values (s) :func:`allan_deviation` would use for a record of ``n_samples`` rate samples.

    Parameters
    ----------
    n_samples : int
        Number of rate samples per channel.
    fs : float
        Sample rate, Hz.
    taus : str, tuple or array_like
        ``"octave"`` (m = 1, 2, 4, ...), ``"decade"`` (1, 2, 4 x 10^k), ``"all"``, ``"log"`` / ``("log", n)``
        (n log-spaced, rounded to whole samples, duplicates removed) or explicit seconds (rounded to whole
        samples; the result reports the tau actually used).
    kind : str
        Statistic, one of :data:`KINDS` or an alias (``"oadev"``, ``"mdev"``, ...).

    Returns
    -------
    numpy.ndarray
        Cluster times tau = m / fs, s.

    Raises
    ------
    InvalidInputError
        If ``kind`` or ``taus`` is not understood.
    InsufficientDataError
        If the record is too short.
    """
    return cluster_sizes(taus, fs, n_samples + 1, _kind(kind)) / fs


def _kind(kind: str) -> str:
    k = _ALIASES.get(kind.lower(), kind.lower())
    if k not in KINDS:
        raise InvalidInputError(f"kind={kind!r} unknown; use one of {KINDS} (or {sorted(_ALIASES)})")
    return k


# ---------------------------------------------------------------------------
def _find_mmap(arr: np.ndarray) -> "_mmap.mmap | None":
    base: Any = arr
    while base is not None:
        mm = getattr(base, "_mmap", None)
        if isinstance(mm, _mmap.mmap):
            return mm
        base = getattr(base, "base", None)
    return None


def _release(arr: np.ndarray, view: np.ndarray | None = None) -> None:
    """Drop the pages of a memory-mapped input (all, or those under ``view``)
    from this process's resident set; the OS page cache keeps them, so
    streaming a huge file keeps the RSS bounded."""
    mm = _find_mmap(arr)
    if mm is None or not hasattr(mm, "madvise") or not hasattr(_mmap, "MADV_DONTNEED"):
        return
    try:
        if view is None or view.size == 0:
            mm.madvise(_mmap.MADV_DONTNEED)
            return
        start_map = np.frombuffer(mm, dtype=np.uint8).__array_interface__["data"][0]
        lo = view.__array_interface__["data"][0] - start_map
        hi = lo + (view.shape[0] - 1) * view.strides[0] + view.itemsize * (view.shape[1] if view.ndim > 1 else 1)
        page = _mmap.PAGESIZE
        lo = max(0, (lo // page) * page)
        hi = min(len(mm), hi)
        if hi > lo:
            mm.madvise(_mmap.MADV_DONTNEED, lo, hi - lo)
    except (OSError, ValueError, TypeError):  # pragma: no cover - platform dependent
        pass


def _channel_phase(
    x: np.ndarray, c: int, input: str, fs: float, gap_breaks: np.ndarray | None, nan_policy: str, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """Phase of channel c (float64, n+1 points) and its contiguous segments.

    Segments are half-open ranges [a, b) of rate samples; the phase points of
    segment [a, b) are phase[a : b+1].
    """
    n_rows = x.shape[0]
    if input == "phase":
        col = np.asarray(x[:, c], dtype=np.float64)
        y = np.diff(col) * fs
        n = y.size
        src = y[:, None]
        cc = 0
    else:
        n = n_rows
        src = x
        cc = c
    scale = (1.0 / fs) if input in ("rate", "phase") else 1.0
    phase = np.empty(n + 1)
    phase[0] = 0.0
    state = np.zeros(2)
    bad: list[np.ndarray] = []
    offset = None
    for i0 in range(0, n, _CHUNK):
        i1 = min(n, i0 + _CHUNK)
        rows = src[i0:i1]
        chunk = np.ascontiguousarray(rows[:, cc], dtype=np.float64)
        fin = np.isfinite(chunk)
        if not fin.all():
            badrows = np.flatnonzero(~fin) + i0
            if nan_policy == "raise":
                row = int(badrows[0]) + (1 if input == "phase" else 0)
                raise NonFiniteError(
                    f"non-finite value in row {row}, column {c} ({name}); pass nan_policy='segments' to analyse "
                    "the contiguous finite segments separately and pool them, or clean the record"
                )
            bad.append(badrows)
        if offset is None:
            # Any constant rate offset leaves every statistic unchanged (the
            # differences cancel it); removing it keeps the phase small so the
            # differences keep their precision over 1e8 samples.
            offset = float(np.mean(chunk[fin])) if fin.any() else 0.0
        _k.phase_accumulate(chunk, scale, offset, phase[i0 + 1 : i1 + 1], state)
        if src is x:
            _release(x, rows)
    breaks = [np.zeros(0, np.int64)] if not bad else [np.concatenate(bad)]
    segs = _segments(n, breaks[0], gap_breaks)
    return phase, segs


def _segments(n: int, bad_rows: np.ndarray, gap_breaks: np.ndarray | None) -> np.ndarray:
    """Half-open segments [a, b) of rate samples without bad rows, not crossing
    time gaps (``gap_breaks`` are the indices k where a gap lies between k-1 and k)."""
    if bad_rows.size == 0 and (gap_breaks is None or len(gap_breaks) == 0):
        return np.array([[0, n]], dtype=np.int64)
    ok = np.ones(n, dtype=bool)
    if bad_rows.size:
        ok[bad_rows] = False
    edges = np.zeros(n + 1, dtype=bool)
    if gap_breaks is not None and len(gap_breaks):
        edges[np.asarray(gap_breaks, dtype=np.int64)] = True
    idx = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(np.int8), [0]))) != 0)
    segs = []
    for a0, b0 in zip(idx[0::2], idx[1::2]):
        cut = np.flatnonzero(edges[a0 + 1 : b0]) + a0 + 1
        bounds = np.concatenate(([a0], cut, [b0]))
        segs.extend((int(s0), int(s1)) for s0, s1 in zip(bounds[:-1], bounds[1:]))
    return np.array(segs, dtype=np.int64).reshape(-1, 2)


def _sums_for(phase: np.ndarray, ms: np.ndarray, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Sums of squared differences and term counts for one contiguous phase."""
    n = phase.size
    sums = np.zeros(ms.size)
    counts = np.zeros(ms.size, dtype=np.int64)
    if kind in ("overlapping", "standard"):
        ok = ms <= (n - 1) // 2
        if ok.any():
            sums[ok] = _k.diff_sums(phase, ms[ok], 2, kind == "overlapping")
        counts[ok] = (n - 2 * ms[ok]) if kind == "overlapping" else ((n - 1) // ms[ok] - 1)
    elif kind in ("hadamard", "overlapping_hadamard"):
        ok = ms <= (n - 1) // 3
        if ok.any():
            sums[ok] = _k.diff_sums(phase, ms[ok], 3, kind == "overlapping_hadamard")
        counts[ok] = (n - 3 * ms[ok]) if kind == "overlapping_hadamard" else ((n - 1) // ms[ok] - 2)
    elif kind in ("modified", "time"):
        for j, m in enumerate(ms):
            if n - 3 * m + 1 >= 1:
                sums[j] = _k.mod_sum(phase, int(m))
                counts[j] = n - 3 * m + 1
    else:  # total
        ok = (ms <= n - 1) & (n >= 3)
        if ok.any():
            sums[ok] = _k.tot_sums(phase, ms[ok])
        counts[ok] = n - 2
    return sums, counts


def _edf_for(kind: str, alpha: int, m: int, n_phase: int) -> float:
    if kind == "total":
        return edf_totdev(n_phase, m, alpha)
    d = 3 if kind in ("hadamard", "overlapping_hadamard") else 2
    lo = -4 if d == 3 else -2
    a = int(min(2, max(lo, alpha)))
    overlapping = kind in ("overlapping", "modified", "time", "overlapping_hadamard")
    modified = kind in ("modified", "time")
    return edf_greenhall(a, d, int(m), int(n_phase), overlapping, modified)


def check_rows_are_samples(shape: tuple[int, ...], name: str = "x") -> None:
    """Refuse a (C, N) array given where (N, C) is expected: more columns (channels) than rows (samples).

    A (6, N) recording would otherwise be taken as N channels of 6 samples each.

    Parameters
    ----------
    shape : tuple of int
        Shape of the array.
    name : str
        Name of the argument, for the message.

    Raises
    ------
    ShapeError
        If the array is 2-D with more columns than rows; the message suggests ``name.T``.
    """
    if len(shape) == 2 and shape[1] > shape[0]:
        raise ShapeError(f"{name} has shape {shape}: {shape[1]} channels of {shape[0]} samples each; samples go in "
                         f"rows, channels in columns, so it looks transposed: pass {name}.T (shape {shape[::-1]})")


def allan_deviation(
    x: ArrayLike,
    fs: float,
    taus: Any = "octave",
    kind: str = "overlapping",
    *,
    input: Literal["rate", "increment", "phase"] = "rate",
    t: ArrayLike | None = None,
    nan_policy: Literal["raise", "segments"] = "raise",
    ci: float = ONE_SIGMA,
    alpha: int | None = None,
    units: str = "",
    channels: Sequence[str] | None = None,
) -> AllanResult:
    """Allan-family deviation of every channel of a recording in one call.

    Parameters
    ----------
    x : array_like, (N,) or (N, C)
        Rates (``input="rate"``), per-sample increments (``"increment"``:
        delta-angle / delta-velocity) or integrated values (``"phase"``).  May
        be a ``numpy.memmap`` (read in chunks; memory ~ 8 N bytes).
    fs : float
        Sample rate, Hz (tau0 = 1/fs).
    taus : str, tuple or array_like
        ``"octave"``, ``"decade"``, ``"all"``, ``"log"``, ``("log", n)`` or an array of cluster times, s;
        see :func:`tau_grid`.
    kind : str
        ``"overlapping"`` (default), ``"standard"``, ``"modified"``, ``"time"``,
        ``"hadamard"``, ``"overlapping_hadamard"``, ``"total"`` (aliases
        ``"oadev"``, ``"adev"``, ``"mdev"``, ``"tdev"``, ``"hdev"``, ``"ohdev"``,
        ``"totdev"``).
    input : {"rate", "increment", "phase"}
        What ``x`` holds: rates, per-sample increments, or their integral (phase).
    t : array_like (N,), optional
        Time stamps; gaps (steps > 1.5/fs) split the record into segments
        (``nan_policy="segments"``) or raise.
    nan_policy : {"raise", "segments"}
        What to do with NaN samples and time gaps; see the module docstring.
    ci : float
        Confidence level of ``adev_lo``/``adev_hi`` (default 68.27 %).
    alpha : int, optional
        Force the noise type used for the EDF (rate-PSD exponent) instead of
        identifying it at each tau.
    units : str
        Unit of the rate, recorded in the result (e.g. ``"rad/s"``).
    channels : sequence of str, optional
        Channel names.

    Returns
    -------
    AllanResult
        Deviations, confidence bounds and EDF at each tau (s), in the unit of ``x`` (phase unit for TDEV).

    Raises
    ------
    InvalidInputError
        If ``input``, ``nan_policy``, ``kind`` or ``taus`` is not understood, ``fs`` is not positive, ``ci``
        is outside (0, 1), ``x`` is not real numbers (text, complex), ``t`` is not strictly increasing, or
        (``nan_policy="raise"``) the time stamps have a gap.
    ShapeError
        If ``x`` is not (N,) / (N, C) or looks transposed, or ``t`` / ``channels`` do not match it.
    NonFiniteError
        If ``x`` has NaN or infinite values and ``nan_policy="raise"``.
    InsufficientDataError
        If the record is too short for one difference or for the requested taus.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).normal(0, 1.0, 100_000)    # white rate, N = 1/sqrt(fs)
    >>> r = allan_deviation(y, fs=100.0)
    >>> bool(abs(r.adev[0] * np.sqrt(r.tau[0]) / 0.1 - 1) < 0.01)
    True
    """
    kind = _kind(kind)
    if input not in ("rate", "increment", "phase"):
        raise InvalidInputError(f"input={input!r}; use 'rate', 'increment' or 'phase'")
    if nan_policy not in ("raise", "segments"):
        raise InvalidInputError(f"nan_policy={nan_policy!r}; use 'raise' or 'segments'")
    if not (np.isfinite(fs) and fs > 0):
        raise InvalidInputError(f"fs must be a positive finite sample rate in Hz, got {fs!r}")
    if not 0.0 < ci < 1.0:
        raise InvalidInputError(f"ci must be a probability in (0, 1), got {ci!r}")
    arr = x if isinstance(x, np.ndarray) else np.asarray(x)  # its own dtype: text or complex numbers are refused
    one_d = arr.ndim == 1
    if arr.ndim not in (1, 2):
        raise ShapeError(f"x must be (N,) or (N, C), got shape {arr.shape}")
    a2 = arr[:, None] if one_d else arr
    check_rows_are_samples(a2.shape, "x")
    if not np.issubdtype(a2.dtype, np.number) or np.iscomplexobj(a2):
        raise InvalidInputError(f"x must hold real numbers (a sensor's samples), got dtype {a2.dtype}")
    n_rows, n_ch = a2.shape
    n = n_rows - 1 if input == "phase" else n_rows
    if n < _min_samples(kind):
        need = _min_samples(kind) + (1 if input == "phase" else 0)
        raise InsufficientDataError(
            f"x: need at least {need} samples (got {n_rows}) for kind={kind!r}: two differences at the shortest "
            "tau (one alone has one degree of freedom: the 68 % interval of the deviation spans a factor of 10)"
        )
    names = tuple(channels) if channels is not None else tuple(f"ch{i}" for i in range(n_ch))
    if len(names) != n_ch:
        raise ShapeError(f"{len(names)} channel names given for {n_ch} columns")

    gap_breaks = None
    if t is not None:
        tt = np.asarray(t, dtype=float)
        if tt.shape != (n_rows,):
            raise ShapeError(f"t must have shape ({n_rows},) like x's rows, got {tt.shape}")
        dt = np.diff(tt)
        if not np.all(np.isfinite(tt)) or np.any(dt <= 0):
            k = int(np.flatnonzero(~(dt > 0))[0]) + 1 if np.any(~(dt > 0)) else 0
            raise InvalidInputError(f"t must be finite and strictly increasing (problem at row {k})")
        gaps = np.flatnonzero(dt > 1.5 / fs) + 1
        if gaps.size:
            if nan_policy == "raise":
                raise InvalidInputError(
                    f"time gap of {dt[gaps[0] - 1]:.6g} s before row {int(gaps[0])} (sample interval {1 / fs:.6g} s); "
                    "pass nan_policy='segments' to analyse the contiguous segments and pool them"
                )
            gap_breaks = gaps - (1 if input == "phase" else 0)

    ms = cluster_sizes(taus, fs, n + 1, kind)
    nt = ms.size
    dev = np.full((nt, n_ch), np.nan)
    edf = np.full((nt, n_ch), np.nan)
    alph = np.full((nt, n_ch), np.nan)
    nterm = np.zeros((nt, n_ch), dtype=np.int64)
    segs_all = []
    tau = ms / fs
    phase = ph = ph_long = None
    for c in range(n_ch):
        phase = ph = ph_long = None  # free the previous channel's phase (and views of it) first
        phase, segs = _channel_phase(a2, c, input, fs, gap_breaks, nan_policy, names[c])
        segs_all.append(segs)
        tot_s = np.zeros(nt)
        tot_n = np.zeros(nt, dtype=np.int64)
        edf_c = np.zeros(nt)
        al_c = np.full(nt, np.nan)
        longest = segs[np.argmax(segs[:, 1] - segs[:, 0])] if segs.size else None
        for s0, s1 in segs:
            ph = phase[s0 : s1 + 1]
            if ph.size < 3:
                continue
            s, k = _sums_for(ph, ms, kind)
            tot_s += s
            tot_n += k
        # noise identification on the longest segment, then EDF per segment (added)
        if longest is not None:
            ph_long = phase[longest[0] : longest[1] + 1]
            last = 0 if alpha is None else int(alpha)
            dmax = 3 if kind in ("hadamard", "overlapping_hadamard") else 2
            for j, m in enumerate(ms):
                if alpha is None:
                    a_id = noise_id_lag1(ph_long, int(m), dmax=dmax)
                    if a_id is not None:
                        last = a_id
                al_c[j] = last
            for s0, s1 in segs:
                npts = s1 - s0 + 1
                for j, m in enumerate(ms):
                    if npts - 1 >= (2 if kind in ("overlapping", "standard", "total") else 3) * m:
                        e = _edf_for(kind, int(al_c[j]), int(m), int(npts))
                        if np.isfinite(e):
                            edf_c[j] += e
        with np.errstate(invalid="ignore", divide="ignore"):
            var = tot_s / np.where(tot_n > 0, tot_n, 1)
            if kind in ("overlapping", "standard", "total"):
                var = var / (2.0 * tau**2)
            elif kind in ("hadamard", "overlapping_hadamard"):
                var = var / (6.0 * tau**2)
            else:
                var = var / (2.0 * ms.astype(float) ** 2 * tau**2)
                if kind == "time":
                    var = var * tau**2 / 3.0
        var[tot_n == 0] = np.nan
        dev[:, c] = np.sqrt(var)
        edf[:, c] = np.where(tot_n > 0, edf_c, np.nan)
        alph[:, c] = al_c
        nterm[:, c] = tot_n
    phase = ph = ph_long = None
    lo, hi = chi2_interval(dev, edf, ci)
    sq = (lambda a: a[:, 0]) if one_d else (lambda a: a)
    return AllanResult(
        tau=tau, m=ms, adev=sq(dev), adev_lo=sq(lo), adev_hi=sq(hi), edf=sq(edf), alpha=sq(alph),
        n_terms=sq(nterm), n_samples=int(n), fs=float(fs), kind=kind, input=input, units=units,
        channels=names, ci=float(ci), segments=tuple(segs_all),
    )


def allan_variance(x: ArrayLike, fs: float, taus: Any = "octave", kind: str = "overlapping", **kw: Any):
    """``(tau, avar)`` of :func:`allan_deviation` (same arguments).

    Parameters
    ----------
    x : array_like, shape (N,) or (N, C)
        Rates (rad/s, m/s^2, ...), increments or phase, per ``input``.
    fs : float
        Sample rate, Hz.
    taus : str, tuple or array_like
        Tau specification (see :func:`tau_grid`).
    kind : str
        Statistic (see :data:`KINDS`).
    **kw
        Further keywords of :func:`allan_deviation` (``input``, ``t``, ``nan_policy``, ``ci``, ...).

    Returns
    -------
    tau : numpy.ndarray, shape (T,)
        Cluster times, s.
    avar : numpy.ndarray, shape (T,) or (T, C)
        The variance (deviation squared), in the square of the input's unit.
    """
    r = allan_deviation(x, fs, taus, kind, **kw)
    return r.tau, r.avar
