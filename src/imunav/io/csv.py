"""CSV recordings: column mapping, declared units, exact float round trip.

Reading
-------
Columns are found by name (case-insensitive, ignoring ``_``, spaces, dots and
unit annotations such as ``[deg/s]``; an annotation declares the unit of its
column and is applied, :mod:`imunav.io._common`): ``t``/``time``/``timestamp``,
``gyro_x``/``gyr_x``/``gx``/``wx``, ``accel_x``/``acc_x``/``ax``,
``mag_x``/``mx``, ``temp``/``temperature``.  Any other naming is mapped
explicitly with ``columns={"t": "time_s", "gx": "GyrX", ...}`` (channel keys
``t gx gy gz ax ay az mx my mz temp``, or group keys ``gyro``/``accel``/``mag``
with a list of three names; integer positions work for header-less files).
Time may also be an ISO 8601 date-time column (seconds since the first sample;
the first date-time goes to ``meta["t_origin"]``).  Units, raw-count scales
and offsets are declared per group
(``units={"gyro": "deg/s", "accel": "g", "t": "ms"}``,
``scales={"accel": 9.80665 / 16384}``) and converted to SI.  The delimiter
(``,`` ``;`` tab ``|`` or whitespace) is detected from the header line.

Writing
-------
One comment line ``# imunav {json}`` (SI units, ``mag_unit``, ``meta``), a
header, then one row per sample with every float written by ``repr`` (the
shortest string that parses back to the same double), so that reading the
file gives the same bits.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import atomic_path
from imunav.io._common import build_imu, check_nonempty, column_units, header_json, parse_header, wrap_read_errors
from imunav.timeseries import ImuData

__all__ = ["read_csv", "write_csv", "CHANNELS", "DEFAULT_NAMES", "resolve_columns"]

#: Logical channels of a tabular recording.
CHANNELS = ("t", "gx", "gy", "gz", "ax", "ay", "az", "mx", "my", "mz", "temp")
#: Column names written by :func:`write_csv` / the Parquet writer.
DEFAULT_NAMES = {
    "t": "t",
    "gx": "gyro_x", "gy": "gyro_y", "gz": "gyro_z",
    "ax": "accel_x", "ay": "accel_y", "az": "accel_z",
    "mx": "mag_x", "my": "mag_y", "mz": "mag_z",
    "temp": "temp",
}  # fmt: skip
_GROUP_CHANNELS = {"gyro": ("gx", "gy", "gz"), "accel": ("ax", "ay", "az"), "mag": ("mx", "my", "mz")}
_PREFIXES = {
    "g": ("gyro", "gyr", "g", "gyroscope", "omega", "w", "angvel", "angularrate", "rate"),
    "a": ("accel", "acc", "a", "accelerometer", "f", "specificforce", "accl"),
    "m": ("mag", "m", "magnetometer", "magn", "h"),
}
_CHANNEL_ALIASES: dict[str, set[str]] = {
    "t": {"t", "time", "times", "timestamp", "timestamps", "sec", "seconds", "timesec"},
    "temp": {"temp", "temperature", "tempc", "temperaturec", "imutemp"},
}
for _g, _prefixes in _PREFIXES.items():
    for _ax in "xyz":
        _CHANNEL_ALIASES[f"{_g}{_ax}"] = {f"{p}{_ax}" for p in _prefixes}

_SNIFF = (",", ";", "\t", "|")
# pandas < 3 parses floats fast but inexactly unless asked for round-trip
# precision; pandas 3 is exact by default and deprecates the option.
_PRECISION = {"float_precision": "round_trip"} if int(pd.__version__.split(".")[0]) < 3 else {}


def _norm(name: str) -> str:
    s = str(name).strip().lower()
    s = re.sub(r"[\[(].*?[\])]", "", s)  # drop "[deg/s]" / "(s)" annotations
    return re.sub(r"[\s_.\-/]", "", s)


def resolve_columns(
    found: Sequence[Any], columns: Mapping[str, Any] | None, source: str
) -> dict[str, Any]:
    """Map channels (``t``, ``gx`` ... ``temp``) to column labels of a table.

    Parameters
    ----------
    found : sequence
        Column labels of the table.
    columns : mapping, optional
        User mapping of channels or groups to labels (see the module docstring); None: by name.
    source : str
        The file, for messages.

    Returns
    -------
    dict
        Channel -> column label, for the channels present.

    Raises
    ------
    FileFormatError
        If a mapped column is absent, if gyro or accel columns cannot be
        found, or if a group is incomplete; the message lists the columns
        found and the names expected.
    InvalidInputError
        If a group of ``columns`` does not list 3 names, or names an unknown channel.
    """
    labels = list(found)
    out: dict[str, Any] = {}
    for k, v in (columns or {}).items():
        key = {"time": "t", "temperature": "temp", "acc": "accel", "gyr": "gyro"}.get(k, k)
        if key in _GROUP_CHANNELS:
            if isinstance(v, (str, bytes)) or not isinstance(v, Sequence) or len(v) != 3:
                raise InvalidInputError(f"columns[{k!r}] must list 3 column names (x, y, z), got {v!r}")
            pairs = list(zip(_GROUP_CHANNELS[key], v, strict=True))
        elif key in CHANNELS:
            pairs = [(key, v)]
        else:
            raise InvalidInputError(
                f"columns has unknown key {k!r}; use channels {list(CHANNELS)} or groups ['gyro', 'accel', 'mag']"
            )
        for ch, name in pairs:
            if name in labels:
                out[ch] = name
            elif isinstance(name, int) and not isinstance(name, bool) and 0 <= name < len(labels):
                out[ch] = labels[name]
            else:
                raise FileFormatError(
                    f"{source}: column {name!r} (columns[{k!r}]) not found; the file has columns {labels}"
                )
    by_norm: dict[str, list[Any]] = {}
    for lab in labels:
        by_norm.setdefault(_norm(lab), []).append(lab)
    taken = set(out.values())
    for ch in CHANNELS:
        if ch in out:
            continue
        hits = [lab for a in _CHANNEL_ALIASES[ch] for lab in by_norm.get(a, []) if lab not in taken]
        if len(hits) > 1:
            raise FileFormatError(
                f"{source}: several columns could be {ch!r}: {hits}; choose one with columns={{{ch!r}: '<name>'}}"
            )
        if hits:
            out[ch] = hits[0]
            taken.add(hits[0])
    missing = [ch for g in ("gyro", "accel") for ch in _GROUP_CHANNELS[g] if ch not in out]
    if missing:
        expected = {ch: DEFAULT_NAMES[ch] for ch in missing}
        raise FileFormatError(
            f"{source}: cannot find the columns for {missing}. Found columns {labels}; expected names like "
            f"{expected} (also gyr_x/gx/wx, acc_x/ax, ...). Map them explicitly, e.g. "
            f"read_imu(path, columns={{'gx': '<name>', ..., 'az': '<name>'}})"
        )
    part = [g for g in ("mag",) if 0 < sum(ch in out for ch in _GROUP_CHANNELS[g]) < 3]
    if part:
        have = [ch for ch in _GROUP_CHANNELS["mag"] if ch in out]
        raise FileFormatError(
            f"{source}: only {have} of the magnetometer columns were found in {labels}; "
            "map all three with columns={'mx': ..., 'my': ..., 'mz': ...}"
        )
    return out


def table_to_arrays(df: pd.DataFrame, cols: Mapping[str, Any], source: str) -> dict[str, np.ndarray | None]:
    """Stack the mapped columns of a table into group arrays.

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    cols : mapping
        Channel -> column label (:func:`resolve_columns`).
    source : str
        The file, for messages.

    Returns
    -------
    dict of str to numpy.ndarray or None
        ``t`` (N,) (date-times become seconds since the first, with ``t_origin`` kept), ``gyro``,
        ``accel`` (N, 3), ``mag`` (N, 3) or None, ``temp`` (N,) or None, float64, in the file's units.

    Raises
    ------
    FileFormatError
        If a column holds non-numeric values, or the time column has a missing or unreadable value.
    """

    def col(ch: str) -> np.ndarray:
        s = df[cols[ch]]
        if not (pd.api.types.is_numeric_dtype(s) and not pd.api.types.is_bool_dtype(s)):
            num = pd.to_numeric(s, errors="coerce")
            bad = np.flatnonzero(num.isna().to_numpy() & s.notna().to_numpy())
            row = int(bad[0]) if bad.size else 0
            raise FileFormatError(
                f"{source}: column {cols[ch]!r} ({ch}) holds non-numeric values, first at data row {row} "
                f"({s.iloc[row]!r}); fix the file or map another column"
            )
        return s.to_numpy(dtype=np.float64)

    arrays: dict[str, Any] = {"t": None}
    if "t" in cols:
        s_t = df[cols["t"]]
        dt_kind = pd.api.types.is_datetime64_any_dtype(s_t) or pd.api.types.is_timedelta64_dtype(s_t)
        if not dt_kind and not pd.api.types.is_numeric_dtype(s_t):
            # ISO 8601 date-time strings ("2024-05-01T12:00:00.010Z") are common in logger files
            try:
                s_t = pd.to_datetime(s_t, format="ISO8601")
                dt_kind = True
            except (ValueError, TypeError):
                parsed = pd.to_datetime(s_t, format="ISO8601", errors="coerce")
                if parsed.notna().iloc[0]:  # a date-time column with a bad entry
                    row = int(np.flatnonzero(parsed.isna().to_numpy())[0])
                    raise FileFormatError(
                        f"{source}: time column {cols['t']!r} holds date-times but data row {row} "
                        f"({s_t.iloc[row]!r}) is not an ISO 8601 date-time"
                    ) from None
        if dt_kind:
            if s_t.isna().any():
                row = int(np.flatnonzero(s_t.isna().to_numpy())[0])
                raise FileFormatError(f"{source}: time column {cols['t']!r} has a missing value at data row {row}")
            if isinstance(s_t.dtype, pd.DatetimeTZDtype):
                s_t = s_t.dt.tz_convert(None)  # to UTC, naive
            ns = s_t.to_numpy().astype("datetime64[ns]" if pd.api.types.is_datetime64_any_dtype(s_t) else "timedelta64[ns]")
            ticks = ns.view(np.int64)
            # seconds since the first sample (exact to the ns for 104 days); the origin goes to meta
            arrays["t"] = (ticks - ticks[0]).astype(np.float64) * 1e-9
            arrays["t_origin"] = str(s_t.iloc[0].isoformat()) if hasattr(s_t.iloc[0], "isoformat") else str(s_t.iloc[0])
        elif pd.api.types.is_integer_dtype(s_t) and len(s_t) and int(np.abs(s_t.to_numpy()).max()) > 2**53:
            # integer stamps beyond 2**53 (ns since 1970: EuRoC, TUM-VI, Kalibr) are not exact as float64:
            # subtract the first one in integer arithmetic; it goes to meta (in the file's time unit)
            ticks = s_t.to_numpy(dtype=np.int64)
            arrays["t"] = (ticks - ticks[0]).astype(np.float64)
            arrays["t_origin_raw"] = int(ticks[0])
        else:
            arrays["t"] = col("t")
    for g, chans in _GROUP_CHANNELS.items():
        arrays[g] = np.column_stack([col(c) for c in chans]) if all(c in cols for c in chans) else None
    arrays["temp"] = col("temp") if "temp" in cols else None
    return arrays


def imu_to_table(data: ImuData) -> tuple[list[str], np.ndarray]:
    """Column names and an (N, k) float64 block of an :class:`ImuData` (SI).

    Parameters
    ----------
    data : ImuData
        The recording.

    Returns
    -------
    names : list of str
        ``t``, gyro, accel, then magnetometer and temperature columns when present.
    block : numpy.ndarray, shape (N, k)
        The values, SI.
    """
    names = [DEFAULT_NAMES[c] for c in ("t", "gx", "gy", "gz", "ax", "ay", "az")]
    blocks = [data.t[:, None], data.gyro, data.accel]
    if data.mag is not None:
        names += [DEFAULT_NAMES[c] for c in ("mx", "my", "mz")]
        blocks.append(data.mag)
    if data.temp is not None:
        names.append(DEFAULT_NAMES["temp"])
        blocks.append(data.temp[:, None])
    return names, np.hstack(blocks)


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def _split(line: str, sep: str | None) -> list[str]:
    return line.split() if sep is None else line.split(sep)


def _last_line(path: str) -> str:
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - 65536))
        tail = fh.read().decode("utf-8", errors="replace")
    lines = [ln for ln in tail.splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def read_csv(
    path: str | os.PathLike[str],
    *,
    columns: Mapping[str, Any] | None = None,
    units: Mapping[str, str] | None = None,
    scales: Mapping[str, float] | None = None,
    offsets: Mapping[str, float] | None = None,
    fs: float | None = None,
    t0: float = 0.0,
    delimiter: str | None = None,
    skiprows: int = 0,
    nan_policy: str = "raise",
    mag_unit: str | None = None,
    meta: Mapping[str, Any] | None = None,
) -> ImuData:
    """Read a CSV (or other delimited text) recording.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    columns : mapping, optional
        Channels / groups to column names (see the module docstring); by default found by name.
    units : mapping of str to str, optional
        Declared unit of each group (``{"gyro": "deg/s", "accel": "g"}``, or ``"counts"``); default SI.
    scales, offsets : mapping of str to float, optional
        For ``"counts"``: ``value_si = (counts - offset) * scale``.
    fs : float, optional
        Sample rate, Hz, when the file has no time (``t = t0 + k / fs``).
    t0 : float
        Time of the first sample with ``fs``, s.
    delimiter : str, optional
        Column separator; detected from the header line when None (``,`` ``;`` tab ``|``, else whitespace).
    skiprows : int
        Lines to skip before the header (after ``#`` comment lines).
    nan_policy : {"raise", "drop", "interpolate"}
        What to do with NaN samples.
    mag_unit : str, optional
        Unit of the magnetometer (kept as stored).
    meta : mapping, optional
        Entries added to the recording's ``meta``.

    Returns
    -------
    ImuData
        The recording, SI, with the declared units and the header's metadata.

    Raises
    ------
    FileFormatError
        Empty file, no data rows, truncated last row, missing / unknown
        columns (the message lists found and expected names), text in a
        numeric column.
    NonFiniteError, TimeOrderError, ShapeError, UnitError
        From the validation of the values (rows named).
    """
    source = check_nonempty(path)
    stored: dict[str, Any] = {}
    n_skip = 0
    header_line = None
    # utf-8-sig: spreadsheet exports often start with a byte-order mark
    with open(source, encoding="utf-8-sig", errors="replace") as fh:
        for i, line in enumerate(fh):
            s = line.strip()
            if i < skiprows:
                continue
            if not s:
                n_skip = i + 1
                continue
            if s.startswith("#"):
                if s.startswith("# imunav "):
                    stored = parse_header(s[len("# imunav ") :], source)
                n_skip = i + 1
                continue
            header_line = s
            n_skip = i
            break
    if header_line is None:
        raise FileFormatError(f"{source}: the file has no header and no data (only comments or blank lines)")
    sep = delimiter
    if sep is None:
        counts = {c: header_line.count(c) for c in _SNIFF}
        best = max(counts, key=lambda c: counts[c])
        sep = best if counts[best] > 0 else None
    fields = _split(header_line, sep)
    has_header = not all(_is_number(f) for f in fields)
    if has_header:
        names = [f.strip().strip('"') for f in fields]
        twice = sorted({n for n in names if names.count(n) > 1 and n})
        if twice:
            raise FileFormatError(f"{source}: the header names column(s) {twice} more than once; which one holds the "
                                  "data is not said: rename or remove the repeated column")
    with wrap_read_errors(source, "delimited text"):
        df = pd.read_csv(
            source,
            sep=r"\s+" if sep is None else sep,
            skiprows=n_skip,
            header=0 if has_header else None,
            **_PRECISION,
            skip_blank_lines=True,
            skipinitialspace=True,
            engine="c",
            encoding="utf-8-sig",
        )
    if has_header:
        df.columns = [str(c).strip() for c in df.columns]
    if len(df) == 0:
        raise FileFormatError(f"{source}: header {list(df.columns)} but no data rows")
    last = _split(_last_line(source).strip(), sep)
    with open(source, "rb") as fh:
        fh.seek(-1, os.SEEK_END)
        ends_with_newline = fh.read(1) in (b"\n", b"\r")
    if len(last) < df.shape[1]:
        raise FileFormatError(
            f"{source}: the last row has {len(last)} of {df.shape[1]} fields; the file looks truncated "
            f"(cut while writing?). Remove the incomplete last line (data row {len(df) - 1}) and read again"
        )
    if stored and not ends_with_newline:
        # imunav always ends its files with a newline: a missing one means the
        # write was cut, possibly inside the last number
        raise FileFormatError(
            f"{source}: the file written by imunav does not end with a newline; it looks truncated "
            f"(cut while writing?). Remove the incomplete last line (data row {len(df) - 1}) and read again"
        )
    cols = resolve_columns(list(df.columns), columns, source)
    arrays = table_to_arrays(df, cols, source)
    return build_imu(
        arrays, source, stored=stored, declared=column_units(cols, source), units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


def write_csv(data: ImuData, path: str | os.PathLike[str], *, delimiter: str = ",") -> Path:
    """Write ``data`` (SI) as CSV with exact (``repr``) floats; atomic.

    The first line is a ``# imunav {json}`` header (units, ``mag_unit``, ``meta``), read back by
    :func:`read_csv`.

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    delimiter : str
        Column separator.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    names, block = imu_to_table(data)
    head = f"# imunav {header_json(data)}\n{delimiter.join(names)}\n"
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(head)
            chunk = 100_000
            for i in range(0, block.shape[0], chunk):
                rows = block[i : i + chunk].tolist()
                fh.write("\n".join(delimiter.join(map(repr, r)) for r in rows))
                fh.write("\n")
    return Path(path)
