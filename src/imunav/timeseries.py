"""Recordings: :class:`ImuData` and its validation.

An :class:`ImuData` holds one IMU recording in SI units: time ``t`` (s,
strictly increasing), angular rate ``gyro`` (rad/s, body FRD), specific force
``accel`` (m/s², body FRD; at rest and level ``(0, 0, -g)``), optionally the
magnetic field ``mag`` (kept in ``mag_unit``) and the temperature ``temp``
(°C).  The constructor validates everything and raises an
:mod:`imunav.errors` exception naming the rows and columns at fault.  Units
other than SI are declared only at the edge, in :meth:`ImuData.from_arrays`
(deg/s, g, raw counts with per-axis scale and offset, ms time stamps ...).

Also here: :meth:`ImuData.gaps` (intervals longer than 1.5 × the median),
:func:`static_intervals` (moving-variance rest detector, numba kernel, 1e7
samples in seconds), :func:`detect_saturation` (samples at a full scale or
stuck at a rail value) and :func:`describe` (the summary behind
``imunav info``).  Files are read and written by :mod:`imunav.io`.
"""

from __future__ import annotations

import dataclasses
import functools
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._timeseries_kernels import covered, moving_var_cols, moving_variance_kernel, runs
from imunav.errors import (
    ImunavWarning,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    SaturationError,
    ShapeError,
    TimeOrderError,
    UnitError,
)
from imunav.provenance import add_step
from imunav.units import DEG as _DEG
from imunav.units import to_si

__all__ = [
    "ImuData",
    "Gap",
    "StaticIntervals",
    "static_intervals",
    "moving_variance",
    "Saturation",
    "detect_saturation",
    "RecordingSummary",
    "describe",
    "rest_force_problem",
    "G_REF",
]

NanPolicy = Literal["raise", "drop", "interpolate"]
#: Most samples :meth:`ImuData.resample` makes beyond 100 x the input's (memory guard).
_RESAMPLE_MAX = 10_000_000
_VECTOR_FIELDS = ("gyro", "accel", "mag")


def _rows(mask: NDArray[np.bool_], limit: int = 10) -> str:
    idx = np.flatnonzero(mask)
    s = ", ".join(map(str, idx[:limit].tolist()))
    return s + (f", ... ({idx.size} rows in all)" if idx.size > limit else "")


@dataclass(frozen=True)
class Gap:
    """A gap in the time stamps: ``t[index + 1] - t[index]`` is ``length_s``.

    Attributes
    ----------
    index : int
        Row before the gap.
    t_start : float
        ``t[index]``, s.
    length_s : float
        Length of the interval, s.
    missing_samples : int
        ``round(length_s / median interval) - 1``: samples that would fill it at the nominal rate.
    """

    index: int
    t_start: float
    length_s: float
    missing_samples: int


@dataclass(frozen=True, eq=False)
class ImuData:
    """One IMU recording in SI units (see module docstring).

    Parameters
    ----------
    t : array_like, shape (N,)
        Time, s, finite and strictly increasing.
    gyro : array_like, shape (N, 3)
        Angular rate, rad/s, body FRD.
    accel : array_like, shape (N, 3)
        Specific force, m/s², body FRD.
    mag : array_like, shape (N, 3), optional
        Magnetic field, in ``mag_unit``.
    temp : array_like, shape (N,), optional
        Temperature, °C.
    mag_unit : str
        Unit of ``mag`` (kept as given), default ``"uT"``.
    meta : dict
        Free-form metadata (source file, sensor, what a NaN policy did, ...).
    """

    t: NDArray[np.float64]
    gyro: NDArray[np.float64]
    accel: NDArray[np.float64]
    mag: NDArray[np.float64] | None = None
    temp: NDArray[np.float64] | None = None
    mag_unit: str = "uT"
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=np.float64, copy=True)
        if t.ndim != 1:
            raise ShapeError(f"t must be 1-D (N,), got shape {t.shape}")
        n = t.shape[0]
        if n < 1:
            raise ShapeError("the recording is empty: t has no samples")
        object.__setattr__(self, "t", t)
        for name in _VECTOR_FIELDS:
            v = getattr(self, name)
            if v is None:
                continue
            a = np.array(v, dtype=np.float64, copy=True)
            if a.ndim != 2 or a.shape[1] != 3:
                hint = f"; it looks transposed: pass {name}.T" if a.shape == (3, n) else ""
                raise ShapeError(f"{name} must have shape (N, 3) = ({n}, 3), got {a.shape}{hint}")
            if a.shape[0] != n:
                raise ShapeError(f"{name} has {a.shape[0]} rows but t has {n}; every channel needs one row per time stamp")
            object.__setattr__(self, name, a)
        if self.temp is not None:
            a = np.array(self.temp, dtype=np.float64, copy=True)
            if a.ndim == 2 and a.shape[1] == 1:
                a = a[:, 0]
            if a.shape != (n,):
                raise ShapeError(f"temp must have shape (N,) = ({n},), got {a.shape}")
            object.__setattr__(self, "temp", a)
        object.__setattr__(self, "meta", dict(self.meta or {}))
        self._check_finite()
        self._check_time()
        for name in (*_VECTOR_FIELDS, "temp"):
            a = getattr(self, name)
            if a is not None:
                a.setflags(write=False)
        t.setflags(write=False)

    # -- validation ---------------------------------------------------------
    def _check_finite(self) -> None:
        bad_t = ~np.isfinite(self.t)
        if bad_t.any():
            raise NonFiniteError(f"t has non-finite values at rows {_rows(bad_t)}; time stamps must all be finite")
        for name in (*_VECTOR_FIELDS, "temp"):
            a = getattr(self, name)
            if a is None:
                continue
            bad = ~np.isfinite(a)
            if bad.any():
                rows = bad if bad.ndim == 1 else bad.any(axis=1)
                if bad.ndim == 1:
                    cols = f"column {name}"
                else:
                    cols = "columns " + ", ".join(f"{name}_{'xyz'[j]}" for j in np.flatnonzero(bad.any(axis=0)))
                raise NonFiniteError(
                    f"{name} has NaN/inf at rows {_rows(rows)} ({cols}). Pass nan_policy='drop' or "
                    "'interpolate' to ImuData.from_arrays / read_imu to handle them explicitly"
                )

    def _check_time(self) -> None:
        if self.t.size < 2:
            return
        d = np.diff(self.t)
        dup = d == 0
        if dup.any():
            raise TimeOrderError(
                f"duplicate time stamps at rows {_rows(dup)} (t[i+1] == t[i]); remove duplicated samples first"
            )
        back = d < 0
        if back.any():
            raise TimeOrderError(
                f"time goes backwards at rows {_rows(back)} (t[i+1] < t[i]); sort the recording or fix the clock"
            )

    # -- construction at the edge --------------------------------------------
    @classmethod
    def from_arrays(
        cls,
        t: ArrayLike | None,
        gyro: ArrayLike,
        accel: ArrayLike,
        mag: ArrayLike | None = None,
        temp: ArrayLike | None = None,
        *,
        time_unit: str = "s",
        gyro_unit: str = "rad/s",
        accel_unit: str = "m/s^2",
        gyro_scale: float | ArrayLike | None = None,
        accel_scale: float | ArrayLike | None = None,
        gyro_offset: float | ArrayLike = 0.0,
        accel_offset: float | ArrayLike = 0.0,
        mag_unit: str = "uT",
        nan_policy: NanPolicy = "raise",
        meta: dict[str, Any] | None = None,
        fs: float | None = None,
        t0: float = 0.0,
    ) -> "ImuData":
        """Build from arrays in declared units, converting to SI.

        ``gyro_unit`` may be ``"rad/s"``, ``"deg/s"``, ``"rpm"`` or
        ``"counts"`` (then ``gyro_scale`` in rad/s per count is required);
        ``accel_unit`` ``"m/s^2"``, ``"g"``, ``"mg"`` or ``"counts"`` (with
        ``accel_scale`` in m/s² per count); with counts, ``value_si =
        (counts - offset) * scale`` where scale and offset are scalars or
        per-axis (3,) arrays.  ``nan_policy``: ``"raise"``
        (default) names the offending rows; ``"drop"`` removes rows with any
        NaN; ``"interpolate"`` fills NaN samples linearly in time.  What was
        done is recorded in ``meta["nan_policy"]`` (policy, affected rows and
        columns).  With ``t=None`` the samples are at ``t0 + k / fs``.

        Parameters
        ----------
        t : array_like, shape (N,), or None
            Time stamps in ``time_unit`` (None: from ``fs`` and ``t0``).
        gyro : array_like, shape (N, 3)
            Angular rate in ``gyro_unit``.
        accel : array_like, shape (N, 3)
            Specific force in ``accel_unit``.
        mag : array_like, shape (N, 3), optional
            Magnetic field in ``mag_unit`` (kept as given).
        temp : array_like, shape (N,), optional
            Temperature, °C.
        time_unit : str
            Unit of ``t`` (``"s"``, ``"ms"``, ``"us"``, ``"ns"``, ...; :func:`imunav.units.to_si`).
        gyro_unit : str
            ``"rad/s"``, ``"deg/s"``, ``"rpm"`` or ``"counts"``.
        accel_unit : str
            ``"m/s^2"``, ``"g"``, ``"mg"`` or ``"counts"``.
        gyro_scale : float or array_like of shape (3,), optional
            rad/s per count (required with ``gyro_unit="counts"``); one value is positive (a negative one would
            mirror the triad), per-axis values may carry signs.
        accel_scale : float or array_like of shape (3,), optional
            m/s² per count (required with ``accel_unit="counts"``), signs as ``gyro_scale``.
        gyro_offset, accel_offset : float or array_like of shape (3,)
            Zero offset in counts, subtracted before scaling.
        mag_unit : str
            Unit of ``mag``.
        nan_policy : {"raise", "drop", "interpolate"}
            What to do with NaN samples in the channels.
        meta : dict, optional
            Free-form metadata; unit conversion and NaN handling are recorded in it.
        fs : float, optional
            Sample rate, Hz, when ``t`` is None (not both).
        t0 : float
            Time of the first sample, s, when ``t`` is None.

        Returns
        -------
        ImuData
            The recording in SI units.

        Raises
        ------
        InvalidInputError
            If ``nan_policy`` is unknown, ``t`` is None without a positive ``fs``, or both ``t`` and ``fs`` are
            given.
        UnitError
            If a unit is unknown, counts come without a scale, or one scale for the three axes is negative.

        Examples
        --------
        >>> d = ImuData.from_arrays(None, [[0, 0, 1.0]] * 4, [[0, 0, -1.0]] * 4,
        ...                         fs=100.0, gyro_unit="deg/s", accel_unit="g")
        >>> round(float(d.accel[0, 2]), 5), d.fs
        (-9.80665, 100.0)
        """
        if nan_policy not in ("raise", "drop", "interpolate"):
            raise InvalidInputError(f"nan_policy must be 'raise', 'drop' or 'interpolate', not {nan_policy!r}")
        if t is None:
            if fs is None or not np.isfinite(fs) or fs <= 0:
                raise InvalidInputError("t is None: give the sampling rate fs (Hz, > 0) so that t = t0 + k / fs")
            t = t0 + np.arange(np.shape(gyro)[0], dtype=np.float64) / float(fs)
        elif fs is not None:
            raise InvalidInputError("give either t or fs, not both")
        ts = to_si(t, time_unit, "time")
        g = _vector_to_si(gyro, gyro_unit, "angular_rate", gyro_scale, gyro_offset, "gyro")
        a = _vector_to_si(accel, accel_unit, "acceleration", accel_scale, accel_offset, "accel")
        m = None if mag is None else np.asarray(mag, dtype=float)
        tp = None if temp is None else np.asarray(temp, dtype=float)
        meta = dict(meta or {})
        declared = {"time": time_unit, "gyro": gyro_unit, "accel": accel_unit}
        if declared != {"time": "s", "gyro": "rad/s", "accel": "m/s^2"}:
            meta.setdefault("units_in", declared)
            params: dict[str, Any] = {"from": declared, "to": {"time": "s", "gyro": "rad/s", "accel": "m/s^2"}}
            for name, v in (("gyro_scale", gyro_scale), ("accel_scale", accel_scale), ("gyro_offset", gyro_offset),
                            ("accel_offset", accel_offset)):
                if v is not None and np.any(np.asarray(v) != 0):
                    params[name] = np.asarray(v, dtype=float).tolist()
            meta = add_step(meta, "convert_units", params)
        if nan_policy != "raise":
            ts, g, a, m, tp, info = _apply_nan_policy(ts, g, a, m, tp, nan_policy)
            meta["nan_policy"] = info
        return cls(ts, g, a, m, tp, mag_unit=mag_unit, meta=meta)

    # -- properties -----------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    @property
    def dt(self) -> NDArray[np.float64]:
        """Sample intervals ``t[i+1] - t[i]`` (N-1,)."""
        return np.diff(self.t)

    @functools.cached_property
    def fs(self) -> float:
        """Nominal sample rate (Hz): 1 / median interval."""
        if self.n < 2:
            raise InvalidInputError("a single-sample recording has no sample rate")
        return float(1.0 / np.median(self.dt))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` in s."""
        return float(self.t[-1] - self.t[0])

    def __len__(self) -> int:
        return self.n

    def __repr__(self) -> str:
        parts = [f"n={self.n}"]
        if self.n >= 2:
            parts += [f"fs={self.fs:.6g} Hz", f"duration={self.duration:.6g} s"]
        parts.append("channels=gyro,accel" + (",mag" if self.mag is not None else "") + (",temp" if self.temp is not None else ""))
        if self.mag is not None:
            parts.append(f"mag_unit={self.mag_unit!r}")
        if self.meta:
            parts.append(f"meta_keys={sorted(self.meta)}")
        return f"ImuData({', '.join(parts)})"

    def gaps(self, factor: float = 1.5) -> list[Gap]:
        """Intervals longer than ``factor`` × the median interval.

        Parameters
        ----------
        factor : float
            Threshold as a multiple of the median sample interval.

        Returns
        -------
        list of Gap
            In time order; empty for fewer than 3 samples.
        """
        if self.n < 3:
            return []
        d = self.dt
        med = float(np.median(d))
        idx = np.flatnonzero(d > factor * med)
        return [
            Gap(int(i), float(self.t[i]), float(d[i]), int(round(d[i] / med)) - 1)
            for i in idx
        ]

    # -- views / copies -------------------------------------------------------
    def with_(self, **changes: Any) -> "ImuData":
        """Copy with some fields replaced (validated again).

        Parameters
        ----------
        **changes
            New values of fields (``t``, ``gyro``, ``accel``, ``mag``, ``temp``, ``mag_unit``, ``meta``).

        Returns
        -------
        ImuData
            The copy.
        """
        return dataclasses.replace(self, **changes)

    def slice(self, start: int | None = None, stop: int | None = None) -> "ImuData":
        """Samples ``start:stop`` (half-open, Python indexing).

        Parameters
        ----------
        start, stop : int, optional
            Row indices (negative counts from the end; None: the ends).

        Returns
        -------
        ImuData
            The rows, with a copy of ``meta``.
        """
        s = np.s_[start:stop]
        return ImuData(
            self.t[s],
            self.gyro[s],
            self.accel[s],
            None if self.mag is None else self.mag[s],
            None if self.temp is None else self.temp[s],
            mag_unit=self.mag_unit,
            meta=dict(self.meta),
        )

    def time_slice(self, t0: float | None = None, t1: float | None = None) -> "ImuData":
        """Samples with ``t0 <= t < t1``.

        Parameters
        ----------
        t0, t1 : float, optional
            Time bounds, s (None: the ends).

        Returns
        -------
        ImuData
            The samples in the interval.

        Raises
        ------
        InvalidInputError
            If no sample lies in the interval.
        """
        i0 = 0 if t0 is None else int(np.searchsorted(self.t, t0, side="left"))
        i1 = self.n if t1 is None else int(np.searchsorted(self.t, t1, side="left"))
        if i1 <= i0:
            raise InvalidInputError(f"no samples in [{t0}, {t1}); the recording spans [{self.t[0]}, {self.t[-1]}]")
        return self.slice(i0, i1)

    def window(self, start: float | None = None, end: float | None = None) -> "ImuData":
        """The samples from ``start`` to ``end`` seconds after the recording's first sample.

        Times count from ``t[0]`` whatever the clock (a PX4 log's boot time, a GPS week): ``start=60,
        end=120`` is the second minute of the recording.  A ``window`` step in ``meta["provenance"]``
        records the cut (in seconds from the start and on the recording's clock).

        Parameters
        ----------
        start, end : float, optional
            Window, s from the first sample (``start <= t - t[0] < end``; None: the ends).

        Returns
        -------
        ImuData
            The samples of the window (the recording itself when both are None).

        Raises
        ------
        InvalidInputError
            If a bound is not a finite number, ``start`` is negative or not before ``end``, or the window
            holds fewer than 2 samples (the message gives the recording's duration).
        """
        if start is None and end is None:
            return self
        for name, v in (("start", start), ("end", end)):
            if v is not None and not np.isfinite(v):
                raise InvalidInputError(f"window {name}={v}: give a finite number of seconds from the recording's start")
        if start is not None and start < 0:
            raise InvalidInputError(f"window start {start:g} s is before the recording's start (0 s)")
        if start is not None and end is not None and end <= start:
            raise InvalidInputError(f"window end {end:g} s is not after its start {start:g} s")
        rel = self.t - self.t[0]
        i0 = 0 if start is None else int(np.searchsorted(rel, start, side="left"))
        i1 = self.n if end is None else int(np.searchsorted(rel, end, side="left"))
        if i1 - i0 < 2:
            raise InvalidInputError(
                f"the window [{start or 0:g}, {'end' if end is None else f'{end:g}'}) s holds {max(i1 - i0, 0)} "
                f"samples; the recording lasts {self.duration:.6g} s from its start")
        out = self.slice(i0, i1)
        out.meta.update(add_step(out.meta, "window", {
            "start_s": float(rel[i0]), "end_s": float(rel[i1 - 1]), "t0": float(self.t[i0]), "t1": float(self.t[i1 - 1]),
            "samples": int(i1 - i0)}))
        return out

    def interp(self, t_new: ArrayLike) -> "ImuData":
        """Linear interpolation of every channel at the times ``t_new`` (s).

        ``t_new`` must be strictly increasing and inside ``[t[0], t[-1]]``;
        no extrapolation.  Interpolating across a gap (see :meth:`gaps`)
        bridges it linearly: check ``gaps()`` first if that matters.

        Parameters
        ----------
        t_new : array_like, shape (M,)
            New time stamps, s.

        Returns
        -------
        ImuData
            Every channel interpolated at ``t_new``.

        Raises
        ------
        ShapeError
            If ``t_new`` is not a non-empty 1-D array.
        InvalidInputError
            If ``t_new`` leaves ``[t[0], t[-1]]``.
        """
        tn = np.asarray(t_new, dtype=np.float64)
        if tn.ndim != 1 or tn.size == 0:
            raise ShapeError(f"t_new must be a non-empty 1-D array, got shape {tn.shape}")
        if tn[0] < self.t[0] or tn[-1] > self.t[-1]:
            raise InvalidInputError(
                f"t_new spans [{tn[0]}, {tn[-1]}] s, outside the recording [{self.t[0]}, {self.t[-1]}] s; "
                "interp does not extrapolate"
            )

        def f(a: NDArray[np.float64] | None) -> NDArray[np.float64] | None:
            if a is None:
                return None
            if a.ndim == 1:
                return np.interp(tn, self.t, a)
            return np.column_stack([np.interp(tn, self.t, a[:, j]) for j in range(a.shape[1])])

        return ImuData(tn, f(self.gyro), f(self.accel), f(self.mag), f(self.temp), mag_unit=self.mag_unit, meta=dict(self.meta))

    def resample(self, fs: float) -> "ImuData":
        """Uniform samples at ``fs`` Hz from ``t[0]`` to ``t[-1]`` (linear, see :meth:`interp`).

        Resampling to a lower rate without low-pass filtering aliases
        noise; decimate with an anti-alias filter first if noise statistics
        matter.  ``meta["resampled_from_hz"]`` and a ``resample`` step in
        ``meta["provenance"]`` record the original rate.  A rate that would make
        more than max(100 N, 1e7) samples is refused (e.g. ``resample(1e12)``
        meant as a period), as is one that leaves fewer than 2 samples.

        Parameters
        ----------
        fs : float
            New sample rate, Hz.

        Returns
        -------
        ImuData
            Samples at ``t[0] + k / fs``, ``k = 0 .. floor(duration fs)``.

        Raises
        ------
        InvalidInputError
            If ``fs`` is not positive and finite, or gives too many or fewer than 2 samples.
        """
        if not (np.isfinite(fs) and fs > 0):
            raise InvalidInputError(f"fs must be positive and finite, got {fs}")
        k = np.floor(self.duration * fs + 1e-9)
        limit = max(100 * self.n, _RESAMPLE_MAX)
        if k + 1 > limit:
            raise InvalidInputError(
                f"resample(fs={fs:g}) would make {k + 1:.3g} samples from {self.n} ({self.duration:g} s); the limit is "
                f"{limit:.3g} (x100 the samples, or {_RESAMPLE_MAX:.0e}): give the new rate in Hz, e.g. "
                f"resample({self.fs if self.n >= 2 else 100:g})"
            )
        if k < 1:
            raise InvalidInputError(
                f"resample(fs={fs:g}) leaves fewer than 2 samples over {self.duration:g} s; use fs >= {1 / self.duration:g} Hz"
                if self.duration > 0 else "a single-sample recording cannot be resampled"
            )

        from_hz = self.fs if self.n >= 2 else None
        out = self.interp(self.t[0] + np.arange(int(k) + 1) / fs)
        out.meta.update(add_step(out.meta, "resample", {"from_hz": from_hz, "to_hz": float(fs), "method": "linear"}))
        out.meta["resampled_from_hz"] = from_hz
        return out

    def static_intervals(self, window_s: float = 1.0, **kwargs: Any) -> "StaticIntervals":
        """Shortcut for :func:`static_intervals` on this recording.

        Parameters
        ----------
        window_s : float
            Moving-variance window, s.
        **kwargs
            Other keyword arguments of :func:`static_intervals`.

        Returns
        -------
        StaticIntervals
            The detected rest intervals.
        """
        return static_intervals(self, window_s=window_s, **kwargs)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of lists (JSON-friendly).

        Returns
        -------
        dict
            ``t``, ``gyro``, ``accel`` (SI), ``mag`` and ``mag_unit`` / ``temp`` when present, ``meta``.
        """
        d: dict[str, Any] = {"t": self.t.tolist(), "gyro": self.gyro.tolist(), "accel": self.accel.tolist()}
        if self.mag is not None:
            d["mag"] = self.mag.tolist()
            d["mag_unit"] = self.mag_unit
        if self.temp is not None:
            d["temp"] = self.temp.tolist()
        d["meta"] = self.meta
        return d


def _vector_to_si(x, unit, quantity, scale, offset, name):
    """``to_si`` for a triad, accepting per-axis (3,) count scales and offsets.

    One scale for the three axes must be positive: a negative one mirrors the triad (a left-handed frame, no
    sensor's); a per-axis scale may carry signs (an axis the sensor counts the other way).
    """
    if np.ndim(scale) == 0 and scale is not None and np.isfinite(scale) and scale < 0:
        raise UnitError(f"{name}_scale={float(scale):g}: one negative scale for the three axes mirrors the {name} "
                        "(a left-handed frame, no sensor's); give the positive SI units per count, or a per-axis "
                        "scale of 3 values where an axis counts the other way")
    if np.ndim(scale) == 0 and np.ndim(offset) == 0:
        return to_si(x, unit, quantity, scale=scale, offset=float(offset))

    if unit.strip().lower() not in ("counts", "count", "lsb", "raw"):
        raise UnitError(f"per-axis {name}_scale / {name}_offset need {name}_unit='counts', not {unit!r}")
    if scale is None:
        raise UnitError(f"{name} declared in raw counts needs {name}_scale (SI units per count)")
    sc = np.asarray(scale, dtype=float)
    of = np.asarray(offset, dtype=float)
    if sc.shape not in ((), (3,)) or of.shape not in ((), (3,)):
        raise ShapeError(f"{name}_scale and {name}_offset must be scalars or 3 values (x, y, z); got shapes {sc.shape}, {of.shape}")
    if not np.all(np.isfinite(sc)) or np.any(sc == 0):
        raise UnitError(f"{name}_scale must be finite and non-zero, got {sc.tolist()}")
    return (np.asarray(x, dtype=float) - of) * sc


def _apply_nan_policy(t, g, a, m, tp, policy):
    chans = [("gyro", g), ("accel", a)] + ([("mag", m)] if m is not None else []) + ([("temp", tp)] if tp is not None else [])
    if not np.all(np.isfinite(t)):
        raise NonFiniteError(
            f"t has non-finite values at rows {_rows(~np.isfinite(t))}; the NaN policy applies to channels, not to time"
        )
    bad = np.zeros(t.shape[0], dtype=bool)
    for _, c in chans:
        c2 = c.reshape(c.shape[0], -1)
        if c2.shape[0] != t.shape[0]:
            raise ShapeError(f"channel has {c2.shape[0]} rows but t has {t.shape[0]}")
        bad |= ~np.isfinite(c2).all(axis=1)
    cols: list[str] = []
    for name, c in chans:
        c2 = ~np.isfinite(c.reshape(c.shape[0], -1))
        if c2.shape[1] == 1:
            cols += [name] if c2.any() else []
        else:
            cols += [f"{name}_{'xyz'[j]}" for j in np.flatnonzero(c2.any(axis=0))]
    action = {"drop": "rows removed", "interpolate": "values linearly interpolated in time"}.get(policy, "")
    info = {"policy": policy, "rows": np.flatnonzero(bad).tolist(), "columns": cols, "n_rows": int(bad.sum()), "action": action}
    if not bad.any():
        return t, g, a, m, tp, info
    if policy == "drop":
        keep = ~bad
        return (t[keep], g[keep], a[keep], None if m is None else m[keep], None if tp is None else tp[keep], info)
    if policy == "interpolate":
        out = []
        for name, c in chans:
            c = np.array(c, dtype=float)
            c2 = c.reshape(c.shape[0], -1)
            for j in range(c2.shape[1]):
                col = c2[:, j]
                ok = np.isfinite(col)
                if not ok.any():
                    raise NonFiniteError(f"{name} column {j} has no finite values to interpolate from")
                if not ok[0] or not ok[-1]:
                    raise NonFiniteError(
                        f"{name} column {j} has NaN at the start or end of the record, which cannot be "
                        "interpolated; use nan_policy='drop' or trim the record"
                    )
                col[~ok] = np.interp(t[~ok], t[ok], col[ok])
            out.append(c2.reshape(c.shape))
        g2, a2 = out[0], out[1]
        k = 2
        m2 = None
        tp2 = None
        if m is not None:
            m2 = out[k]
            k += 1
        if tp is not None:
            tp2 = out[k]
        return t, g2, a2, m2, tp2, info
    raise InvalidInputError(f"nan_policy must be 'raise', 'drop' or 'interpolate', not {policy!r}")


# -- moving variance and static intervals --------------------------------------


def moving_variance(x: ArrayLike, window: int, *, align: Literal["trailing", "centred"] = "trailing",
                    per_column: bool = False) -> NDArray[np.float64]:
    """Population variance of ``x`` over a moving window of ``window`` samples.

    The one moving variance of the package (static intervals, steady calibration
    segments, the multi-pose static detector); numba kernels, O(N).

    Parameters
    ----------
    x : array_like, (N,) or (N, k)
        Samples, one row per sample.
    window : int
        Window length in samples (at least 2).
    align : {"trailing", "centred"}
        ``"trailing"``: one value per complete window, ``out[j] = var(x[j:j+window])``
        (the window that ends at sample ``j + window - 1``), ``N - window + 1`` values;
        sliding Welford update.  ``"centred"``: one value per sample, the window
        ``x[i - window//2 : i - window//2 + window]`` cut at both ends of the record
        (shorter windows there); sliding sums of ``x - x[0]``.  Both recompute their
        sums exactly every ``64 window`` samples, so rounding cannot accumulate.
    per_column : bool
        For (N, k) input: False sums the per-column variances (``sum_k var(x_k)``,
        one value per window), True returns them per column, shape (M, k).

    Returns
    -------
    numpy.ndarray
        (M,) or, with ``per_column`` and 2-D input, (M, k); M as given by ``align``.

    Raises
    ------
    InvalidInputError
        If ``align`` is unknown, ``window`` < 2, or (trailing) ``x`` has fewer samples than one window.
    """

    a = np.asarray(x, dtype=np.float64)
    w = int(window)
    if align not in ("trailing", "centred"):
        raise InvalidInputError(f"align={align!r}: choose 'trailing' or 'centred'")
    if w < 2:
        raise InvalidInputError(f"the window must hold at least 2 samples, got {w}")
    cols = np.ascontiguousarray(a.reshape(a.shape[0], -1))
    if align == "centred":
        v = moving_variance_kernel(cols, w)
    else:
        if a.shape[0] < w:
            raise InvalidInputError(f"{a.shape[0]} samples are fewer than one window of {w} samples")
        if not per_column:
            return moving_var_cols(cols, w)
        v = np.column_stack([moving_var_cols(cols[:, c : c + 1], w) for c in range(cols.shape[1])])
    if not per_column:
        return v.sum(axis=1)
    return v if a.ndim > 1 else v[:, 0]


@dataclass(frozen=True, eq=False)
class StaticIntervals:
    """Static (at rest) intervals of a recording.

    Attributes
    ----------
    starts, stops : (K,) int64
        Half-open sample index ranges ``[starts[k], stops[k])``.
    t_start, t_stop : (K,) float
        ``t[starts]`` and ``t[stops - 1]`` (time of the first / last static sample).
    mask : (N,) bool
        True on static samples (only those in the returned intervals).
    accel_threshold, gyro_threshold : float
        Thresholds applied to the moving-variance statistics, (m/s²)² and
        (rad/s)² (``nan`` when a sensor was not used).
    window : int
        Window length in samples.
    method : str
        ``"axes"`` (sum of per-axis variances) or ``"norm"`` (variance of the norm).
    """

    starts: NDArray[np.int64]
    stops: NDArray[np.int64]
    t_start: NDArray[np.float64]
    t_stop: NDArray[np.float64]
    mask: NDArray[np.bool_]
    accel_threshold: float
    gyro_threshold: float
    window: int
    method: str

    def __len__(self) -> int:
        return int(self.starts.shape[0])

    def __iter__(self):
        return iter(zip(self.starts.tolist(), self.stops.tolist(), strict=True))

    @property
    def durations(self) -> NDArray[np.float64]:
        """``t_stop - t_start`` of each interval (s)."""
        return self.t_stop - self.t_start

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form.

        Returns
        -------
        dict
            ``starts``, ``stops``, ``t_start``, ``t_stop`` (lists), ``n_static_samples``, the thresholds,
            ``window`` and ``method``.
        """
        return {
            "starts": self.starts.tolist(),
            "stops": self.stops.tolist(),
            "t_start": self.t_start.tolist(),
            "t_stop": self.t_stop.tolist(),
            "n_static_samples": int(self.mask.sum()),
            "accel_threshold": self.accel_threshold,
            "gyro_threshold": self.gyro_threshold,
            "window": self.window,
            "method": self.method,
        }


def _statistic(x: NDArray[np.float64], w: int, method: str) -> NDArray[np.float64]:
    if method == "norm":
        return moving_variance(np.sqrt(np.einsum("ij,ij->i", x, x)), w)
    return moving_variance(x, w)


#: Lowest automatic thresholds: variances far below any real sensor's noise
#: (σ = 1 µm/s² ≈ 0.1 µg and σ = 1e-7 rad/s ≈ 0.02 °/h per sample) but above
#: the rounding residue of the moving variance, so that noise-free simulated
#: records are still split into rest and motion.
_AUTO_FLOOR = {"accel": 1e-12, "gyro": 1e-14}


def _quietest(stat: NDArray[np.float64], w: int) -> float:
    """Variance of the quietest of the non-overlapping windows (floored above 0)."""
    blocks = stat[::w]
    pos = blocks[blocks > 0]
    # a window of identical (quantised) samples has variance 0: take the
    # quietest window that moved at all instead
    return float(pos.min()) if pos.size else float(np.finfo(float).tiny)


def static_intervals(
    data: ImuData,
    window_s: float = 1.0,
    threshold: float | tuple[float, float] | None = None,
    min_duration_s: float | None = None,
    *,
    factor: float = 6.0,
    use_gyro: bool = False,
    method: Literal["axes", "norm"] = "axes",
) -> StaticIntervals:
    """Find the static intervals of a recording by a moving-variance test.

    For every window of ``w = round(window_s * fs)`` samples, the statistic
    ``s_a = Σ_k var(a_k)`` (``method="axes"``, sum of the per-axis
    variances) or ``s_a = var(‖a‖)`` (``method="norm"``) of the specific
    force is computed, and the same ``s_g`` for the angular rate.  A window
    is static when ``s_a ≤ λ_a`` and (if ``use_gyro``) ``s_g ≤ λ_g``; a
    sample is static when it lies in at least one static window, so that a
    static segment is recovered to its edges rather than shrunk by half a
    window.  Runs shorter than ``min_duration_s`` (default ``window_s``)
    are discarded.  This is the detector of Tedaldi et al. (ICRA 2014, §IV-A:
    variance of the accelerometer over a sliding window against a multiple
    of its value in an initial static period), extended to the gyroscope.

    ``"axes"`` is the default because the norm of the specific force barely
    changes during a slow rotation (gravity only changes direction), whereas
    the per-axis variance sees it.

    Parameters
    ----------
    data : ImuData
        The recording.
    window_s : float
        Window length (s).
    threshold : float or (float, float), optional
        ``λ_a`` in (m/s²)², or ``(λ_a, λ_g)`` with ``λ_g`` in (rad/s)².  With
        a single value ``λ_g`` is automatic.  ``None``: both automatic,
        ``λ = factor ×`` the statistic of the quietest non-overlapping window
        (this assumes the record has at least one window at rest), but at
        least 1e-12 (m/s²)² and 1e-14 (rad/s)² so that noise-free simulated
        data work too.
    min_duration_s : float, optional
        Shortest interval kept (s); default ``window_s``.
    factor : float
        Multiple of the quietest-window variance for automatic thresholds.
        For white noise, a window variance estimate has relative spread
        ``sqrt(2 / (w - 1))``; the default 6 leaves room for that and for
        slow drift while still rejecting hand motion.
    use_gyro : bool
        Also require a quiet gyroscope.
    method : {"axes", "norm"}
        Statistic: sum of the per-axis variances, or variance of the norm.

    Returns
    -------
    StaticIntervals
        The intervals, their mask and the thresholds used.

    Raises
    ------
    InvalidInputError
        If ``data`` is not an ImuData, ``method`` is unknown, ``window_s`` or ``factor`` is not positive, or a
        threshold is negative, not finite or not one or two values.
    InsufficientDataError
        If the recording is shorter than one window.
    """
    if not isinstance(data, ImuData):
        raise InvalidInputError(f"static_intervals needs an ImuData, got {type(data).__name__}")
    if method not in ("axes", "norm"):
        raise InvalidInputError(f"method must be 'axes' or 'norm', not {method!r}")
    if not (np.isfinite(window_s) and window_s > 0):
        raise InvalidInputError(f"window_s must be positive, got {window_s}")
    if not (np.isfinite(factor) and factor > 0):
        raise InvalidInputError(f"factor must be positive, got {factor}")
    n = data.n
    w = max(int(round(window_s * data.fs)), 2)
    if n < w:
        raise InsufficientDataError(
            f"the recording has {n} samples, fewer than one window of {w} samples ({window_s} s); use a shorter window_s"
        )
    if min_duration_s is None:
        min_duration_s = window_s
    if threshold is None:
        thr_a, thr_g = None, None
    elif np.ndim(threshold) == 0:
        thr_a, thr_g = float(threshold), None  # type: ignore[arg-type]
    else:
        thr = tuple(float(v) for v in threshold)  # type: ignore[union-attr]
        if len(thr) != 2:
            raise InvalidInputError(f"threshold must be a float or (accel, gyro), got {threshold!r}")
        thr_a, thr_g = thr
    for name, v in (("accel", thr_a), ("gyro", thr_g)):
        if v is not None and not (np.isfinite(v) and v >= 0):
            raise InvalidInputError(f"the {name} threshold must be finite and >= 0, got {v}")

    s_a = _statistic(data.accel, w, method)
    if thr_a is None:
        thr_a = max(factor * _quietest(s_a, w), _AUTO_FLOOR["accel"])
    quiet = s_a <= thr_a
    if use_gyro:
        s_g = _statistic(data.gyro, w, method)
        if thr_g is None:
            thr_g = max(factor * _quietest(s_g, w), _AUTO_FLOOR["gyro"])
        quiet &= s_g <= thr_g
    else:
        thr_g = float("nan")
    # sample i is static if a static window starts in [i - w + 1, i]
    starts, stops = runs(covered(quiet, n, w))
    # duration of a run of samples = its count times the sample interval
    keep = (data.t[stops - 1] - data.t[starts]) + 1.0 / data.fs >= min_duration_s - 1e-9
    starts, stops = starts[keep], stops[keep]
    mask = np.zeros(n, dtype=bool)
    for a, b in zip(starts.tolist(), stops.tolist(), strict=True):
        mask[a:b] = True
    return StaticIntervals(
        starts=starts.astype(np.int64),
        stops=stops.astype(np.int64),
        t_start=data.t[starts].copy(),
        t_stop=data.t[stops - 1].copy() if stops.size else np.empty(0),
        mask=mask,
        accel_threshold=float(thr_a),
        gyro_threshold=float(thr_g),
        window=w,
        method=method,
    )


# -- saturation ----------------------------------------------------------------

_SAT_CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")


@dataclass(frozen=True, eq=False)
class Saturation:
    """Samples at (or stuck at) a sensor's range limit.

    Attributes
    ----------
    mask : (N, 6) bool
        Saturated samples of ``gyro_x … accel_z``.
    counts : dict[str, int]
        Saturated samples per channel.
    method : str
        ``"full_scale"`` or ``"runs"`` (runs of identical extreme values).
    """

    mask: NDArray[np.bool_]
    counts: dict[str, int]
    method: str

    @property
    def any(self) -> bool:
        return bool(self.mask.any())

    @property
    def rows(self) -> NDArray[np.int64]:
        """Indices of samples with at least one saturated channel."""
        return np.flatnonzero(self.mask.any(axis=1))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form.

        Returns
        -------
        dict
            ``method``, ``counts`` per channel and ``n_rows`` (samples with a saturated channel).
        """
        return {"method": self.method, "counts": dict(self.counts), "n_rows": int(self.rows.size)}

    def check(self, where: str = "the recording") -> None:
        """Raise :class:`~imunav.errors.SaturationError` if any sample is saturated.

        Parameters
        ----------
        where : str
            What to name in the message (e.g. the file).

        Raises
        ------
        SaturationError
            If any sample is saturated; the message names the rows and channels.
        """
        if not self.any:
            return
        chans = ", ".join(f"{k} ({v})" for k, v in self.counts.items() if v)
        raise SaturationError(
            f"{where} has saturated samples at rows {_rows(self.mask.any(axis=1))}: {chans}. "
            "Exclude them (e.g. data.slice) or use a sensor range that covers the motion"
        )


def _extreme_runs(x: NDArray[np.float64], min_run: int) -> NDArray[np.bool_]:
    out = np.zeros(x.shape[0], dtype=bool)
    med = float(np.median(x))
    mad = float(np.median(np.abs(x - med))) * 1.4826
    for ext in (x.max(), x.min()):
        at = x == ext
        # an extreme is a plausible clip only if it is far from the bulk of the data
        if abs(ext - med) <= 10.0 * mad or at.sum() < min_run:
            continue
        s, e = runs(at)
        for a, b in zip(s.tolist(), e.tolist(), strict=True):
            if b - a >= min_run:
                out[a:b] = True
    return out


def detect_saturation(
    data: ImuData,
    gyro_full_scale: float | None = None,
    accel_full_scale: float | None = None,
    *,
    rtol: float = 1e-3,
    min_run: int = 2,
) -> Saturation:
    """Find saturated samples.

    With a full scale (SI: rad/s, m/s²), samples with ``|x| ≥ FS·(1 − rtol)``
    are saturated.  Without one, a channel is saturated where it sits at
    its own maximum or minimum value for at least ``min_run`` consecutive
    samples and that value lies more than 10 robust standard deviations
    (1.4826·MAD) from the median (a clipped sensor repeats its rail value;
    a quantised static signal's extremes are near its median).

    Parameters
    ----------
    data : ImuData
        The recording.
    gyro_full_scale : float, optional
        Gyro range, rad/s.
    accel_full_scale : float, optional
        Accelerometer range, m/s².
    rtol : float
        Relative margin below the full scale that counts as saturated.
    min_run : int
        Shortest run of identical extreme values that counts (without a full scale).

    Returns
    -------
    Saturation
        Per-sample mask and per-channel counts; with one full scale given, the other sensor is not checked.

    Raises
    ------
    InvalidInputError
        If a full scale is not positive and finite.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.zeros((6, 3)); g[2:4, 0] = 4.36   # a ±250 °/s gyro clipped on x
    >>> d = ImuData(np.arange(6) / 100, g, np.zeros((6, 3)))
    >>> detect_saturation(d, gyro_full_scale=np.deg2rad(250)).counts["gyro_x"]
    2
    """
    mask = np.zeros((data.n, 6), dtype=bool)
    method = "full_scale" if (gyro_full_scale is not None or accel_full_scale is not None) else "runs"
    for k, (arr, fs_) in enumerate(((data.gyro, gyro_full_scale), (data.accel, accel_full_scale))):
        for j in range(3):
            x = arr[:, j]
            if method == "full_scale":
                if fs_ is None:
                    continue
                if not (np.isfinite(fs_) and fs_ > 0):
                    raise InvalidInputError(f"full scale must be positive, got {fs_}")
                mask[:, 3 * k + j] = np.abs(x) >= fs_ * (1.0 - rtol)
            else:
                mask[:, 3 * k + j] = _extreme_runs(x, min_run)
    counts = {c: int(mask[:, i].sum()) for i, c in enumerate(_SAT_CHANNELS)}
    return Saturation(mask=mask, counts=counts, method=method)


# -- summary (imunav info) --------------------------------------------------------


@dataclass(frozen=True, eq=False)
class RecordingSummary:
    """What ``imunav info`` reports about a recording.

    ``channels`` rows hold per-channel statistics in display units (gyro
    °/s, accel m/s², mag in ``mag_unit``, temp °C).

    Attributes
    ----------
    n : int
        Number of samples.
    duration_s : float
        ``t[-1] - t[0]``, s.
    fs_hz : float
        Nominal sample rate (1 / median interval), Hz; NaN for one sample.
    dt_min_s, dt_max_s, dt_std_s : float
        Smallest, largest and standard deviation of the sample intervals, s.
    gaps : list of Gap
        Intervals longer than 1.5 × the median.
    saturation : Saturation
        Saturated samples.
    static : StaticIntervals or None
        Rest intervals (None when the record is shorter than one window).
    channels : list of dict
        Per channel: ``channel``, ``unit``, ``mean``, ``std``, ``min``, ``max``.
    mag_unit : str or None
        Unit of the magnetometer (None without one).
    meta : dict
        The recording's metadata.
    warnings : list of str
        Problems found (e.g. an implausible specific force at rest).
    """

    n: int
    duration_s: float
    fs_hz: float
    dt_min_s: float
    dt_max_s: float
    dt_std_s: float
    gaps: list[Gap]
    saturation: Saturation
    static: StaticIntervals | None
    channels: list[dict[str, Any]]
    mag_unit: str | None
    meta: dict[str, Any]
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the output of ``imunav info --json``).

        Returns
        -------
        dict
            Every field, gaps as dicts, plus ``missing_samples`` (total over the gaps).
        """
        return {
            "warnings": list(self.warnings),
            "n": self.n,
            "duration_s": self.duration_s,
            "fs_hz": self.fs_hz,
            "dt_min_s": self.dt_min_s,
            "dt_max_s": self.dt_max_s,
            "dt_std_s": self.dt_std_s,
            "gaps": [dataclasses.asdict(g) for g in self.gaps],
            "missing_samples": int(sum(g.missing_samples for g in self.gaps)),
            "saturation": self.saturation.to_dict(),
            "static_intervals": None if self.static is None else self.static.to_dict(),
            "channels": self.channels,
            "mag_unit": self.mag_unit,
            "meta": self.meta,
        }


#: Reference gravity (m/s²) of the mean-specific-force test (accepted: G_REF / 4 to 2 G_REF).
G_REF = 9.80665


def rest_force_problem(fmag: float, gravity: float = G_REF) -> str | None:
    """Why a specific force of magnitude ``fmag`` (m/s²) cannot be a sensor at rest, or None if it can.

    Accepted: ``g/4 ≤ fmag ≤ 2 g`` (see the module docstring).  The message names the likely unit
    mistake (a reading of about 1 is an accelerometer in g, about 1000 one in mg).

    Parameters
    ----------
    fmag : float
        Magnitude of the mean specific force, m/s².
    gravity : float
        Expected magnitude at rest, m/s² (default: standard gravity).

    Returns
    -------
    str or None
        The reason, ready for an error message, or None when ``fmag`` is plausible at rest.
    """
    if 0.25 * gravity <= fmag <= 2.0 * gravity:
        return None
    if 0.9 < fmag < 1.1:
        hint = "the accelerometer looks like it is in g: declare its unit (--accel-unit g, units={'accel': 'g'})"
    elif 900 < fmag < 1100:
        hint = "the accelerometer looks like it is in mg: declare its unit (--accel-unit mg)"
    else:
        hint = "check the accelerometer's unit and that the file holds its data"
    return (f"the mean specific force at rest is {fmag:.4g} m/s^2, outside g/4 .. 2 g (g = {gravity:.4g} m/s^2); "
            + hint)


def describe(
    data: ImuData,
    *,
    window_s: float = 1.0,
    min_duration_s: float | None = None,
    gyro_full_scale: float | None = None,
    accel_full_scale: float | None = None,
) -> RecordingSummary:
    """Rate, duration, gaps, saturation, static intervals and channel statistics.

    Static intervals are skipped (``None``) when the record is shorter than
    one window.  A specific force at rest outside g/4 .. 2 g (e.g. an
    accelerometer in g read as m/s²) is reported in ``warnings`` and with an
    :class:`~imunav.errors.ImunavWarning`.  Full scales are SI (rad/s, m/s²); without them saturation
    is detected from runs at the channels' extreme values.

    Parameters
    ----------
    data : ImuData
        The recording.
    window_s : float
        Window of the static detector, s (:func:`static_intervals`).
    min_duration_s : float, optional
        Shortest static interval kept, s (default ``window_s``).
    gyro_full_scale : float, optional
        Gyro range, rad/s (:func:`detect_saturation`).
    accel_full_scale : float, optional
        Accelerometer range, m/s².

    Returns
    -------
    RecordingSummary
        The summary behind ``imunav info``.
    """

    n = data.n
    dt = data.dt
    static = None
    if n >= 2 and n >= max(int(round(window_s * data.fs)), 2):
        static = static_intervals(data, window_s=window_s, min_duration_s=min_duration_s)
    channels: list[dict[str, Any]] = []

    def add(group: str, arr: NDArray[np.float64] | None, unit: str, factor: float) -> None:
        if arr is None:
            return
        cols = [arr] if arr.ndim == 1 else [arr[:, j] for j in range(arr.shape[1])]
        for j, c in enumerate(cols):
            # mean and std of x / max|x|, scaled back: no overflow for values near the float range (1e300)
            s = float(np.max(np.abs(c)))
            y = c / s if s > 0 else c
            with np.errstate(over="ignore"):
                channels.append(
                    {
                        "channel": group if arr.ndim == 1 else f"{group}_{'xyz'[j]}",
                        "unit": unit,
                        "mean": float(y.mean()) * (s or 1.0) * factor,
                        "std": float(y.std()) * (s or 1.0) * factor,
                        "min": float(c.min()) * factor,
                        "max": float(c.max()) * factor,
                    }
                )

    add("gyro", data.gyro, "deg/s", 1.0 / _DEG)
    add("accel", data.accel, "m/s^2", 1.0)
    add("mag", data.mag, data.mag_unit, 1.0)
    add("temp", data.temp, "degC", 1.0)
    notes: list[str] = []
    if static is not None and static.mask.any():
        problem = rest_force_problem(float(np.median(np.linalg.norm(data.accel[static.mask], axis=1))))
        if problem:
            notes.append(problem)
            warnings.warn(problem, ImunavWarning, stacklevel=2)
    return RecordingSummary(
        n=n,
        duration_s=data.duration,
        fs_hz=data.fs if n >= 2 else float("nan"),
        dt_min_s=float(dt.min()) if n >= 2 else float("nan"),
        dt_max_s=float(dt.max()) if n >= 2 else float("nan"),
        dt_std_s=float(dt.std()) if n >= 2 else float("nan"),
        gaps=data.gaps(),
        saturation=detect_saturation(data, gyro_full_scale, accel_full_scale),
        static=static,
        channels=channels,
        mag_unit=data.mag_unit if data.mag is not None else None,
        meta=dict(data.meta),
        warnings=notes,
    )
