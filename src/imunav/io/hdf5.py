"""HDF5 recordings (h5py).

Layout written (inside ``group``, default the root): datasets ``t`` (N,),
``gyro`` (N, 3), ``accel`` (N, 3), optional ``mag`` (N, 3) and ``temp`` (N,),
all float64 SI; attributes ``units`` (JSON: unit of each dataset),
``mag_unit`` and ``imunav`` (the full JSON header with ``meta``).  Reading
finds datasets by name (``t``/``time``, ``gyro``/``gyr``/``imu_gyr``,
``accel``/``acc``/``imu_acc``, ``mag``, ``temp``, or a scalar ``fs``) or by an
explicit ``columns={"gyro": "imu/gyr"}`` mapping; ``units`` / ``scales``
declare non-SI content as in the CSV reader.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from imunav._docstrings import fill_doc
from imunav.errors import FileFormatError
from imunav.files import atomic_path
from imunav.io._common import (
    SI_UNITS,
    build_imu,
    check_nonempty,
    find_array_names,
    header_json,
    parse_header,
    wrap_read_errors,
)
from imunav.timeseries import ImuData

__all__ = ["read_hdf5", "write_hdf5"]


def _datasets(group: h5py.Group) -> list[str]:
    names: list[str] = []

    def visit(name: str, obj: Any) -> None:
        if isinstance(obj, h5py.Dataset):
            names.append(name)

    group.visititems(visit)
    return names


@fill_doc
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

    %(reader_head)s
    group : str
        HDF5 group holding the datasets.
    %(array_columns)s
    %(reader_options)s

    %(reader_returns)s
    """
    source = check_nonempty(path)
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
        for key, name in found.items():
            arrays[key] = np.asarray(g[name][()])
    return build_imu(
        arrays, source, stored=stored, units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


@fill_doc
def write_hdf5(
    data: ImuData, path: str | os.PathLike[str], *, group: str = "/", compression: str | None = None
) -> Path:
    """Write ``data`` (SI, float64) to HDF5 atomically (layout in the module docstring).

    %(imu_writer_params)s
    group : str
        HDF5 group to write into.
    compression : str, optional
        h5py dataset compression (e.g. ``"gzip"``).

    %(returns_file_written)s
    """
    units = dict(SI_UNITS)
    if data.mag is not None:
        units["mag"] = data.mag_unit
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as fh:
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
    return Path(path)
