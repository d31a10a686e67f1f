"""HDF5 recordings (h5py, the ``hdf5`` extra: ``pip install 'imunav[hdf5]'``).

Layout written (inside ``group``, default the root): datasets ``t`` (N,),
``gyro`` (N, 3), ``accel`` (N, 3), optional ``mag`` (N, 3) and ``temp`` (N,),
all float64 SI; attributes ``units`` (JSON: unit of each dataset),
``mag_unit`` and ``imunav`` (the full JSON header with ``meta``).  Reading
finds datasets by name (``t``/``time``, ``gyro``/``gyr``/``imu_gyr``,
``accel``/``acc``/``imu_acc``, ``mag``, ``temp``, or a scalar ``fs``) or by an
explicit ``columns={"gyro": "imu/gyr"}`` mapping; ``units`` / ``scales``
declare non-SI content as in the CSV reader.  Unit attributes (a dataset's
``unit`` / ``units``, the group's ``units`` JSON) declare the units of the
file and are applied (:mod:`imunav.io._common`).
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imunav.errors import FileFormatError, MissingDependencyError
from imunav.files import atomic_path
from imunav.io._common import (
    SI_UNITS,
    build_imu,
    check_nonempty,
    find_array_names,
    header_json,
    merge_declared,
    parse_header,
    wrap_read_errors,
)
from imunav.timeseries import ImuData

if TYPE_CHECKING:
    import h5py

__all__ = ["read_hdf5", "write_hdf5"]


def load_h5py(feature: str) -> Any:
    """The ``h5py`` module; h5py (17 MB with its HDF5 library) is the ``hdf5`` extra, kept out of the core install.

    Parameters
    ----------
    feature : str
        What needs it, for the message (e.g. ``"Reading and writing HDF5 files"``).

    Returns
    -------
    module
        ``h5py``.

    Raises
    ------
    MissingDependencyError
        If h5py is not installed (the message names the extra).
    """
    try:
        import h5py  # optional: the `hdf5` extra
    except ImportError as exc:
        raise MissingDependencyError("h5py", "hdf5", feature) from exc
    return h5py


def _text(v: Any) -> Any:
    """An HDF5 string attribute as text (bytes and 0-d arrays unpacked)."""
    v = v.item() if isinstance(v, np.ndarray) and v.ndim == 0 else v
    return v.decode("utf-8", errors="replace") if isinstance(v, bytes) else v


def _datasets(group: h5py.Group) -> list[str]:
    names: list[str] = []
    dataset = load_h5py("Reading HDF5 files").Dataset

    def visit(name: str, obj: Any) -> None:
        if isinstance(obj, dataset):
            names.append(name)

    group.visititems(visit)
    return names


def read_hdf5(
    path: str | os.PathLike[str],
    *,
    group: str = "/",
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    scales: Mapping[str, float] | None = None,
    offsets: Mapping[str, float] | None = None,
    fs: float | None = None,
    t0: float = 0.0,
    nan_policy: str = "raise",
    mag_unit: str | None = None,
    meta: Mapping[str, Any] | None = None,
) -> ImuData:
    """Read an HDF5 recording (see the module docstring for the layout).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    group : str
        HDF5 group holding the datasets.
    columns : mapping of str to str, optional
        Where each group is stored (e.g. ``{"gyro": "imu/gyr"}``); by default found by name.
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
    """
    source = check_nonempty(path)
    h5py = load_h5py("Reading HDF5 files")
    with wrap_read_errors(source, "HDF5"):
        fh = h5py.File(source, "r")
    with fh, wrap_read_errors(source, "HDF5"):
        if group not in fh:
            raise FileFormatError(f"{source}: no group {group!r}; groups/datasets at the root: {sorted(fh.keys())}")
        g = fh[group]
        names = _datasets(g)
        found = find_array_names(names, columns, source, kind="dataset")
        stored = parse_header(g.attrs.get("imunav"), source)
        arrays: dict[str, Any] = {}
        attrs: dict[str, Any] = {}
        for key, name in found.items():
            arrays[key] = np.asarray(g[name][()])
            for a in ("unit", "units"):
                if a in g[name].attrs and key != "fs":
                    attrs[key] = _text(g[name].attrs[a])
        group_units = g.attrs.get("units")
        group_units = None if group_units is None else parse_header(_text(group_units), f"{source} (units attribute)")
    return build_imu(
        arrays, source, stored=stored,
        declared=merge_declared(source, ("the units attribute of the group", group_units or None),
                                ("the unit attributes of the datasets", attrs)),
        units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


def write_hdf5(
    data: ImuData, path: str | os.PathLike[str], *, group: str = "/", compression: str | None = None
) -> Path:
    """Write ``data`` (SI, float64) to HDF5 atomically (layout in the module docstring).

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    group : str
        HDF5 group to write into.
    compression : str, optional
        h5py dataset compression (e.g. ``"gzip"``).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    units = dict(SI_UNITS)
    if data.mag is not None:
        units["mag"] = data.mag_unit
    def fill(fh: Any) -> None:
        g = fh.require_group(group)
        for name in ("t", "gyro", "accel", "mag", "temp"):
            a = getattr(data, name)
            if a is None:
                continue
            ds = g.create_dataset(name, data=np.ascontiguousarray(a, dtype=np.float64), compression=compression)
            ds.attrs["unit"] = units[name]
        g.attrs["units"] = json.dumps({k: v for k, v in units.items() if getattr(data, k) is not None})
        g.attrs["mag_unit"] = data.mag_unit
        g.attrs["imunav"] = header_json(data)

    image = hdf5_image(fill, "Writing HDF5 files")
    with atomic_path(path) as tmp:
        tmp.write_bytes(image)
    return Path(path)


def hdf5_image(fill: Callable[[Any], None], feature: str, **file_options: Any) -> bytes:
    """The bytes of an HDF5 file built in memory by ``fill(h5py.File)``: the HDF5 library never writes to the
    file system, so a write the file system refuses (full disk, a file-size limit) is an :class:`OSError` of
    Python's own write, not a crash inside the library.

    Parameters
    ----------
    fill : callable
        Called with the open (in-memory) ``h5py.File``; creates the groups and datasets.
    feature : str
        What needs h5py, for the message when it is not installed.
    **file_options
        Keywords of ``h5py.File`` (e.g. ``userblock_size``, ``libver``).

    Returns
    -------
    bytes
        The complete file.
    """
    h5py = load_h5py(feature)
    buf = io.BytesIO()
    with h5py.File(buf, "w", **file_options) as fh:
        fill(fh)
    return buf.getvalue()
