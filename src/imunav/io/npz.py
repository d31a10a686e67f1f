"""NumPy ``.npz`` recordings.

Arrays written: ``t`` (N,), ``gyro``, ``accel`` (N, 3), optional ``mag``
(N, 3), ``temp`` (N,), float64 SI, and ``imunav`` (0-d unicode array with the
JSON header: SI units, ``mag_unit``, ``meta``).  No pickled objects are
written or read (``allow_pickle=False``).  Reading finds arrays by name
(``t``/``time``, ``gyro``/``gyr``, ``accel``/``acc``, ``mag``, ``temp``,
scalar ``fs``) or an explicit ``columns`` mapping, with ``units``/``scales``
for non-SI content (e.g. ``units={"gyro": "deg/s", "accel": "g"}``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.files import atomic_path
from imunav.io._common import build_imu, check_nonempty, find_array_names, header_json, parse_header, wrap_read_errors
from imunav.timeseries import ImuData

__all__ = ["read_npz", "write_npz"]


def read_npz(
    path: str | os.PathLike[str],
    *,
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
    """Read an ``.npz`` recording (see the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
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
    # open the file ourselves: np.load leaks its handle when the zip is damaged
    with wrap_read_errors(source, "NPZ (zip of .npy arrays)"), open(source, "rb") as fh:
        with np.load(fh, allow_pickle=False) as z:
            names = list(z.files)
            found = find_array_names(names, columns, source, kind="array")
            arrays: dict[str, Any] = {k: z[v] for k, v in found.items()}
            stored = parse_header(str(z["imunav"]) if "imunav" in names else None, source)
    return build_imu(
        arrays, source, stored=stored, units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


def write_npz(data: ImuData, path: str | os.PathLike[str], *, compress: bool = False) -> Path:
    """Write ``data`` as ``.npz`` (float64 SI arrays + JSON header), atomically.

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    compress : bool
        Use ``numpy.savez_compressed``.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    arrays: dict[str, np.ndarray] = {"t": data.t, "gyro": data.gyro, "accel": data.accel}
    if data.mag is not None:
        arrays["mag"] = data.mag
    if data.temp is not None:
        arrays["temp"] = data.temp
    arrays["imunav"] = np.array(header_json(data))
    save = np.savez_compressed if compress else np.savez
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            save(fh, **arrays)
    return Path(path)
