"""``read_imu`` / ``write_imu``: one entry point for every recording format.

The format comes from the file suffix unless given:

=========  ==========================  ====================================
format     suffixes                    module
=========  ==========================  ====================================
csv        .csv .txt .tsv .dat         :mod:`imunav.io.csv`
parquet    .parquet .pq                :mod:`imunav.io.parquet`
hdf5       .h5 .hdf5 .hdf              :mod:`imunav.io.hdf5`
mat        .mat (v5; v7.3 on read)     :mod:`imunav.io.mat`
mat73      (write MAT v7.3)            :mod:`imunav.io.mat`
npz        .npz                        :mod:`imunav.io.npz`
=========  ==========================  ====================================
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from imunav.errors import InvalidInputError
from imunav.timeseries import ImuData

__all__ = ["read_imu", "write_imu", "FORMATS", "format_from_suffix"]

FORMATS = ("csv", "parquet", "hdf5", "mat", "mat73", "npz")
_SUFFIXES = {
    ".csv": "csv", ".txt": "csv", ".tsv": "csv", ".dat": "csv",
    ".parquet": "parquet", ".pq": "parquet",
    ".h5": "hdf5", ".hdf5": "hdf5", ".hdf": "hdf5", ".he5": "hdf5",
    ".mat": "mat",
    ".npz": "npz",
}  # fmt: skip
_ALIASES = {"h5": "hdf5", "hdf": "hdf5", "pq": "parquet", "mat5": "mat", "matv5": "mat", "mat7.3": "mat73", "matv73": "mat73", "txt": "csv"}


def format_from_suffix(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format name for ``path`` (or the normalised ``format`` if given)."""
    if format is not None:
        f = str(format).lower().lstrip(".")
        f = _ALIASES.get(f, f)
        if f not in FORMATS:
            raise InvalidInputError(f"unknown format {format!r}; choose one of {list(FORMATS)}")
        return f
    suffix = Path(path).suffix.lower()
    if suffix not in _SUFFIXES:
        raise InvalidInputError(
            f"cannot tell the format of {os.fspath(path)!r} from its suffix {suffix!r}; known suffixes "
            f"{sorted(_SUFFIXES)}; pass format= one of {list(FORMATS)}"
        )
    return _SUFFIXES[suffix]


def _call(fn: Callable[..., Any], what: str, *args: Any, **options: Any) -> Any:
    params = inspect.signature(fn).parameters
    unknown = [k for k in options if k not in params]
    if unknown:
        allowed = [k for k, p in params.items() if p.kind is inspect.Parameter.KEYWORD_ONLY]
        raise InvalidInputError(f"{what} does not take option(s) {unknown}; it accepts {allowed}")
    return fn(*args, **options)


def read_imu(path: str | os.PathLike[str], format: str | None = None, **options: Any) -> ImuData:
    """Read a recording into a validated :class:`~imunav.timeseries.ImuData` (SI).

    Parameters
    ----------
    path : file to read.
    format : ``"csv"``, ``"parquet"``, ``"hdf5"``, ``"mat"`` (v5 and v7.3),
        ``"npz"``; from the suffix when None.
    **options : reader options, common to all formats: ``columns`` (name
        mapping), ``units`` / ``scales`` / ``offsets`` (per group, for non-SI
        or raw-count content), ``fs`` and ``t0`` (when there is no time
        column), ``nan_policy``, ``mag_unit``, ``meta``; CSV also takes
        ``delimiter`` and ``skiprows``, HDF5 ``group``.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from imunav.timeseries import ImuData
    >>> d = ImuData(np.arange(3) / 100, np.zeros((3, 3)), np.tile([0, 0, -9.81], (3, 1)))
    >>> p = os.path.join(tempfile.mkdtemp(), "rec.h5")
    >>> _ = write_imu(d, p)
    >>> read_imu(p).accel[0, 2]
    np.float64(-9.81)
    """
    fmt = format_from_suffix(path, format)
    from imunav.io import csv, hdf5, mat, npz, parquet

    reader = {"csv": csv.read_csv, "parquet": parquet.read_parquet, "hdf5": hdf5.read_hdf5,
              "mat": mat.read_mat, "mat73": mat.read_mat, "npz": npz.read_npz}[fmt]  # fmt: skip
    return _call(reader, f"read_imu(format={fmt!r})", path, **options)


def write_imu(data: ImuData, path: str | os.PathLike[str], format: str | None = None, **options: Any) -> Path:
    """Write ``data`` atomically (temporary file in the same folder, then rename).

    ``format`` as in :func:`read_imu`, plus ``"mat73"`` for MAT v7.3 (or
    ``format="mat", version="7.3"``).  SI values, ``mag_unit`` and ``meta``
    are stored; every reader gives back the same bits.
    """
    if not isinstance(data, ImuData):
        raise InvalidInputError(f"write_imu needs an ImuData, got {type(data).__name__}")
    fmt = format_from_suffix(path, format)
    from imunav.io import csv, hdf5, mat, npz, parquet

    if fmt == "mat73":
        options.setdefault("version", "7.3")
    writer = {"csv": csv.write_csv, "parquet": parquet.write_parquet, "hdf5": hdf5.write_hdf5,
              "mat": mat.write_mat, "mat73": mat.write_mat, "npz": npz.write_npz}[fmt]  # fmt: skip
    return _call(writer, f"write_imu(format={fmt!r})", data, path, **options)
