"""Parquet recordings (pyarrow): one float64 column per channel.

Columns are named as in the CSV writer (``t, gyro_x ... temp``); the imunav
JSON header (SI units, ``mag_unit``, ``meta``) is stored in the schema
metadata under the key ``imunav``.  Reading accepts the same ``columns`` /
``units`` / ``scales`` options as :func:`imunav.io.csv.read_csv`, so Parquet
files from other tools can be mapped.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, MissingDependencyError
from imunav.files import atomic_path
from imunav.io._common import build_imu, check_nonempty, column_units, header_json, parse_header, wrap_read_errors
from imunav.io.csv import imu_to_table, resolve_columns, table_to_arrays
from imunav.timeseries import ImuData

__all__ = ["read_parquet", "write_parquet"]


def _pyarrow() -> tuple[Any, Any]:
    """``(pyarrow, pyarrow.parquet)``; pyarrow (170 MB) is the ``parquet`` extra, kept out of the core install."""
    try:
        import pyarrow as pa  # optional: the `parquet` extra
        import pyarrow.parquet as pq  # optional: the `parquet` extra
    except ImportError as exc:
        raise MissingDependencyError("pyarrow", "parquet", "Reading and writing Parquet files") from exc
    return pa, pq


_META_KEY = b"imunav"


def read_parquet(
    path: str | os.PathLike[str],
    *,
    columns: Mapping[str, Any] | None = None,
    units: Mapping[str, str] | None = None,
    scales: Mapping[str, float] | None = None,
    offsets: Mapping[str, float] | None = None,
    fs: float | None = None,
    t0: float = 0.0,
    nan_policy: str = "raise",
    mag_unit: str | None = None,
    meta: Mapping[str, Any] | None = None,
) -> ImuData:
    """Read a Parquet recording (options as :func:`imunav.io.csv.read_csv`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    columns : mapping, optional
        Column names of each channel or group (see :func:`imunav.io.csv.read_csv`); by default found by
        name.
    units : mapping of str to str, optional
        Declared unit of each group (``{"gyro": "deg/s", "accel": "g"}``, or ``"counts"``); default SI.
    scales, offsets : mapping of str to float, optional
        For ``"counts"``: ``value_si = (counts - offset) * scale``.
    fs : float, optional
        Sample rate, Hz, when the file has no time (``t = t0 + k / fs``).
    t0 : float
        Time of the first sample with ``fs``, s.
    nan_policy : {"raise", "drop", "interpolate"}
        What to do with NaN samples.
    mag_unit : str, optional
        Unit of the magnetometer (kept as stored).
    meta : mapping, optional
        Entries added to the recording's ``meta``.

    Returns
    -------
    ImuData
        The recording, SI.

    Raises
    ------
    FileFormatError
        If the file is missing, unreadable, or lacks a required group (the message lists what was found).
    NonFiniteError, TimeOrderError, ShapeError, UnitError
        From the validation of the values.
    MissingDependencyError
        If pyarrow is not installed (``pip install 'imunav[parquet]'``).
    """
    _, pq = _pyarrow()
    source = check_nonempty(path)
    with wrap_read_errors(source, "Parquet"):
        table = pq.read_table(source)
    md = table.schema.metadata or {}
    stored = parse_header(md.get(_META_KEY), source)
    if table.num_rows == 0:
        raise FileFormatError(f"{source}: the Parquet file has columns {table.column_names} but no rows")
    with wrap_read_errors(source, "Parquet"):
        df = table.to_pandas()
    cols = resolve_columns(list(df.columns), columns, source)
    arrays = table_to_arrays(df, cols, source)
    attrs = {}
    for f in table.schema:
        unit = (f.metadata or {}).get(b"unit", (f.metadata or {}).get(b"units"))
        if unit is not None:
            attrs[f.name] = unit.decode("utf-8", errors="replace")
    return build_imu(
        arrays, source, stored=stored, declared=column_units(cols, source, attrs), units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


def write_parquet(data: ImuData, path: str | os.PathLike[str], *, compression: str = "zstd") -> Path:
    """Write ``data`` (SI) as Parquet, float64 columns, atomically.

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    compression : str
        Parquet codec (``"zstd"``, ``"snappy"``, ``"gzip"``, ``"none"``).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    MissingDependencyError
        If pyarrow is not installed.
    """
    pa, pq = _pyarrow()
    names, block = imu_to_table(data)
    schema = pa.schema([pa.field(n, pa.float64(), nullable=False) for n in names], metadata={_META_KEY: header_json(data).encode()})
    table = pa.table([pa.array(np.ascontiguousarray(block[:, j])) for j in range(block.shape[1])], schema=schema)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp, compression=compression)
    return Path(path)
