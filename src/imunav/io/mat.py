"""MATLAB MAT-files: version 5 (scipy.io) and version 7.3 (HDF5: h5py, the ``hdf5`` extra).

Variables written: ``t`` (N×1), ``gyro``, ``accel`` (N×3), optional ``mag``
(N×3) and ``temp`` (N×1), all double SI, plus the char variables
``mag_unit`` and ``imunav_meta`` (the JSON header).  In MATLAB:
``load('rec.mat'); plot(t, gyro)``.

Version 7.3 files are HDF5 files with a 512-byte user block holding MATLAB's
text header (116 bytes of text, 8 bytes of subsystem offset, version
``0x0200`` and the endian indicator ``'IM'``).  MATLAB stores arrays
column-major, so an N×3 MATLAB matrix is an HDF5 dataset of shape (3, N):
the writer transposes on the way out and the reader on the way in.  Each
dataset carries the ``MATLAB_class`` attribute (``double`` / ``char``;
chars are uint16 code units with ``MATLAB_int_decode = 2``).

Reading detects the version from the file header; variables are found by
name (``t``/``time``, ``gyro``/``gyr``/``imu_gyr``, ``accel``/``acc``/
``imu_acc``, ``mag``/``imu_mag``, ``temp``, scalar ``fs`` / ``rate``) or an
explicit ``columns`` mapping.  Char variables ``units`` (JSON: group -> unit)
and ``<name>_unit`` (e.g. ``gyro_unit = 'deg/s'``) declare the units of the
file and are applied (:mod:`imunav.io._common`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io

from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import atomic_path
from imunav.io._common import (
    build_imu,
    check_nonempty,
    find_array_names,
    header_json,
    merge_declared,
    parse_header,
    wrap_read_errors,
)
from imunav.io.hdf5 import hdf5_image, load_h5py
from imunav.timeseries import ImuData

__all__ = ["read_mat", "write_mat", "mat_version"]

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def mat_version(path: str | os.PathLike[str]) -> str:
    """``"5"`` or ``"7.3"`` from the file header.

    Parameters
    ----------
    path : str or os.PathLike
        The MAT-file.

    Returns
    -------
    str
        ``"5"`` or ``"7.3"``.

    Raises
    ------
    FileFormatError
        If the file is not a MAT-file, is truncated, or is a v4 MAT-file.
    """
    source = os.fspath(path)
    with open(source, "rb") as fh:
        head = fh.read(520)
    if len(head) >= 520 and head[512:520] == _HDF5_SIGNATURE:
        return "7.3"
    if len(head) < 128:
        raise FileFormatError(f"{source}: {len(head)} bytes is too short for a MAT-file header (128 bytes); truncated?")
    if head[126:128] in (b"IM", b"MI") and head[:6] == b"MATLAB":
        version = head[124:126]
        if version in (b"\x00\x01", b"\x01\x00"):
            return "5"
        if version in (b"\x00\x02", b"\x02\x00"):
            return "7.3"
    if head[:4] == b"\x00\x00\x00\x00" or head[:1] in (b"\x00",):
        raise FileFormatError(f"{source}: MATLAB v4 MAT-files are not supported; re-save with save -v7 or -v7.3")
    raise FileFormatError(f"{source}: not a MAT-file (no 'MATLAB' header with version and endian indicator)")


def _mat_char_to_str(a: np.ndarray) -> str:
    a = np.asarray(a)
    if a.dtype.kind in "US":
        return "".join(np.atleast_1d(a).astype(str).tolist())
    # v7.3 chars are UTF-16 code units
    return np.ascontiguousarray(a.ravel(order="F"), dtype="<u2").tobytes().decode("utf-16-le")


def _read_v5(source: str) -> tuple[dict[str, Any], dict[str, Any]]:
    with wrap_read_errors(source, "MAT v5"):
        raw = scipy.io.loadmat(source, squeeze_me=False, chars_as_strings=True, mat_dtype=False)
    arrays = {k: v for k, v in raw.items() if not k.startswith("__")}
    strings = {k: _mat_char_to_str(v) for k, v in arrays.items() if np.asarray(v).dtype.kind in "US"}
    numeric = {k: np.asarray(v) for k, v in arrays.items() if np.asarray(v).dtype.kind in "fiub"}
    return numeric, strings


def _read_v73(source: str) -> tuple[dict[str, Any], dict[str, Any]]:
    numeric: dict[str, Any] = {}
    strings: dict[str, Any] = {}
    h5py = load_h5py("Reading MAT v7.3 files")
    with wrap_read_errors(source, "MAT v7.3 (HDF5)"):
        with h5py.File(source, "r") as fh:
            for name, obj in fh.items():
                if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                    continue
                cls = obj.attrs.get("MATLAB_class", b"")
                cls = cls.decode() if isinstance(cls, bytes) else str(cls)
                if obj.attrs.get("MATLAB_empty", 0):
                    continue
                a = np.asarray(obj[()])
                if cls == "char":
                    strings[name] = _mat_char_to_str(a.T)
                elif a.dtype.kind in "fiub":
                    numeric[name] = a.T  # MATLAB is column-major: HDF5 (3, N) is MATLAB N×3
    return numeric, strings


def _vector(a: np.ndarray) -> np.ndarray:
    """MATLAB N×1 / 1×N -> (N,)."""
    a = np.asarray(a)
    if a.ndim == 2 and 1 in a.shape:
        return a.reshape(-1)
    return a


def read_mat(
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
    """Read a MAT-file (v5 or v7.3, detected from the header).

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
    version = mat_version(source)
    numeric, strings = _read_v73(source) if version == "7.3" else _read_v5(source)
    found = find_array_names(sorted(numeric), columns, source, kind="variable")
    arrays: dict[str, Any] = {}
    for key, name in found.items():
        a = numeric[name]
        arrays[key] = _vector(a) if key in ("t", "temp", "fs") else a
    stored = parse_header(strings.get("imunav_meta"), source)
    if "mag_unit" in strings and not stored:
        stored = {"mag_unit": strings["mag_unit"]}
    per_var = {key: strings[f"{name}_unit"] for key, name in found.items() if f"{name}_unit" in strings}
    units_var = parse_header(strings["units"], f"{source} (variable 'units')") if "units" in strings else None
    return build_imu(
        arrays, source, stored=stored,
        declared=merge_declared(source, ("the variable 'units'", units_var),
                                ("the <name>_unit variables", per_var)),
        units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip


def _mat_vars(data: ImuData) -> dict[str, np.ndarray]:
    out = {"t": data.t[:, None], "gyro": data.gyro, "accel": data.accel}
    if data.mag is not None:
        out["mag"] = data.mag
    if data.temp is not None:
        out["temp"] = data.temp[:, None]
    return out


def _v73_header() -> bytes:
    text = (
        "MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: "
        + time.strftime("%a %b %d %H:%M:%S %Y", time.gmtime())
        + " HDF5 schema 1.00 ."
    ).encode("ascii")
    head = text.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    return head.ljust(512, b"\x00")


def _write_v73(data: ImuData, tmp: Path) -> None:
    def fill(fh: Any) -> None:
        for name, a in _mat_vars(data).items():
            ds = fh.create_dataset(name, data=np.ascontiguousarray(np.asarray(a, dtype=np.float64).T))
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        for name, text in (("mag_unit", data.mag_unit), ("imunav_meta", header_json(data))):
            if not text:
                continue
            codes = np.frombuffer(text.encode("utf-16-le"), dtype="<u2")  # MATLAB chars are UTF-16
            ds = fh.create_dataset(name, data=codes.reshape(-1, 1))  # MATLAB 1×L char row
            ds.attrs["MATLAB_class"] = np.bytes_("char")
            ds.attrs["MATLAB_int_decode"] = np.int32(2)

    image = hdf5_image(fill, "Writing MAT v7.3 files", userblock_size=512, libver="earliest")
    tmp.write_bytes(_v73_header() + image[512:])


def write_mat(data: ImuData, path: str | os.PathLike[str], *, version: str = "5") -> Path:
    """Write a MAT-file, ``version="5"`` (scipy) or ``"7.3"`` (HDF5), atomically.

    Parameters
    ----------
    data : ImuData
        The recording.
    path : str or os.PathLike
        Output file.
    version : {"5", "7.3"}
        MAT-file version.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InvalidInputError
        If the version is not "5" or "7.3".
    """
    v = str(version).lstrip("v")
    if v not in ("5", "7", "7.3", "73"):
        raise InvalidInputError(f"MAT version must be '5' or '7.3', not {version!r}")
    with atomic_path(path) as tmp:
        if v in ("7.3", "73"):
            _write_v73(data, tmp)
        else:
            mdict: dict[str, Any] = dict(_mat_vars(data))
            mdict["mag_unit"] = data.mag_unit
            mdict["imunav_meta"] = header_json(data)
            with open(tmp, "wb") as fh:
                scipy.io.savemat(fh, mdict, format="5", do_compression=False, oned_as="column")
    return Path(path)
