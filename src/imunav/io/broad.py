"""Loader for BROAD trials (Berlin Robust Orientation Estimation Assessment Dataset).

Laidig, Caruso, Cereatti, Seel, "BROAD — A Benchmark for Robust Inertial
Orientation Estimation", Data 6(7):72, 2021 (data CC BY 4.0).

Frames (explicit adapter, tested in ``tests/attitude/test_broad.py``):

* The **body frame** of the returned recording is the IMU sensor frame as
  recorded (myon aktos-t board).  It is *not* FRD, and nothing in imunav's
  attitude filters needs it to be: they only assume a right-handed body frame
  and a specific-force accelerometer (at rest the accelerometer reads +g along
  the axis pointing up, which is the specific-force convention f = a − g).
* The file's reference ``opt_quat`` is the sensor orientation relative to an
  **ENU** Earth frame whose y axis points to *magnetic* north
  (v_ENU = q ⊗ v_S ⊗ q*).  imunav uses NED, so the loader returns
  ``q_ref_nb = Q_NED_ENU ⊗ opt_quat`` (north = magnetic north, down), where
  ``Q_NED_ENU`` is the rotation of π about (1, 1, 0)/√2 (x↔y, z → −z).
  ``to_enu(q_nb)`` is the inverse adapter for exporting estimates.
* The BROAD error metric is invariant to this Earth-frame change (see
  :mod:`imunav.attitude.metrics`), so RMSEs computed in NED equal the ENU ones.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.io import loadmat

from imunav.errors import FileFormatError, InvalidInputError
from imunav.rotation import Q_ENU_NED, from_convention, to_convention
from imunav.timeseries import ImuData

Array = NDArray[np.float64]

__all__ = ["BroadTrial", "load_broad", "broad_trials", "Q_NED_ENU", "to_enu", "from_enu"]

#: q_ned_enu: v_ned = q ⊗ v_enu ⊗ q* (swap x/y, negate z); its own inverse up to sign.  C_ENU_NED is
#: symmetric, so this is rotation.Q_ENU_NED (bit for bit ``quat_from_dcm(C_ENU_NED.T)``), a constant:
#: importing this module runs no numba kernel.
Q_NED_ENU = Q_ENU_NED

_KEYS = ("imu_gyr", "imu_acc", "imu_mag", "opt_quat", "movement", "sampling_rate")


def _finite_rows(q: Array, convert) -> Array:
    """Apply ``convert`` to the finite rows of (N, 4) ``q``; NaN rows stay NaN."""
    q = np.asarray(q, float)
    if q.ndim == 1:
        return convert(q)
    out = np.full(q.shape, np.nan)
    ok = np.all(np.isfinite(q), axis=1)
    if ok.any():
        out[ok] = convert(q[ok])
    return out


def to_enu(q_nb: Array) -> Array:
    """Body->NED quaternions to body->ENU (for BROAD-style output); NaN rows stay NaN.

    ``q_enu = Q_ENU_NED ⊗ q_nb`` (module docstring).

    Parameters
    ----------
    q_nb : numpy.ndarray, shape (N, 4)
        Attitude, body to NED, scalar first.

    Returns
    -------
    numpy.ndarray, shape (N, 4)
        Attitude, body to ENU, scalar first.
    """
    return _finite_rows(q_nb, lambda q: to_convention(q, "broad"))


def from_enu(q_enu: Array) -> Array:
    """Body->ENU quaternions (BROAD ``opt_quat``) to body->NED; NaN rows stay NaN.

    Parameters
    ----------
    q_enu : numpy.ndarray, shape (N, 4)
        Attitude, body to ENU (y to magnetic north), scalar first.

    Returns
    -------
    numpy.ndarray, shape (N, 4)
        Attitude ``q_nb``, body to NED (north = magnetic north).
    """
    return _finite_rows(q_enu, lambda q: from_convention(q, "broad"))


@dataclass(frozen=True)
class BroadTrial:
    """One BROAD trial: IMU recording, reference in NED, scored-sample mask.

    Attributes
    ----------
    name : str
        Trial name (file stem).
    imu : ImuData
        Gyro (rad/s), accelerometer (m/s², specific force), magnetometer (µT), sensor frame.
    q_ref_nb : numpy.ndarray, shape (N, 4)
        Optical reference attitude, sensor to NED; NaN rows where the motion capture had no data.
    movement : numpy.ndarray of bool, shape (N,)
        The samples the BROAD metric scores.
    fs : float
        Sample rate, Hz.
    path : pathlib.Path
        The file read.
    meta : dict
        Further fields of the file.
    """

    name: str
    imu: ImuData
    q_ref_nb: Array  # (N, 4) NED reference, NaN rows where the OMC had no data
    movement: NDArray[np.bool_]
    fs: float
    path: Path
    meta: dict[str, Any] = field(default_factory=dict)


def load_broad(path: str | Path) -> BroadTrial:
    """Read a BROAD ``.mat`` trial (MATLAB v5, as in the dataset's ``data_mat/``).

    Time is ``t = k / sampling_rate``.  Gyro rad/s, accelerometer m/s² (specific
    force), magnetometer µT, all in the sensor frame (see module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The trial file.

    Returns
    -------
    BroadTrial
        Recording, NED reference and movement mask.

    Raises
    ------
    InvalidInputError
        If the file does not exist.
    FileFormatError
        If it is not a MAT v5 file, lacks a BROAD variable, or its variables disagree in length.
    """

    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"BROAD trial file not found: {p}; pass the path of a *.mat trial file")
    try:
        mat = loadmat(p)
    except Exception as exc:  # scipy raises several types for bad files
        raise FileFormatError(f"{p}: not a readable MATLAB v5 file ({exc}); expected a BROAD data_mat/*.mat trial") from exc
    missing = [k for k in _KEYS if k not in mat]
    if missing:
        raise FileFormatError(f"{p}: missing BROAD variables {missing}; expected {list(_KEYS)}")
    fs = float(np.squeeze(mat["sampling_rate"]))
    gyr = np.ascontiguousarray(mat["imu_gyr"], dtype=np.float64)
    acc = np.ascontiguousarray(mat["imu_acc"], dtype=np.float64)
    mag = np.ascontiguousarray(mat["imu_mag"], dtype=np.float64)
    n = gyr.shape[0]
    for k, a in (("imu_acc", acc), ("imu_mag", mag), ("opt_quat", mat["opt_quat"])):
        if a.shape[0] != n:
            raise FileFormatError(f"{p}: {k} has {a.shape[0]} rows, imu_gyr {n}; the file is inconsistent")
    t = np.arange(n, dtype=np.float64) / fs
    info = mat.get("info")
    meta: dict[str, Any] = {"source": "BROAD", "file": p.name}
    if info is not None:
        meta["info"] = str(np.squeeze(info))
    imu = ImuData(t=t, gyro=gyr, accel=acc, mag=mag, mag_unit="uT", meta=meta)
    q_enu = np.asarray(mat["opt_quat"], dtype=np.float64)
    q_ned = from_enu(q_enu)
    mv = np.asarray(mat["movement"]).reshape(-1).astype(bool)
    return BroadTrial(name=p.stem, imu=imu, q_ref_nb=q_ned, movement=mv, fs=fs, path=p, meta=meta)


def broad_trials(directory: str | Path) -> list[Path]:
    """Sorted ``*.mat`` trial files in ``directory``.

    Parameters
    ----------
    directory : str or pathlib.Path
        Folder of BROAD trials.

    Returns
    -------
    list of pathlib.Path
        The trial files, sorted by name.

    Raises
    ------
    InvalidInputError
        If the folder does not exist or holds no ``.mat`` file.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InvalidInputError(f"BROAD folder not found: {d}; pass the folder holding the *.mat trials")
    files = sorted(d.glob("*.mat"))
    if not files:
        raise InvalidInputError(f"no *.mat trial files in {d}; pass the BROAD data_mat folder")
    return files
