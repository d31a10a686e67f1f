"""A log that never stands still (issue 33): a simulated car that starts at 8 m/s, its phone-class IMU tilted in
the car with a raw gyro bias of several deg/s, CAN-like speed at 50 Hz and 10 Hz fixes 0.08 s late.  The coarse
mounting levelled while driving, the gyro bias from the course change, and the log run that starts moving, each
against the simulation's truth and inside the σ it reports."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imunav.earth import lla_to_ned
from imunav.ins.gins.alignment import gyro_bias_in_motion
from imunav.ins.gins.layout import LAY
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.mounting import estimate_mounting
from imunav.io.navsources import NavSources
from imunav.rotation import dcm_from_euler, dcm_from_quat, quat_from_dcm, quat_multiply
from imunav.sim import presets
from imunav.sim.error_model import simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.trajectory import Trajectory
from imunav.sim.vehicle import hill, simulate_odometer, speed_change, straight, turn, vehicle_trajectory
from imunav.timeseries import ImuData

MOUNT_DEG = (1.5, -4.0, 2.5)  # roll, pitch, yaw of the IMU in the car
RAW_BIAS = np.radians([-0.6, -2.0, 3.9])  # a phone's raw gyro bias, deg/s
LATENCY = 0.08
T0_NS = 1_533_226_488 * 1_000_000_000


def _car(seed: int) -> tuple[NavSources, Trajectory, np.ndarray]:
    rng = np.random.default_rng(seed)
    drive = [straight(8.0), turn(25.0, 6.0), speed_change(20.0, 15.0), straight(10.0), turn(-40.0, 10.0),
             hill(2.0, 20.0, 5.0), straight(8.0), turn(15.0, 5.0), speed_change(14.0, 8.0), straight(10.0)]
    base = vehicle_trajectory(drive, fs=100.0, speed0=8.0, heading0_deg=20.0,
                              origin_lla=(math.radians(37.7), math.radians(-122.47), 30.0))
    C_vb = dcm_from_euler(np.radians(MOUNT_DEG))
    q_vb = quat_from_dcm(C_vb)
    w = base.omega_nb_b @ C_vb  # the IMU's rates: C_bv w_v, row-wise
    imu_truth = Trajectory(base.t, quat_multiply(base.q_nb, q_vb), vel_ned=base.vel_ned, pos_lla=base.pos_lla,
                           omega_nb_b=w, accel_ned=base.accel_ned)
    sim = simulate_imu(imu_truth, presets.get("consumer_mems"), rng=int(rng.integers(2**31)))
    imu = ImuData(sim.t - sim.t[0], sim.gyro + RAW_BIAS, sim.accel, meta={"t0_ns": T0_NS})
    odo = simulate_odometer(base, noise_std=0.05, rate_hz=50.0, rng=int(rng.integers(2**31)))
    gnss = simulate_gnss(base, rate_hz=10.0, pos_noise=(0.3, 0.3, 0.6), vel_noise=None, latency_s=LATENCY,
                         rng=int(rng.integers(2**31)))
    g = type(gnss)(gnss.t - base.t[0], gnss.lla, gnss.pos_std * 2.0, meta={})  # reported σ twice the truth
    o = type(odo)(odo.t - base.t[0], odo.speed, meta={})
    src = NavSources("simulated car", T0_NS, imu, g, o, None, None, {}, T0_NS * 1e-9, None, None, {})
    # the sim's own bias: the preset's turn-on bias plus the raw offset
    return src, base, RAW_BIAS + presets.get("consumer_mems").gyro.bias


@pytest.fixture(scope="module", params=(1, 2))
def car(request):
    return _car(request.param)


def test_gyro_bias_from_the_course_change(car):
    """The bias of a gyro that never rests, read over the drive less its GNSS course change: within 3σ of the
    simulated bias on every axis, and its σ under 0.1 deg/s."""
    src, _, bias = car
    b, sd = gyro_bias_in_motion(src.imu, src.gnss)
    assert np.all(np.abs(b - bias) <= 3 * sd), np.degrees(b - bias)
    assert np.degrees(sd).max() < 0.1


def test_mounting_levelled_while_driving(car):
    """No rest at all: roll and pitch from the specific force less the car's own acceleration, yaw from the
    accelerations against the speed, within their 3σ of the truth (and yaw within 1 deg)."""
    src, _, bias = car
    st = np.zeros(src.imu.n, dtype=bool)
    m = estimate_mounting(src.imu, st, speed_t=src.odometer.t, speed=src.odometer.speed, gyro_bias=bias)
    E = dcm_from_quat(m.q_vb) @ dcm_from_euler(np.radians(MOUNT_DEG)).T
    err = np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]) / 2
    assert np.all(np.abs(err) <= 3 * m.std), (np.degrees(err), np.degrees(m.std))
    assert abs(math.degrees(err[2])) < 1.0
    assert "while driving" in m.meta["method"]
    with pytest.raises(Exception, match="1 s standing still"):
        estimate_mounting(src.imu, st)


def test_log_run_that_starts_moving(car):
    """``run_log`` with defaults: it starts at the odometer's speed (not at rest), finds the latency within 3σ of
    0.08 s, its mounting within 3σ, and the smoothed track within 0.4 m RMS of the truth (fixes of σ 0.3 m reported
    as 0.6 m), inside its own σ."""
    src, base, _ = car
    run = run_log(src, LogRunOptions())
    res = run.result
    assert np.linalg.norm(res.vel_ned[0] - base.vel_ned[0]) < 0.5
    lay_i = run.state_layout()
    i = int(lay_i[LAY.gnss_delay])
    assert abs(res.gnss_delay[-1] - LATENCY) <= 3 * math.sqrt(res.cov_diag[-1, i])
    e, sd = run.mounting_euler()
    d = np.remainder(e - np.radians(MOUNT_DEG) + math.pi, 2 * math.pi) - math.pi
    assert np.all(np.abs(d[1:]) <= 3 * sd[1:] + 1e-3), (np.degrees(d), np.degrees(sd))
    tb = base.t - base.t[0]
    j = np.searchsorted(tb, res.t)
    j = np.clip(j, 0, tb.size - 1)
    s = res.smoothed
    err = lla_to_ned(s.lla, base.pos_lla[j][0]) - lla_to_ned(base.pos_lla[j], base.pos_lla[j][0])
    assert float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1)))) < 0.4
    # the smoothed σ is not overconfident: the horizontal error's normalised square averages at most its 2 dof (a σ
    # 1.5 times too small moves a mean of 2 to 4.5).  It is conservative on drive 1, where the process model's
    # cross-validation chose 4 times the preset's bias instability: d² 0.21 at 0.058 m RMS, against 0.68 at 0.127 m
    # with the preset's (the smoother's σ shrank less than its error); drive 2 keeps the preset's
    k = np.clip(np.searchsorted(s.cov_t, res.t), 0, s.cov_t.size - 1)
    d2 = np.einsum("ni,nij,nj->n", err[:, :2], np.linalg.inv(s.cov_nav[k, :2, :2]), err[:, :2])
    assert 0.15 <= float(d2.mean()) <= 3.0
    assert run.initial["gyro_bias"].startswith("mean rate over the drive")
