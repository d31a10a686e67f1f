"""A simulated ground robot's own log, with its truth: the scenario of the log-to-trajectory tests.

:func:`simulate_robot_log` drives a small robot about 400 m in rectangular loops at 1 m/s with stops
(:func:`robot_loops`, :func:`~imunav.sim.vehicle.vehicle_trajectory`) and records what its ROS stack
would: a consumer IMU (:func:`~imunav.sim.presets.get` ``"consumer_mems"``) at 30 Hz screwed in at an
angle, wheel odometry at 10 Hz reading 9 % short with noise, and GNSS fixes at 2.5 Hz (σ 0.8 m) stamped
0.15 s late, 2 % of them jumping 10–30 m; stamps in UTC of a real date.  :func:`write_robot_log` writes
the same drive as a ROS 1 bag, a ROS 2 bag and KF-GINS text files.

Frames.  The vehicle (ROS ``base_link``) is FRD in imunav terms; the IMU sits at its origin.  The IMU's
own axes, those of the values in its ``sensor_msgs/Imu`` messages, point **x right, y up, z backward**
of the vehicle.  imunav's readers flip ROS vectors ``(x, -y, -z)`` (REP-103 FLU → FRD) at the edge, so
the IMU frame a filter sees (the reader's, written ``b`` here) points x right, y down, z forward; the
truth's :attr:`RobotLogTruth.q_base_imu` is the rotation from that frame to the vehicle FRD frame
(``v_base = C(q_base_imu) v_b``), :attr:`RobotLogTruth.c_base_sensor_flu` the raw sensor axes in the
vehicle's FLU frame (what a ROS ``/tf_static`` from ``base_link`` to the IMU frame would hold).

Time.  Every stamp is ``t0_ns + round(t · 1e9)`` with ``t`` the truth's time (0 at the first IMU
sample): a GNSS fix stamped ``t`` holds the antenna's position at ``t − 0.15 s``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.files import atomic_path
from imunav.io.aiding import OdometerData
from imunav.io.gnss import GnssData, write_table
from imunav.io.gpstime import utc_to_gps
from imunav.io.kfgins import NavTrack, write_kfgins_nav
from imunav.io.navlog import TEXT_LOG_CONFIG, NavSources, SourceInfo, text_log_intervals
from imunav.io.rosbag import StaticTransform, write_bag
from imunav.rotation import C_FLU_FRD, euler_from_quat, quat_from_dcm, quat_multiply
from imunav.sim import presets
from imunav.sim.error_model import ImuErrorModel, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.log_faults import LogFaults, gnss_faults, imu_stamps, warmup_temperature
from imunav.sim.trajectory import Trajectory
from imunav.sim.vehicle import (
    Maneuver,
    bank,
    bump,
    hill,
    simulate_odometer,
    speed_change,
    stop,
    straight,
    turn,
    vehicle_trajectory,
)
from imunav.timeseries import ImuData
from imunav.units import DEG

__all__ = ["RobotLogTruth", "RobotLog", "robot_loops", "simulate_robot_log", "simulate_vehicle_log",
           "write_robot_log", "C_BASE_IMU", "ROBOT_T0_NS"]

Array = NDArray[np.float64]

#: The reader's IMU frame (x right, y down, z forward of the vehicle) in the vehicle's FRD frame: its
#: columns are the IMU axes resolved in the vehicle frame, ``v_base = C_BASE_IMU @ v_imu``.
C_BASE_IMU = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: 2024-05-14T09:30:00Z, ns since 1970: the UTC stamp of the first IMU sample.
ROBOT_T0_NS = 1_715_679_000 * 1_000_000_000


def robot_loops(distance_m: float = 400.0, *, speed: float = 1.0, bank_deg: float = 0.0, grade_deg: float = 0.0,
                bump_deg: float = 0.0) -> list[Maneuver]:
    """Rectangular loops (20 m × 10 m, left turns of 90°) at ``speed`` with a 5 s stop after each, from rest.

    Rough ground (each off by default): the first long side crosses a slope of ``bank_deg`` roll
    (:func:`~imunav.sim.vehicle.bank`, 3 s ramps), the second climbs ``grade_deg`` over its first half and
    descends it over its second (:func:`~imunav.sim.vehicle.hill`, 3 s ramps: each loop ends at the height it
    began), the middle of the first short side drives over a 1 s :func:`~imunav.sim.vehicle.bump` of
    ``bump_deg`` pitch and half that roll.

    Parameters
    ----------
    distance_m : float
        Approximate distance driven, m (at least one loop, about 80 m).
    speed : float
        Cruise speed, m/s (> 0).
    bank_deg, grade_deg, bump_deg : float
        Roll of the slope, grade of the hill and peak pitch of the bump, degrees (0: flat).

    Returns
    -------
    list of Maneuver
        The drive, for :func:`~imunav.sim.vehicle.vehicle_trajectory`; it starts and ends with 10 s at rest.

    Raises
    ------
    InvalidInputError
        If ``distance_m`` is shorter than one loop or ``speed`` is not positive.
    """
    if not (math.isfinite(speed) and speed > 0):
        raise InvalidInputError(f"robot_loops: speed must be > 0 m/s; got {speed!r}")
    turn_s = 0.5 * math.pi * 4.0 / speed  # a 4 m radius
    side = (20.0 / speed, 10.0 / speed)
    loop = [straight(side[0]), turn(90.0, turn_s), straight(side[1]), turn(90.0, turn_s), straight(side[0]),
            turn(90.0, turn_s), straight(side[1]), turn(90.0, turn_s)]
    if bank_deg:
        loop[0] = bank(bank_deg, side[0], min(3.0, side[0] / 2))
    if bump_deg:
        loop[2:3] = [straight((side[1] - 1.0) / 2), bump(bump_deg, bump_deg / 2, 1.0), straight((side[1] - 1.0) / 2)]
    if grade_deg:
        i = len(loop) - 4  # the second long side
        ramp = min(3.0, side[0] / 4)
        loop[i:i + 1] = [hill(grade_deg, side[0] / 2, ramp), hill(-grade_deg, side[0] / 2, ramp)]
    loop_m = speed * sum(m.duration_s for m in loop)
    n = int(round(distance_m / loop_m))
    if n < 1:
        raise InvalidInputError(f"robot_loops: distance_m must be at least one loop ({loop_m:.0f} m); got {distance_m!r}")
    ramp = 3.0
    m: list[Maneuver] = [stop(10.0)]
    for _ in range(n):
        m += [speed_change(speed, ramp), *loop, speed_change(0.0, ramp), stop(5.0)]
    m.append(stop(5.0))
    return m


@dataclass(frozen=True)
class RobotLogTruth:
    """What the robot's log does not say: its true motion and the sensors' errors.

    Attributes
    ----------
    trajectory : Trajectory
        The vehicle base frame (FRD) at the IMU's stamps (t = 0 at the first one).
    q_base_imu : numpy.ndarray, shape (4,)
        Rotation from the reader's IMU frame (FRD flip of the sensor axes) to the vehicle FRD frame,
        Hamilton scalar-first (:data:`C_BASE_IMU`); as ZYX Euler (roll, pitch, yaw): ``mounting_euler_deg``.
    mounting_euler_deg : tuple of float
        ``q_base_imu`` as ZYX Euler angles, degrees.
    c_base_sensor_flu : numpy.ndarray, shape (3, 3)
        The raw sensor axes (x right, y up, z backward) as columns in the vehicle's FLU frame.
    odometer_scale : float
        Odometer reading / true forward speed (0.91: 9 % short).
    odometer_noise_std : float
        White noise of each odometer sample, m/s.
    gnss_latency_s : float
        A fix stamped t holds the antenna at t − latency, s.
    gnss_lever_arm_base : numpy.ndarray, shape (3,)
        Antenna from the vehicle origin (= the IMU), vehicle FRD, m.
    gnss_outlier : numpy.ndarray of bool, shape (M,)
        Which written fixes jump.
    gnss_outlier_offset_ned : numpy.ndarray, shape (M, 3)
        The jump of each fix (zero for the others), NED, m.
    t0_ns : int
        UTC of t = 0, ns since 1970.
    meta : dict
        Seed, IMU model, noise levels.
    faults : dict
        The :class:`~imunav.sim.log_faults.LogFaults` switches (``"switches"``) and what they realised: the
        IMU's temperature (``imu_temp_c``, °C per sample), its stamps' errors (``imu_stamp_error_s``), the
        fixes' rest offsets, repeats and true σ (:func:`~imunav.sim.log_faults.gnss_faults`); empty without
        faults.
    """

    trajectory: Trajectory
    q_base_imu: Array
    mounting_euler_deg: tuple[float, float, float]
    c_base_sensor_flu: Array
    odometer_scale: float
    odometer_noise_std: float
    gnss_latency_s: float
    gnss_lever_arm_base: Array
    gnss_outlier: NDArray[np.bool_]
    gnss_outlier_offset_ned: Array
    t0_ns: int
    meta: dict[str, Any] = field(default_factory=dict)
    faults: dict[str, Any] = field(default_factory=dict)

    def nav_track(self) -> NavTrack:
        """The vehicle truth as a :class:`~imunav.io.kfgins.NavTrack` on the sources' time origin (t = 0 at the
        first IMU stamp).

        Returns
        -------
        NavTrack
            Position, velocity and attitude of the vehicle base frame.
        """
        tr = self.trajectory
        assert tr.pos_lla is not None and tr.vel_ned is not None
        return NavTrack(tr.t.copy(), tr.pos_lla.copy(), tr.vel_ned.copy(), tr.q_nb.copy(), 0,
                        {"source": "imunav.sim.robot_log truth", "frame": "vehicle base (FRD)"})


@dataclass(frozen=True)
class RobotLog:
    """The robot's recorded streams (as its log holds them, on the truth's time axis) and the truth.

    Attributes
    ----------
    imu : ImuData
        In the reader's IMU frame (module docstring), ``meta["t0_ns"]`` the UTC of t = 0.
    gnss : GnssData
        The fixes as stamped (antenna positions 0.15 s older), outliers included.
    odometer : OdometerData
        Forward speeds of the base frame with ``speed_std``.
    truth : RobotLogTruth
        What the log does not say.
    """

    imu: ImuData
    gnss: GnssData
    odometer: OdometerData
    truth: RobotLogTruth

    @property
    def sources(self) -> NavSources:
        """The streams as :func:`imunav.ins.gins.logrun.run_log` takes a log's (what
        :func:`imunav.io.navlog.read_nav_sources` reads from :func:`write_robot_log`'s bag without
        ``/tf_static``, to the ns of its stamps), without writing the bag.

        Returns
        -------
        NavSources
            IMU, GNSS and odometer on the IMU's time origin (UTC ``truth.t0_ns``), no mounting.
        """
        t0 = int(self.truth.t0_ns)
        roles = (("imu", "/imu/data", "sensor_msgs/msg/Imu", self.imu.t),
                 ("gnss", "/gps/fix", "sensor_msgs/msg/NavSatFix", self.gnss.t),
                 ("odometer", "/odom", "nav_msgs/msg/Odometry", self.odometer.t))
        topics = {r: SourceInfo(r, topic, mt, int(t.size), int(t.size),
                                float((t.size - 1) / (t[-1] - t[0])) if t.size > 1 else None)
                  for r, topic, mt, t in roles}
        meta = {"time": "header stamps in UTC", "mounting": "no /tf_static in the bag",
                "simulation": str(self.imu.meta.get("source", "imunav.sim.robot_log"))}
        return NavSources(str(self.imu.meta.get("source", "imunav.sim.robot_log")), t0, self.imu, self.gnss,
                          self.odometer, None, None, topics, t0 * 1e-9, None, None, meta)


def _imu_trajectory(base: Trajectory, c_base_imu: Array) -> Trajectory:
    """The truth of a sensor frame rotated by ``c_base_imu`` from the base frame, at the base origin."""
    q_bi = quat_from_dcm(c_base_imu)
    q = quat_multiply(base.q_nb, q_bi)
    assert base.omega_nb_b is not None
    w = base.omega_nb_b @ c_base_imu  # C_ib w_b, row-wise: w_i = C_base_imu^T w_b
    return Trajectory(base.t, q, vel_ned=base.vel_ned, pos_lla=base.pos_lla, omega_nb_b=w, accel_ned=base.accel_ned)


def simulate_robot_log(seed: int = 0, *, distance_m: float = 400.0, speed: float = 1.0, imu_rate_hz: float = 30.0,
                       odometer_rate_hz: float = 10.0, odometer_scale: float = 0.91, odometer_noise_std: float = 0.02,
                       gnss_rate_hz: float = 2.5, gnss_std_m: float = 0.8, gnss_latency_s: float = 0.15,
                       outlier_fraction: float = 0.02, outlier_range_m: tuple[float, float] = (10.0, 30.0),
                       gnss_lever_arm_base: tuple[float, float, float] = (0.0, 0.0, -0.3),
                       origin_lla: tuple[float, float, float] = (48.137 * DEG, 11.575 * DEG, 520.0),
                       t0_ns: int = ROBOT_T0_NS, imu_model: str | ImuErrorModel = "consumer_mems",
                       slip_std: tuple[float, float] = (0.0, 0.0), idle_vibration_std: float = 0.0,
                       vibration_band_hz: tuple[float, float] = (0.1, 2.6),
                       faults: LogFaults | None = None) -> RobotLog:
    """The robot scenario (module docstring), seeded.

    Parameters
    ----------
    seed : int
        Seed of every random draw (IMU errors, odometer and GNSS noise, the outliers).
    distance_m, speed : float
        Approximate distance (m) and cruise speed (m/s) of :func:`robot_loops`.
    imu_rate_hz, odometer_rate_hz, gnss_rate_hz : float
        Rates, Hz (the odometer's and the GNSS's at most the IMU's).
    odometer_scale : float
        Odometer reading / true forward speed.
    odometer_noise_std : float
        White noise σ of each odometer sample, m/s (also written as its covariance).
    gnss_std_m : float
        White position noise σ north, east and down, m.
    gnss_latency_s : float
        Age of each fix at its stamp, s.
    outlier_fraction : float
        Share of the fixes that jump (round(fraction × fixes) of them, drawn without replacement).
    outlier_range_m : tuple of float
        Horizontal jump size, uniform in this range, m, in a uniform direction.
    gnss_lever_arm_base : tuple of float
        Antenna from the vehicle origin, vehicle FRD, m.
    origin_lla : tuple of float
        Start position (lat rad, lon rad, ellipsoidal height m).
    t0_ns : int
        UTC of the first IMU stamp, ns since 1970.
    imu_model : str or ImuErrorModel
        The IMU's errors: a preset name of :mod:`imunav.sim.presets`, or a model (e.g. one drawn from a filter's
        own model by :func:`imunav.ins.gins.truth.matched_errors`, for consistency tests).
    slip_std : tuple of float
        σ of the base's lateral (wheel slip) and vertical (suspension) velocity while it moves, m/s (what the
        non-holonomic constraint's σ stands for; default none: the constraint holds exactly).
    idle_vibration_std : float
        σ of the base's velocity on each axis during the stops, m/s (default none: exactly still).
    vibration_band_hz : tuple of float
        Band of both perturbations, Hz (:func:`~imunav.sim.vehicle.vehicle_trajectory`); the default
        0.1-2.6 Hz is white on a 0.4 s grid (correlation −0.08 at the filter's 0.2 s epochs) and far enough
        below the 30 Hz IMU's Nyquist frequency for the mechanization's fourth-order integration of point samples
        (a sinusoid of f Hz comes out ``1 − 11 x⁴ / 720``, ``x = 2π f / 30``, times its amplitude: 0.13 % small at
        2.6 Hz; the trapezoid's ``(x/2) cot(x/2)``, 2.5 % small, left the NHC's NIS 2 % under 1 over 30 drives).
    faults : LogFaults, optional
        What real logs add (:mod:`imunav.sim.log_faults`); None: none, the drive as before they existed, to the
        bit.

    Returns
    -------
    RobotLog
        The streams and the truth.

    Raises
    ------
    InvalidInputError
        If a rate or σ is out of range (from the simulators).
    """
    return simulate_vehicle_log(
        seed, robot_loops(distance_m, speed=speed), imu_rate_hz=imu_rate_hz, odometer_rate_hz=odometer_rate_hz,
        odometer_scale=odometer_scale, odometer_noise_std=odometer_noise_std, gnss_rate_hz=gnss_rate_hz,
        gnss_std_m=gnss_std_m, gnss_latency_s=gnss_latency_s, outlier_fraction=outlier_fraction,
        outlier_range_m=outlier_range_m, gnss_lever_arm_base=gnss_lever_arm_base, origin_lla=origin_lla, t0_ns=t0_ns,
        imu_model=imu_model, slip_std=slip_std, idle_vibration_std=idle_vibration_std,
        vibration_band_hz=vibration_band_hz, faults=faults)


def simulate_vehicle_log(seed: int, maneuvers: list[Maneuver], *, imu_rate_hz: float = 30.0,
                         odometer_rate_hz: float = 10.0, odometer_scale: float = 0.91,
                         odometer_noise_std: float = 0.02, gnss_rate_hz: float = 2.5,
                         gnss_std_m: float | tuple[float, float, float] = 0.8, gnss_latency_s: float = 0.15,
                         outlier_fraction: float = 0.02, outlier_range_m: tuple[float, float] = (10.0, 30.0),
                         gnss_lever_arm_base: tuple[float, float, float] = (0.0, 0.0, -0.3),
                         origin_lla: tuple[float, float, float] = (48.137 * DEG, 11.575 * DEG, 520.0),
                         t0_ns: int = ROBOT_T0_NS, imu_model: str | ImuErrorModel = "consumer_mems",
                         slip_std: tuple[float, float] = (0.0, 0.0), idle_vibration_std: float = 0.0,
                         vibration_band_hz: tuple[float, float] = (0.1, 2.6), heading0_deg: float = 30.0,
                         speed0: float = 0.0, c_base_imu: Array = C_BASE_IMU, faults: LogFaults | None = None,
                         source: str = "imunav.sim.robot_log") -> RobotLog:
    """A wheeled vehicle's log (IMU, wheel speed, GNSS) on any drive, seeded: :func:`simulate_robot_log` on its
    loops, :func:`imunav.sim.hard_log.simulate_hard_car_log` on a highway.

    Parameters
    ----------
    seed : int
        Seed of every random draw.
    maneuvers : list of Maneuver
        The drive (:func:`~imunav.sim.vehicle.vehicle_trajectory`).
    imu_rate_hz, odometer_rate_hz, gnss_rate_hz : float
        Rates, Hz (the odometer's and the GNSS's at most the IMU's).
    odometer_scale : float
        Odometer reading / true forward speed.
    odometer_noise_std : float
        White noise σ of each odometer sample, m/s (also written as its covariance).
    gnss_std_m : float or tuple of float
        White position noise σ (north, east, down, or one for all), m.
    gnss_latency_s : float
        Age of each fix at its stamp, s.
    outlier_fraction : float
        Share of the fixes that jump.
    outlier_range_m : tuple of float
        Horizontal jump size, uniform in this range, m, in a uniform direction.
    gnss_lever_arm_base : tuple of float
        Antenna from the vehicle origin, vehicle FRD, m.
    origin_lla : tuple of float
        Start position (lat rad, lon rad, ellipsoidal height m).
    t0_ns : int
        UTC of the first IMU stamp, ns since 1970.
    imu_model : str or ImuErrorModel
        The IMU's errors (a preset name or a model).
    slip_std : tuple of float
        σ of the base's white lateral and vertical velocity in motion, m/s.
    idle_vibration_std : float
        σ of the base's velocity during the stops, m/s.
    vibration_band_hz : tuple of float
        Band of both perturbations, Hz.
    heading0_deg : float
        Initial heading, degrees from north.
    speed0 : float
        Initial speed, m/s (a drive that never stops starts moving).
    c_base_imu : numpy.ndarray, shape (3, 3)
        The reader's IMU frame in the vehicle's FRD frame (columns: IMU axes), a rotation.
    faults : LogFaults, optional
        What real logs add (:mod:`imunav.sim.log_faults`); None: none.
    source : str
        The name the IMU's ``meta["source"]`` and the sources carry.

    Returns
    -------
    RobotLog
        The streams and the truth (``truth.faults``: what the faults realised).

    Raises
    ------
    InvalidInputError
        If a rate, σ or fault is out of range (from the simulators).
    """
    rng = np.random.default_rng(seed)
    seeds = rng.integers(0, 2**63 - 1, size=4)
    vib = int(rng.integers(0, 2**63 - 1))  # drawn after the others: the drive without perturbations is unchanged
    f = faults if faults is not None else LogFaults()
    rf = np.random.default_rng(int(rng.integers(0, 2**63 - 1)))  # the faults' draws, after every earlier one
    base = vehicle_trajectory(maneuvers, fs=imu_rate_hz, origin_lla=origin_lla, heading0_deg=heading0_deg,
                              speed0=speed0, slip_std=slip_std, idle_vibration_std=idle_vibration_std,
                              vibration_band_hz=vibration_band_hz, rng=vib, turn_slip=f.turn_slip)
    model = presets.get(imu_model) if isinstance(imu_model, str) else imu_model
    c_bi = np.asarray(c_base_imu, dtype=np.float64)
    rec: dict[str, Any] = {} if faults is None else {"switches": f.to_dict()}
    temp = None
    if f.imu_temp_rise_c != 0:
        temp = warmup_temperature(base.t, f.imu_temp_rise_c, f.imu_temp_tau_s, model.temp_ref_c)
        rec["imu_temp_c"] = temp
    imu = simulate_imu(_imu_trajectory(base, c_bi), model, rng=int(seeds[0]), temp_c=temp)
    assert isinstance(imu, ImuData)
    t_imu = imu.t
    if f.imu_stamp_jitter_s > 0:
        t_imu = imu_stamps(imu.t, f.imu_stamp_jitter_s, rf)
        rec["imu_stamp_error_s"] = t_imu - imu.t
    imu = ImuData(t_imu, imu.gyro, imu.accel, meta={"t0_ns": int(t0_ns), "source": source,
                                                    "frame": "IMU (reader's FRD flip of the sensor axes)"})
    odo = simulate_odometer(base, scale_factor=odometer_scale - 1.0, noise_std=odometer_noise_std,
                            rate_hz=odometer_rate_hz, rng=int(seeds[1]), latency_s=f.odometer_latency_s,
                            scale_change=f.odometer_scale_change, scale_change_tau_s=f.odometer_scale_tau_s,
                            turn_overread=f.odometer_turn_overread, resolution=f.odometer_resolution,
                            terrain_scale_std=f.odometer_terrain_std, terrain_scale_tau_s=f.odometer_terrain_tau_s,
                            slip_std=f.odometer_slip_std, slip_every_s=f.odometer_slip_every_s,
                            slip_s=f.odometer_slip_s)
    odo = OdometerData(odo.t, odo.speed, {**odo.meta, "t0_ns": int(t0_ns)},
                       np.full(odo.t.size, float(odometer_noise_std)))
    lever = np.asarray(gnss_lever_arm_base, dtype=np.float64)
    std = (gnss_std_m,) * 3 if np.ndim(gnss_std_m) == 0 else tuple(gnss_std_m)  # type: ignore[arg-type]
    corr = {} if not any(f.gnss_corr_sigma_m) else {"pos_corr_sigma": f.gnss_corr_sigma_m,
                                                      "pos_corr_tau": f.gnss_corr_tau_s}
    g = simulate_gnss(base, rate_hz=gnss_rate_hz, pos_noise=std, vel_noise=None,
                      latency_s=gnss_latency_s, lever_arm=lever, rng=int(seeds[2]), **corr)
    if faults is not None:
        speed = np.interp(g.t - gnss_latency_s, base.t, np.linalg.norm(base.vel_ned, axis=1))
        g, realised = gnss_faults(g, speed, f, rf)
        rec.update(realised)
    r3 = np.random.default_rng(int(seeds[3]))
    k = int(round(outlier_fraction * g.n))
    idx = np.sort(r3.choice(g.n, size=k, replace=False)) if k else np.zeros(0, dtype=np.intp)
    off = np.zeros((g.n, 3))
    size = r3.uniform(*outlier_range_m, size=k)
    ang = r3.uniform(0.0, 2.0 * math.pi, size=k)
    off[idx, 0], off[idx, 1] = size * np.cos(ang), size * np.sin(ang)
    outlier = np.zeros(g.n, dtype=bool)
    outlier[idx] = True
    lla = g.lla + earth.ned_to_dlla(off, g.lla)
    gnss = GnssData(g.t, lla, g.pos_std, meta={**g.meta, "t0_ns": int(t0_ns), "outliers": int(k)})
    c_sensor_flu = C_FLU_FRD @ c_bi @ C_FLU_FRD  # raw sensor axes in the vehicle's FLU frame
    q_bi = quat_from_dcm(c_bi)
    e = np.degrees(euler_from_quat(q_bi))
    truth = RobotLogTruth(base, q_bi, (float(e[0]), float(e[1]), float(e[2])), c_sensor_flu, float(odometer_scale),
                          float(odometer_noise_std), float(gnss_latency_s), lever, outlier, off, int(t0_ns),
                          {"seed": int(seed), "imu_model": model.name, "slip_std": list(slip_std),
                           "idle_vibration_std": float(idle_vibration_std), "imu_rate_hz": float(imu_rate_hz),
                           "gnss_std_m": float(np.max(std)), "outlier_range_m": list(outlier_range_m)}, rec)
    return RobotLog(imu, gnss, odo, truth)


def write_robot_log(log: RobotLog, folder: str | os.PathLike[str], *, formats: tuple[str, ...] = ("ros1", "ros2", "kfgins"),
                    ros2_storage: str = "mcap", static_tf: bool = False) -> dict[str, Path]:
    """Write the robot's log as a ROS 1 bag, a ROS 2 bag and KF-GINS text files (same stamps, same values).

    Bags: ``/imu/data`` (``sensor_msgs/Imu``, frame ``imu_link``), ``/odom`` (``nav_msgs/Odometry``,
    ``odom`` → ``base_link``), ``/gps/fix`` (``sensor_msgs/NavSatFix``, frame ``gps``); with ``static_tf``
    also ``/tf_static`` ``base_link`` → ``imu_link`` (the mounting; without it the mounting must be
    estimated).  KF-GINS text (time: GPS seconds of week of the bags' stamps; every value written
    repr-exact): ``imu.txt`` (increments: each 30 Hz sample times its interval,
    :func:`imunav.io.navlog.text_log_intervals`), ``gnss.txt`` (the fixes with their σ), ``odo.txt`` (time,
    speed, σ), ``truth.nav`` (the vehicle truth) and ``sources.toml`` (the files and the GPS week): a log of
    its own for :func:`imunav.io.navlog.read_nav_sources` and ``imunav gins run``, the same sources as the
    bags.

    Parameters
    ----------
    log : RobotLog
        From :func:`simulate_robot_log`.
    folder : str or os.PathLike
        An existing folder; the files are ``robot.bag``, ``robot_ros2/`` and ``kfgins/``.
    formats : tuple of str
        Any of ``"ros1"``, ``"ros2"``, ``"kfgins"``.
    ros2_storage : str
        ``"mcap"`` or ``"sqlite3"``.
    static_tf : bool
        Write the mounting on ``/tf_static``.

    Returns
    -------
    dict of str to pathlib.Path
        Format -> what was written (the KF-GINS entry is the folder).

    Raises
    ------
    InvalidInputError
        If a format is unknown or a target exists.
    """
    out_dir = Path(folder)
    unknown = set(formats) - {"ros1", "ros2", "kfgins"}
    if unknown:
        raise InvalidInputError(f"write_robot_log: unknown formats {sorted(unknown)}; choose among ros1, ros2, kfgins")
    topics = {"/imu/data": log.imu, "/odom": log.odometer, "/gps/fix": log.gnss}
    frames = {"/imu/data": "imu_link", "/gps/fix": "gps"}
    tf = [StaticTransform("base_link", "imu_link", quat_from_dcm(log.truth.c_base_sensor_flu), np.zeros(3))] \
        if static_tf else []
    out: dict[str, Path] = {}
    for fmt in formats:
        if fmt == "ros1":
            target = out_dir / "robot.bag"
            if target.exists():
                raise InvalidInputError(f"{target} exists; outputs never overwrite - choose another folder")
            out[fmt] = write_bag(target, topics, storage="ros1", frame_ids=frames, static_tf=tf)
        elif fmt == "ros2":
            out[fmt] = write_bag(out_dir / "robot_ros2", topics, storage=ros2_storage, frame_ids=frames, static_tf=tf)
        else:
            out[fmt] = _write_kfgins(log, out_dir / "kfgins")
    return out


def _write_kfgins(log: RobotLog, folder: Path) -> Path:
    """The KF-GINS text files of the drive (:func:`write_robot_log`), a log for
    :func:`imunav.io.navlog.read_nav_sources`: the stamps the bags hold, as GPS seconds of week written
    repr-exact, the IMU as increments ``rate · interval`` (:func:`imunav.io.navlog.text_log_intervals`), the
    fixes and speeds with their σ, and ``sources.toml`` naming them with the GPS week."""
    if folder.exists():
        raise InvalidInputError(f"{folder} exists; outputs never overwrite - choose another folder")
    folder.mkdir()
    t0_ns = log.truth.t0_ns
    exact = "%.17g"  # repr-exact doubles

    def stamps(t: Array) -> NDArray[np.int64]:  # the bags' header stamps (imunav.io.rosbag.write_bag)
        return t0_ns + np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)

    def sow(t: Array) -> Array:
        return utc_to_gps((stamps(t) - t0_ns) * 1e-9, t0_ns).sow

    imu = log.imu
    s_imu = stamps(imu.t)
    dt = text_log_intervals((s_imu - s_imu[0]) * 1e-9)[:, None]  # the reader's intervals, from the same stamps
    write_table(folder / "imu.txt", [sow(imu.t), imu.gyro * dt, imu.accel * dt], fmt=exact)
    g = log.gnss
    write_table(folder / "gnss.txt", [sow(g.t), np.degrees(g.lla[:, :2]), g.lla[:, 2], g.pos_std], fmt=exact)
    o = log.odometer
    write_table(folder / "odo.txt", [sow(o.t), o.speed] + ([] if o.speed_std is None else [o.speed_std]), fmt=exact)
    nav = log.truth.nav_track()
    week = int(utc_to_gps([0.0], t0_ns).week[0])
    write_kfgins_nav(folder / "truth.nav", NavTrack(sow(nav.t), nav.lla, nav.vel_ned, nav.q_nb, week, nav.meta))
    with atomic_path(folder / TEXT_LOG_CONFIG) as tmp:
        tmp.write_text(
            "# The simulated robot's drive as KF-GINS text files: imunav gins run FOLDER --out DIR runs it as a log\n"
            "# (imunav.io.navlog.read_text_sources; the same sources as the drive's ROS bags)\n"
            f"gps_week = {week}  # of the files' seconds of week (UTC stamps + the date's leap seconds)\n"
            'imu = "imu.txt"  # s of week, dtheta x y z (rad), dvel x y z (m/s): rate x interval, IMU frame FRD\n'
            'gnss = "gnss.txt"  # s of week, lat lon (deg), h (m), sigma N E D (m)\n'
            'odometer = "odo.txt"  # s of week, forward speed (m/s), its sigma (m/s)\n', encoding="utf-8")
    return folder
