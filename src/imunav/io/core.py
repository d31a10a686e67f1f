"""``read_imu`` / ``write_imu``: one entry point for every recording format.

The format comes from the file suffix unless given:

=======  =============================  =============================================
format   suffixes                       module
=======  =============================  =============================================
csv      .csv .txt .tsv .dat            :mod:`imunav.io.csv`
parquet  .parquet .pq                   :mod:`imunav.io.parquet`
hdf5     .h5 .hdf5 .hdf                 :mod:`imunav.io.hdf5`
mat      .mat (v5; v7.3 on read)        :mod:`imunav.io.mat`
mat73    (write MAT v7.3)               :mod:`imunav.io.mat`
npz      .npz                           :mod:`imunav.io.npz`
rosbag   .bag .db3 .mcap, ROS 2 folder  :mod:`imunav.io.rosbag` (read; extra ``ros``)
ulog     .ulg                           :mod:`imunav.io.ulog` (read; extra ``px4``)
=======  =============================  =============================================

Bags and logs are also recognised by their content (magic bytes) whatever their suffix; see
:mod:`imunav.io.logs`.  Named CSV layouts (``layout="euroc"`` ...) are in :mod:`imunav.io.layouts`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from imunav.errors import InvalidInputError
from imunav.io import csv, hdf5, mat, npz, parquet
from imunav.io._common import call_reader
from imunav.io.layouts import read_layout
from imunav.io.logs import log_kind, read_log_imu
from imunav.timeseries import ImuData

__all__ = ["read_imu", "write_imu", "FORMATS", "format_from_suffix"]

FORMATS = ("csv", "parquet", "hdf5", "mat", "mat73", "npz")
#: Formats that are read only (through an optional extra).
LOG_FORMATS = ("rosbag", "ulog")
_SUFFIXES = {
    ".csv": "csv", ".txt": "csv", ".tsv": "csv", ".dat": "csv",
    ".parquet": "parquet", ".pq": "parquet",
    ".h5": "hdf5", ".hdf5": "hdf5", ".hdf": "hdf5", ".he5": "hdf5",
    ".mat": "mat",
    ".npz": "npz",
}  # fmt: skip
_ALIASES = {"bag": "rosbag", "mcap": "rosbag", "db3": "rosbag", "ulg": "ulog", "h5": "hdf5", "hdf": "hdf5", "pq": "parquet", "mat5": "mat", "matv5": "mat", "mat7.3": "mat73", "matv73": "mat73", "txt": "csv"}


def format_from_suffix(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format name for ``path`` (or the normalised ``format`` if given), from the table of the module
    docstring.

    Parameters
    ----------
    path : str or os.PathLike
        The file (or ROS 2 bag folder).
    format : str, optional
        A format name or alias; overrides the suffix.

    Returns
    -------
    str
        ``"csv"``, ``"parquet"``, ``"hdf5"``, ``"mat"``, ``"mat73"``, ``"npz"``, ``"rosbag"`` or ``"ulog"``.

    Raises
    ------
    InvalidInputError
        If the format is unknown or the suffix not recognised.
    """
    if format is not None:
        f = str(format).lower().lstrip(".")
        f = _ALIASES.get(f, f)
        if f not in FORMATS + LOG_FORMATS:
            raise InvalidInputError(f"unknown format {format!r}; choose one of {list(FORMATS + LOG_FORMATS)}")
        return f

    kind = log_kind(path)
    if kind is not None:
        return kind
    suffix = Path(path).suffix.lower()
    if suffix not in _SUFFIXES:
        what = ("a folder that is not a ROS 2 bag (no metadata.yaml; a comma2k19 segment is read by gins run)"
                if os.path.isdir(path) else f"its suffix {suffix!r}")
        raise InvalidInputError(
            f"cannot tell the format of {os.fspath(path)!r} from {what}; known suffixes "
            f"{sorted(_SUFFIXES) + ['.bag', '.db3', '.mcap', '.ulg']}; give format=NAME (command line: --format "
            f"NAME), NAME one of {', '.join(FORMATS)}"
        )
    return _SUFFIXES[suffix]


def read_imu(path: str | os.PathLike[str], format: str | None = None, *, layout: str | None = None,
             **options: Any) -> ImuData:
    """Read a recording into a validated :class:`~imunav.timeseries.ImuData` (SI).

    Parameters
    ----------
    path : str or os.PathLike
        File to read (a ROS 2 bag may be its folder).
    format : str, optional
        ``"csv"``, ``"parquet"``, ``"hdf5"``, ``"mat"`` (v5 and v7.3),
        ``"npz"``, ``"rosbag"`` (ROS 1 / ROS 2 sqlite3 / MCAP), ``"ulog"``
        (PX4); from the suffix or content when None.
    layout : str, optional
        A named CSV layout (``"euroc"``, ``"tum-vi"``, ``"kalibr"``,
        ``"px4-csv"``, ``"xio"``; see :mod:`imunav.io.layouts`).
    **options
        Reader options, common to all formats: ``columns`` (name
        mapping), ``units`` / ``scales`` / ``offsets`` (per group, for non-SI
        or raw-count content), ``fs`` and ``t0`` (when there is no time
        column), ``nan_policy``, ``mag_unit``, ``meta``; CSV also takes
        ``delimiter`` and ``skiprows``, HDF5 ``group``.  Bags and ULogs take
        ``topic``, ``instance`` (PX4 ``multi_id``), ``mag_topic``,
        ``temp_topic`` and ``meta`` (:func:`imunav.io.logs.read_log_imu`).

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from imunav.timeseries import ImuData
    >>> d = ImuData(np.arange(3) / 100, np.zeros((3, 3)), np.tile([0, 0, -9.81], (3, 1)))
    >>> p = os.path.join(tempfile.mkdtemp(), "rec.h5")
    >>> _ = write_imu(d, p)
    >>> read_imu(p).accel[0, 2]
    np.float64(-9.81)

    Returns
    -------
    ImuData
        The recording in SI units (rad/s, m/s², °C), time in s.

    Raises
    ------
    InvalidInputError
        If the format cannot be told or the options do not fit it; the readers raise
        :class:`~imunav.errors.FileFormatError`, :class:`~imunav.errors.UnitError`, ... for bad content.
    """
    if layout is not None:
        if format not in (None, "csv"):
            raise InvalidInputError(f"layout={layout!r} names a CSV layout; it does not combine with format={format!r}")
        return call_reader(read_layout, f"read_imu(layout={layout!r})", path, layout, **options)
    fmt = format_from_suffix(path, format)
    if fmt in LOG_FORMATS:
        return call_reader(read_log_imu, f"read_imu(format={fmt!r})", path, **options)

    reader = {"csv": csv.read_csv, "parquet": parquet.read_parquet, "hdf5": hdf5.read_hdf5,
              "mat": mat.read_mat, "mat73": mat.read_mat, "npz": npz.read_npz}[fmt]  # fmt: skip
    return call_reader(reader, f"read_imu(format={fmt!r})", path, **options)


def write_imu(data: ImuData, path: str | os.PathLike[str], format: str | None = None, **options: Any) -> Path:
    """Write ``data`` atomically (temporary file in the same folder, then rename).

    SI values, ``mag_unit`` and ``meta`` are stored; every reader gives back the same bits.

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    format : str, optional
        As in :func:`read_imu`, plus ``"mat73"`` for MAT v7.3 (or ``format="mat", version="7.3"``); from the
        suffix when None.  Bags and logs cannot be written.
    **options
        Writer options (e.g. ``compression`` for HDF5, ``version`` for MAT).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InvalidInputError
        If ``data`` is not an ImuData, or the format is unknown or read-only.
    """
    if not isinstance(data, ImuData):
        raise InvalidInputError(f"write_imu needs an ImuData, got {type(data).__name__}")
    fmt = format_from_suffix(path, format)
    if fmt in LOG_FORMATS:
        raise InvalidInputError(f"write_imu does not write {fmt} files; write_bag in imunav.io.rosbag writes a ROS bag, "
                                f"or choose a table format {list(FORMATS)}")

    if fmt == "mat73":
        options.setdefault("version", "7.3")
    writer = {"csv": csv.write_csv, "parquet": parquet.write_parquet, "hdf5": hdf5.write_hdf5,
              "mat": mat.write_mat, "mat73": mat.write_mat, "npz": npz.write_npz}[fmt]  # fmt: skip
    return call_reader(writer, f"write_imu(format={fmt!r})", data, path, **options)
