"""Initial alignment for the GNSS/INS filter: static (levelling + gyrocompassing) and in motion (GNSS velocity).

* :func:`static_alignment`: the mean specific force levels the platform and the mean angular rate, the Earth
  rate ``ω_ie^b``, gives true north by the same TRIAD construction as a magnetometer
  (:func:`imunav.attitude.alignment.align`; Groves 2013, §5.6.2-5.6.3).  The heading error of gyrocompassing is
  about ``√(b_g² + N²/T) / (Ω cos φ)`` (gyro bias ``b_g``, ARW ``N``, averaging time ``T``); when that exceeds
  ``max_heading_std`` (MEMS gyros: a 2 °/h bias is already 0.5° at the equator) the heading must be given —
  from a magnetometer or a known heading — and is refused otherwise.
* :func:`motion_alignment`: for a land vehicle that cannot gyrocompass, heading and pitch from the GNSS velocity
  once the speed exceeds ``min_speed`` (the non-holonomic vehicle moves along its body x axis), roll zero;
  the filter starts at that fix (Groves 2013, §14.4.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imunav.attitude.alignment import align
from imunav.earth import OMEGA_E
from imunav.errors import InsufficientDataError, InvalidInputError
from imunav.io.gnss import GnssData
from imunav.results import EulerMixin
from imunav.rotation import quat_from_euler
from imunav.timeseries import ImuData

__all__ = ["Alignment", "static_alignment", "motion_alignment"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Alignment(EulerMixin):
    """Initial state for :meth:`imunav.ins.gins.GinsFilter.run`.

    Attributes
    ----------
    t : float
        Time of the alignment, s (first IMU sample, or the GNSS fix used).
    q_nb : numpy.ndarray, shape (4,)
        Attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    heading_std : float
        Predicted heading σ, rad (0 when the heading was given).
    method : str
        How the heading was found (``"levelling + gyrocompassing"``, ``"levelling + given heading"``,
        ``"GNSS velocity (track)"``).
    lla : numpy.ndarray, shape (3,), or None
        From a motion alignment, the position of the fix (lat rad, lon rad, h m); None for a static one
        (use the known position).
    vel_ned : numpy.ndarray, shape (3,), or None
        From a motion alignment, the velocity of the fix, NED, m/s; None for a static one (zero velocity).
    """

    t: float
    q_nb: Array
    heading_std: float
    method: str
    lla: Array | None = None
    vel_ned: Array | None = None


def static_alignment(imu: ImuData, lat: float, *, gyro_bias_std: float, yaw: float | None = None,
                     max_heading_std: float = math.radians(1.0)) -> Alignment:
    """Coarse alignment of a static recording: levelling, then gyrocompassing when the gyro grade allows.

    Parameters
    ----------
    imu : ImuData
        A static period (rates: rad/s and m/s², body FRD), at least 10 samples.
    lat : float
        Latitude, rad.
    gyro_bias_std : float
        1σ gyro bias the alignment must tolerate, rad/s (e.g. ``GinsConfig.gyro_bias_std``).
    yaw : float, optional
        Known heading, rad, used instead of gyrocompassing (magnetometer or a surveyed heading).
    max_heading_std : float
        Largest predicted heading σ accepted from gyrocompassing, rad.

    Returns
    -------
    Alignment
        At the first IMU sample, ``lla`` and ``vel_ned`` None; ``heading_std`` the predicted
        ``√(b_g² + σ_mean²) / (Ω cos φ)`` (0 with a given ``yaw``).

    Raises
    ------
    InsufficientDataError
        If ``imu`` is not an ImuData of at least 10 samples.
    InvalidInputError
        A latitude outside (-π/2, π/2), or gyrocompassing predicted worse than ``max_heading_std`` and
        no ``yaw`` given.
    """
    if not isinstance(imu, ImuData) or imu.n < 10:
        raise InsufficientDataError("static_alignment needs an ImuData with at least 10 samples of a static period")
    if not (abs(lat) < math.pi / 2):
        raise InvalidInputError(f"lat must be a latitude in radians inside (-pi/2, pi/2); got {lat!r}")
    if yaw is not None:
        q = align(imu.accel, yaw=float(yaw))
        return Alignment(float(imu.t[0]), q, 0.0, "levelling + given heading")
    horiz = OMEGA_E * math.cos(lat)
    T = float(imu.t[-1] - imu.t[0])
    w = imu.gyro.mean(axis=0)
    noise = float(np.std(imu.gyro, axis=0).mean()) / math.sqrt(max(imu.n, 1))  # white-noise error of the mean
    sd = math.sqrt(gyro_bias_std**2 + noise**2) / horiz
    if sd > max_heading_std:
        raise InvalidInputError(
            f"the gyros cannot gyrocompass here: a {gyro_bias_std * 180 / math.pi * 3600:.3g} deg/h bias against the "
            f"{horiz * 180 / math.pi * 3600:.3g} deg/h horizontal Earth rate gives a {math.degrees(sd):.3g} deg heading "
            f"sigma (> {math.degrees(max_heading_std):.3g} deg over {T:.0f} s); give yaw= (magnetometer or known "
            "heading) or align in motion from GNSS velocity (motion_alignment)"
        )
    q = align(imu.accel, mag=w)  # the Earth rate plays the magnetometer's part: its horizontal part points north
    return Alignment(float(imu.t[0]), q, sd, "levelling + gyrocompassing")


def motion_alignment(gnss: GnssData, *, min_speed: float = 5.0, t_start: float | None = None) -> Alignment:
    """In-motion alignment of a land vehicle from GNSS velocity: yaw = track, pitch = climb angle, roll 0.

    Parameters
    ----------
    gnss : GnssData
        Fixes with velocity (``vel_ned`` and ``vel_std``).
    min_speed : float
        Ground speed from which the track defines the heading, m/s (> 0).
    t_start : float, optional
        First usable time, s (default: the first fix).

    Returns
    -------
    Alignment
        At the first fix at or above ``min_speed``, with its position and velocity; ``heading_std`` from the
        fix's velocity σ (``σ_v / speed``).

    Raises
    ------
    InvalidInputError
        If ``gnss`` has no velocity or ``min_speed`` is not > 0.
    InsufficientDataError
        If no usable fix reaches ``min_speed``.
    """
    if gnss.vel_ned is None or gnss.vel_std is None:
        raise InvalidInputError("motion_alignment needs GNSS velocity (a 13-column KF-GINS GNSS file or vel columns)")
    if not (min_speed > 0):
        raise InvalidInputError(f"min_speed must be > 0 m/s; got {min_speed!r}")
    v = gnss.vel_ned
    sp = np.hypot(v[:, 0], v[:, 1])
    ok = sp >= min_speed
    if t_start is not None:
        ok &= gnss.t >= t_start
    if not ok.any():
        raise InsufficientDataError(f"no GNSS fix reaches {min_speed:g} m/s; the vehicle must drive to align in motion")
    k = int(np.argmax(ok))
    yaw = math.atan2(v[k, 1], v[k, 0])
    pitch = math.atan2(-v[k, 2], sp[k])
    q = quat_from_euler(0.0, pitch, yaw)
    sd = float(np.hypot(gnss.vel_std[k, 0], gnss.vel_std[k, 1]) / sp[k])
    return Alignment(float(gnss.t[k]), np.asarray(q), sd, "GNSS velocity (track)", gnss.lla[k].copy(), v[k].copy())
