"""A simulated quadrotor flight written as a PX4 ULog, with its truth: the PX4 side of the log tests.

:func:`quadrotor_flight` takes off, climbs to 20 m, flies circles of 30 m radius at 6 m/s, slows down,
lands and rests; its attitude is a multirotor's: the body z axis (down) opposes the specific force
``a − g`` (the thrust) and the nose points along the track.  :func:`simulate_quad_log` records what
PX4 would (consumer IMU at 250 Hz, GNSS at 5 Hz stamped 0.1 s late, magnetometer at 50 Hz, barometer
at 25 Hz) and :func:`write_quad_ulog` writes PX4's topics (``sensor_combined``,
``vehicle_gps_position`` with PX4's integer units, ``vehicle_magnetometer``, ``vehicle_air_data``,
and the simulator's ``*_groundtruth`` topics) with :func:`imunav.io.ulog.write_ulog`, in PX4's float32.

Clocks: the log's clock is PX4 boot time (µs); t = 0 of the truth is ``boot0_us`` on it, and the
receiver's ``time_utc_usec`` gives the UTC of every fix (``t0_ns`` + t).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav import earth
from imunav.atmosphere import isa
from imunav.io.aiding import BaroData, MagnetometerData
from imunav.io.gnss import GnssData
from imunav.io.ulog import write_ulog
from imunav.rotation import quat_from_dcm
from imunav.sim import presets
from imunav.sim.error_model import simulate_imu
from imunav.sim.gnss import simulate_gnss, simulate_magnetometer
from imunav.sim.trajectory import Trajectory, trajectory_from_functions
from imunav.sim.vehicle import simulate_baro
from imunav.timeseries import ImuData
from imunav.units import DEFAULT_GRAVITY, DEG

__all__ = ["QuadTruth", "QuadLog", "quadrotor_flight", "simulate_quad_log", "write_quad_ulog", "QUAD_T0_NS"]

Array = NDArray[np.float64]

#: 2024-05-14T10:00:00Z, ns since 1970: the UTC of the first IMU sample.
QUAD_T0_NS = 1_715_680_800 * 1_000_000_000
_G = DEFAULT_GRAVITY


def _ramp(x: Array) -> tuple[Array, Array, Array, Array]:
    """Quintic smooth step on [0, 1] (clipped): its integral, value, first and second derivative in x."""
    c = np.clip(x, 0.0, 1.0)
    integral = np.where(x > 1.0, 0.5 + (x - 1.0), 2.5 * c**4 - 3 * c**5 + c**6)
    return integral, 10 * c**3 - 15 * c**4 + 6 * c**5, 30 * c**2 * (1 - c) ** 2, 60 * c * (1 - c) * (1 - 2 * c)


@dataclass(frozen=True)
class _Plan:
    radius: float
    speed: float
    height: float
    duration: float
    ramp_s: float = 8.0

    def times(self) -> tuple[float, float, float, float]:
        d = self.duration
        return 8.0, 18.0, d - 40.0, d - 28.0  # climb, accelerate, decelerate, descend starts

    def track(self, t: Array) -> tuple[Array, Array, Array]:
        """Distance along the circle, speed and along-track acceleration."""
        _, acc0, dec0, _ = self.times()
        T, V = self.ramp_s, self.speed
        i1, r1, d1, _ = _ramp((t - acc0) / T)
        i2, r2, d2, _ = _ramp((t - dec0) / T)
        return V * T * (i1 - i2), V * (r1 - r2), V / T * (d1 - d2)

    def height_of(self, t: Array) -> tuple[Array, Array]:
        climb, _, _, down = self.times()
        T, H = self.ramp_s, self.height
        _, r1, _, e1 = _ramp((t - climb) / T)
        _, r2, _, e2 = _ramp((t - down) / T)
        return H * (r1 - r2), H / T**2 * (e1 - e2)

    def position(self, t: Array) -> Array:
        s, _, _ = self.track(t)
        th = s / self.radius
        h, _ = self.height_of(t)
        return np.column_stack([self.radius * np.sin(th), self.radius * (1 - np.cos(th)), -h])

    def attitude(self, t: Array) -> Array:
        s, v, a = self.track(t)
        th = s / self.radius
        _, hdd = self.height_of(t)
        acc = np.column_stack([a * np.cos(th) - v**2 / self.radius * np.sin(th),
                               a * np.sin(th) + v**2 / self.radius * np.cos(th), -hdd])
        f = acc - np.array([0.0, 0.0, _G])  # specific force; the thrust axis is -z_body
        zb = -f / np.linalg.norm(f, axis=1, keepdims=True)
        xc = np.column_stack([np.cos(th), np.sin(th), np.zeros_like(th)])  # nose along the track
        yb = np.cross(zb, xc)
        yb /= np.linalg.norm(yb, axis=1, keepdims=True)
        xb = np.cross(yb, zb)
        return quat_from_dcm(np.stack([xb, yb, zb], axis=2))


def quadrotor_flight(*, duration_s: float = 150.0, radius_m: float = 30.0, speed: float = 6.0, height_m: float = 20.0,
                     fs: float = 250.0, origin_lla: tuple[float, float, float] = (47.3977 * DEG, 8.5456 * DEG, 535.0)
                     ) -> Trajectory:
    """The quadrotor's truth (module docstring): 8 s on the ground, climb, circles, slow down, land, rest.

    Parameters
    ----------
    duration_s : float
        Length of the flight, s (>= 80: climb, accelerate, decelerate and descend take 8 s each).
    radius_m, speed, height_m : float
        Circle radius (m), cruise speed (m/s) and flight height above the take-off point (m).
    fs : float
        Sample rate, Hz.
    origin_lla : tuple of float
        Take-off point (lat rad, lon rad, ellipsoidal height m).

    Returns
    -------
    Trajectory
        Position, velocity, attitude, body rate and acceleration at ``fs``.
    """
    plan = _Plan(float(radius_m), float(speed), float(height_m), float(duration_s))
    return trajectory_from_functions(plan.attitude, plan.position, duration_s=duration_s, fs=fs,
                                     origin_lla=origin_lla)


@dataclass(frozen=True)
class QuadTruth:
    """What the quadrotor's log does not say.

    Attributes
    ----------
    trajectory : Trajectory
        The body frame (FRD, the IMU's), t = 0 at the first IMU sample.
    boot0_us : int
        t = 0 on the log's clock (PX4 boot time), µs.
    t0_ns : int
        UTC of t = 0, ns since 1970.
    gnss_latency_s : float
        A fix stamped t holds the antenna at t − latency.
    geoid_height_m : float
        Ellipsoidal minus mean-sea-level height written in the GNSS ``alt``, m.
    meta : dict
        Seed, IMU model, noise levels.
    """

    trajectory: Trajectory
    boot0_us: int
    t0_ns: int
    gnss_latency_s: float
    geoid_height_m: float
    meta: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class QuadLog:
    """The quadrotor's recorded streams (on the truth's time axis, float64) and the truth.

    Attributes
    ----------
    imu : ImuData
        Body FRD.
    gnss : GnssData
        Fixes with NED velocity.
    mag : MagnetometerData
        µT, body FRD.
    baro : BaroData
        Barometric height (the ISA altitude of the pressure written).
    truth : QuadTruth
        What the log does not say.
    """

    imu: ImuData
    gnss: GnssData
    mag: MagnetometerData
    baro: BaroData
    truth: QuadTruth


def simulate_quad_log(seed: int = 0, *, duration_s: float = 150.0, gnss_latency_s: float = 0.1,
                      boot0_us: int = 5_000_000, t0_ns: int = QUAD_T0_NS, geoid_height_m: float = 47.0) -> QuadLog:
    """The quadrotor scenario (module docstring), seeded.

    Parameters
    ----------
    seed : int
        Seed of every random draw.
    duration_s : float
        Length of the flight, s.
    gnss_latency_s : float
        Age of each fix at its stamp, s.
    boot0_us : int
        t = 0 on the log's boot clock, µs.
    t0_ns : int
        UTC of t = 0, ns since 1970.
    geoid_height_m : float
        Ellipsoidal − mean-sea-level height, m (PX4 logs both).

    Returns
    -------
    QuadLog
        The streams and the truth.
    """
    rng = np.random.default_rng(seed)
    seeds = [int(s) for s in rng.integers(0, 2**63 - 1, size=4)]
    tr = quadrotor_flight(duration_s=duration_s)
    imu = simulate_imu(tr, presets.get("consumer_mems"), rng=seeds[0])
    assert isinstance(imu, ImuData)
    gnss = simulate_gnss(tr, rate_hz=5.0, pos_noise=(0.4, 0.4, 0.7), vel_noise=(0.08, 0.08, 0.12),
                         latency_s=gnss_latency_s, rng=seeds[1])
    mag = simulate_magnetometer(tr, declination=3.0 * DEG, inclination=64.0 * DEG, strength=48.0, noise_std=0.3,
                                rate_hz=50.0, rng=seeds[2])
    baro = simulate_baro(tr, noise_std=0.3, bias_std=1.0, bias_tau=300.0, rate_hz=25.0, rng=seeds[3])
    truth = QuadTruth(tr, int(boot0_us), int(t0_ns), float(gnss_latency_s), float(geoid_height_m),
                      {"seed": int(seed), "imu_model": "consumer_mems", "imu_rate_hz": 250.0})
    return QuadLog(imu, gnss, mag, baro, truth)


def write_quad_ulog(log: QuadLog, path: str | os.PathLike[str]) -> Path:
    """Write the quadrotor's log as a PX4 ULog (topics and units in the module docstring).

    ``vehicle_magnetometer`` and ``vehicle_air_data`` are published 2 ms after their ``timestamp_sample``
    (the readers must use the sample time); the baro pressure is the ISA pressure of the simulated height.

    Parameters
    ----------
    log : QuadLog
        From :func:`simulate_quad_log`.
    path : str or os.PathLike
        The ``.ulg`` to write (never an existing file).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    b0 = log.truth.boot0_us
    f32 = np.float32

    def us(t: Array) -> NDArray[np.uint64]:
        return (b0 + np.round(np.asarray(t) * 1e6)).astype(np.uint64)

    n = log.imu.n
    g = log.gnss
    lat, lon = np.degrees(g.lla[:, 0]), np.degrees(g.lla[:, 1])
    assert g.vel_ned is not None and g.vel_std is not None
    utc_us = ((log.truth.t0_ns // 1000) + np.round(g.t * 1e6)).astype(np.uint64)
    tr = log.truth.trajectory
    assert tr.pos_lla is not None and tr.vel_ned is not None
    gt = slice(0, tr.n, 25)  # ground truth at 10 Hz
    local = earth.dlla_to_ned(tr.pos_lla[gt] - tr.pos_lla[0], tr.pos_lla[gt])  # from the take-off point
    p = isa(log.baro.height).pressure
    topics = {
        "sensor_combined": {
            "timestamp": us(log.imu.t), "gyro_rad": log.imu.gyro.astype(f32),
            "gyro_integral_dt": np.full(n, 4000, np.uint32), "accelerometer_timestamp_relative": np.zeros(n, np.int32),
            "accelerometer_m_s2": log.imu.accel.astype(f32), "accelerometer_integral_dt": np.full(n, 4000, np.uint32)},
        "vehicle_gps_position": {
            "timestamp": us(g.t), "time_utc_usec": utc_us,
            "lat": np.round(lat * 1e7).astype(np.int32), "lon": np.round(lon * 1e7).astype(np.int32),
            "alt": np.round((g.lla[:, 2] - log.truth.geoid_height_m) * 1e3).astype(np.int32),
            "alt_ellipsoid": np.round(g.lla[:, 2] * 1e3).astype(np.int32),
            "s_variance_m_s": g.vel_std[:, 0].astype(f32), "eph": g.pos_std[:, 0].astype(f32),
            "epv": g.pos_std[:, 2].astype(f32), "vel_m_s": np.linalg.norm(g.vel_ned[:, :2], axis=1).astype(f32),
            "vel_n_m_s": g.vel_ned[:, 0].astype(f32), "vel_e_m_s": g.vel_ned[:, 1].astype(f32),
            "vel_d_m_s": g.vel_ned[:, 2].astype(f32), "fix_type": np.full(g.n, 3, np.uint8),
            "vel_ned_valid": np.ones(g.n, np.bool_), "satellites_used": np.full(g.n, 14, np.uint8)},
        "vehicle_magnetometer": {
            "timestamp": us(log.mag.t) + np.uint64(2000), "timestamp_sample": us(log.mag.t),
            "magnetometer_ga": (log.mag.field_b / 100.0).astype(f32)},
        "vehicle_air_data": {
            "timestamp": us(log.baro.t) + np.uint64(2000), "timestamp_sample": us(log.baro.t),
            "baro_alt_meter": log.baro.height.astype(f32), "baro_temp_celcius": np.full(log.baro.t.size, 25.0, f32),
            "baro_pressure_pa": p.astype(f32), "rho": (p / (287.05 * 298.15)).astype(f32)},
        "vehicle_global_position_groundtruth": {
            "timestamp": us(tr.t[gt]), "timestamp_sample": np.zeros(local.shape[0], np.uint64),
            "lat": np.degrees(tr.pos_lla[gt, 0]), "lon": np.degrees(tr.pos_lla[gt, 1]),
            "alt": (tr.pos_lla[gt, 2] - log.truth.geoid_height_m).astype(f32),
            "alt_ellipsoid": tr.pos_lla[gt, 2].astype(f32)},
        "vehicle_local_position_groundtruth": {
            "timestamp": us(tr.t[gt]), "x": local[:, 0].astype(f32), "y": local[:, 1].astype(f32),
            "z": local[:, 2].astype(f32), "vx": tr.vel_ned[gt, 0].astype(f32), "vy": tr.vel_ned[gt, 1].astype(f32),
            "vz": tr.vel_ned[gt, 2].astype(f32)},
        "vehicle_attitude_groundtruth": {"timestamp": us(tr.t[gt]), "q": tr.q_nb[gt].astype(f32)},
    }
    return write_ulog(path, topics, info={"sys_name": "imunav quadrotor simulation", "ver_sw": "imunav"},
                      t_start_us=b0)
