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
* :func:`gyro_bias_in_motion`: a vehicle that never stands still reads its gyro bias over the drive: the mean
  rate is the bias plus the attitude's change over the span, whose roll and pitch return and whose heading change
  the GNSS course gives.
* :func:`fine_alignment`: after a static coarse alignment, the GNSS/INS filter itself over the static period
  (zero-velocity and zero-angular-rate updates, the known position) refines the attitude and estimates the IMU
  biases, and reports the attitude σ of its covariance (Groves 2013, §14.2.2: "fine alignment" by Kalman
  filtering).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.attitude.alignment import align
from imunav.earth import OMEGA_E, lla_to_ned
from imunav.errors import InsufficientDataError, InvalidInputError, ShapeError
from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.io.gnss import GnssData
from imunav.io.kfgins import ImuIncrements
from imunav.results import EulerMixin
from imunav.rotation import quat_from_euler
from imunav.timeseries import ImuData

__all__ = ["Alignment", "static_alignment", "motion_alignment", "gnss_course", "gyro_bias_in_motion",
           "fine_alignment"]

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
        ``"GNSS velocity (track)"``, and ``" + fine (Kalman filter)"`` after :func:`fine_alignment`).
    lla : numpy.ndarray, shape (3,), or None
        From a motion alignment, the position of the fix (lat rad, lon rad, h m); None for a static one
        (use the known position).
    vel_ned : numpy.ndarray, shape (3,), or None
        From a motion alignment, the velocity of the fix, NED, m/s; None for a static one (zero velocity).
    att_std : numpy.ndarray, shape (3,), or None
        From :func:`fine_alignment`: σ of the attitude error φ about N, E, D, rad (the filter's covariance; pass
        it as ``GinsConfig.init_att_std``).
    imu_errors : numpy.ndarray, shape (12,), or None
        From :func:`fine_alignment`: gyro bias (rad/s), accel bias (m/s²), gyro and accel scale estimated over
        the static period (pass it as ``imu_errors0``).
    heading_given : bool
        True when the heading was given (``static_alignment(..., yaw=...)``), not found by the gyros.
    """

    t: float
    q_nb: Array
    heading_std: float
    method: str
    lla: Array | None = None
    vel_ned: Array | None = None
    att_std: Array | None = None
    imu_errors: Array | None = None
    heading_given: bool = False


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
        return Alignment(float(imu.t[0]), q, 0.0, "levelling + given heading", heading_given=True)
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


def motion_alignment(gnss: GnssData, *, min_speed: float = 5.0, t_start: float | None = None,
                     slip_std: float = 0.0) -> Alignment:
    """In-motion alignment of a land vehicle from GNSS velocity: yaw = track, pitch = climb angle, roll 0.

    Parameters
    ----------
    gnss : GnssData
        Fixes with velocity (``vel_ned`` and ``vel_std``).
    min_speed : float
        Ground speed from which the track defines the heading, m/s (> 0).
    t_start : float, optional
        First usable time, s (default: the first fix).
    slip_std : float
        σ of the vehicle's lateral (side-slip) velocity, m/s (>= 0; e.g. ``GinsConfig.nhc_noise_std``): the track
        differs from the heading by ``v_lat / speed``.

    Returns
    -------
    Alignment
        At the first fix at or above ``min_speed``, with its position and velocity; ``heading_std`` from the
        fix's cross-track velocity σ and the side slip, ``√(σ_N² sin²ψ + σ_E² cos²ψ + σ_slip²) / speed``.

    Raises
    ------
    InvalidInputError
        If ``gnss`` has no velocity, ``min_speed`` is not > 0 or ``slip_std`` is negative.
    InsufficientDataError
        If no usable fix reaches ``min_speed``.
    """
    if gnss.vel_ned is None or gnss.vel_std is None:
        raise InvalidInputError("motion_alignment needs GNSS velocity (a 13-column KF-GINS GNSS file or vel columns)")
    if not (min_speed > 0):
        raise InvalidInputError(f"min_speed must be > 0 m/s; got {min_speed!r}")
    if not (math.isfinite(slip_std) and slip_std >= 0):
        raise InvalidInputError(f"slip_std must be >= 0 m/s; got {slip_std!r}")
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
    # the heading error is the cross-track velocity error (and the slip) over the speed
    cross = np.hypot(gnss.vel_std[k, 0] * math.sin(yaw), gnss.vel_std[k, 1] * math.cos(yaw))
    sd = float(np.hypot(cross, slip_std) / sp[k])
    return Alignment(float(gnss.t[k]), np.asarray(q), sd, "GNSS velocity (track)", gnss.lla[k].copy(), v[k].copy())


def gnss_course(gnss: GnssData, *, min_speed: float = 3.0, baseline_s: float = 1.0) -> tuple[Array, Array]:
    """The vehicle's course over ground from its fixes, unwrapped: ``ψ = atan2(ΔE, ΔN)`` between fixes
    ``baseline_s`` apart, where the speed over that baseline is at least ``min_speed``.

    Parameters
    ----------
    gnss : GnssData
        The fixes.
    min_speed : float
        Slowest speed whose displacement defines a course, m/s (a fix's noise over a short baseline does not).
    baseline_s : float
        Time between the two fixes of a course, s.

    Returns
    -------
    t : numpy.ndarray, shape (K,)
        Midpoint times of the courses, s.
    course : numpy.ndarray, shape (K,)
        Course, rad, unwrapped (continuous over the drive).
    """
    ne = lla_to_ned(gnss.lla, gnss.lla[0])[:, :2]
    j = np.searchsorted(gnss.t, gnss.t + baseline_s)
    ok = j < gnss.n
    i = np.flatnonzero(ok)
    j = j[ok]
    d = ne[j] - ne[i]
    dt = gnss.t[j] - gnss.t[i]
    fast = np.hypot(d[:, 0], d[:, 1]) >= min_speed * dt
    i, j, d = i[fast], j[fast], d[fast]
    return 0.5 * (gnss.t[i] + gnss.t[j]), np.unwrap(np.arctan2(d[:, 1], d[:, 0]))


def gyro_bias_in_motion(imu: ImuData, gnss: GnssData, *, tilt_change_std: float = math.radians(3.0),
                        course_std: float = math.radians(1.0), min_span_s: float = 20.0) -> tuple[Array, Array]:
    """The gyro bias of a vehicle that never stands still, from its mean rate and its course change.

    Over a span ``[t_a, t_b]`` the mean body rate is the bias plus the attitude's mean rate of change: a road
    vehicle's roll and pitch end about where they began, and its heading changes as its course (side slip is
    small), so with ``d_b`` the down direction in IMU axes (the mean specific force)::

        b ≈ mean(ω̃) − d_b (ψ_b − ψ_a) / (t_b − t_a)

    (Earth and transport rates, 1e-4 rad/s, are left in the bias).  σ per axis: the roll and pitch change
    ``tilt_change_std`` and the two courses' error ``√2 course_std`` over the span.

    Parameters
    ----------
    imu : ImuData
        The IMU as recorded.
    gnss : GnssData
        The fixes (the course from their displacement, :func:`gnss_course`).
    tilt_change_std : float
        σ of the vehicle's roll and pitch change between the span's ends, rad.
    course_std : float
        σ of a course at the span's ends (fix noise over the baseline, side slip), rad.
    min_span_s : float
        Shortest span between the first and the last course, s.

    Returns
    -------
    bias : numpy.ndarray, shape (3,)
        Gyro bias, IMU axes, rad/s.
    std : numpy.ndarray, shape (3,)
        Its σ, rad/s.

    Raises
    ------
    InsufficientDataError
        If the courses span less than ``min_span_s``.
    """
    tc, course = gnss_course(gnss)
    inside = (tc >= imu.t[0]) & (tc <= imu.t[-1])
    tc, course = tc[inside], course[inside]
    if tc.size < 2 or tc[-1] - tc[0] < min_span_s:
        raise InsufficientDataError(f"gyro_bias_in_motion: the GNSS course spans {0 if tc.size < 2 else tc[-1] - tc[0]:.1f} "
                                    f"s of the IMU; it needs {min_span_s:g} s of driving above 3 m/s")
    a, b = int(np.searchsorted(imu.t, tc[0])), int(np.searchsorted(imu.t, tc[-1]))
    span = float(imu.t[b] - imu.t[a])
    f = imu.accel[a:b].mean(axis=0)
    d_b = -f / np.linalg.norm(f)
    rate = (course[-1] - course[0]) / (tc[-1] - tc[0])
    dt = np.diff(imu.t[a:b + 1])
    mean_w = (imu.gyro[a:b] * dt[:, None]).sum(axis=0) / dt.sum()
    sd = math.hypot(tilt_change_std, math.sqrt(2.0) * course_std) / span
    return mean_w - d_b * rate, np.full(3, sd)


def fine_alignment(imu: ImuData | ImuIncrements, lla: Any, coarse: Alignment, config: GinsConfig, *,
                   pos_std: float = 1.0, heading_std: float | None = None) -> Alignment:
    """Fine alignment over a static period: the GNSS/INS filter with ZUPT, ZARU and the known position.

    The filter starts from the coarse attitude and runs over the whole static period with zero-velocity and
    zero-angular-rate updates (the gyros measure ``C_b^n ᵀ ω_ie^n`` plus their bias: gyrocompassing inside the
    filter) and 1 Hz fixes of the known position.  Levelling and gyrocompassing used the same samples, so the
    coarse attitude is not information independent of the biases: the filter starts from a diffuse attitude
    (level σ 1°, heading σ 5°, or ``heading_std`` for a given heading) and its covariance then holds the
    limits of a static alignment, ``δθ_level ≈ b_a / g`` and ``δψ ≈ ε_E / (Ω cos φ)`` (Groves 2013, §5.6.3,
    §14.2.2), instead of counting the data twice.

    Parameters
    ----------
    imu : ImuData or ImuIncrements
        The static period (the one given to :func:`static_alignment`).
    lla : array_like, shape (3,)
        Known position: lat rad, lon rad, ellipsoidal height m.
    coarse : Alignment
        The result of :func:`static_alignment` on the same period.
    config : GinsConfig
        The filter's IMU model; over the static period the biases and scale factors are random constants of
        its initial σ (``corr_time = inf``), ``zaru_noise_std`` is zero (the ZARU's variance is the gyro white noise
        of the mean rate over each covariance step, ``ARW² / Δt``: a stand without vibration), the lever arm zero
        and the initial attitude σ as said above.
    pos_std : float
        σ of the known position, m (> 0).
    heading_std : float, optional
        σ of the heading given to :func:`static_alignment` (``yaw=``), rad (> 0); required then.  When the
        gyros can gyrocompass, the filter refines that heading.

    Returns
    -------
    Alignment
        At the last sample: ``q_nb``, the filter's ``att_std`` (φ N/E/D, rad) and ``heading_std`` (its D
        component), the estimated ``imu_errors``; ``lla`` and ``vel_ned`` None (the known position, at rest).
        Its σ are marginals: the heading error and the east gyro bias stay correlated (``δψ ≈ ε_E / (Ω cos L)``),
        which a restart from ``att_std`` and the configuration's bias σ does not carry.

    Raises
    ------
    InvalidInputError
        If ``imu`` is not rates or increments, ``coarse`` was made in motion, ``pos_std`` / ``heading_std`` are
        not > 0, or a given heading has no ``heading_std``.
    InsufficientDataError
        If the static period is shorter than 2 s.
    ShapeError
        If ``lla`` is not a finite 3-vector.
    """
    if not isinstance(imu, (ImuData, ImuIncrements)):
        raise InvalidInputError(f"fine_alignment needs the static period as ImuData or ImuIncrements; got "
                                f"{type(imu).__name__}")
    if imu.t[-1] - imu.t[0] < 2.0:
        raise InsufficientDataError("fine_alignment needs a static period of at least 2 s")
    if coarse.lla is not None:
        raise InvalidInputError("fine_alignment refines a static alignment (static_alignment); this one was made "
                                "in motion")
    p = np.asarray(lla, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ShapeError(f"lla must be a finite 3-vector (lat rad, lon rad, h m); got {lla!r}")
    if not (pos_std > 0 and math.isfinite(pos_std)):
        raise InvalidInputError(f"pos_std must be > 0 m; got {pos_std!r}")
    if coarse.heading_given and heading_std is None:
        raise InvalidInputError("the coarse heading was given (yaw=): give heading_std, its sigma in rad")
    if heading_std is not None and not (heading_std > 0 and math.isfinite(heading_std)):
        raise InvalidInputError(f"heading_std must be > 0 rad; got {heading_std!r}")
    # over the static period the biases are random constants (Groves 2013, §14.2.2): a Gauss-Markov state whose
    # initial sigma (the turn-on bias) exceeds its stationary sigma would lose variance as exp(-2t/T) while the
    # turn-on bias stays, and the filter would claim a level and heading better than the data hold
    cfg = replace(config, corr_time=math.inf, scale_corr_time=math.inf, lever_arm=np.zeros(3),
                  use_gnss_velocity=False, zaru_noise_std=0.0,
                  init_att_std=np.radians([1.0, 1.0, 5.0]) if heading_std is None
                  else np.array([math.radians(1.0), math.radians(1.0), heading_std]))
    tg = imu.t[0] + np.arange(1.0, math.floor(imu.t[-1] - imu.t[0]) + 1.0)
    fixes = GnssData(tg, np.tile(p, (tg.size, 1)), np.full((tg.size, 3), float(pos_std)),
                     meta={"source": "fine alignment: the known position"})
    res = GinsFilter(cfg).run(imu, fixes, lla0=p, vel0=np.zeros(3), q0=coarse.q_nb,
                              static=np.ones(imu.t.size, dtype=bool))
    att_std = np.sqrt(np.diag(res.cov_nav[-1][6:9, 6:9]))
    err = np.concatenate([res.gyro_bias[-1], res.accel_bias[-1], res.gyro_scale[-1], res.accel_scale[-1]])
    return Alignment(float(imu.t[-1]), res.q_nb[-1].copy(), float(att_std[2]), coarse.method + " + fine (Kalman filter)",
                     None, None, att_std, err, coarse.heading_given)
