"""Pieces shared by the readers and writers: names, units, metadata, errors.

Every reader turns a file into a dict of raw arrays ``{"t", "gyro", "accel",
"mag", "temp"}`` (plus an optional sampling rate ``fs`` when there is no time
column) and hands it to :func:`build_imu`, which applies the declared units,
scales and offsets (:meth:`imunav.timeseries.ImuData.from_arrays`) and names the
file in any validation error.  Every writer stores SI values plus a JSON
header (:func:`header_json`) holding ``mag_unit`` and ``meta``.

Declared units
--------------
Units declared in a file win and are applied, with the same rules in every
format: the imunav header's ``units`` (CSV ``# imunav {...}`` line, HDF5 /
Parquet / NPZ / MAT header), unit annotations in column names (``gx[deg/s]``,
``gx (deg/s)``, ``t[ms]``: :func:`column_units`), and unit attributes (HDF5
dataset ``unit`` / ``units`` attributes and the group's ``units`` JSON,
Parquet field metadata ``unit``, MAT char variables ``units`` (JSON) or
``<name>_unit``).  Every declared unit must be a known unit of its quantity
(``deg/s`` for a gyro, not ``g``); two declarations of one group that
disagree, or a reader option that contradicts a declaration, are errors
(:class:`~imunav.errors.UnitError`) naming both.  A reader option only fills
in the unit of a group the file does not declare.
"""

from __future__ import annotations

import inspect
import json
import os
import re
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
    "check_unit",
    "column_units",
    "merge_declared",
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


_COUNTS = ("counts", "count", "lsb", "raw")


def check_unit(unit: Any, group: str, where: str) -> str:
    """A declared unit of ``group`` checked: a non-empty string that is a known unit of the group's quantity.

    Parameters
    ----------
    unit : object
        The declared unit.
    group : str
        ``"t"``, ``"gyro"``, ``"accel"``, ``"mag"`` or ``"temp"``.
    where : str
        Where it is declared (file and place), for the message.

    Returns
    -------
    str
        ``unit``, stripped.

    Raises
    ------
    UnitError
        If the unit is not a string, is empty, or is not a unit of the group's quantity (the message lists
        the accepted spellings).
    """
    if not isinstance(unit, str) or not unit.strip():
        raise UnitError(f"{where}: the unit of {group} must be a unit string such as "
                        f"{SI_UNITS.get(group, 'uT')!r}, got {unit!r}")
    u = re.sub(r"\s*s\^-1$", "/s", re.sub(r"\s*s\^-2$", "/s^2", unit.strip()))  # "rad s^-1" (EuRoC)
    if normalize_unit(u) in _COUNTS:
        return u
    try:
        unit_factor(u, _QUANTITY_OF[group])
    except UnitError as e:
        raise UnitError(f"{where}: {group} is declared in {u!r}, which is not a unit of {_QUANTITY_OF[group]}; "
                        f"{e}") from None
    return u


_ANNOTATION = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<b>[^\]]*)\]|\((?P<p>[^)]*)\))\s*$")


def column_units(cols: Mapping[str, Any], source: str,
                 attributes: Mapping[str, Any] | None = None) -> dict[str, str]:
    """Group units declared by the columns of a table: name annotations and per-column unit attributes.

    Parameters
    ----------
    cols : mapping
        Channel (``t``, ``gx`` ... ``temp``) -> column label.
    source : str
        The file, for messages.
    attributes : mapping, optional
        Column label -> unit attribute (e.g. Parquet field metadata ``unit``).

    Returns
    -------
    dict
        Group -> unit, for the groups whose columns declare one.

    Raises
    ------
    UnitError
        If a declared unit is empty, unknown or of another quantity, if the columns of one group declare
        different units, or some declare one and others none.
    """
    group_of = {"t": "t", "temp": "temp", **{f"{g}{a}": n for g, n in (("g", "gyro"), ("a", "accel"), ("m", "mag"))
                                             for a in "xyz"}}
    per: dict[str, dict[Any, str | None]] = {}
    for ch, label in cols.items():
        g = group_of.get(ch)
        if g is None:
            continue
        unit = None
        m = _ANNOTATION.match(str(label))
        if m is not None and m.group("name"):
            unit = m.group("b") if m.group("b") is not None else m.group("p")
            # an index (``gyro_rad[0]``, PX4) is not a unit
            unit = None if unit.strip().isdigit() else check_unit(unit, g, f"{source}: column {label!r}")
        attr = (attributes or {}).get(label)
        if attr is not None:
            attr = check_unit(attr, g, f"{source}: the unit attribute of column {label!r}")
            if unit is not None and not _same_unit(unit, attr, g):
                raise UnitError(f"{source}: column {label!r} says {unit!r} in its name but {attr!r} in its unit "
                                "attribute; fix one of them")
            unit = unit or attr
        per.setdefault(g, {})[label] = unit
    out: dict[str, str] = {}
    for g, units in per.items():
        given = {lab: u for lab, u in units.items() if u is not None}
        if not given:
            continue
        first_label, first = next(iter(given.items()))
        for lab, u in units.items():
            if u is None or not _same_unit(first, u, g):
                raise UnitError(f"{source}: the {g} columns declare different units ({first_label!r}: {first!r}, "
                                f"{lab!r}: {u!r}); declare one unit for all of them")
        out[g] = first
    return out


def merge_declared(source: str, *declarations: tuple[str, Any]) -> dict[str, str]:
    """The units a file declares, from several places (header, names, attributes), checked and merged.

    Parameters
    ----------
    source : str
        The file, for messages.
    *declarations : tuple of (str, mapping or None)
        ``(where, {group: unit})`` for each place that declares units (None: that place declares none).

    Returns
    -------
    dict
        Group -> unit.

    Raises
    ------
    UnitError
        If a unit is empty, unknown or of another quantity, or two places declare different units for one group.
    FileFormatError
        If a declaration is not a mapping of groups to units.
    """
    out: dict[str, tuple[str, str]] = {}
    for where, decl in declarations:
        if decl is None:
            continue
        if not isinstance(decl, Mapping):
            raise FileFormatError(f"{source}: {where} must map groups to unit strings, got {decl!r}")
        for k, v in decl.items():
            g = {"time": "t", "acc": "accel", "gyr": "gyro", "temperature": "temp"}.get(k, k)
            if g not in _QUANTITY_OF:
                continue  # units of other data (e.g. position) are not ours to check
            u = check_unit(v, g, f"{source}: {where}")
            if g in out and not _same_unit(out[g][1], u, g):
                raise UnitError(f"{source}: {out[g][0]} declares {g} in {out[g][1]!r} but {where} says {u!r}; "
                                "the file contradicts itself: fix one of them")
            out.setdefault(g, (where, u))
    return {g: u for g, (_, u) in out.items()}


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
    declared: Mapping[str, str] | None = None,
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
    stays in its unit (``mag_unit``), optionally scaled from counts.  Units the
    file declares (``stored["units"]``, the imunav header, and ``declared``, from
    column names and attributes: module docstring) win and are applied; an option
    only fills in an undeclared group.
    """
    stored = dict(stored or {})
    u = _group_option(units, "units")
    sc = _group_option(scales, "scales")
    of = _group_option(offsets, "offsets")
    for k, v in u.items():
        if not isinstance(v, str):
            raise UnitError(f"units[{k!r}] must be a unit string such as 'deg/s', got {v!r}")
    decl = merge_declared(source, ("the imunav header", stored.get("units")),
                          ("the column names / unit attributes", declared))
    _check_declared_units(decl, u, source)
    u = {**u, **decl}  # the file's declaration wins (and is applied)
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
            if np.ndim(sc["mag"]) == 0 and not float(sc["mag"]) > 0:
                raise UnitError(f"scales['mag']={sc['mag']!r}: one scale for the three axes is positive (a negative "
                                "one mirrors the triad; zero or NaN loses it); give the field unit per count")
            mag = (np.asarray(mag, dtype=float) - of.get("mag", 0.0)) * np.asarray(sc["mag"], dtype=float)
        elif mu is not None and mag_unit is None:
            mag_unit = mu
    tp = arrays.get("temp")
    if tp is not None and u.get("temp") is not None and normalize_unit(u["temp"]) not in ("degc", "c", "°c"):
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
    if a.dtype.kind == "c":
        raise FileFormatError(f"{source}: {name} holds complex numbers (dtype {a.dtype}); a recording holds real "
                              "samples: write the real part (or the magnitude) as the column")
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
