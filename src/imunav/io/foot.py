"""Readers of foot-mounted IMU datasets, with explicit frame adapters.

Every reader returns a :class:`FootTrial` whose IMU is in the imunav
conventions (SI units, body FRD: at rest and level ``f_b = (0, 0, -g)``) and
whose reference positions, if any, are in the local NED frame in which
:meth:`imunav.ins.ZuptFilter.run` integrates (x, y horizontal, z down), so the
two can be compared directly by :mod:`imunav.ins.zupt.metrics`.

Frame adapters (each tested against the data):

* pyshoe_vicon ``.mat``: ``imu`` is already FRD-like (z down, acc_z ≈ -9.8
  at rest); ``gt`` has z **up** and an x-y plane that matches a z-down
  navigation frame directly, so ``p_ned = (gt_x, gt_y, -gt_z)``
  (:data:`PYSHOE_GT_TO_NED`).
* x-io Gait-Tracking ``.csv``: gyroscope deg/s, accelerometer g, sensor frame
  z **up** (+1 g at rest) → FRD by a 180° rotation about x:
  ``(x, y, z) → (x, -y, -z)`` (:data:`Z_UP_TO_FRD`); per-sample time.
* Constrained-ZUPT-FGO ``.csv``: 60 Hz sample index, accelerometer m/s² with
  z up, gyroscope rad/s → FRD by :data:`Z_UP_TO_FRD`; ``positionGt.csv`` is
  z-down and right-handed, i.e. already in the INS frame up to a heading
  rotation (:data:`FGO_GT_TO_NED` = I; mirroring y makes the error 5-10×
  larger, see the tests).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io
from numpy.typing import NDArray

from imunav.errors import FileFormatError
from imunav.timeseries import ImuData
from imunav.units import DEG, G0

__all__ = [
    "FootTrial",
    "Z_UP_TO_FRD",
    "PYSHOE_GT_TO_NED",
    "FGO_GT_TO_NED",
    "read_pyshoe_mat",
    "read_xio_gait_csv",
    "spread_duplicate_times",
    "read_fgo_csv",
]

Array = NDArray[np.float64]

#: Sensor axes with z up (right-handed) -> body FRD: rotation by 180° about x.
Z_UP_TO_FRD: Array = np.diag([1.0, -1.0, -1.0])
#: pyshoe VICON ground truth (z up, x-y as the z-down nav frame) -> NED.
PYSHOE_GT_TO_NED: Array = np.diag([1.0, 1.0, -1.0])
#: Constrained-ZUPT-FGO ground truth (z down, right-handed: already NED-like; checked:
#: the y-mirrored alternative gives 0.75 m / 1.04 m instead of 0.16 m / 0.09 m 2-D error).
FGO_GT_TO_NED: Array = np.eye(3)


@dataclass(frozen=True)
class FootTrial:
    """One foot-mounted recording.

    Attributes
    ----------
    imu : ImuData
        The IMU in SI, body FRD.
    position : numpy.ndarray, shape (N, 3), or None
        Reference position in the INS NED frame, m.
    labels : dict of str to numpy.ndarray
        Stored zero-velocity labels by detector name (bool (N,)).
    thresholds : dict of str to float
        Stored optimal thresholds by detector name.
    published_error : dict of str to float
        Stored per-detector 2-D errors, m, by name.
    name : str
        Trial name (file stem).
    meta : dict
        Anything else.
    """

    imu: ImuData
    position: Array | None = None
    labels: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    thresholds: dict[str, float] = field(default_factory=dict)
    published_error: dict[str, float] = field(default_factory=dict)
    name: str = ""
    meta: dict[str, Any] = field(default_factory=dict)


#: Order of ``trial_error`` in the pyshoe files (AMVD was never stored: the
#: third entry duplicates ARED).
_PYSHOE_ERROR_ORDER = ("shoe", "ared", "ared_dup", "mbgtd", "vicon")


def read_pyshoe_mat(path: str | Path) -> FootTrial:
    """Read a processed trial of the Toronto foot dataset (pyshoe ``.mat``; Wagstaff, Peretroukhin & Kelly,
    IEEE Sensors J. 20(2), 2020).

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.mat`` file.

    Returns
    -------
    FootTrial
        IMU (FRD), reference position (NED, :data:`PYSHOE_GT_TO_NED`), stored labels, thresholds and errors.

    Raises
    ------
    FileFormatError
        If the file is unreadable or lacks the ``imu`` / ``gt`` variables, or they disagree.
    """

    p = Path(path)
    try:
        d = scipy.io.loadmat(p)
    except FileNotFoundError:
        raise
    except Exception as exc:  # scipy raises several types for bad files
        raise FileFormatError(f"{p}: not a readable MATLAB file ({exc})") from exc
    for key in ("imu", "ts"):
        if key not in d:
            raise FileFormatError(f"{p}: variable {key!r} missing; expected a pyshoe trial with imu (N, 6) and ts")
    imu = np.asarray(d["imu"], dtype=float)
    t = np.asarray(d["ts"], dtype=float).ravel()
    if imu.ndim != 2 or imu.shape[1] != 6 or imu.shape[0] != t.size:
        raise FileFormatError(f"{p}: imu must be (N, 6) with N = len(ts) = {t.size}; got {imu.shape}")
    data = ImuData(t, imu[:, 3:6], imu[:, 0:3], meta={"source": str(p), "format": "pyshoe_mat"})
    pos = None
    if "gt" in d:
        gt = np.asarray(d["gt"], dtype=float)
        if gt.shape != (t.size, 3):
            raise FileFormatError(f"{p}: gt must be (N, 3) with N = {t.size}; got {gt.shape}")
        pos = gt @ PYSHOE_GT_TO_NED.T
    labels = {}
    thresholds = {}
    for name in ("shoe", "ared", "amvd", "mbgtd", "vicon"):
        if f"zv_{name}_opt" in d:
            labels[name] = np.asarray(d[f"zv_{name}_opt"]).ravel().astype(bool)
        if f"G_{name}_opt" in d:
            thresholds[name] = float(np.asarray(d[f"G_{name}_opt"]).ravel()[0])
    published = {}
    if "trial_error" in d:
        te = np.asarray(d["trial_error"], dtype=float).ravel()
        published = {k: float(v) for k, v in zip(_PYSHOE_ERROR_ORDER, te) if k != "ared_dup"}
    meta: dict[str, Any] = {}
    if "best_detector" in d:
        meta["best_detector"] = str(np.asarray(d["best_detector"]).ravel()[0]).strip()
    return FootTrial(data, pos, labels, thresholds, published, p.stem, meta)


def _read_csv(p: Path) -> tuple[list[str], Array]:
    try:
        with open(p, newline="") as fh:
            reader = csv.reader(fh)
            header = next(reader)
            rows = [r for r in reader if r]
    except StopIteration:
        raise FileFormatError(f"{p}: empty file") from None
    try:
        arr = np.array(rows, dtype=float)
    except ValueError as exc:
        raise FileFormatError(f"{p}: non-numeric value ({exc})") from exc
    if arr.ndim != 2 or arr.shape[1] != len(header):
        raise FileFormatError(f"{p}: rows must have {len(header)} columns like the header")
    return [h.strip() for h in header], arr


def _col(header: list[str], arr: Array, name: str, p: Path) -> Array:
    try:
        return arr[:, header.index(name)]
    except ValueError:
        raise FileFormatError(f"{p}: column {name!r} missing; found {header}") from None


def spread_duplicate_times(t: Array) -> tuple[Array, int]:
    """Spread runs of equal time stamps evenly between their distinct neighbours.

    x-io loggers stamp some samples twice (an interval of 0 next to one of
    twice the period); the samples are real, so instead of dropping them each
    run of equal stamps ``t_b = ... = t_b`` between ``t_a < t_b`` and
    ``t_c > t_b`` is placed evenly on ``(t_a, t_c)``.  Returns the new times and
    the number of samples moved.  Stamps going backwards raise.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time stamps, s, non-decreasing.

    Returns
    -------
    t_new : numpy.ndarray, shape (N,)
        Strictly increasing times, s.
    n_moved : int
        Number of samples moved.

    Raises
    ------
    FileFormatError
        If a stamp goes backwards.
    """
    t = np.asarray(t, dtype=float).copy()
    d = np.diff(t)
    if np.any(d < 0):
        bad = np.flatnonzero(d < 0) + 1
        raise FileFormatError(f"time stamps go backwards at rows {bad[:10].tolist()}; sort the file first")
    moved = 0
    i = 0
    n = t.size
    while i < n - 1:
        if t[i + 1] != t[i]:
            i += 1
            continue
        j = i
        while j + 1 < n and t[j + 1] == t[i]:
            j += 1
        # run i..j of equal stamps; neighbours i-1 and j+1
        if i == 0 or j == n - 1:
            period = float(np.median(d[d > 0]))
            if i == 0:
                t[i:j + 1] = t[j] - period * np.arange(j - i, -1, -1)
            else:
                t[i:j + 1] = t[i] + period * np.arange(0, j - i + 1)
        else:
            t[i:j + 1] = np.linspace(t[i - 1], t[j + 1], j - i + 3)[1:-1]
        moved += j - i + 1
        i = j + 1
    return t, moved


def read_xio_gait_csv(path: str | Path) -> FootTrial:
    """Read an x-io Gait-Tracking recording (NGIMU, deg/s and g, z up).

    Duplicated time stamps are spread by :func:`spread_duplicate_times`
    (count in ``imu.meta["duplicate_times_spread"]``).

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file.

    Returns
    -------
    FootTrial
        The IMU in SI, body FRD (:data:`Z_UP_TO_FRD`); no reference position.

    Raises
    ------
    FileFormatError
        If the file is empty, holds non-numeric values or ragged rows, lacks an x-io column, or its times go
        backwards.
    """
    p = Path(path)
    header, arr = _read_csv(p)
    t, moved = spread_duplicate_times(_col(header, arr, "Time (s)", p))
    gyr = np.column_stack([_col(header, arr, f"Gyroscope {a} (deg/s)", p) for a in "XYZ"]) * DEG
    acc = np.column_stack([_col(header, arr, f"Accelerometer {a} (g)", p) for a in "XYZ"]) * G0
    data = ImuData(t, gyr @ Z_UP_TO_FRD.T, acc @ Z_UP_TO_FRD.T,
                   meta={"source": str(p), "format": "xio_gait_csv", "frame_adapter": "z-up -> FRD",
                         "duplicate_times_spread": moved})
    return FootTrial(data, None, name=p.stem, meta={"reference": "loop closure (ends at start)"})


def read_fgo_csv(imu_path: str | Path, position_path: str | Path | None = None, *, foot: str | None = None,
                 fs: float = 60.0) -> FootTrial:
    """Read a Constrained-ZUPT-FGO foot recording (60 Hz, m/s², rad/s, z up).

    ``foot`` (``"left"`` / ``"right"``) picks the ground-truth columns of
    ``positionGt.csv``; by default it is inferred from the IMU file name.
    The authors' ``is_zero_vel`` flags are returned as ``labels["authors"]``.

    Parameters
    ----------
    imu_path : str or pathlib.Path
        The IMU CSV file.
    position_path : str or pathlib.Path, optional
        ``positionGt.csv`` with the reference positions.
    foot : {"left", "right"}, optional
        Which foot's reference columns to take (default: from the IMU file name).
    fs : float
        Sample rate, Hz (the file holds sample indices).

    Returns
    -------
    FootTrial
        IMU in SI, body FRD; reference position (NED, m) when given; the authors' labels.

    Raises
    ------
    FileFormatError
        If a file is unreadable or lacks a column, the foot cannot be told, or the lengths disagree.
    """
    p = Path(imu_path)
    header, arr = _read_csv(p)
    idx = _col(header, arr, "time_index", p)
    t = idx / float(fs)
    acc = np.column_stack([_col(header, arr, f"acc_{a}", p) for a in "xyz"])
    gyr = np.column_stack([_col(header, arr, f"gyro_{a}", p) for a in "xyz"])
    data = ImuData(t, gyr @ Z_UP_TO_FRD.T, acc @ Z_UP_TO_FRD.T,
                   meta={"source": str(p), "format": "fgo_csv", "frame_adapter": "z-up -> FRD"})
    labels = {}
    if "is_zero_vel" in header:
        labels["authors"] = _col(header, arr, "is_zero_vel", p).astype(bool)
    pos = None
    if position_path is not None:
        side = foot or ("left" if "left" in p.stem.lower() else "right" if "right" in p.stem.lower() else None)
        if side not in ("left", "right"):
            raise FileFormatError(f"{p}: cannot tell the foot from the file name; pass foot='left' or 'right'")
        q = Path(position_path)
        h2, a2 = _read_csv(q)
        gt = np.column_stack([_col(h2, a2, f"pos_{side}_{a}", q) for a in "xyz"])
        if gt.shape[0] != t.size:
            raise FileFormatError(f"{q}: {gt.shape[0]} rows but the IMU file has {t.size}")
        pos = gt @ FGO_GT_TO_NED.T
    return FootTrial(data, pos, labels, name=p.stem, meta={"foot": foot})
