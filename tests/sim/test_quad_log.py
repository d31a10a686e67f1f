"""The simulated quadrotor flight written as a PX4 ULog goes through the PX4 readers (imunav.sim.quad_log,
imunav.io.ulog.write_ulog, imunav.io.navlog) back to what was written, to PX4's quantisation."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.io.navlog import read_nav_sources
from imunav.io.ulog import read_px4_groundtruth
from imunav.sim.quad_log import QUAD_T0_NS, simulate_quad_log, write_quad_ulog

pytest.importorskip("pyulog")


@pytest.fixture(scope="module")
def quad(tmp_path_factory):
    log = simulate_quad_log(2, duration_s=90.0)
    p = write_quad_ulog(log, tmp_path_factory.mktemp("quad") / "quad.ulg")
    return log, p


def test_flight_is_a_multirotor(quad):
    log, _ = quad
    tr = log.truth.trajectory
    e = tr.euler()
    assert np.degrees(np.abs(e[:, :2]).max()) < 12.0  # banks ~7 deg in the 1.2 m/s^2 turns
    assert np.linalg.norm(tr.vel_ned, axis=1).max() == pytest.approx(6.0, abs=1e-6)
    assert tr.pos_lla[:, 2].max() - tr.pos_lla[0, 2] == pytest.approx(20.0, abs=1e-3)
    # thrust along -z body: the specific force has no body x / y part beyond the IMU noise and Earth rate
    f = log.imu.accel
    assert np.abs(np.median(f[:, :2], axis=0)).max() < 0.5 and np.median(f[:, 2]) == pytest.approx(-9.8, abs=0.3)


def test_ulog_round_trip(quad):
    log, p = quad
    s = read_nav_sources(p)
    assert s.t0_ns == log.truth.boot0_us * 1000 and s.time_is_utc and s.utc_t0_ns == QUAD_T0_NS
    assert {k: v.topic for k, v in s.topics.items()} == {
        "imu": "sensor_combined", "gnss": "vehicle_gps_position", "mag": "vehicle_magnetometer",
        "baro": "vehicle_air_data"}
    f32 = np.float32
    np.testing.assert_allclose(s.imu.t, log.imu.t, rtol=0, atol=1e-9)  # integer us of k / 250 Hz
    np.testing.assert_array_equal(s.imu.gyro, log.imu.gyro.astype(f32))
    np.testing.assert_array_equal(s.imu.accel, log.imu.accel.astype(f32))
    g = s.gnss
    np.testing.assert_allclose(g.t, log.gnss.t, rtol=0, atol=1e-9)
    d = earth.dlla_to_ned(g.lla - log.gnss.lla, log.gnss.lla)
    assert np.abs(d[:, :2]).max() < 0.5e-7 * np.pi / 180 * 6.4e6  # lat / lon in 1e-7 deg
    assert np.abs(d[:, 2]).max() <= 0.5e-3 + 1e-9  # ellipsoidal height in mm
    np.testing.assert_array_equal(g.vel_ned, log.gnss.vel_ned.astype(f32))
    np.testing.assert_array_equal(g.pos_std[:, 0], log.gnss.pos_std[:, 0].astype(f32))
    assert g.meta["height"] == "ellipsoid (PX4 alt_ellipsoid)"
    # magnetometer and barometer on their sample stamps (published 2 ms later)
    np.testing.assert_allclose(s.mag.t, log.mag.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(s.mag.field_b, (log.mag.field_b / 100).astype(f32).astype(float) * 100.0, rtol=1e-15)
    np.testing.assert_allclose(s.baro.t, log.baro.t, rtol=0, atol=1e-9)
    # float32 pressure: 2^-24 relative, about 6 mPa, 0.5 mm of height
    np.testing.assert_allclose(s.baro.height, log.baro.height, rtol=0, atol=2e-3)
    # GPS time of the first IMU sample: 2024-05-14T10:00:00Z + 18 s in week 2314
    assert s.gps_time([0.0]).sow[0] == pytest.approx(2 * 86400 + 10 * 3600 + 18, abs=1e-9)


def test_groundtruth_reference_track(quad):
    log, p = quad
    s = read_nav_sources(p)
    ref = read_px4_groundtruth(p, t0_ns=s.t0_ns)
    tr = log.truth.trajectory
    k = slice(0, tr.n, 25)
    np.testing.assert_allclose(ref.t, tr.t[k], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ref.lla[:, :2], tr.pos_lla[k, :2], rtol=0, atol=1e-15)  # doubles in degrees
    np.testing.assert_allclose(ref.lla[:, 2], tr.pos_lla[k, 2], rtol=0, atol=1e-4)  # float32 of ~550 m
    np.testing.assert_allclose(ref.vel_ned, tr.vel_ned[k], rtol=0, atol=1e-6)
    np.testing.assert_allclose(ref.q_nb, tr.q_nb[k], rtol=0, atol=1e-7)
    assert ref.meta["altitude_filled"]
