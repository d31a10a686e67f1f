"""Static (levelling + gyrocompassing) and in-motion alignment for the GNSS/INS filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imunav.errors import InvalidInputError
from imunav.ins.gins_alignment import motion_alignment, static_alignment
from imunav.rotation import euler_from_quat
from imunav.sim import presets, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, stop, vehicle_trajectory
from imunav.units import DEG

LAT = 30.44 * DEG


def _static(preset, heading_deg=37.0, seconds=300.0, seed=1):
    tr = vehicle_trajectory([stop(seconds)], fs=100, origin_lla=(LAT, 114.47 * DEG, 20.0), heading0_deg=heading_deg)
    return tr, simulate_imu(tr, presets.get(preset), rng=seed)


def test_navigation_grade_gyrocompasses_within_its_predicted_sigma():
    """navigation_a15 (GM gyro bias sigma 0.027 deg/h): 5 min static gives the heading within 3 predicted
    sigma (~0.5 deg at 30 deg N) over 10 seeds, and the level within 0.01 deg (accel bias 15 mGal ~ 1.5e-5 rad)."""
    sd_bias = presets.get("navigation_a15").gyro.bias_instability.sigma[0]
    for seed in range(10):
        tr, imu = _static("navigation_a15", seed=seed)
        al = static_alignment(imu, LAT, gyro_bias_std=float(sd_bias))
        e = np.degrees(al.euler() - euler_from_quat(tr.q_nb[0]))
        assert abs((e[2] + 180) % 360 - 180) < 3 * math.degrees(al.heading_std), (seed, e, al.heading_std)
        assert np.all(np.abs(e[:2]) < 0.01)
        assert al.method.endswith("gyrocompassing")


def test_mems_cannot_gyrocompass_and_says_what_to_do():
    tr, imu = _static("mems_adis16465", seconds=60.0)
    with pytest.raises(InvalidInputError, match="give yaw="):
        static_alignment(imu, LAT, gyro_bias_std=0.05 * DEG)
    al = static_alignment(imu, LAT, gyro_bias_std=0.05 * DEG, yaw=math.radians(37.0))
    assert np.degrees(al.euler()[2]) == pytest.approx(37.0, abs=1e-9)


def test_motion_alignment_from_gnss_velocity():
    """Heading from the track at >= 5 m/s: error within 3 x sigma_v / speed; the start is that fix."""
    tr = vehicle_trajectory(demo_drive(120), fs=100, origin_lla=(LAT, 114.47 * DEG, 20.0), heading0_deg=75.0)
    g = simulate_gnss(tr, vel_noise=(0.05, 0.05, 0.1), rng=4)
    al = motion_alignment(g, min_speed=5.0)
    k = np.searchsorted(tr.t, al.t)
    assert np.linalg.norm(tr.vel_ned[k, :2]) >= 4.9
    e = np.degrees(al.euler()[2] - euler_from_quat(tr.q_nb[k])[2])
    assert abs(e) < 3 * math.degrees(al.heading_std) + 1e-6
    with pytest.raises(InvalidInputError, match="velocity"):
        motion_alignment(simulate_gnss(tr, vel_noise=None, rng=4))
