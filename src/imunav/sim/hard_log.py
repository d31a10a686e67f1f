"""Seeded drives that fail the way real logs fail: a "hard robot" and a "hard car" (issue 33).

:func:`simulate_hard_robot_log` is :func:`~imunav.sim.robot_log.simulate_robot_log`'s robot (30 Hz consumer IMU
mounted x right, y up, z back; 10 Hz wheel odometry reading 9 % short; 2.5 Hz GNSS 0.15 s late, 2 % outliers)
on rough ground (a 5° side slope, a 4° hill, bumps) with every fault of :class:`~imunav.sim.log_faults.LogFaults`
on: GNSS errors correlated over 30 s (σ 1.5 m horizontal beside the robot's white 0.8 m) whose reported σ is
0.4 of the truth, drifts and jumps while it stands, repeated fixes; an IMU warming by 15 °C with 3 ms stamp
jitter; wheels that slide in turns, over-read there, change radius, are quantised to 1 cm/s and 50 ms late, and
meet changing ground (their scale wandering by 8 % over 20 s: the real bag's wheel odometry with the gyro heading
ended its 60 s outages 15.8 m off, a quarter of the distance driven), and spin or lock for 2 s about every 30 s
(a reading off by σ 0.5 m/s then: the real Jackal bag's wheels read 1.98 m/s for 3 s while its IMU shows the body
decelerating).
Its fixes' reported σ (0.4 × 1.7 = 0.68 m horizontal), their scatter about the truth (1.7 m per axis) and the
NIS they give a filter that believes them resemble the real Husky bag of issue 33 (reported 0.8-1.1 m, 2.2 m
RMS residual, NIS 8.9 for 3 degrees of freedom; today's log run gives 8.3 on 30 hard robots:
``benchmarks/bench_gins_hard_sim.py``).

:func:`simulate_hard_car_log` is a car on a highway that never stops (8-30 m/s, a few minutes): a phone-class IMU
(the ``consumer_mems`` preset: an MPU-6050-class part, like a phone's) at 100 Hz roughly aligned with the car
(a seeded rotation of about 2° per axis), CAN speed at 50 Hz (0.01 km/h resolution, 20 ms late), u-blox-like
fixes at 10 Hz, 0.07 s late, with errors correlated over 60 s and an optimistic reported σ (half the truth),
gentle curves with side slip, hills, banked stretches and bumps.  A filter that levels its mounting at rest
cannot start on it: give the true mounting (``log.truth.q_base_imu``).

Both return a :class:`~imunav.sim.robot_log.RobotLog`: ``log.sources`` runs in
:func:`imunav.ins.gins.logrun.run_log` as a log read from a bag, :func:`~imunav.sim.robot_log.write_robot_log`
writes the bag (``imunav gins run robot.bag``).
"""

from __future__ import annotations

import numpy as np

from imunav.rotation import dcm_from_euler
from imunav.sim.log_faults import LogFaults
from imunav.sim.robot_log import ROBOT_T0_NS, RobotLog, robot_loops, simulate_vehicle_log
from imunav.sim.vehicle import Maneuver, bank, bump, hill, speed_change, straight, turn
from imunav.units import DEG

__all__ = ["HARD_ROBOT_FAULTS", "HARD_CAR_FAULTS", "highway_drive", "simulate_hard_robot_log",
           "simulate_hard_car_log"]

#: The hard robot's faults (module docstring).
HARD_ROBOT_FAULTS = LogFaults(
    gnss_corr_sigma_m=(1.5, 1.5, 2.0), gnss_corr_tau_s=30.0, gnss_std_factor=0.4, gnss_rest_drift_mps=0.02,
    gnss_rest_jump_m=3.0, gnss_rest_jump_prob=0.5, gnss_rest_relax_s=10.0, gnss_repeat_prob=0.05, gnss_repeat_max=3,
    imu_temp_rise_c=15.0, imu_temp_tau_s=300.0, imu_stamp_jitter_s=0.003, turn_slip=0.2, odometer_turn_overread=0.3,
    odometer_scale_change=-0.02, odometer_scale_tau_s=200.0, odometer_resolution=0.01, odometer_latency_s=0.05,
    odometer_terrain_std=0.08, odometer_terrain_tau_s=20.0, odometer_slip_std=0.5, odometer_slip_every_s=30.0,
    odometer_slip_s=2.0)
#: The hard car's faults (module docstring); the car never stands, so the faults at rest never act.
HARD_CAR_FAULTS = LogFaults(
    gnss_corr_sigma_m=(0.8, 0.8, 1.5), gnss_corr_tau_s=60.0, gnss_std_factor=0.5, gnss_repeat_prob=0.03,
    gnss_repeat_max=2, imu_temp_rise_c=10.0, imu_temp_tau_s=400.0, imu_stamp_jitter_s=0.001, turn_slip=0.004,
    odometer_turn_overread=0.0, odometer_scale_change=0.005, odometer_scale_tau_s=300.0,
    odometer_resolution=0.01 / 3.6, odometer_latency_s=0.02)


def simulate_hard_robot_log(seed: int = 0, *, distance_m: float = 400.0, faults: LogFaults = HARD_ROBOT_FAULTS,
                            bank_deg: float = 5.0, grade_deg: float = 4.0, bump_deg: float = 4.0) -> RobotLog:
    """The hard robot (module docstring), seeded.

    Parameters
    ----------
    seed : int
        Seed of every random draw.
    distance_m : float
        Approximate distance of the loops, m (at least 80).
    faults : LogFaults
        The faults (default :data:`HARD_ROBOT_FAULTS`; ``LogFaults()`` turns them off).
    bank_deg, grade_deg, bump_deg : float
        Terrain of :func:`~imunav.sim.robot_log.robot_loops`, degrees (0: flat).

    Returns
    -------
    RobotLog
        The streams (``.sources`` for :func:`~imunav.ins.gins.logrun.run_log`) and the truth.
    """
    drive = robot_loops(distance_m, bank_deg=bank_deg, grade_deg=grade_deg, bump_deg=bump_deg)
    return simulate_vehicle_log(seed, drive, faults=faults, source="imunav.sim.hard_log robot")


def highway_drive(duration_s: float, rng: np.random.Generator, *, speed0: float = 20.0) -> list[Maneuver]:
    """A drive that never stops, of about ``duration_s`` s from ``speed0``: straights, curves of 10-40° over
    8-20 s, speed changes between 8 and 30 m/s (at most 2 m/s² at the peak), 1-4° hills (climbing and coming
    back down), 1-4° banked stretches and 1-3° bumps, in a seeded random order.

    Parameters
    ----------
    duration_s : float
        Approximate length, s (>= 30).
    rng : numpy.random.Generator
        Source of the draws.
    speed0 : float
        Speed at the start, m/s (8-30).

    Returns
    -------
    list of Maneuver
        For :func:`~imunav.sim.vehicle.vehicle_trajectory` with ``speed0``.
    """
    m: list[Maneuver] = [straight(5.0)]
    t, v = 5.0, float(speed0)
    while t < duration_s:
        kind = rng.choice(["straight", "curve", "speed", "hill", "bank", "bump"], p=[0.2, 0.3, 0.15, 0.1, 0.1, 0.15])
        if kind == "straight":
            m.append(straight(float(rng.uniform(3.0, 15.0))))
        elif kind == "curve":
            m.append(turn(float(rng.choice([-1.0, 1.0]) * rng.uniform(10.0, 40.0)), float(rng.uniform(8.0, 20.0))))
        elif kind == "speed":
            to = float(rng.uniform(8.0, 30.0))
            m.append(speed_change(to, max(4.0, abs(to - v))))  # peak 2 dv / T <= 2 m/s²
            v = to
        elif kind == "hill":
            g, d = float(rng.uniform(1.0, 4.0)), float(rng.uniform(8.0, 15.0))
            m += [hill(g, d, d / 4), hill(-g, d, d / 4)]
        elif kind == "bank":
            d = float(rng.uniform(8.0, 20.0))
            m.append(bank(float(rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 4.0)), d, d / 4))
        else:
            m += [bump(float(rng.uniform(1.0, 3.0)), float(rng.uniform(-1.0, 1.0)), float(rng.uniform(0.4, 0.8))),
                  straight(1.0)]
        t += sum(x.duration_s for x in m[-2:]) if kind in ("hill", "bump") else m[-1].duration_s
    return m


def simulate_hard_car_log(seed: int = 0, *, duration_s: float = 240.0,
                          faults: LogFaults = HARD_CAR_FAULTS) -> RobotLog:
    """The hard car (module docstring), seeded: a highway drive that never stops.

    Parameters
    ----------
    seed : int
        Seed of every random draw (the drive, the mounting, the sensors).
    duration_s : float
        Approximate length, s (>= 30).
    faults : LogFaults
        The faults (default :data:`HARD_CAR_FAULTS`; ``LogFaults()`` turns them off).

    Returns
    -------
    RobotLog
        The streams (``.sources``) and the truth (``truth.q_base_imu``: the mounting to give the filter).
    """
    r = np.random.default_rng([seed, 33])
    speed0 = float(r.uniform(12.0, 25.0))
    drive = highway_drive(duration_s, r, speed0=speed0)
    c_base_imu = dcm_from_euler(*(r.normal(0.0, 2.0, size=3) * DEG))  # roughly aligned with the car
    heading0 = float(r.uniform(0.0, 360.0))
    return simulate_vehicle_log(
        seed, drive, imu_rate_hz=100.0, odometer_rate_hz=50.0, odometer_scale=1.015, odometer_noise_std=0.05,
        gnss_rate_hz=10.0, gnss_std_m=(0.3, 0.3, 0.5), gnss_latency_s=0.07, outlier_fraction=0.005,
        outlier_range_m=(5.0, 15.0), gnss_lever_arm_base=(0.5, 0.0, -1.2),
        origin_lla=(37.40 * DEG, -122.08 * DEG, 20.0), t0_ns=ROBOT_T0_NS, slip_std=(0.02, 0.02),
        vibration_band_hz=(0.5, 10.5), heading0_deg=heading0, speed0=speed0, c_base_imu=c_base_imu, faults=faults,
        source="imunav.sim.hard_log car")
