"""Pieces shared by the readers and writers: names, units, metadata, errors.

Every reader turns a file into a dict of raw arrays ``{"t", "gyro", "accel",
"mag", "temp"}`` (plus an optional sampling rate ``fs`` when there is no time
column) and hands it to :func:`build_imu`, which applies the declared units,
scales and offsets (:meth:`imunav.timeseries.ImuData.from_arrays`) and names the
file in any validation error.  Every writer stores SI values plus a JSON
header (:func:`header_json`) holding ``mag_unit`` and ``meta``.
"""

from __future__ import annotations

import inspect
import json
import os
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, InvalidInputError, UnitError
from imunav.timeseries import ImuData
from imunav.units import normalize_unit, unit_factor

__all__ = [
    "GROUPS",
    "ARRAY_ALIASES",
    "SI_UNITS",
    "header_json",
    "parse_header",
    "build_imu",
    "find_array_names",
    "wrap_read_errors",
    "check_nonempty",
]

#: The channel groups of an :class:`ImuData`, in file order.
GROUPS = ("t", "gyro", "accel", "mag", "temp")

#: SI unit of each group as stored by imunav's writers (mag: see ``mag_unit``).
SI_UNITS = {"t": "s", "gyro": "rad/s", "accel": "m/s^2", "temp": "degC"}

#: Accepted names (lower case) of whole arrays in HDF5 / MAT / NPZ files.
ARRAY_ALIASES: dict[str, tuple[str, ...]] = {
    "t": ("t", "time", "times", "timestamp", "timestamps", "time_s", "imu_t", "imu_time"),
    "gyro": ("gyro", "gyr", "imu_gyr", "imu_gyro", "omega", "angular_rate", "gyroscope", "w"),
    "accel": ("accel", "acc", "imu_acc", "imu_accel", "specific_force", "accelerometer", "f", "a"),
    "mag": ("mag", "imu_mag", "magnetometer", "magnetic_field"),
    "temp": ("temp", "temperature", "imu_temp", "temp_c"),
    "fs": ("fs", "rate", "sampling_rate", "sample_rate", "freq"),
}

_FORMAT_TAG = "imunav-imu"
_FORMAT_VERSION = 1


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, os.PathLike):
        return os.fspath(o)
    raise TypeError(f"meta value of type {type(o).__name__} is not JSON-serialisable")


def header_json(data: ImuData) -> str:
    """JSON text stored with a recording: format tag, SI units, ``mag_unit``, ``meta``."""
    units = dict(SI_UNITS)
    if data.mag is not None:
        units["mag"] = data.mag_unit
    doc = {
        "format": _FORMAT_TAG,
        "version": _FORMAT_VERSION,
        "units": units,
        "mag_unit": data.mag_unit,
        "meta": data.meta,
    }
    try:
        return json.dumps(doc, default=_json_default, allow_nan=True)
    except TypeError as e:
        raise InvalidInputError(f"cannot store ImuData.meta: {e}; keep meta to JSON types") from None


def parse_header(text: str | bytes | None, source: str) -> dict[str, Any]:
    """Inverse of :func:`header_json`; ``{}`` for ``None``/empty text."""
    if text is None:
        return {}
    if isinstance(text, bytes):
        text = text.decode("utf-8")
    text = str(text).strip()
    if not text:
        return {}
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise FileFormatError(f"{source}: the imunav header is not valid JSON ({e}); the file may be damaged") from None
    if not isinstance(doc, dict):
        raise FileFormatError(f"{source}: the imunav header is not a JSON object")
    return doc


def _group_option(opt: Mapping[str, Any] | None, name: str) -> dict[str, Any]:
    """Normalise a per-group option dict (``units``, ``scales``, ``offsets``)."""
    if opt is None:
        return {}
    if not isinstance(opt, Mapping):
        raise InvalidInputError(f"{name} must be a dict keyed by group ('t', 'gyro', 'accel', 'mag', 'temp'), got {opt!r}")
    out: dict[str, Any] = {}
    for k, v in opt.items():
        key = {"time": "t", "acc": "accel", "gyr": "gyro", "temperature": "temp"}.get(k, k)
        if key not in GROUPS:
            raise InvalidInputError(f"{name} has unknown key {k!r}; use one of {list(GROUPS)}")
        out[key] = v
    return out


_QUANTITY_OF = {"t": "time", "gyro": "angular_rate", "accel": "acceleration", "mag": "magnetic_field",
                "temp": "temperature"}


def _same_unit(a: str, b: str, group: str) -> bool:
    q = _QUANTITY_OF.get(group)
    raw = normalize_unit(b) in ("counts", "count", "lsb", "raw")
    fb = unit_factor(b, q) if q is not None and not raw else None  # an unknown unit option is reported as such
    if normalize_unit(a) == normalize_unit(b):
        return True
    if fb is None:
        return False
    try:
        return unit_factor(a, q) == fb
    except UnitError:
        return False


def _check_declared_units(declared: Any, given: Mapping[str, str], source: str) -> None:
    """Units declared in the file win: an option that contradicts them is an error naming both.

    An option may only fill in the unit of a group the file does not declare.
    """
    if not isinstance(declared, Mapping):
        return
    for k, v in given.items():
        d = declared.get(k)
        if isinstance(d, str) and not _same_unit(d, v, k):
            raise UnitError(
                f"{source}: the file declares {k} in {d!r}, but the option says {v!r}; the file's declaration "
                f"wins - drop the {k} unit option (the values are read as {d!r})"
            )


def build_imu(
    arrays: Mapping[str, Any],
    source: str,
    *,
    stored: Mapping[str, Any] | None = None,
    units: Mapping[str, str] | None = None,
    scales: Mapping[str, float] | None = None,
    offsets: Mapping[str, float] | None = None,
    fs: float | None = None,
    t0: float = 0.0,
    nan_policy: str = "raise",
    mag_unit: str | None = None,
    meta: Mapping[str, Any] | None = None,
) -> ImuData:
    """Raw arrays of a file -> validated :class:`ImuData` in SI.

    ``arrays`` holds ``t`` (or ``fs``), ``gyro``, ``accel`` and optionally
    ``mag`` / ``temp``.  ``units``/``scales``/``offsets`` are keyed by group
    (``"t"``, ``"gyro"``, ``"accel"``, ``"mag"``); raw counts are declared as
    ``units={"gyro": "counts"}, scales={"gyro": <rad/s per count>}``.  ``mag``
    stays in its unit (``mag_unit``), optionally scaled from counts.
    """
    stored = dict(stored or {})
    u = _group_option(units, "units")
    sc = _group_option(scales, "scales")
    of = _group_option(offsets, "offsets")
    for k, v in u.items():
        if not isinstance(v, str):
            raise UnitError(f"units[{k!r}] must be a unit string such as 'deg/s', got {v!r}")
    _check_declared_units(stored.get("units"), u, source)
    for k in sc:
        if k == "t":
            raise InvalidInputError("scales['t'] is not supported; declare the time unit with units={'t': 'ms'}")
    n_rows = None
    for g in ("gyro", "accel"):
        if arrays.get(g) is None:
            raise FileFormatError(f"{source}: no {g} data found")
        n_rows = np.shape(arrays[g])[0] if np.ndim(arrays[g]) >= 1 else 0
    t = arrays.get("t")
    if t is None:
        rate = fs if fs is not None else arrays.get("fs")
        if rate is None:
            raise FileFormatError(
                f"{source}: no time column/array found and no sampling rate given; pass fs=<Hz> "
                "(samples are then at t0 + k/fs) or name the time column with columns={'t': '<name>'}"
            )
        rate = float(np.asarray(rate).reshape(-1)[0])
        if not np.isfinite(rate) or rate <= 0:
            raise InvalidInputError(f"{source}: the sampling rate must be positive and finite, got fs={rate}")
        t = t0 + np.arange(n_rows or 0, dtype=np.float64) / rate
        time_unit = "s"
    elif arrays.get("t_origin") is not None:
        time_unit = "s"  # date-time column, already seconds since its first sample
    else:
        time_unit = u.get("t", "s")
    mag = arrays.get("mag")
    if mag is not None:
        mu = u.get("mag")
        if mu is not None and mu.strip().lower() in ("counts", "count", "lsb", "raw"):
            if "mag" not in sc:
                raise UnitError("mag declared in counts needs scales={'mag': <mag_unit per count>}")
            mag = (np.asarray(mag, dtype=float) - of.get("mag", 0.0)) * float(sc["mag"])
        elif mu is not None and mag_unit is None:
            mag_unit = mu
    tp = arrays.get("temp")
    if tp is not None and u.get("temp") not in (None, "degC", "degc", "C", "°C", "c"):
        raise UnitError(f"{source}: temperature must be in degC (°C); got units['temp']={u['temp']!r}")
    out_meta = dict(stored.get("meta") or {})
    if arrays.get("t_origin") is not None:
        out_meta.setdefault("t_origin", arrays["t_origin"])
    if arrays.get("t_origin_raw") is not None:
        out_meta.setdefault("t_origin_raw", arrays["t_origin_raw"])
    if meta:
        out_meta.update(meta)
    declared = {"gyro": u.get("gyro", "rad/s"), "accel": u.get("accel", "m/s^2")}
    try:
        data = ImuData.from_arrays(
            _as_float(t, "t", source),
            _as_float(arrays["gyro"], "gyro", source),
            _as_float(arrays["accel"], "accel", source),
            None if mag is None else _as_float(mag, "mag", source),
            None if tp is None else _as_float(tp, "temp", source),
            time_unit=time_unit,
            gyro_unit=declared["gyro"],
            accel_unit=declared["accel"],
            gyro_scale=sc.get("gyro"),
            accel_scale=sc.get("accel"),
            gyro_offset=of.get("gyro", 0.0),
            accel_offset=of.get("accel", 0.0),
            mag_unit=mag_unit or stored.get("mag_unit") or "uT",
            nan_policy=nan_policy,  # type: ignore[arg-type]
            meta=out_meta,
        )
    except InvalidInputError as e:
        if str(e).startswith(source):
            raise
        raise type(e)(f"{source}: {e}") from None
    if fs is not None and arrays.get("t") is not None and data.n >= 2:
        # the file's time stamps win; a sampling rate that contradicts them is an error, not silently ignored
        if not (np.isfinite(fs) and fs > 0) or abs(data.fs / float(fs) - 1.0) > 0.01:
            raise InvalidInputError(
                f"{source}: the file has a time column (samples at {data.fs:.6g} Hz), but the option says "
                f"fs={fs!r}; the time stamps win - drop the fs option (it is for files without time stamps)"
            )
    return data


def _as_float(x: Any, name: str, source: str) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind in "fiub":
        return a.astype(np.float64, copy=False)
    try:
        return a.astype(np.float64)
    except (TypeError, ValueError):
        raise FileFormatError(f"{source}: {name} holds non-numeric values (dtype {a.dtype}); expected numbers") from None


def find_array_names(
    names: list[str], columns: Mapping[str, str] | None, source: str, kind: str = "array"
) -> dict[str, str]:
    """Map groups (t, gyro, accel, mag, temp, fs) to the names present in a file.

    ``columns`` overrides the automatic choice (``{"gyro": "imu_gyr"}``).
    Raises :class:`FileFormatError` listing what was found and what is
    expected when gyro or accel cannot be found.
    """
    found: dict[str, str] = {}
    lower = {n.lower(): n for n in names}
    for n in names:  # nested datasets ("imu/gyr") are also found by their last name
        lower.setdefault(n.rsplit("/", 1)[-1].lower(), n)
    user = dict(columns or {})
    for k, v in user.items():
        key = {"time": "t", "acc": "accel", "gyr": "gyro", "temperature": "temp"}.get(k, k)
        if key not in ARRAY_ALIASES:
            raise InvalidInputError(f"columns has unknown key {k!r}; use one of {list(ARRAY_ALIASES)}")
        if v not in names:
            raise FileFormatError(
                f"{source}: {kind} {v!r} (columns[{k!r}]) not found; the file has {sorted(names)}"
            )
        found[key] = v
    for g, aliases in ARRAY_ALIASES.items():
        if g in found:
            continue
        for a in aliases:
            if a in lower:
                found[g] = lower[a]
                break
    missing = [g for g in ("gyro", "accel") if g not in found]
    if missing:
        expect = "; ".join(f"{g}: one of {list(ARRAY_ALIASES[g][:4])}" for g in missing)
        raise FileFormatError(
            f"{source}: missing {kind}(s) for {missing}. Found {sorted(names)}; expected {expect} "
            f"(or map them with columns={{'gyro': '<name>', 'accel': '<name>'}})"
        )
    return found


class wrap_read_errors:
    """Context manager turning library read errors into :class:`FileFormatError`.

    imunav's own :class:`InvalidInputError` and ``FileNotFoundError`` pass
    through unchanged.
    """

    def __init__(self, source: str, what: str) -> None:
        self.source = source
        self.what = what

    def __enter__(self) -> "wrap_read_errors":
        return self

    def __exit__(self, et, ev, tb) -> bool:
        if ev is None or isinstance(ev, (InvalidInputError, FileNotFoundError, IsADirectoryError, PermissionError)):
            return False
        if isinstance(ev, (KeyboardInterrupt, SystemExit, MemoryError)):
            return False
        raise FileFormatError(
            f"{self.source}: cannot read it as {self.what} ({type(ev).__name__}: {ev}). "
            "The file may be empty, truncated or of another format; pass format=... to choose the reader"
        ) from ev


def check_nonempty(path: os.PathLike[str] | str) -> str:
    """Source name of ``path``; raise if missing or empty."""
    p = os.fspath(path)
    if not os.path.exists(p):
        raise FileNotFoundError(f"{p}: no such file")
    if os.path.isdir(p):
        raise FileFormatError(f"{p} is a directory, not a recording file")
    if os.path.getsize(p) == 0:
        raise FileFormatError(f"{p}: the file is empty (0 bytes)")
    return p


def call_reader(fn: Callable[..., Any], what: str, *args: Any, **options: Any) -> Any:
    """Call a reader or writer with ``options``, naming ``what`` when it does not take one of them."""
    params = inspect.signature(fn).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return fn(*args, **options)  # the reader passes its options on and checks them there
    unknown = [k for k in options if k not in params]
    if unknown:
        allowed = [k for k, p in params.items() if p.kind is inspect.Parameter.KEYWORD_ONLY]
        raise InvalidInputError(f"{what} does not take option(s) {unknown}; it accepts {allowed}")
    return fn(*args, **options)
