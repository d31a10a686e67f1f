"""KF-GINS files: IMU increments, navigation results, IMU errors, state σ, and the YAML configuration.

KF-GINS (i2Nav-WHU, GPS Solutions 2025) and the awesome-gins-datasets use
plain text tables (columns separated by spaces):

* IMU: seconds of week; Δθ x y z (rad); Δv x y z (m/s), body FRD;
* GNSS: see :mod:`imunav.io.gnss` (seconds of week, lat °, lon °, h, σ N E D);
* navigation ``.nav``: week; seconds of week; lat °, lon °, h m; v N E D (m/s); roll pitch yaw (°);
* IMU errors (``KF_GINS_IMU_ERR.txt``, 13 columns, as KF-GINS's ``writeNavResult``): seconds; gyro bias x y z
  (°/h); accel bias x y z (mGal, 1e-5 m/s²); gyro scale x y z (ppm); accel scale x y z (ppm);
* state σ (``KF_GINS_STD.txt``, 22 columns, as KF-GINS's ``writeSTD``): seconds; σ position error N E D (m);
  σ velocity error N E D (m/s); σ attitude error φ about N E D (°: the navigation-frame rotation-vector error,
  KF-GINS's ``PHI_ID`` states, *not* the σ of roll / pitch / yaw, which differ from it away from level);
  σ gyro bias x y z (°/h); σ accel bias x y z (mGal); σ gyro scale x y z (ppm); σ accel scale x y z (ppm).
  KF-GINS writes one row per IMU sample; imunav writes one per covariance record of the filter.

:func:`load_kfgins_config` reads KF-GINS's own YAML configuration with its
keys and units into a typed :class:`KfGinsConfig` in SI; paths are relative to
the YAML file.  Writers write atomically (:func:`imunav.files.atomic_path`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import earth
from imunav._timeseries_kernels import interval_integrals
from imunav.errors import ConfigError, InvalidInputError, MissingDependencyError, ShapeError, TimeOrderError
from imunav.files import atomic_path
from imunav.io.gnss import lat_lon_radians, read_table, write_table
from imunav.results import EulerMixin
from imunav.rotation import quat_from_euler, quat_interp
from imunav.timeseries import ImuData
from imunav.units import DEG, HOUR

__all__ = [
    "ImuIncrements",
    "NavTrack",
    "ImuNoise",
    "KfGinsConfig",
    "read_kfgins_imu",
    "write_kfgins_imu",
    "read_kfgins_nav",
    "write_kfgins_nav",
    "write_kfgins_imu_errors",
    "write_kfgins_std",
    "load_kfgins_config",
    "write_kfgins_config",
    "KFGINS_KEYS",
]

Array = NDArray[np.float64]

MGAL = 1e-5  # m/s^2
PPM = 1e-6
DPH = DEG / HOUR  # deg/h -> rad/s
#: Largest relative difference between the declared IMU rate and the one of the time stamps (median step).
RATE_TOLERANCE = 0.01


# ---------------------------------------------------------------------------
# IMU increments
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ImuIncrements:
    """IMU output as increments over ``[t_{k-1}, t_k]`` (row k), the way many logging IMUs deliver it.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Strictly increasing end time of each interval, s.
    dtheta : numpy.ndarray, shape (N, 3)
        Angle increments (integrated angular rate), rad, body FRD.
    dvel : numpy.ndarray, shape (N, 3)
        Velocity increments (integrated specific force), m/s, body FRD.
    dt : numpy.ndarray, shape (N,)
        Interval lengths, s (> 0; row 0: ``1 / rate``).
    meta : dict
        Source file, rate, gaps found ...

    Raises
    ------
    ShapeError
        If ``dtheta`` or ``dvel`` is not (N, 3).
    InvalidInputError
        If ``dt`` is not (N,) or has a length <= 0.
    """

    t: Array
    dtheta: Array
    dvel: Array
    dt: Array
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        n = t.size
        for name in ("dtheta", "dvel"):
            if np.shape(getattr(self, name)) != (n, 3):
                raise ShapeError(f"ImuIncrements.{name} must have shape ({n}, 3); got {np.shape(getattr(self, name))}")
        if np.shape(self.dt) != (n,) or np.any(np.asarray(self.dt) <= 0):
            raise InvalidInputError("ImuIncrements.dt must be (N,) positive interval lengths in seconds")

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    def to_imu_data(self) -> ImuData:
        """Mean rates over each interval (increment / dt) as an :class:`ImuData` stamped at the interval ends.

        Returns
        -------
        ImuData
            ``gyro = dtheta / dt`` (rad/s) and ``accel = dvel / dt`` (m/s²), body FRD, at times ``t``;
            ``meta["from_increments"]`` is True.
        """
        return ImuData(self.t, self.dtheta / self.dt[:, None], self.dvel / self.dt[:, None],
                       meta={**self.meta, "from_increments": True})

    @classmethod
    def from_imu_data(cls, imu: ImuData, rate_hz: float | None = None) -> ImuIncrements:
        """Increments of point-sampled rates: each interval's integral of the cubic through its samples and one
        more on each side (:func:`imunav.ins.strapdown.coning_sculling_increments`' rule, before its coning and
        sculling terms; a quadratic at the ends and beside gaps), row 0 over ``1 / rate_hz`` at its own rate.

        Parameters
        ----------
        imu : ImuData
            Point samples of the angular rate (rad/s) and specific force (m/s²), body FRD, at least 2.
        rate_hz : float, optional
            Nominal rate for row 0, Hz (default: the median rate of ``imu``).

        Returns
        -------
        ImuIncrements
            Row k > 0: ``∫ x dt`` over ``[t_{k-1}, t_k]`` (``h (−x_{k−2} + 13 x_{k−1} + 13 x_k − x_{k+1}) / 24``
            on a uniform grid); row 0: ``x_0 / rate_hz``.

        Raises
        ------
        InvalidInputError
            If ``imu`` has fewer than 2 samples.
        """
        t = np.asarray(imu.t, dtype=float)
        if t.size < 2:
            raise InvalidInputError("ImuIncrements.from_imu_data needs at least 2 samples")
        rate = float(rate_hz) if rate_hz is not None else float(1.0 / np.median(np.diff(t)))
        dt = np.concatenate([[1.0 / rate], np.diff(t)])
        dth = np.empty((t.size, 3))
        dv = np.empty((t.size, 3))
        dth[1:] = interval_integrals(t, np.ascontiguousarray(imu.gyro, dtype=np.float64))[1:]
        dv[1:] = interval_integrals(t, np.ascontiguousarray(imu.accel, dtype=np.float64))[1:]
        dth[0], dv[0] = imu.gyro[0] * dt[0], imu.accel[0] * dt[0]
        return cls(t, dth, dv, dt, {"rate_hz": rate, "source": imu.meta.get("source", "ImuData")})


def read_kfgins_imu(path: str | os.PathLike[str], rate_hz: float | None = None) -> ImuIncrements:
    """Read a KF-GINS IMU text file (seconds of week, Δθ rad, Δv m/s; extra columns such as odometer ignored).

    Parameters
    ----------
    path : str or os.PathLike
        Text file with 7 or more columns.
    rate_hz : float, optional
        The declared IMU rate (KF-GINS's ``imudatarate``), Hz, checked against the time stamps; None: the rate
        of the median time step.

    Returns
    -------
    ImuIncrements
        ``meta["gaps"]`` lists intervals longer than 1.5 / rate (start time, length s).

    Raises
    ------
    TimeOrderError
        Time stamps that do not increase.
    InvalidInputError
        A declared rate that the time stamps contradict (median step off by more than 1 %), or
        values that are not increments (rates or degrees).
    """
    rate = float("nan") if rate_hz is None else float(rate_hz)
    if rate_hz is not None and not (math.isfinite(rate) and rate > 0):
        raise InvalidInputError(f"rate_hz (imudatarate) must be a positive rate in Hz; got {rate_hz!r}")
    a = read_table(path, tuple(range(7, 40)), "KF-GINS IMU")
    src = os.fspath(path)
    t = a[:, 0]
    if t.size < 2:
        raise InvalidInputError(f"{src}: an IMU file needs at least 2 samples")
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise TimeOrderError(f"{src}: IMU time is not strictly increasing at data row {k + 1} "
                             f"({t[k - 1]!r} then {t[k]!r}); sort the file and remove duplicates")
    med = float(np.median(d))
    if rate_hz is None:
        rate = 1.0 / med
    elif abs(med * rate - 1.0) > RATE_TOLERANCE:
        raise InvalidInputError(
            f"{src}: the time stamps step by {med:.6g} s ({1 / med:.6g} Hz) but the declared rate is {rate:g} Hz; "
            "fix imudatarate (or rate_hz) to the file's rate"
        )
    dt = np.concatenate([[1.0 / rate], d])
    dth, dv = a[:, 1:4], a[:, 4:7]
    big = np.max(np.linalg.norm(dth, axis=1) / dt)
    if big > 50.0:  # rad/s: no vehicle IMU turns faster; degrees or rates were given
        raise InvalidInputError(f"{src}: the angle increments reach {big:.3g} rad/s; KF-GINS files hold increments "
                                "in radians (not degrees, not rates)")
    f_med = float(np.median(np.linalg.norm(dv, axis=1) / dt))
    if f_med > 200.0:
        raise InvalidInputError(f"{src}: the velocity increments average {f_med:.3g} m/s^2 of specific force; "
                                "the file holds rates or another unit, not increments in m/s")
    gaps = np.flatnonzero(d > 1.5 / rate)
    meta = {"source": src, "format": "kf-gins-imu", "rate_hz": rate,
            "gaps": [[float(t[i]), float(d[i])] for i in gaps[:1000]], "n_gaps": int(gaps.size)}
    return ImuIncrements(t, dth, dv, dt, meta)


def write_kfgins_imu(path: str | os.PathLike[str], inc: ImuIncrements) -> Path:
    """Write increments as a KF-GINS IMU text file (7 columns), atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    inc : ImuIncrements
        The increments (time s, Δθ rad, Δv m/s).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    return write_table(path, [inc.t, *inc.dtheta.T, *inc.dvel.T])


# ---------------------------------------------------------------------------
# navigation results and truth
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class NavTrack(EulerMixin):
    """A navigation solution or truth: time, geodetic position, NED velocity and attitude (SI).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s (seconds of week in KF-GINS files).
    lla : numpy.ndarray, shape (N, 3)
        Geodetic position: lat rad, lon rad, ellipsoidal height m.
    vel_ned : numpy.ndarray, shape (N, 3)
        Velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    week : int
        GPS week (KF-GINS writes 0 when unknown).
    meta : dict
        Source file, format ...

    Raises
    ------
    ShapeError
        If ``lla``, ``vel_ned`` or ``q_nb`` does not have N rows of 3, 3, 4 columns.
    """

    t: Array
    lla: Array
    vel_ned: Array
    q_nb: Array
    week: int = 0
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = np.size(self.t)
        for name, w in (("lla", 3), ("vel_ned", 3), ("q_nb", 4)):
            if np.shape(getattr(self, name)) != (n, w):
                raise ShapeError(f"NavTrack.{name} must have shape ({n}, {w}); got {np.shape(getattr(self, name))}")


    def at(self, t: ArrayLike) -> NavTrack:
        """The track at times ``t`` inside its span: position and velocity interpolated linearly, the attitude by
        slerp (:func:`imunav.rotation.quat_interp`); times outside the span are left out.  A reference at 20 Hz
        (comma2k19's pose) is compared with a run at the IMU's stamps this way.

        Parameters
        ----------
        t : array_like, shape (M,)
            Increasing times, s (this track's clock).

        Returns
        -------
        NavTrack
            At the times of ``t`` within ``[self.t[0], self.t[-1]]``.

        Raises
        ------
        InvalidInputError
            If no time of ``t`` lies in the span, or the track has fewer than 2 rows.
        """
        tq = np.asarray(t, dtype=float)
        if self.t.size < 2:
            raise InvalidInputError(f"{self.meta.get('source', 'the track')}: {self.t.size} row(s); interpolation "
                                    "needs 2")
        tq = tq[(tq >= self.t[0]) & (tq <= self.t[-1])]
        if tq.size == 0:
            raise InvalidInputError(f"{self.meta.get('source', 'the track')} ({self.t[0]:.3f}..{self.t[-1]:.3f} s) "
                                    "covers none of the times asked for")

        def lin(x: Array) -> Array:
            return np.column_stack([np.interp(tq, self.t, x[:, j]) for j in range(x.shape[1])])

        return NavTrack(tq, lin(self.lla), lin(self.vel_ned), quat_interp(self.t, self.q_nb, tq), self.week,
                        dict(self.meta))

    def difference(self, truth: NavTrack, *, tol_s: float = 1e-6) -> tuple[Array, Array, Array, Array]:
        """Errors of this track against ``truth`` at their common time stamps.

        Parameters
        ----------
        truth : NavTrack
            The reference, sampled on (some of) the same time stamps.
        tol_s : float
            Two stamps closer than this are the same epoch, s (a KF-GINS file keeps 9 decimals).

        Returns
        -------
        t : numpy.ndarray, shape (M,)
            The common time stamps, s.
        pos_ned : numpy.ndarray, shape (M, 3)
            Position error (this minus truth) north, east, down, m (local radii of the truth).
        vel_ned : numpy.ndarray, shape (M, 3)
            Velocity error, NED, m/s.
        euler : numpy.ndarray, shape (M, 3)
            Roll, pitch, yaw error, rad, wrapped to [-π, π).

        Raises
        ------
        InvalidInputError
            If the two tracks share no time stamp.
        """
        j = np.clip(np.searchsorted(truth.t, self.t - tol_s), 0, truth.t.size - 1)
        ia = np.flatnonzero(np.abs(truth.t[j] - self.t) <= tol_s)
        if ia.size == 0:
            src = truth.meta.get("source", "the truth")
            raise InvalidInputError(f"{src} shares no time stamp with the navigation solution "
                                    f"({self.t[0]:.3f}..{self.t[-1]:.3f} s); sample the truth on the IMU stamps")
        ib = j[ia]
        a, b = self.lla[ia], truth.lla[ib]
        d = earth.dlla_to_ned(a - b, b)
        de = self.euler()[ia] - truth.euler()[ib]
        return self.t[ia], d, self.vel_ned[ia] - truth.vel_ned[ib], (de + np.pi) % (2 * np.pi) - np.pi


def read_kfgins_nav(path: str | os.PathLike[str]) -> NavTrack:
    """Read a KF-GINS navigation / truth file (``.nav``: week, seconds, lat °, lon °, h, v NED, roll pitch yaw °).

    Parameters
    ----------
    path : str or os.PathLike
        The 11-column text file.

    Returns
    -------
    NavTrack
        In SI (radians; attitude as ``q_nb`` from the ZYX Euler angles); ``week`` the first week of the file.

    Raises
    ------
    FileFormatError
        If the file is empty, ragged, not numeric, or does not have 11 columns.
    TimeOrderError
        If the seconds do not strictly increase.
    InvalidInputError
        If a latitude or longitude is out of range for degrees.
    """
    a = read_table(path, (11,), "KF-GINS navigation (.nav)")
    src = os.fspath(path)
    t = a[:, 1]
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise TimeOrderError(f"{src}: time is not strictly increasing at data row {k + 1}")
    lat, lon = lat_lon_radians(a[:, 2], a[:, 3], "deg", src)
    q = quat_from_euler(np.radians(a[:, 8:11]))
    weeks = np.unique(a[:, 0])
    return NavTrack(t, np.column_stack([lat, lon, a[:, 4]]), a[:, 5:8], q, int(weeks[0]),
                    {"source": src, "format": "kf-gins-nav"})


def write_kfgins_nav(path: str | os.PathLike[str], nav: NavTrack) -> Path:
    """Write a KF-GINS ``.nav`` file (11 columns, degrees), atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    nav : NavTrack
        The track; the attitude is written as ZYX Euler angles (roll, pitch, yaw) in degrees.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    eul = np.degrees(nav.euler())
    return write_table(path, [np.full(nav.t.size, float(nav.week)), nav.t, np.degrees(nav.lla[:, 0]),
                              np.degrees(nav.lla[:, 1]), nav.lla[:, 2], *nav.vel_ned.T, *eul.T])


def _cols(x: ArrayLike, n: int, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (n, 3):
        raise ShapeError(f"{name} must have shape ({n}, 3); got {a.shape}")
    return a


def write_kfgins_imu_errors(path: str | os.PathLike[str], t: ArrayLike, gyro_bias: ArrayLike, accel_bias: ArrayLike,
                            gyro_scale: ArrayLike, accel_scale: ArrayLike) -> Path:
    """Write KF-GINS's IMU error file: seconds, gyro bias °/h, accel bias mGal, gyro and accel scale ppm.

    Parameters
    ----------
    path : str or os.PathLike
        Output file (13 columns).
    t : array_like, shape (N,)
        Time, s.
    gyro_bias : array_like, shape (N, 3)
        Gyro biases, rad/s (written in °/h).
    accel_bias : array_like, shape (N, 3)
        Accelerometer biases, m/s² (written in mGal, 1 mGal = 1e-5 m/s²).
    gyro_scale, accel_scale : array_like, shape (N, 3)
        Dimensionless scale-factor errors (written in ppm).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ShapeError
        If an error array is not (N, 3).
    """
    ta = np.asarray(t, dtype=float)
    n = ta.size
    return write_table(path, [ta, *(_cols(gyro_bias, n, "gyro_bias") / DPH).T,
                              *(_cols(accel_bias, n, "accel_bias") / MGAL).T,
                              *(_cols(gyro_scale, n, "gyro_scale") / PPM).T,
                              *(_cols(accel_scale, n, "accel_scale") / PPM).T])


def write_kfgins_std(path: str | os.PathLike[str], t: ArrayLike, pos_std: ArrayLike, vel_std: ArrayLike,
                     att_std: ArrayLike, gyro_bias_std: ArrayLike, accel_bias_std: ArrayLike,
                     gyro_scale_std: ArrayLike, accel_scale_std: ArrayLike) -> Path:
    """Write KF-GINS's state σ file (22 columns, the columns of KF-GINS's ``writeSTD``): seconds, σ pos N E D m,
    σ vel N E D m/s, σ attitude error φ about N E D °, σ gyro bias °/h, σ accel bias mGal, σ gyro and accel
    scale ppm.  Inputs in SI (m, m/s, rad, rad/s, m/s^2, 1).

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    t : array_like, shape (N,)
        Time, s.
    pos_std : array_like, shape (N, 3)
        Position σ north/east/down, m.
    vel_std : array_like, shape (N, 3)
        Velocity σ north/east/down, m/s.
    att_std : array_like, shape (N, 3)
        σ of the attitude error φ (navigation-frame rotation vector) about north, east, down, rad; KF-GINS
        writes the same states (``PHI_ID``), not the σ of roll / pitch / yaw.
    gyro_bias_std, accel_bias_std : array_like, shape (N, 3)
        Bias σ, rad/s and m/s².
    gyro_scale_std, accel_scale_std : array_like, shape (N, 3)
        Scale-factor σ, dimensionless.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ShapeError
        If a σ array is not (N, 3).
    """
    ta = np.asarray(t, dtype=float)
    n = ta.size
    return write_table(path, [ta, *_cols(pos_std, n, "pos_std").T, *_cols(vel_std, n, "vel_std").T,
                              *np.degrees(_cols(att_std, n, "att_std")).T,
                              *(_cols(gyro_bias_std, n, "gyro_bias_std") / DPH).T,
                              *(_cols(accel_bias_std, n, "accel_bias_std") / MGAL).T,
                              *(_cols(gyro_scale_std, n, "gyro_scale_std") / PPM).T,
                              *(_cols(accel_scale_std, n, "accel_scale_std") / PPM).T])


# ---------------------------------------------------------------------------
# YAML configuration
# ---------------------------------------------------------------------------

#: KF-GINS configuration keys (dataset/kf-gins.yaml) and their units.
KFGINS_KEYS: dict[str, str] = {
    "imupath": "path", "gnsspath": "path", "outputpath": "path", "imudatalen": "columns", "imudatarate": "Hz",
    "starttime": "s of week", "endtime": "s of week (-1: end of file)",
    "initpos": "deg, deg, m", "initvel": "m/s NED", "initatt": "deg roll pitch yaw",
    "initgyrbias": "deg/h", "initaccbias": "mGal", "initgyrscale": "ppm", "initaccscale": "ppm",
    "initposstd": "m NED", "initvelstd": "m/s NED", "initattstd": "deg",
    "initbgstd": "deg/h", "initbastd": "mGal", "initsgstd": "ppm", "initsastd": "ppm",
    "imunoise": "arw deg/sqrt(h), vrw m/s/sqrt(h), gbstd deg/h, abstd mGal, gsstd ppm, asstd ppm, corrtime h",
    "antlever": "m FRD",
}
_NOISE_KEYS = ("arw", "vrw", "gbstd", "abstd", "gsstd", "asstd", "corrtime")


@dataclass(frozen=True)
class ImuNoise:
    """IMU noise of the filter in SI (KF-GINS's ``imunoise`` block, converted).

    Attributes
    ----------
    gyro_noise_density : numpy.ndarray, shape (3,)
        Gyro angle random walk, rad/√s (``arw`` °/√h in the YAML).
    accel_noise_density : numpy.ndarray, shape (3,)
        Accelerometer velocity random walk, m/s/√s (``accel_noise_density`` m/s/√h).
    gyro_bias_std, accel_bias_std : numpy.ndarray, shape (3,)
        Stationary σ of the Gauss–Markov biases, rad/s and m/s² (``gbstd`` °/h, ``abstd`` mGal).
    gyro_scale_std, accel_scale_std : numpy.ndarray, shape (3,)
        Stationary σ of the Gauss–Markov scale-factor errors, dimensionless (``gsstd``, ``asstd`` ppm).
    corr_time : float
        Correlation time of the biases and scale factors, s (``corrtime`` h).
    """

    gyro_noise_density: Array
    accel_noise_density: Array
    gyro_bias_std: Array
    accel_bias_std: Array
    gyro_scale_std: Array
    accel_scale_std: Array
    corr_time: float


@dataclass(frozen=True)
class KfGinsConfig:
    """KF-GINS configuration in SI (angles rad, biases rad/s and m/s², scale factors dimensionless).

    Built by :func:`load_kfgins_config`; the YAML key of each field is in :data:`KFGINS_KEYS`.

    Attributes
    ----------
    source : pathlib.Path
        The YAML file.
    imu_path, gnss_path, output_path : pathlib.Path
        IMU file, GNSS file and output folder, resolved against the YAML file's folder.
    imu_rate_hz : float
        IMU rate, Hz.
    imu_columns : int
        Number of columns of the IMU file (>= 7).
    start_time : float
        First second of week to process, s.
    end_time : float or None
        Last second of week, s; None for KF-GINS's ``-1`` (to the end of the IMU file).
    init_lla : numpy.ndarray, shape (3,)
        Initial position: lat rad, lon rad, h m.
    init_vel : numpy.ndarray, shape (3,)
        Initial velocity, NED, m/s.
    init_euler : numpy.ndarray, shape (3,)
        Initial attitude, ZYX Euler (roll, pitch, yaw), rad.
    init_gyro_bias, init_accel_bias : numpy.ndarray, shape (3,)
        Initial biases, rad/s and m/s² (zero when absent).
    init_gyro_scale, init_accel_scale : numpy.ndarray, shape (3,)
        Initial scale-factor errors, dimensionless (zero when absent).
    init_pos_std, init_vel_std, init_att_std : numpy.ndarray, shape (3,)
        Initial σ of position (NED, m), velocity (NED, m/s) and attitude (rad).
    init_gyro_bias_std, init_accel_bias_std : numpy.ndarray, shape (3,)
        Initial σ of the biases, rad/s and m/s² (default: those of ``imu_noise_model``).
    init_gyro_scale_std, init_accel_scale_std : numpy.ndarray, shape (3,)
        Initial σ of the scale factors, dimensionless (default: those of ``imu_noise_model``).
    imu_noise_model : ImuNoise
        The IMU noise of the filter.
    antenna_lever_arm : numpy.ndarray, shape (3,)
        GNSS antenna from the IMU, body FRD, m.
    options : dict
        The keys KF-GINS does not know (imunav options such as an odometer file), as written.
    """

    source: Path
    imu_path: Path
    gnss_path: Path
    output_path: Path
    imu_rate_hz: float
    imu_columns: int
    start_time: float
    end_time: float | None
    init_lla: Array
    init_vel: Array
    init_euler: Array
    init_gyro_bias: Array
    init_accel_bias: Array
    init_gyro_scale: Array
    init_accel_scale: Array
    init_pos_std: Array
    init_vel_std: Array
    init_att_std: Array
    init_gyro_bias_std: Array
    init_accel_bias_std: Array
    init_gyro_scale_std: Array
    init_accel_scale_std: Array
    imu_noise_model: ImuNoise
    antenna_lever_arm: Array
    options: dict[str, object] = field(default_factory=dict)


def _vec(doc: dict[str, Any], key: str, src: str, *, scale: float = 1.0, positive: bool = False,
         default: Any = None) -> Array:
    if key not in doc:
        if default is None:
            unit = KFGINS_KEYS.get(key, "see KF-GINS's imunoise")
            raise ConfigError(f"{src}: missing key '{key}' ({unit}); add it as in KF-GINS's dataset/kf-gins.yaml")
        return np.asarray(default, dtype=float) * scale
    v = doc[key]
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{src}: '{key}' must be a list of 3 numbers; got {v!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ConfigError(f"{src}: '{key}' must be a list of 3 finite numbers; got {v!r}")
    if positive and np.any(a <= 0):
        raise ConfigError(f"{src}: '{key}' = {v!r}; a standard deviation must be > 0 (in {KFGINS_KEYS.get(key, key)})")
    return a * scale


def _num(doc: dict[str, Any], key: str, src: str, default: float | None = None) -> float:
    if key not in doc:
        if default is None:
            raise ConfigError(f"{src}: missing key '{key}' ({KFGINS_KEYS.get(key, '')})")
        return default
    try:
        x = float(doc[key])
    except (TypeError, ValueError):
        raise ConfigError(f"{src}: '{key}' must be a number; got {doc[key]!r}") from None
    if not math.isfinite(x):
        raise ConfigError(f"{src}: '{key}' must be finite; got {doc[key]!r}")
    return x


def _path(doc: dict[str, Any], key: str, base: Path, src: str) -> Path:
    if not isinstance(doc.get(key), str) or not doc[key].strip():
        raise ConfigError(f"{src}: '{key}' must be a file path (relative to the YAML file); got {doc.get(key)!r}")
    p = Path(doc[key])
    return p if p.is_absolute() else (base / p)


def _yaml_vec(x: ArrayLike, fmt: str = "{:.10g}") -> str:
    return "[ " + ", ".join(fmt.format(float(a)) for a in np.asarray(x, dtype=float)) + " ]"


def write_kfgins_config(path: str | os.PathLike[str], cfg: KfGinsConfig, *, comment: str | None = None) -> Path:
    """Write a :class:`KfGinsConfig` (SI) as KF-GINS's YAML (its keys and units), atomically.

    The inverse of :func:`load_kfgins_config`: reading the file back gives ``cfg`` to 10 significant digits
    (the initial latitude and longitude to 1e-10 degree, the initial attitude to 1e-8 degree).  The paths are
    written relative to the YAML's folder when they lie below it.  Keys KF-GINS does not know (``cfg.options``)
    are not written.

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file to write.
    cfg : KfGinsConfig
        The configuration, SI.
    comment : str, optional
        A first comment line (without ``#``).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    p = Path(path)
    base = p.resolve().parent

    def rel(q: Path) -> str:
        q = Path(q).resolve()
        return q.relative_to(base).as_posix() if q.is_relative_to(base) else q.as_posix()

    n = cfg.imu_noise_model
    lla_deg = np.r_[np.degrees(cfg.init_lla[:2]), cfg.init_lla[2]]
    lines = [] if comment is None else [f"# {comment}"]
    lines += [
        f'imupath: "{rel(cfg.imu_path)}"', f'gnsspath: "{rel(cfg.gnss_path)}"', f'outputpath: "{rel(cfg.output_path)}"',
        f"imudatalen: {cfg.imu_columns:d}", f"imudatarate: {cfg.imu_rate_hz:g}", f"starttime: {cfg.start_time:.3f}",
        "endtime: -1" if cfg.end_time is None else f"endtime: {cfg.end_time:.3f}",
        f"initpos: {_yaml_vec(lla_deg, '{:.10f}')}", f"initvel: {_yaml_vec(cfg.init_vel)}",
        f"initatt: {_yaml_vec(np.degrees(cfg.init_euler), '{:.8f}')}",
        f"initgyrbias: {_yaml_vec(cfg.init_gyro_bias / DPH)}", f"initaccbias: {_yaml_vec(cfg.init_accel_bias / MGAL)}",
        f"initgyrscale: {_yaml_vec(cfg.init_gyro_scale / PPM)}",
        f"initaccscale: {_yaml_vec(cfg.init_accel_scale / PPM)}",
        f"initposstd: {_yaml_vec(cfg.init_pos_std)}", f"initvelstd: {_yaml_vec(cfg.init_vel_std)}",
        f"initattstd: {_yaml_vec(np.degrees(cfg.init_att_std))}",
        f"initbgstd: {_yaml_vec(cfg.init_gyro_bias_std / DPH)}", f"initbastd: {_yaml_vec(cfg.init_accel_bias_std / MGAL)}",
        f"initsgstd: {_yaml_vec(cfg.init_gyro_scale_std / PPM)}",
        f"initsastd: {_yaml_vec(cfg.init_accel_scale_std / PPM)}",
        "imunoise:",
        f"  arw: {_yaml_vec(n.gyro_noise_density / (DEG / 60.0))}", f"  vrw: {_yaml_vec(n.accel_noise_density * 60.0)}",
        f"  gbstd: {_yaml_vec(n.gyro_bias_std / DPH)}", f"  abstd: {_yaml_vec(n.accel_bias_std / MGAL)}",
        f"  gsstd: {_yaml_vec(n.gyro_scale_std / PPM)}", f"  asstd: {_yaml_vec(n.accel_scale_std / PPM)}",
        f"  corrtime: {n.corr_time / HOUR:.6g}",
        f"antlever: {_yaml_vec(cfg.antenna_lever_arm)}", ""]
    with atomic_path(p) as tmp:
        tmp.write_text("\n".join(lines), encoding="utf-8")
    return p


def load_kfgins_config(path: str | os.PathLike[str]) -> KfGinsConfig:
    """Read KF-GINS's YAML configuration (same keys and units) into a :class:`KfGinsConfig` in SI.

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file; ``imupath``, ``gnsspath`` and ``outputpath`` are relative to its folder.

    Returns
    -------
    KfGinsConfig
        The configuration in SI.

    Raises
    ------
    ConfigError
        Not valid YAML, a missing key, a value of the wrong shape, a σ <= 0, a start time outside a
        GPS week or an end time before it.
    InvalidInputError
        An initial position out of range for degrees, or in radians.
    FileNotFoundError
        If ``path`` is not a file.
    MissingDependencyError
        If PyYAML is not installed (extra ``yaml``).
    """
    try:
        import yaml  # optional: KF-GINS YAML support (extra 'yaml')
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise MissingDependencyError("pyyaml", "yaml", "Reading KF-GINS YAML configurations") from exc
    p = Path(path)
    src = os.fspath(p)
    if not p.is_file():
        raise FileNotFoundError(f"{src}: no such configuration file")
    try:
        doc = yaml.safe_load(p.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ConfigError(f"{src}: not valid YAML ({exc})") from None
    if not isinstance(doc, dict):
        raise ConfigError(f"{src}: a KF-GINS configuration is a mapping of keys (imupath, gnsspath, ...)")
    base = p.resolve().parent
    noise_doc = doc.get("imunoise")
    if not isinstance(noise_doc, dict):
        raise ConfigError(f"{src}: 'imunoise' must be a mapping with keys {', '.join(_NOISE_KEYS)}")
    nsrc = f"{src}: imunoise"
    corr = _num(noise_doc, "corrtime", nsrc)
    if corr <= 0:
        raise ConfigError(f"{nsrc}: 'corrtime' = {corr!r} h; a correlation time must be > 0 hours")
    noise = ImuNoise(
        gyro_noise_density=_vec(noise_doc, "arw", nsrc, scale=DEG / 60.0, positive=True),
        accel_noise_density=_vec(noise_doc, "vrw", nsrc, scale=1.0 / 60.0, positive=True),
        gyro_bias_std=_vec(noise_doc, "gbstd", nsrc, scale=DPH, positive=True),
        accel_bias_std=_vec(noise_doc, "abstd", nsrc, scale=MGAL, positive=True),
        gyro_scale_std=_vec(noise_doc, "gsstd", nsrc, scale=PPM, positive=True),
        accel_scale_std=_vec(noise_doc, "asstd", nsrc, scale=PPM, positive=True),
        corr_time=corr * HOUR,
    )
    pos = _vec(doc, "initpos", src)
    lat, lon = lat_lon_radians(pos[:1], pos[1:2], "deg", f"{src}: initpos")
    rate = _num(doc, "imudatarate", src)
    if rate <= 0:
        raise ConfigError(f"{src}: 'imudatarate' = {rate!r}; the IMU rate must be > 0 Hz")
    cols = int(_num(doc, "imudatalen", src, 7.0))
    if cols < 7:
        raise ConfigError(f"{src}: 'imudatalen' = {cols}; a KF-GINS IMU file has at least 7 columns")
    start = _num(doc, "starttime", src)
    end = _num(doc, "endtime", src)
    if not (0 <= start <= 604800):
        raise ConfigError(f"{src}: 'starttime' = {start!r}; it is a GPS second of week in [0, 604800]")
    if end != -1 and not (start < end <= 604800):
        raise ConfigError(f"{src}: 'endtime' = {end!r}; use -1 (to the end of the IMU file) or a second of week "
                          f"after starttime {start!r}")
    options = {k: v for k, v in doc.items() if k not in KFGINS_KEYS}
    return KfGinsConfig(
        source=p,
        imu_path=_path(doc, "imupath", base, src),
        gnss_path=_path(doc, "gnsspath", base, src),
        output_path=_path(doc, "outputpath", base, src),
        imu_rate_hz=rate,
        imu_columns=cols,
        start_time=start,
        end_time=None if end == -1 else end,
        init_lla=np.array([lat[0], lon[0], pos[2]]),
        init_vel=_vec(doc, "initvel", src),
        init_euler=_vec(doc, "initatt", src, scale=DEG),
        init_gyro_bias=_vec(doc, "initgyrbias", src, scale=DPH, default=np.zeros(3)),
        init_accel_bias=_vec(doc, "initaccbias", src, scale=MGAL, default=np.zeros(3)),
        init_gyro_scale=_vec(doc, "initgyrscale", src, scale=PPM, default=np.zeros(3)),
        init_accel_scale=_vec(doc, "initaccscale", src, scale=PPM, default=np.zeros(3)),
        init_pos_std=_vec(doc, "initposstd", src, positive=True),
        init_vel_std=_vec(doc, "initvelstd", src, positive=True),
        init_att_std=_vec(doc, "initattstd", src, scale=DEG, positive=True),
        init_gyro_bias_std=_vec(doc, "initbgstd", src, scale=DPH, positive=True,
                                default=noise.gyro_bias_std / DPH),
        init_accel_bias_std=_vec(doc, "initbastd", src, scale=MGAL, positive=True,
                                 default=noise.accel_bias_std / MGAL),
        init_gyro_scale_std=_vec(doc, "initsgstd", src, scale=PPM, positive=True,
                                 default=noise.gyro_scale_std / PPM),
        init_accel_scale_std=_vec(doc, "initsastd", src, scale=PPM, positive=True,
                                  default=noise.accel_scale_std / PPM),
        imu_noise_model=noise,
        antenna_lever_arm=_vec(doc, "antlever", src),
        options=options,
    )
