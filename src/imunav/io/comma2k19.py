"""comma2k19 segments: a real car's phone IMU, u-blox fixes and CAN speed as a navigation log, its fused pose as a
truth.

comma2k19 (Schafer et al. 2018, "A Commute in Data: The comma2k19 Dataset", arXiv:1812.05752; MIT licence) holds
33 hours of highway driving in one-minute *segments*.  A segment's folder holds, each as two NumPy arrays ``t``
(seconds of the device's boot clock) and ``value`` saved without the ``.npy`` suffix::

    SEGMENT/processed_log/IMU/accelerometer       specific force, m/s², device axes forward, right, down (FRD)
    SEGMENT/processed_log/IMU/gyro                rad/s, FRD, Android's bias correction applied
    SEGMENT/processed_log/IMU/gyro_uncalibrated   rad/s, FRD, raw (bias up to a few deg/s)
    SEGMENT/processed_log/IMU/gyro_bias           rad/s, Android's bias estimate (uncalibrated − calibrated)
    SEGMENT/processed_log/IMU/magnetometer        µT, FRD (the upstream README says T: it is µT)
    SEGMENT/processed_log/GNSS/live_gnss_ublox    lat deg, lon deg, speed m/s, UTC ms, altitude m, bearing deg
    SEGMENT/processed_log/CAN/speed               the car's speed, m/s
    SEGMENT/global_pose/frame_times               boot-clock stamps of the camera frames, s
    SEGMENT/global_pose/frame_gps_times           GPS week and seconds of week of the same frames
    SEGMENT/global_pose/frame_positions           ECEF position of the camera, m
    SEGMENT/global_pose/frame_velocities          ECEF velocity, m/s
    SEGMENT/global_pose/frame_orientations        Hamilton quaternion (scalar first) of the camera's FRD axes in ECEF

:func:`read_comma2k19` reads a segment as the :class:`~imunav.io.navlog.NavSources` of a log (the IMU with the
calibrated or the raw gyro, the u-blox fixes, the CAN speed as the odometer, the magnetometer);
:func:`read_comma2k19_pose` reads comma's fused pose (a tightly coupled INS / GNSS / vision optimiser: a peer's
output, not survey truth) as a :class:`~imunav.io.kfgins.NavTrack` in the ``.nav`` convention (GPS week and
seconds of week, geodetic position, NED velocity, ``q_nb``).

Time
----
Every sensor is stamped on the boot clock when its sample reached the logger, as a ROS bag stamps messages.  The
boot clock is mapped to GPS time by the pose's own ``frame_gps_times`` (a line of slope 1 fitted to the frames:
its residual and slope are checked, and reported in ``meta["time"]``), GPS time to UTC by the leap seconds of the
date: the sources' ``t0_ns`` is the UTC of the first IMU sample, so a run's ``.nav`` is stamped in GPS time like
the pose.

The u-blox fixes also carry the UTC of their own measurement epoch.  They reach the logger about 0.2 s after it
(``meta["gnss"]["receive_after_epoch_s"]``), but the fixes are stamped, like every other sensor, when they arrived:
how late a fix is against the IMU is the filter's GNSS latency state to estimate (about 0.09 s against the pose on
the segment of the shared data: the camera's clock and the receiver's epochs differ by about 0.11 s, which
``meta["gnss"]["pose_clock_minus_epoch_s"]`` reports).

The fixes have no accuracy field: they take ``gnss_pos_std`` (default :data:`UBLOX_POS_STD`, the receiver's
datasheet accuracy) and are counted as ``sigma_assumed``; the filter's adaptive noise then scales them to what
their innovations show.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.earth import dcm_en, ecef_to_lla, ecef_to_ned, lla_to_ecef, vel_ned_from_ecef
from imunav.errors import FileFormatError, InvalidInputError
from imunav.io.aiding import MagnetometerData, OdometerData
from imunav.io.gnss import GnssData
from imunav.io.gpstime import GPS_EPOCH_UNIX, leap_seconds
from imunav.io.kfgins import NavTrack
from imunav.io.navsources import NavSources, SourceInfo
from imunav.rotation import dcm_from_quat, quat_from_dcm
from imunav.timeseries import ImuData

__all__ = ["GYRO_CHOICES", "UBLOX_POS_STD", "is_comma2k19_segment", "read_comma2k19", "read_comma2k19_pose"]

Array = NDArray[np.float64]

#: The gyro a reader takes: Android's bias-corrected rates, or the raw ones.
GYRO_CHOICES = ("calibrated", "raw")
#: σ north, east, down (m) of a u-blox fix without an accuracy field: the u-blox M8's datasheet horizontal
#: accuracy, 2.5 m CEP (σ = CEP / 1.1774 per axis for a circular Gaussian), and twice that vertically.
UBLOX_POS_STD = (2.1, 2.1, 4.2)
_GPS_WEEK_S = 604_800.0
_IMU = "processed_log/IMU"
_GNSS = "processed_log/GNSS/live_gnss_ublox"
_CAN = "processed_log/CAN/speed"
_POSE = "global_pose"
#: Largest residual (s) of the boot clock -> GPS time line through the pose's frames.
_CLOCK_FIT_TOL = 1e-3


def is_comma2k19_segment(path: str | os.PathLike[str]) -> bool:
    """True for a comma2k19 segment folder (module docstring): it holds the folder ``processed_log/IMU`` (its
    files are then read, and one that is missing or damaged is named).

    Parameters
    ----------
    path : str or os.PathLike
        Any path.

    Returns
    -------
    bool
        Whether :func:`read_comma2k19` reads it.
    """
    return os.path.isdir(os.path.join(os.fspath(path), _IMU))


def _npy(folder: str, rel: str, what: str = "") -> Array:
    """One array file of a segment (``.npy`` content, no suffix) as float64, or a FileFormatError naming it: missing,
    empty, truncated, not NumPy, pickled objects, not real numbers."""
    p = os.path.join(folder, rel)
    try:
        a = np.load(p, allow_pickle=False)
    except FileNotFoundError:
        raise FileFormatError(f"{folder}: the comma2k19 segment has no {rel}" + (f" ({what})" if what else "")) \
            from None
    except (ValueError, OSError, EOFError) as exc:  # EOFError: an empty file
        raise FileFormatError(f"{p}: not a NumPy array file ({exc or type(exc).__name__}); the segment's file is "
                              "damaged or incomplete: copy it again") from None
    if not isinstance(a, np.ndarray) or a.ndim == 0 or not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
        raise FileFormatError(f"{p}: expected a real numeric array, got {getattr(a, 'dtype', type(a).__name__)} of "
                              f"shape {getattr(a, 'shape', ())}")
    return np.asarray(a, dtype=np.float64)


def _load(folder: str, rel: str, what: str, width: int | None) -> tuple[Array, Array]:
    """A sensor folder's ``t`` and ``value`` arrays, checked: finite, increasing stamps, one row per stamp."""
    base = os.path.join(folder, rel)
    arrays = [_npy(folder, f"{rel}/{name}", what) for name in ("t", "value")]
    t, v = arrays
    v = v.reshape(v.shape[0], -1) if v.ndim > 1 else v[:, None]
    if t.ndim != 1 or v.shape[0] != t.size or t.size < 2:
        raise FileFormatError(f"{base}: {t.size} stamps but {v.shape[0]} values ({what}); a comma2k19 sensor "
                              "holds one row per stamp")
    if width is not None and v.shape[1] < width:
        raise FileFormatError(f"{base}/value: {v.shape[1]} columns, {what} needs {width}")
    if not np.all(np.isfinite(t)):
        raise FileFormatError(f"{base}/t: non-finite stamps at rows {np.flatnonzero(~np.isfinite(t))[:5].tolist()}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise FileFormatError(f"{base}/t: stamps do not increase at row {int(bad[0]) + 1}")
    return t, v


def _frame_times(folder: str) -> Array:
    """``global_pose/frame_times`` (a single array, no ``t`` / ``value`` pair)."""
    return _npy(folder, f"{_POSE}/frame_times").ravel()


def _pose_array(folder: str, name: str, width: int, n: int) -> Array:
    p = os.path.join(folder, _POSE, name)
    a = _npy(folder, f"{_POSE}/{name}")
    if a.shape != (n, width) or not np.all(np.isfinite(a)):
        raise FileFormatError(f"{p}: expected {n} finite rows of {width}; got shape {a.shape}")
    return a


def _clock(folder: str) -> tuple[float, int, dict[str, Any]]:
    """Boot -> GPS seconds of week of the pose's first frame's week (module docstring)."""
    ft = _frame_times(folder)
    gps = _pose_array(folder, "frame_gps_times", 2, ft.size)
    if ft.size < 2 or np.any(np.diff(ft) <= 0):
        raise FileFormatError(f"{folder}/{_POSE}/frame_times: fewer than 2 frames or stamps not increasing")
    week0 = int(gps[0, 0])
    sow = (gps[:, 0] - week0) * _GPS_WEEK_S + gps[:, 1]
    offset = float(np.median(sow - ft))
    slope = float(np.polyfit(ft - ft[0], sow - sow[0], 1)[0])
    resid = float(np.max(np.abs(sow - ft - offset)))
    if resid > _CLOCK_FIT_TOL:
        raise FileFormatError(f"{folder}: the pose's GPS times depart from one offset of the boot clock by up to "
                              f"{resid:.4f} s (slope {slope:.9f}): the clocks cannot be mapped")
    return offset, week0, {"boot_to_gps_sow_offset_s": offset, "gps_week": week0, "clock_slope": slope,
                           "clock_fit_max_residual_s": resid}


def _utc_ns(boot: float | Array, offset: float, week: int) -> Any:
    """UTC ns since 1970 of boot-clock times (GPS − leap seconds of the date)."""
    gps_unix = GPS_EPOCH_UNIX + week * _GPS_WEEK_S + np.asarray(boot, dtype=np.float64) + offset
    leap = leap_seconds(gps_unix - leap_seconds(gps_unix))
    return np.round((gps_unix - leap) * 1e9).astype(np.int64)


def _rate(t: Array) -> float:
    return float((t.size - 1) / (t[-1] - t[0]))


def read_comma2k19(path: str | os.PathLike[str], *, gyro: str = "calibrated",
                   gnss_pos_std: ArrayLike | None = None) -> NavSources:
    """A comma2k19 segment as a navigation log (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The segment folder (holding ``processed_log`` and ``global_pose``).
    gyro : {"calibrated", "raw"}
        Android's bias-corrected gyro, or the raw one (its bias, up to a few deg/s, is then the filter's to
        estimate; Android's own estimate is in ``meta["imu"]["android_gyro_bias_end"]``).
    gnss_pos_std : array_like, shape (3,) or (), optional
        σ north, east, down of the u-blox fixes, m (they have no accuracy field); default
        :data:`UBLOX_POS_STD`.

    Returns
    -------
    NavSources
        The IMU (FRD, SI; the magnetometer in µT as ``mag``), the u-blox fixes, the CAN speed as the odometer,
        every one in s since ``t0_ns``, the UTC of the first IMU sample (``time_is_utc``).

    Raises
    ------
    FileFormatError
        If a file is missing or not a NumPy array of the expected shape, or the pose's clock cannot be mapped.
    InvalidInputError
        If ``gyro`` or ``gnss_pos_std`` is not valid.
    """
    folder = os.fspath(path)
    if gyro not in GYRO_CHOICES:
        raise InvalidInputError(f"gyro={gyro!r}: choose one of {list(GYRO_CHOICES)}")
    std = np.broadcast_to(np.asarray(UBLOX_POS_STD if gnss_pos_std is None else gnss_pos_std, dtype=float),
                          (3,)).copy()
    if not np.all(np.isfinite(std)) or np.any(std <= 0):
        raise InvalidInputError(f"gnss_pos_std must be > 0 m (north, east, down); got {std.tolist()}")
    offset, week, clock = _clock(folder)
    ta, acc = _load(folder, f"{_IMU}/accelerometer", "accelerometer", 3)
    tg, gyr = _load(folder, f"{_IMU}/gyro" if gyro == "calibrated" else f"{_IMU}/gyro_uncalibrated", "gyro", 3)
    if ta.size != tg.size or np.any(ta != tg):
        raise FileFormatError(f"{folder}: the accelerometer and the gyro are not on the same stamps")
    t0 = float(ta[0])
    t0_ns = int(_utc_ns(t0, offset, week))
    tb, gb = _load(folder, f"{_IMU}/gyro_bias", "gyro bias", 3)
    imu = ImuData.from_arrays(ta - t0, gyr[:, :3], acc[:, :3],
                              meta={"source": folder, "format": "comma2k19", "t0_ns": t0_ns,
                                    "gyro": f"{gyro} ({'Android bias-corrected' if gyro == 'calibrated' else 'raw'})",
                                    "time": "boot clock mapped to GPS time by global_pose/frame_gps_times"})
    meta: dict[str, Any] = {"imu": {"time": "boot clock", "frame_id": "device FRD", "gyro": gyro,
                                    "android_gyro_bias_end": gb[-1, :3].tolist(),
                                    "android_gyro_bias_t": float(tb[-1] - t0)},
                            "time": ("boot clock mapped to GPS time by the pose's frame_gps_times "
                                     f"(offset {offset:.6f} s, max residual {clock['clock_fit_max_residual_s']:.1e} s)"
                                     ", as UTC by the leap seconds of the date"),
                            "clock": clock}
    t_end = float(imu.t[-1])
    topics = {"imu": SourceInfo("imu", f"{_IMU}/{'gyro' if gyro == 'calibrated' else 'gyro_uncalibrated'}",
                                "comma2k19 IMU", int(ta.size), imu.n, _rate(imu.t))}
    # -- u-blox fixes, stamped when received; their own UTC epochs give the check of the clock
    tf, fv = _load(folder, _GNSS, "u-blox fixes", 6)
    tf = tf - t0
    keep = (tf >= 0.0) & (tf <= t_end) & np.all(np.isfinite(fv[:, [0, 1, 4]]), axis=1)
    keep &= ~((fv[:, 0] == 0.0) & (fv[:, 1] == 0.0))
    lat, lon = np.radians(fv[:, 0]), np.radians(fv[:, 1])
    epoch_sow = (fv[:, 3] * 1e-3 - GPS_EPOCH_UNIX) + leap_seconds(fv[:, 3] * 1e-3) - week * _GPS_WEEK_S
    rx_sow = tf + t0 + offset
    late = rx_sow - epoch_sow
    ok_epoch = np.isfinite(late)
    gnss = GnssData(tf[keep], np.column_stack([lat, lon, fv[:, 4]])[keep], np.tile(std, (int(keep.sum()), 1)),
                    meta={"source": f"{folder}/{_GNSS}", "faults": {"sigma_assumed": int(keep.sum()),
                                                                     "outside_or_invalid": int((~keep).sum())},
                          "removed": [], "t0_ns": t0_ns})
    meta["gnss"] = {"faults": gnss.meta["faults"], "removed": [],
                    "sigma": f"no accuracy field: sigma N E D {std.tolist()} m assumed (u-blox M8 datasheet)",
                    "stamps": "when each fix reached the logger (boot clock), as a ROS bag stamps it",
                    "receive_after_epoch_s": {"mean": float(np.mean(late[ok_epoch])),
                                              "std": float(np.std(late[ok_epoch]))} if ok_epoch.any() else None}
    topics["gnss"] = SourceInfo("gnss", _GNSS, "comma2k19 u-blox fix", int(fv.shape[0]), gnss.n, _rate(gnss.t))
    # -- CAN speed as the odometer
    tc, sp = _load(folder, _CAN, "CAN speed", 1)
    tc = tc - t0
    inside = (tc >= 0.0) & (tc <= t_end) & np.isfinite(sp[:, 0])
    odo = OdometerData(tc[inside], sp[inside, 0], meta={"source": f"{folder}/{_CAN}", "speed": "CAN vehicle speed"})
    meta["odometer"] = {"speed": "the car's CAN speed (forward, m/s)", "cut": int((~inside).sum())}
    topics["odometer"] = SourceInfo("odometer", _CAN, "comma2k19 CAN speed", int(tc.size), odo.t.size, _rate(odo.t))
    # -- magnetometer (calibrated, µT)
    mag = None
    if os.path.isdir(os.path.join(folder, _IMU, "magnetometer")):
        tm, mv = _load(folder, f"{_IMU}/magnetometer", "magnetometer", 3)
        tm = tm - t0
        inm = (tm >= 0.0) & (tm <= t_end)
        mag = MagnetometerData(tm[inm], mv[inm, :3], meta={"source": folder, "unit": "uT"})
        topics["mag"] = SourceInfo("mag", f"{_IMU}/magnetometer", "comma2k19 magnetometer", int(tm.size),
                                   mag.t.size, _rate(mag.t))
        meta["mag"] = {"unit": "uT"}
    else:
        meta["mag"] = "no magnetometer in the segment"
    meta["baro"] = "comma2k19 has no barometer"
    pose_epoch = _pose_clock_check(folder, gnss, rx_sow[keep], epoch_sow[keep], offset, t0)
    if pose_epoch is not None:
        meta["gnss"]["pose_clock_minus_epoch_s"] = pose_epoch
    return NavSources(folder, t0_ns, imu, gnss, odo, mag, None, topics, t0_ns * 1e-9, None, None, meta)


def _pose_clock_check(folder: str, gnss: GnssData, rx_sow: Array, epoch_sow: Array, offset: float,
                      t0: float) -> float | None:
    """How far the pose's clock runs behind the receiver's epochs, s: the shift of the pose's time that brings its
    position closest (horizontal RMS) to the fixes placed at their own epochs, on a 5 ms grid over ±0.5 s."""
    try:
        ft = _frame_times(folder)
        pos = _pose_array(folder, "frame_positions", 3, ft.size)
    except FileFormatError:
        return None
    sow = ft + offset
    ne = ecef_to_ned(lla_to_ecef(gnss.lla), gnss.lla[0])[:, :2]
    best, arg = math.inf, None
    for d in np.arange(-0.5, 0.5 + 1e-9, 0.005):
        tq = epoch_sow + d
        m = (tq > sow[0]) & (tq < sow[-1])
        if m.sum() < 10:
            continue
        p = np.column_stack([np.interp(tq[m], sow, pos[:, j]) for j in range(3)])
        r = float(np.mean(np.sum((ne[m] - ecef_to_ned(p, gnss.lla[0])[:, :2]) ** 2, axis=1)))
        if r < best:
            best, arg = r, float(d)
    return arg


def read_comma2k19_pose(path: str | os.PathLike[str]) -> NavTrack:
    """comma's fused pose of a segment as a ``.nav`` track (module docstring): the reference of a run.

    The pose is the camera's: ECEF position and velocity, and the quaternion of the camera's FRD axes in ECEF
    (``v_e = C(q) v_cam``).  It becomes geodetic position, NED velocity and ``q_nb = q(C_ne C_ec)`` at the GPS
    seconds of week of ``frame_gps_times``.

    Parameters
    ----------
    path : str or os.PathLike
        The segment folder.

    Returns
    -------
    NavTrack
        ``t`` GPS seconds of week of ``week``; ``meta["reference"]`` says what it is.

    Raises
    ------
    FileFormatError
        If a pose file is missing or of the wrong shape.
    """
    folder = os.fspath(path)
    ft = _frame_times(folder)
    gps = _pose_array(folder, "frame_gps_times", 2, ft.size)
    pos = _pose_array(folder, "frame_positions", 3, ft.size)
    vel = _pose_array(folder, "frame_velocities", 3, ft.size)
    qe = _pose_array(folder, "frame_orientations", 4, ft.size)
    week = int(gps[0, 0])
    sow = (gps[:, 0] - week) * _GPS_WEEK_S + gps[:, 1]
    if np.any(np.diff(sow) <= 0):
        raise FileFormatError(f"{folder}/{_POSE}/frame_gps_times: times do not increase")
    lla = ecef_to_lla(pos)
    C_ne = np.transpose(dcm_en(lla[:, 0], lla[:, 1]), (0, 2, 1))
    v_ned = vel_ned_from_ecef(vel, lla)
    q_nb = quat_from_dcm(C_ne @ dcm_from_quat(qe / np.linalg.norm(qe, axis=1, keepdims=True)))
    return NavTrack(sow, lla, v_ned, q_nb, week,
                    meta={"source": folder, "format": "comma2k19 global_pose",
                          "reference": "comma's fused pose of the camera (INS/GNSS/vision): a peer's output, "
                                       "not survey truth"})
