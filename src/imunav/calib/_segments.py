"""Steady-segment detection and per-segment means (internal).

A calibration session alternates steady segments (static poses, or constant
table rates) with transitions.  A sample is *steady* when the moving variance
of every channel over ``window_s`` stays below a threshold; transitions are
excluded because any window overlapping one has a large variance, and
``trim_s`` more is removed at both ends of every segment.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from imunav.calib._kernels import moving_variance_kernel
from imunav.errors import InsufficientDataError, InvalidInputError, SaturationError

Array = NDArray[np.float64]


def moving_variance(x: Array, n: int) -> Array:
    """Centred moving variance of each column over ``n`` samples (edges use shorter windows)."""

    return moving_variance_kernel(np.ascontiguousarray(x, dtype=float), int(n))


def steady_segments(
    x: Array,
    fs: float,
    *,
    window_s: float = 1.0,
    threshold: float | Array | None = None,
    factor: float = 6.0,
    min_duration_s: float = 2.0,
    trim_s: float = 0.0,
) -> tuple[NDArray[np.int64], Array]:
    """Half-open index intervals ``(K, 2)`` where ``x`` (N, m) is steady.

    ``threshold`` (per column) defaults to ``factor`` × the median moving
    variance, which is the steady-state noise variance when most of the
    session is steady (true of calibration sessions).
    """
    n = max(int(round(window_s * fs)), 8)  # a few samples at least: the variance of 2 samples is too noisy
    v = moving_variance(x, n)
    if threshold is None:
        # floor: noise-free (simulated) data have a rounding-level variance only
        thr = np.maximum(factor * np.median(v, axis=0), 1e-9 * np.mean(x**2, axis=0) + np.finfo(float).tiny)
    else:
        thr = np.broadcast_to(np.asarray(threshold, float), (x.shape[1],))
    mask = np.all(v <= thr, axis=1)
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    trim = int(round(trim_s * fs))
    starts, stops = starts + trim, stops - trim
    keep = (stops - starts) >= max(int(round(min_duration_s * fs)), 1)
    return np.stack([starts[keep], stops[keep]], axis=1).astype(np.int64), thr


def segment_means(x: Array, segs: NDArray[np.int64]) -> tuple[Array, Array, NDArray[np.int64]]:
    """Mean, standard deviation and sample count of ``x`` in every segment."""
    m = np.array([x[a:b].mean(0) for a, b in segs])
    s = np.array([x[a:b].std(0, ddof=1) if b - a > 1 else np.zeros(x.shape[1]) for a, b in segs])
    return m, s, (segs[:, 1] - segs[:, 0]).astype(np.int64)


def assign_to_windows(
    steady: NDArray[np.int64], t: Array, windows: Array, *, what: str, min_samples: int = 2
) -> NDArray[np.int64]:
    """For each hinted time window (K, 2), the longest steady piece inside it.

    Raises :class:`InsufficientDataError` naming the windows with no steady data.
    """
    out = np.zeros((len(windows), 2), dtype=np.int64)
    missing = []
    for k, (t0, t1) in enumerate(windows):
        i0, i1 = np.searchsorted(t, t0, "left"), np.searchsorted(t, t1, "left")
        a = np.maximum(steady[:, 0], i0)
        b = np.minimum(steady[:, 1], i1)
        ln = b - a
        if ln.size == 0 or ln.max() < min_samples:
            missing.append(k)
            continue
        j = int(np.argmax(ln))
        out[k] = (a[j], b[j])
    if missing:
        raise InsufficientDataError(
            f"{what}: no steady data inside hinted windows {missing[:10]} (of {len(windows)}); "
            "check the time hints or lower the detector's window/threshold"
        )
    return out


def check_saturation(x: Array, full_scale: float | None, segs: NDArray[np.int64], *, what: str) -> None:
    """Refuse segments that touch the full-scale range."""
    if full_scale is None:
        return
    for k, (a, b) in enumerate(segs):
        if np.any(np.abs(x[a:b]) >= full_scale):
            raise SaturationError(
                f"{what}: segment {k} (samples {a}..{b}) reaches the full-scale range {full_scale:g}; "
                "the reference input exceeds the sensor range - drop this position or use a larger range"
            )


def as_time(t: Array | None, n: int, fs: float | None) -> tuple[Array, float]:
    """Time vector and sampling rate from either."""
    if t is None:
        if fs is None or fs <= 0:
            raise InvalidInputError("give the time vector t or a positive sampling rate fs")
        return np.arange(n) / fs, float(fs)
    t = np.asarray(t, dtype=float)
    if t.shape != (n,):
        raise InvalidInputError(f"t has shape {t.shape}, expected ({n},)")
    return t, float(fs) if fs else float(1.0 / np.median(np.diff(t)))
