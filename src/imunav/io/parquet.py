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

from imunav._docstrings import fill_doc
from imunav.errors import FileFormatError, MissingDependencyError
from imunav.files import atomic_path
from imunav.io._common import build_imu, check_nonempty, header_json, parse_header, wrap_read_errors
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


@fill_doc
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

    %(reader_head)s
    columns : mapping, optional
        Column names of each channel or group (see :func:`imunav.io.csv.read_csv`); by default found by
        name.
    %(reader_options)s

    %(reader_returns)s
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
    return build_imu(
        arrays, source, stored=stored, units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


@fill_doc
def write_parquet(data: ImuData, path: str | os.PathLike[str], *, compression: str = "zstd") -> Path:
    """Write ``data`` (SI) as Parquet, float64 columns, atomically.

    %(imu_writer_params)s
    compression : str
        Parquet codec (``"zstd"``, ``"snappy"``, ``"gzip"``, ``"none"``).

    %(returns_file_written)s

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
