"""The simulated robot log's truth says what its streams hold (imunav.sim.robot_log)."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.rotation import dcm_from_quat
from imunav.sim.gnss import truth_at
from imunav.sim.robot_log import C_BASE_IMU, simulate_robot_log


@pytest.fixture(scope="module")
def log():
    return simulate_robot_log(3)


def test_drive_and_rates(log):
    tr = log.truth.trajectory
    v = np.linalg.norm(tr.vel_ned, axis=1)
    dist = float(np.sum(v[1:] + v[:-1]) / 2 / 30.0)
    assert 350.0 < dist < 480.0  # "about 400 m"
    assert v.max() == pytest.approx(1.0, abs=1e-9)
    assert np.sum(v < 1e-9) / v.size > 0.05  # stops (10 s, 5 s after each loop, 5 s)
    assert np.median(np.diff(log.imu.t)) == pytest.approx(1 / 30)
    assert np.median(np.diff(log.odometer.t)) == pytest.approx(0.1)
    assert np.median(np.diff(log.gnss.t)) == pytest.approx(0.4)


def test_mounting_x_right_y_up_z_backward(log):
    # the sensor's raw axes (FLU convention of the message) resolved in the vehicle's FLU frame
    c = log.truth.c_base_sensor_flu
    np.testing.assert_array_equal(c[:, 0], [0, -1, 0])   # x right
    np.testing.assert_array_equal(c[:, 1], [0, 0, 1])    # y up
    np.testing.assert_array_equal(c[:, 2], [-1, 0, 0])   # z backward
    np.testing.assert_allclose(dcm_from_quat(log.truth.q_base_imu), C_BASE_IMU, atol=1e-15)
    # at rest the reader-frame accelerometer reads gravity's reaction (up) on its -y axis (y down)
    rest = slice(30, 270)
    f = log.imu.accel[rest].mean(axis=0)
    assert f[1] == pytest.approx(-9.8, abs=0.2) and abs(f[0]) < 0.5 and abs(f[2]) < 0.5


def test_odometer_short_and_gnss_late_with_outliers(log):
    tr = log.truth.trajectory
    moving = np.interp(log.odometer.t, tr.t, np.linalg.norm(tr.vel_ned, axis=1))
    m = moving > 0.99
    ratio = log.odometer.speed[m].mean() / moving[m].mean()
    assert ratio == pytest.approx(0.91, abs=3 * 0.02 / np.sqrt(m.sum()) + 1e-3)
    lla_true, _ = truth_at(tr, log.gnss.t - 0.15, log.truth.gnss_lever_arm_base)
    err = earth.dlla_to_ned(log.gnss.lla - lla_true, lla_true)
    horiz = np.linalg.norm(err[:, :2], axis=1)
    out = log.truth.gnss_outlier
    assert out.sum() == round(0.02 * log.gnss.n)
    assert np.all((horiz[out] > 10 - 4) & (horiz[out] < 30 + 4))  # the jump, give or take 5 sigma of noise
    clean = err[~out]
    np.testing.assert_allclose(clean.std(axis=0), 0.8, rtol=0.1)  # 1200 fixes: 2 % sigma of a sigma
    # stamped 0.15 s late: against the truth at the stamp the moving fixes lag by 0.15 m
    lla_at_stamp, vel = truth_at(tr, log.gnss.t[~out], log.truth.gnss_lever_arm_base)
    lag = earth.dlla_to_ned(log.gnss.lla[~out] - lla_at_stamp, lla_at_stamp)
    mv = np.linalg.norm(vel, axis=1) > 0.99
    along = -np.sum(lag[mv, :2] * vel[mv, :2], axis=1)
    assert along.mean() == pytest.approx(0.15, abs=4 * 0.8 / np.sqrt(mv.sum()))
