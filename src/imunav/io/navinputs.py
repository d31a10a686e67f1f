"""Reading the inputs of a GNSS/INS run from files: the IMU, the GNSS fixes and the odometer.

What ``imunav gins run``, ``imunav gins outage-test`` and the ``gins`` lab step read (through
:func:`imunav.ins.gins.setup.load_inputs`, which adds the configuration):

* IMU (:func:`read_imu_input`): a KF-GINS text file of increments (seconds of week, Δθ rad, Δv m/s, FRD;
  recognised by its first line of 7 or more numbers, or declared with ``format = "kf-gins"``), or any recording
  :func:`imunav.io.read_imu` reads (rates, SI, FRD);
* GNSS (:func:`read_gnss_input`): the KF-GINS text file (:func:`imunav.io.gnss.read_gnss_text`) or, for a
  ``.csv``, a generic CSV (:func:`imunav.io.gnss.read_gnss_csv`, its column names in the options);
* odometer (:func:`read_odometer`): a text file of two columns, time (s, the IMU's clock) and forward speed (m/s),
  or three with the speed's σ (m/s).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import ConfigError, InvalidInputError
from imunav.io.aiding import OdometerData
from imunav.io.core import read_imu
from imunav.io.gnss import GnssData, read_gnss_csv, read_gnss_text, read_table
from imunav.io.kfgins import RATE_TOLERANCE, ImuIncrements, read_kfgins_imu
from imunav.timeseries import ImuData

__all__ = ["read_imu_input", "read_gnss_input", "read_odometer"]


def _looks_like_kfgins(path: Path) -> bool:
    """First data line of 7 or more numbers (KF-GINS's IMU file has no header)."""
    if path.suffix.lower() not in (".txt", ".imu", ".dat", ""):
        return False
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                words = line.split("#", 1)[0].replace(",", " ").split()
                if words:
                    [float(w) for w in words]
                    return len(words) >= 7
    except (ValueError, UnicodeDecodeError):
        return False
    return False


def read_imu_input(path: str | os.PathLike[str], options: dict[str, Any] | None = None) -> ImuData | ImuIncrements:
    """Read the IMU of a GNSS/INS run: KF-GINS increments or any recording of :func:`imunav.io.read_imu`.

    Parameters
    ----------
    path : str or os.PathLike
        The IMU file.
    options : dict, optional
        The ``[imu]`` options: ``format`` (``"kf-gins"`` or a :func:`~imunav.io.read_imu` format; default:
        KF-GINS when the first line is 7 or more numbers), ``rate_hz``, ``start_time``, ``end_time`` (s).

    Returns
    -------
    ImuData or ImuIncrements
        The samples inside the window.

    Raises
    ------
    ConfigError
        If the window holds fewer than 2 samples, or a recording of rates contradicts ``rate_hz``.
    InvalidInputError
        If a KF-GINS file contradicts ``rate_hz`` or holds no increments (:func:`~imunav.io.kfgins.read_kfgins_imu`).
    """
    opts = options or {}
    p = Path(path)
    fmt = opts.get("format")
    if fmt == "kf-gins" or (fmt is None and p.is_file() and _looks_like_kfgins(p)):
        data: ImuData | ImuIncrements = read_kfgins_imu(p, opts.get("rate_hz"))
    else:
        data = read_imu(p, fmt)
        if "rate_hz" in opts:
            med = float(np.median(np.diff(data.t)))
            if abs(med * float(opts["rate_hz"]) - 1.0) > RATE_TOLERANCE:
                raise ConfigError(f"{os.fspath(p)}: the time stamps step by {med:.6g} s ({1 / med:.6g} Hz) but "
                                  f"[imu] rate_hz is {opts['rate_hz']:g} Hz; fix rate_hz or remove it")
    t = np.asarray(data.t, dtype=float)
    t0 = float(opts.get("start_time", t[0]))
    t1 = float(opts.get("end_time", t[-1]))
    keep = (t >= t0) & (t <= t1)
    if keep.sum() < 2:
        raise ConfigError(f"{os.fspath(p)}: no IMU samples between start_time {t0} and end_time {t1} "
                          f"(the file spans {t[0]:.3f}..{t[-1]:.3f} s)")
    if keep.all():
        return data
    if isinstance(data, ImuIncrements):
        return ImuIncrements(data.t[keep], data.dtheta[keep], data.dvel[keep], data.dt[keep], data.meta)
    i = np.flatnonzero(keep)
    return data.slice(int(i[0]), int(i[-1]) + 1)


def read_gnss_input(path: str | os.PathLike[str], options: dict[str, Any] | None = None) -> GnssData:
    """Read the GNSS of a GNSS/INS run: KF-GINS text, or a CSV (``.csv`` or ``format = "csv"``).

    Parameters
    ----------
    path : str or os.PathLike
        The GNSS file.
    options : dict, optional
        The ``[gnss]`` options: ``format`` (``"kf-gins"`` or ``"csv"``), ``angle_unit`` and, for a CSV, the
        keyword arguments of :func:`imunav.io.gnss.read_gnss_csv`.

    Returns
    -------
    GnssData
        The fixes.

    Raises
    ------
    ConfigError
        If ``format`` is neither, or CSV options are given for a KF-GINS text file.
    """
    opts = dict(options or {})
    fmt = opts.pop("format", "csv" if Path(path).suffix.lower() == ".csv" else "kf-gins")
    if fmt == "csv":
        for k in ("pos_std", "vel", "vel_std"):
            if k in opts and opts[k] is not None:
                opts[k] = tuple(opts[k])
        return read_gnss_csv(path, **opts)
    if fmt != "kf-gins":
        raise ConfigError(f"[gnss] format must be 'kf-gins' or 'csv'; got {fmt!r}")
    extra = sorted(set(opts) - {"angle_unit"})
    if extra:
        raise ConfigError(f"[gnss] {extra} apply to a CSV only; {os.fspath(path)} is read as KF-GINS text")
    return read_gnss_text(path, **opts)


def read_odometer(path: str | os.PathLike[str]) -> OdometerData:
    """Read an odometer text file: two columns, time (s, the IMU's clock) and forward speed (m/s), or three with
    the speed's σ (m/s) of each sample.

    Parameters
    ----------
    path : str or os.PathLike
        Whitespace- or comma-separated text (``#`` comments).

    Returns
    -------
    OdometerData
        The wheel speeds (with ``speed_std`` from a third column).

    Raises
    ------
    FileFormatError
        If the file does not have 2 or 3 numeric columns.
    InvalidInputError
        If the time does not strictly increase, a speed exceeds 150 m/s or a σ is not positive.
    """
    a = read_table(path, (2, 3), "odometer (time s, speed m/s[, sigma m/s])")
    src = os.fspath(path)
    bad = np.flatnonzero(np.diff(a[:, 0]) <= 0)
    if bad.size:
        raise InvalidInputError(f"{src}: odometer time is not strictly increasing at data row {int(bad[0]) + 2}; "
                                "sort the file and remove duplicates")
    if np.max(np.abs(a[:, 1])) > 150.0:
        raise InvalidInputError(f"{src}: an odometer speed reaches {np.max(np.abs(a[:, 1])):.4g}; the column must "
                                "be the forward speed in m/s (not km/h, not wheel ticks)")
    if a.shape[1] == 3 and not np.all(a[:, 2] > 0):
        raise InvalidInputError(f"{src}: the third column (the speed's sigma, m/s) must be > 0; row "
                                f"{int(np.flatnonzero(~(a[:, 2] > 0))[0]) + 1} holds {a[np.flatnonzero(~(a[:, 2] > 0))[0], 2]!r}")
    return OdometerData(a[:, 0], a[:, 1], {"source": src}, a[:, 2].copy() if a.shape[1] == 3 else None)
