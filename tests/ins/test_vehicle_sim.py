"""Vehicle truth generator, odometer and barometer: closed-form oracles and the strapdown round trip."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.ins.strapdown import strapdown_ned
from imunav.rotation import dcm_from_quat, euler_from_quat, quat_conjugate, quat_multiply, rotvec_from_quat
from imunav.sim import ideal_imu, presets, simulate_imu
from imunav.sim.trajectory import body_rate_from_attitude
from imunav.sim.vehicle import (
    demo_drive,
    hill,
    simulate_baro,
    simulate_odometer,
    speed_change,
    stop,
    straight,
    turn,
    vehicle_trajectory,
)
from imunav.units import ARCSEC, DEG

ORIGIN = np.array([30.4 * DEG, 114.5 * DEG, 20.0])


def _strapdown_errors(truth, imu):
    """Horizontal / vertical position error (m) and attitude error (rad), per sample."""
    r = strapdown_ned(imu, truth.q_nb[0], truth.pos_lla[0], v0=truth.vel_ned[0])
    d = earth.lla_to_ned(r.lla, truth.pos_lla[0]) - earth.lla_to_ned(truth.pos_lla, truth.pos_lla[0])
    ang = np.linalg.norm(rotvec_from_quat(quat_multiply(quat_conjugate(truth.q_nb), r.q_nb)), axis=1)
    return np.hypot(d[:, 0], d[:, 1]), np.abs(d[:, 2]), ang


def test_straight_drive_distance_and_heading_are_the_closed_form():
    """Rest, 0 -> 20 m/s in 10 s (distance V T / 2 = 100 m), 100 s at 20 m/s (2000 m), 20 -> 0 in 10 s (100 m):
    2200 m along heading 60 deg.  The tangent-plane distance differs from the ellipsoid arc by
    d^3 / (3 R^2) ~ 1e-4 m; a constant heading is a rhumb line, whose chord from the origin turns by half the
    meridian convergence, dlon sin(lat) / 2."""
    tr = vehicle_trajectory([stop(5), speed_change(20, 10), straight(100), speed_change(0, 10)], fs=100,
                            origin_lla=ORIGIN, heading0_deg=60.0)
    ned = earth.lla_to_ned(tr.pos_lla[-1], ORIGIN)
    assert np.hypot(ned[0], ned[1]) == pytest.approx(2200.0, abs=2e-3)
    dlon = tr.pos_lla[-1, 1] - ORIGIN[1]
    assert dlon == pytest.approx(2200 * np.sin(60 * DEG) / (earth.radii(ORIGIN[0])[1] * np.cos(ORIGIN[0])), rel=1e-3)
    az = 60.0 - np.degrees(dlon * np.sin(ORIGIN[0]) / 2)
    assert np.degrees(np.arctan2(ned[1], ned[0])) == pytest.approx(az, abs=1e-5)
    assert abs(ned[2]) < 0.5  # the tangent plane drops below the ellipsoid by d^2 / (2R) = 0.38 m
    assert tr.pos_lla[-1, 2] == pytest.approx(20.0, abs=1e-9)
    assert np.abs(tr.vel_ned[-1]).max() < 1e-12
    assert np.linalg.norm(tr.vel_ned[tr.n // 2]) == pytest.approx(20.0, abs=1e-12)


def test_turn_and_hill_reach_their_targets():
    """turn(+90) ends 90 deg to the right; a 3 deg hill of 40 s with 5 s ramps at 10 m/s climbs
    10 * sin(3 deg) * (40 - 5) m (each Hann ramp averages half the grade), to |sin g - g| <= g^3/6."""
    tr = vehicle_trajectory([speed_change(10, 10), turn(90, 8), straight(5), hill(3, 40, 5), straight(5)],
                            fs=100, origin_lla=ORIGIN)
    yaw = euler_from_quat(tr.q_nb)[:, 2]
    assert np.degrees(yaw[-1]) == pytest.approx(90.0, abs=1e-9)
    g = 3 * DEG
    climb = tr.pos_lla[-1, 2] - tr.pos_lla[0, 2]
    assert climb == pytest.approx(10 * g * 35, rel=g**2 / 6 + 1e-6)
    assert np.degrees(euler_from_quat(tr.q_nb)[tr.n - 2000, 1]) == pytest.approx(3.0, abs=1e-9)  # pitch on the hill


def test_derivative_fields_match_the_sampled_motion():
    """omega_nb_b, accel_ned and vel_ned are exact; finite differences of the sampled attitude, velocity and
    position agree to their second-order truncation error (dt = 5 ms)."""
    tr = vehicle_trajectory(demo_drive(200), fs=200, origin_lla=ORIGIN)
    w = body_rate_from_attitude(tr.t, tr.q_nb)
    assert np.abs(w - tr.omega_nb_b)[1:-1].max() < 1e-6
    a = np.gradient(tr.vel_ned, tr.t, axis=0)
    assert np.abs(a - tr.accel_ned)[1:-1].max() < 1e-4
    ned = earth.lla_to_ned(tr.pos_lla, ORIGIN)
    v_tp = np.gradient(ned, tr.t, axis=0)  # tangent-plane velocity: within 1e-3 of v^n a few km from the origin
    assert np.abs(v_tp - tr.vel_ned)[1:-1].max() < 2e-3 * np.abs(tr.vel_ned).max()
    # no side slip / vertical body velocity: the non-holonomic constraint holds exactly
    v_b = np.einsum("nji,nj->ni", dcm_from_quat(tr.q_nb), tr.vel_ned)
    assert np.abs(v_b[:, 1:]).max() < 1e-12


def _drive_errors(T, fs, **ideal_kw):
    tr = vehicle_trajectory(demo_drive(T), fs=fs, origin_lla=ORIGIN)
    return _strapdown_errors(tr, ideal_imu(tr, **ideal_kw))


def test_noise_free_imu_follows_the_truth_through_the_ned_mechanization():
    """10 min of driving (8.4 km, turns, hills, stops): the error-free IMU of the generator, integrated by
    ins.strapdown_ned, stays within 5 mm horizontally, 1 mm vertically and 0.1 arcsec (measured 3.2 mm,
    0.4 mm, 0.04 arcsec at 200 Hz).  Halving the step divides the horizontal error by more than 3: the
    residual is the mechanization's second-order truncation, not a model mismatch between the simulator
    and the mechanization (a mismatch does not shrink with the step)."""
    hz, vt, ang = _drive_errors(600, 200)
    assert hz.max() < 5e-3 and vt.max() < 1e-3 and ang.max() < 0.1 * ARCSEC
    hz2, _, _ = _drive_errors(600, 400)
    assert hz2.max() < hz.max() / 3


def test_a_model_mismatch_is_caught():
    """The check above can fail: an IMU without the transport rate (what a flat-Earth simulator would give)
    drifts by metres through the NED mechanization within 10 min."""
    hz, _, ang = _drive_errors(600, 100, transport_rate=False)
    assert hz.max() > 1.0 and ang.max() > 10 * ARCSEC


@pytest.mark.slow
def test_one_hour_drive_round_trip():
    """1 h, 53 km at 200 Hz: attitude within 0.2 arcsec, horizontal 5 cm, vertical 0.2 m (measured 0.04 arcsec,
    2.1 cm, 9 cm: the free-inertial vertical channel amplifies the truncation error by e^(t/570 s))."""
    hz, vt, ang = _drive_errors(3600, 200)
    assert ang.max() < 0.2 * ARCSEC and hz.max() < 0.05 and vt.max() < 0.2


def test_presets_drive_the_generator():
    """simulate_imu on the vehicle truth with the new presets: the Gauss-Markov bias of navigation_a15 and
    ADIS16465's noise show in the static part (first 20 s) with the preset's magnitudes."""
    tr = vehicle_trajectory(demo_drive(120), fs=200, origin_lla=ORIGIN)
    ideal = ideal_imu(tr)
    rest = slice(0, 20 * 200)
    for name, arw in (("navigation_a15", 0.003), ("mems_adis16465", 0.15)):
        imu = simulate_imu(tr, presets.get(name), rng=3)
        dg = (imu.gyro - ideal.gyro)[rest]
        # per-sample sigma = N sqrt(fs); bias sigma of the navigation unit is far below it
        n_sigma = arw * DEG / 60 * np.sqrt(200)
        s = dg.std(axis=0)
        assert np.all(np.abs(s / n_sigma - 1) < 0.1), (name, s / n_sigma)


def test_odometer_sees_the_lever_arm_in_a_turn():
    """A wheel 0.8 m to the right in a right turn at 10 m/s reads (1 + k)(s - psidot l_y)."""
    tr = vehicle_trajectory([speed_change(10, 10), turn(90, 10), straight(2)], fs=100, origin_lla=ORIGIN)
    k = 0.01
    od = simulate_odometer(tr, lever_arm=(0.0, 0.8, 0.0), scale_factor=k)
    s = np.linalg.norm(tr.vel_ned, axis=1)
    psidot = tr.omega_nb_b[:, 2]
    expected = (1 + k) * (s - psidot * 0.8)
    assert np.abs(od.speed - expected).max() < 1e-4 * 10  # the transport-rate term is ~1e-5 rad/s x 0.8 m
    assert np.abs(od.speed - (1 + k) * s).max() > 0.1  # the lever arm matters in the turn
    noisy = simulate_odometer(tr, noise_std=0.05, rate_hz=10, rng=1)
    assert noisy.t.size == 221 and 0.04 < np.std(noisy.speed - s[::10]) < 0.06


def test_baro_height_error_statistics():
    """White noise only: the residual std is noise_std within 5 chi^2 sigmas (n = 1201, rel. sd 2 %)."""
    tr = vehicle_trajectory(demo_drive(120), fs=100, origin_lla=ORIGIN)
    b = simulate_baro(tr, noise_std=0.5, bias_std=0.0, rng=2)
    r = b.height - tr.pos_lla[::10, 2]
    assert r.size == 1201
    assert abs(r.std() / 0.5 - 1) < 5 * np.sqrt(1 / (2 * r.size))
    with pytest.raises(InvalidInputError):
        simulate_baro(tr, noise_std=-1)


@pytest.mark.parametrize(
    "drive, kw, match",
    [
        ([speed_change(5, 5), stop(5)], {}, "brake first"),
        ([speed_change(-5, 5)], {}, ">= 0"),
        ([hill(3, 10, 1)], {}, "standstill"),
        ([straight(10)], {"origin_lla": (30.0, 114.0, 0.0)}, "radians"),
        ([], {}, "at least one"),
    ],
)
def test_bad_drives_are_refused(drive, kw, match):
    with pytest.raises(InvalidInputError, match=match):
        vehicle_trajectory(drive, **kw)
