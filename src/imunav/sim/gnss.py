"""GNSS receiver simulator: position and velocity fixes from a truth trajectory.

Fix ``k`` with time stamp ``t_k`` describes the antenna at ``t_k − latency``
(the receiver's solution arrives and is stamped late; a filter that does not
know the latency sees a time error):

    p_k = p_ant(t_k − latency) + b_k + w_k,      b: Gauss–Markov (σ_c, T), w: white (σ_w),
    v_k = v_ant(t_k − latency) + u_k,            u: white (σ_v),

per north/east/down axis, with the antenna at the body lever arm ``l``:
``p_ant = p + C_nb l`` and ``v_ant = v + C_nb (ω_eb^b × l)`` (Groves 2013 eqs.
14.121-14.122 in NED).  The truth between its samples is interpolated by cubic
Hermite polynomials (position from velocity, velocity from acceleration) and
attitude by slerp.  Epochs are dropped at random (``dropout_prob``) and inside
scheduled outages; the fixes report ``σ = √(σ_w² + σ_c²)`` per axis.  Every
removal is recorded in ``meta``.  Seeded with ``rng``: the same seed gives the
same fixes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import earth
from imunav.errors import InvalidInputError, ShapeError
from imunav.io.aiding import MagnetometerData
from imunav.io.gnss import GnssData
from imunav.io.gnss_heading import DualAntennaData
from imunav.rotation import dcm_from_quat, quat_interp
from imunav.sim.trajectory import Trajectory
from imunav.sim.vehicle import _decimate, gauss_markov_sequence, omega_eb_b

__all__ = ["MagnetometerData", "simulate_dual_antenna", "simulate_gnss", "simulate_magnetometer", "outage_schedule",
           "truth_at"]

Array = NDArray[np.float64]


def _hermite(t: Array, x: Array, xd: Array, tq: Array) -> Array:
    """Cubic Hermite interpolation of rows of ``x`` (with derivative ``xd``) at ``tq``."""
    i = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 2)
    h = (t[i + 1] - t[i])[:, None]
    s = ((tq - t[i]) / (t[i + 1] - t[i]))[:, None]
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    return h00 * x[i] + h10 * h * xd[i] + h01 * x[i + 1] + h11 * h * xd[i + 1]


def truth_at(truth: Trajectory, tq: ArrayLike, lever_arm: ArrayLike = (0.0, 0.0, 0.0)) -> tuple[Array, Array]:
    """Geodetic position (lat rad, lon rad, h m) and NED velocity (m/s) of the point at body ``lever_arm``
    at times ``tq`` inside the truth's span (interpolated, see the module docstring).

    Parameters
    ----------
    truth : Trajectory
        With ``pos_lla`` (lat rad, lon rad, h m), ``vel_ned`` (m/s) and ``q_nb`` (body FRD -> NED).
    tq : array_like, shape (M,)
        Times, s, within ``truth.t[0] .. truth.t[-1]``.
    lever_arm : array_like, shape (3,)
        Offset of the point from the IMU, body FRD, m.

    Returns
    -------
    lla : numpy.ndarray, shape (M, 3)
        Geodetic position of the point (lat rad, lon rad, ellipsoidal height m).
    vel : numpy.ndarray, shape (M, 3)
        Its velocity, NED, m/s (``v + C_nb (ω_eb^b × l)``).

    Raises
    ------
    InvalidInputError
        If ``truth`` has no ``pos_lla`` or ``vel_ned``, or a time of ``tq`` is outside its span.
    ShapeError
        If ``lever_arm`` is not a finite 3-vector.
    """
    if truth.pos_lla is None or truth.vel_ned is None:
        raise InvalidInputError("the truth trajectory needs pos_lla and vel_ned (use imunav.sim.vehicle_trajectory)")
    tq = np.atleast_1d(np.asarray(tq, dtype=float))
    if tq.size and (tq.min() < truth.t[0] - 1e-9 or tq.max() > truth.t[-1] + 1e-9):
        raise InvalidInputError(f"times {tq.min():.3f}..{tq.max():.3f} s are outside the truth span "
                                f"{truth.t[0]:.3f}..{truth.t[-1]:.3f} s")
    la = np.asarray(lever_arm, dtype=float)
    if la.shape != (3,) or not np.all(np.isfinite(la)):
        raise ShapeError(f"lever_arm must be a finite 3-vector (body FRD, m); got {lever_arm!r}")
    lla0 = truth.pos_lla[0]
    ned = earth.lla_to_ned(truth.pos_lla, lla0)
    # d(ned)/dt of the tangent-plane coordinates = C_n0^n-ish rotation of v^n; differentiate the samples
    # exactly enough by expressing v^n in the tangent frame at the origin
    C_e0 = earth.dcm_en(lla0[0], lla0[1])
    C_ek = earth.dcm_en(truth.pos_lla[:, 0], truth.pos_lla[:, 1])
    v0 = np.einsum("ij,njk,nk->ni", C_e0.T, C_ek, truth.vel_ned)
    acc = truth.accel_ned if truth.accel_ned is not None else np.gradient(truth.vel_ned, truth.t, axis=0)
    vq = _hermite(truth.t, truth.vel_ned, acc, tq)
    nq = _hermite(truth.t, ned, v0, tq)
    lla = earth.ned_to_lla(nq, lla0)
    if np.any(la != 0):
        q = quat_interp(truth.t, truth.q_nb, tq)
        C = dcm_from_quat(q)
        w = omega_eb_b(truth)
        wq = np.stack([np.interp(tq, truth.t, w[:, j]) for j in range(3)], axis=1)
        d_n = np.einsum("nij,j->ni", C, la)
        lla = lla + earth.ned_to_dlla(d_n, lla)
        vq = vq + np.einsum("nij,nj->ni", C, np.cross(wq, la))
    return lla, vq


def outage_schedule(t_start: float, t_end: float, *, every_s: float = 180.0, length_s: float = 60.0,
                    first_s: float = 0.0) -> list[tuple[float, float]]:
    """Outages ``(start, length)`` of ``length_s`` every ``every_s`` from ``t_start + first_s`` while they
    end before ``t_end`` (the KF-GINS protocol: 60 s every 180 s, first at 0, 60 or 120 s after convergence).

    Parameters
    ----------
    t_start, t_end : float
        Span of the data, s.
    every_s : float
        Period of the outages, s (> ``length_s``).
    length_s : float
        Length of each outage, s (> 0).
    first_s : float
        Start of the first outage after ``t_start``, s.

    Returns
    -------
    list of tuple of float
        ``(start s, length s)`` of each outage, in time order (empty when none fits).

    Raises
    ------
    InvalidInputError
        Unless ``every_s > length_s > 0``.
    """
    if not (every_s > length_s > 0):
        raise InvalidInputError(f"need every_s > length_s > 0; got every_s={every_s}, length_s={length_s}")
    out = []
    s = t_start + first_s
    while s + length_s <= t_end:
        out.append((float(s), float(length_s)))
        s += every_s
    return out


def simulate_gnss(
    truth: Trajectory,
    *,
    rate_hz: float = 1.0,
    pos_noise: ArrayLike = (0.5, 0.5, 1.0),
    pos_corr_sigma: ArrayLike = (0.0, 0.0, 0.0),
    pos_corr_tau: float = 300.0,
    vel_noise: ArrayLike | None = (0.05, 0.05, 0.1),
    latency_s: float = 0.0,
    lever_arm: ArrayLike = (0.0, 0.0, 0.0),
    dropout_prob: float = 0.0,
    outages: Sequence[tuple[float, float]] = (),
    t_offset: float = 0.0,
    rng: Any = None,
) -> GnssData:
    """Simulated GNSS fixes of the antenna on a truth trajectory.

    Parameters
    ----------
    truth : Trajectory
        With ``pos_lla`` and ``vel_ned`` (e.g. :func:`imunav.sim.vehicle.vehicle_trajectory`).
    rate_hz : float
        Fix rate, Hz, at most the truth rate; stamps ``truth.t[0] + latency_s + (t_offset mod 1/rate_hz)
        + k / rate_hz``.
    pos_noise : array_like, shape (3,)
        White position noise σ_w north/east/down, m (> 0).
    pos_corr_sigma, pos_corr_tau : array_like, shape (3,), and float
        σ_c (m, >= 0) and correlation time T (s) of the Gauss–Markov position error (multipath,
        atmosphere).
    vel_noise : array_like, shape (3,), or None
        White velocity noise σ_v north/east/down, m/s (> 0), or None for position-only fixes.
    latency_s : float
        Age of each fix at its time stamp, s (>= 0).
    lever_arm : array_like, shape (3,)
        Antenna from the IMU, body FRD, m.
    dropout_prob : float
        Probability that an epoch is missing, independently (0 <= p < 1).
    outages : sequence of (float, float)
        ``(start s, length s)`` pairs with no fix (see :func:`outage_schedule`).
    t_offset : float
        Offset of the stamps from the grid, s (fixes between IMU samples).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    GnssData
        ``meta`` holds the settings, the outages and the epochs removed (``meta["removed"]``).

    Raises
    ------
    InvalidInputError
        If a noise σ, ``rate_hz``, ``latency_s``, ``dropout_prob`` or an outage length is out of range,
        or the truth is shorter than one fix interval after the latency.
    """
    g = np.random.default_rng(rng)
    pw = np.asarray(pos_noise, dtype=float) * np.ones(3)
    pc = np.asarray(pos_corr_sigma, dtype=float) * np.ones(3)
    if np.any(pw <= 0) or np.any(pc < 0):
        raise InvalidInputError(f"pos_noise must be > 0 and pos_corr_sigma >= 0 (m); got {pos_noise!r}, {pos_corr_sigma!r}")
    if not (math.isfinite(rate_hz) and 0 < rate_hz <= truth.fs):
        raise InvalidInputError(f"rate_hz must be in (0, {truth.fs:g}] Hz; got {rate_hz!r}")
    if not (math.isfinite(latency_s) and latency_s >= 0):
        raise InvalidInputError(f"latency_s must be >= 0 s; got {latency_s!r}")
    if not (0.0 <= dropout_prob < 1.0):
        raise InvalidInputError(f"dropout_prob must be in [0, 1); got {dropout_prob!r}")
    t0 = truth.t[0] + latency_s + (float(t_offset) % (1.0 / rate_hz))
    n = int(math.floor((truth.t[-1] - t0) * rate_hz + 1e-9)) + 1
    if n < 1:
        raise InvalidInputError("the truth is shorter than one GNSS interval after the latency")
    t = t0 + np.arange(n) / rate_hz
    lla, vel = truth_at(truth, t - latency_s, lever_arm)
    err = pw * g.standard_normal((n, 3))
    if np.any(pc > 0):
        err += gauss_markov_sequence(t, pc, float(pos_corr_tau), g)
    lla = lla + earth.ned_to_dlla(err, lla)
    vstd = None
    if vel_noise is not None:
        vstd = np.asarray(vel_noise, dtype=float) * np.ones(3)
        if np.any(vstd <= 0):
            raise InvalidInputError(f"vel_noise must be > 0 m/s (or None); got {vel_noise!r}")
        vel = vel + vstd * g.standard_normal((n, 3))
    keep_drop = g.random(n) >= dropout_prob
    in_outage = np.zeros(n, dtype=bool)
    for s, d in outages:
        if not (d > 0):
            raise InvalidInputError(f"an outage length must be > 0 s; got {d!r}")
        in_outage |= (t >= s) & (t < s + d)
    meta = {
        "source": "imunav.sim.simulate_gnss",
        "rate_hz": float(rate_hz), "pos_noise": pw.tolist(), "pos_corr_sigma": pc.tolist(),
        "pos_corr_tau": float(pos_corr_tau), "vel_noise": None if vstd is None else vstd.tolist(),
        "latency_s": float(latency_s), "lever_arm": np.asarray(lever_arm, dtype=float).tolist(),
        "dropout_prob": float(dropout_prob), "outages": [[float(s), float(d)] for s, d in outages],
    }
    full = GnssData(t, lla, np.sqrt(pw**2 + pc**2), None if vstd is None else vel, vstd, meta)
    return full.select(keep_drop, "random dropout").select(~in_outage[keep_drop], "scheduled outage")


def simulate_magnetometer(truth: Trajectory, *, declination: float = 0.0, inclination: float = math.radians(45.0),
                          strength: float = 50.0, noise_std: float = 0.2, rate_hz: float | None = 10.0,
                          rng: Any = None) -> MagnetometerData:
    """A calibrated magnetometer on the truth: ``m^b = C_nbᵀ mⁿ + w`` with a uniform Earth field
    ``mⁿ = B (cos I cos D, cos I sin D, sin I)`` and white noise (σ ``noise_std`` per axis).

    The heading noise is then about ``noise_std / (B cos I)`` rad (0.2 / 35.4 µT: 0.32°).

    Parameters
    ----------
    truth : Trajectory
        With ``q_nb`` (e.g. :func:`imunav.sim.vehicle.vehicle_trajectory`).
    declination, inclination : float
        Declination D (east positive) and inclination I (down positive) of the field, rad (|I| < pi/2).
    strength : float
        Field strength B, µT (> 0).
    noise_std : float
        White noise σ per axis, µT (>= 0).
    rate_hz : float, optional
        Output rate, Hz, at most the truth rate (None: every truth sample).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    MagnetometerData
        The samples; ``meta`` holds the field and the noise.

    Raises
    ------
    InvalidInputError
        If the inclination is not inside (-pi/2, pi/2), the strength is not > 0, the noise is negative or the
        rate is out of range.
    """
    if not (math.isfinite(inclination) and abs(inclination) < math.pi / 2):
        raise InvalidInputError(f"inclination must be in (-pi/2, pi/2) rad; got {inclination!r}")
    if not (math.isfinite(strength) and strength > 0):
        raise InvalidInputError(f"strength must be > 0 (uT); got {strength!r}")
    if not (math.isfinite(noise_std) and noise_std >= 0):
        raise InvalidInputError(f"noise_std must be >= 0 (uT); got {noise_std!r}")
    g = np.random.default_rng(rng)
    idx = _decimate(truth, rate_hz)
    mn = strength * np.array([math.cos(inclination) * math.cos(declination),
                              math.cos(inclination) * math.sin(declination), math.sin(inclination)])
    mb = np.einsum("nji,j->ni", dcm_from_quat(truth.q_nb[idx]), mn) + noise_std * g.standard_normal((idx.size, 3))
    return MagnetometerData(truth.t[idx].copy(), mb, {"field_ned": mn.tolist(), "noise_std": noise_std,
                                                       "declination": declination, "inclination": inclination})


def simulate_dual_antenna(truth: Trajectory, baseline: ArrayLike, *, heading_std: float = math.radians(0.3),
                          pitch_std: float = math.radians(0.8), rate_hz: float | None = 5.0,
                          rng: Any = None) -> DualAntennaData:
    """A dual-antenna (moving-base) GNSS receiver on the truth: azimuth and elevation of the baseline
    ``bⁿ = C_nb b`` with white noise.

    ``ψ = atan2(b_E, b_N) + w_ψ``, ``θ = atan2(−b_D, √(b_N² + b_E²)) + w_θ`` (the heading σ of a real pair is
    about its carrier-phase noise over the baseline length: 0.3° for 1 m is typical of RTK receivers).

    Parameters
    ----------
    truth : Trajectory
        With ``q_nb`` (e.g. :func:`imunav.sim.vehicle.vehicle_trajectory`).
    baseline : array_like, shape (3,)
        Secondary antenna from the primary, body FRD, m (at least 1 cm).
    heading_std, pitch_std : float
        White noise σ, rad (> 0).
    rate_hz : float, optional
        Output rate, Hz, at most the truth rate (None: every truth sample); the first truth sample is left out.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    DualAntennaData
        The epochs; ``meta`` holds the baseline and the noise.

    Raises
    ------
    InvalidInputError
        If the baseline is shorter than 1 cm or vertical, a σ is not > 0 or the rate is out of range.
    """
    b = np.asarray(baseline, dtype=float)
    if b.shape != (3,) or not np.all(np.isfinite(b)) or np.linalg.norm(b) < 0.01:
        raise InvalidInputError(f"baseline must be a finite 3-vector of at least 1 cm, body FRD m; got {baseline!r}")
    for name, v in (("heading_std", heading_std), ("pitch_std", pitch_std)):
        if not (math.isfinite(v) and v > 0):
            raise InvalidInputError(f"{name} must be > 0 rad; got {v!r}")
    g = np.random.default_rng(rng)
    idx = _decimate(truth, rate_hz)[1:]
    bn = np.einsum("kij,j->ki", dcm_from_quat(truth.q_nb[idx]), b)
    h = np.hypot(bn[:, 0], bn[:, 1])
    if np.any(h < 1e-3 * np.linalg.norm(b)):
        raise InvalidInputError("the baseline is vertical along the trajectory: its heading is undefined")
    heading = np.arctan2(bn[:, 1], bn[:, 0]) + heading_std * g.standard_normal(idx.size)
    pitch = np.arctan2(-bn[:, 2], h) + pitch_std * g.standard_normal(idx.size)
    return DualAntennaData(truth.t[idx].copy(), (heading + np.pi) % (2 * np.pi) - np.pi, pitch, heading_std,
                           pitch_std, {"baseline": b.tolist(), "heading_std": heading_std, "pitch_std": pitch_std})

