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


SLIP, IDLE = (0.1, 0.04), 0.02


def _shaken(T, fs, rng=1, **kw):
    """The demo drive with side slip, suspension and idle vibration, and the same drive unperturbed."""
    d = demo_drive(T)
    return (vehicle_trajectory(d, fs=fs, origin_lla=ORIGIN, slip_std=SLIP, idle_vibration_std=IDLE, rng=rng, **kw),
            vehicle_trajectory(d, fs=fs, origin_lla=ORIGIN))


def test_slip_bounce_and_idle_vibration_of_the_body():
    """The perturbation is a body velocity: attitude and body rate stay those of the manoeuvres; in motion the body
    gains a lateral and a vertical velocity of sigma SLIP and no forward one, at rest one of sigma IDLE on every
    axis.  A band-limited signal of B = 10 Hz over T s has about 2 B T independent samples: its sample sigma is
    within 1 / sqrt(4 B T) (1 % over 260 s in motion, 3 % over the 28 s of stops) of its sigma; asserted at
    5 of those.  At rest the position stays within sqrt(2 M) sigma / (2 pi f_low) of where it stood."""
    tr, ref = _shaken(300, 100)
    assert np.array_equal(tr.q_nb, ref.q_nb) and np.array_equal(tr.omega_nb_b, ref.omega_nb_b)
    c = dcm_from_quat(tr.q_nb)
    dv = np.einsum("nji,nj->ni", c, tr.vel_ned - ref.vel_ned)
    s = np.linalg.norm(ref.vel_ned, axis=1)
    moving, rest = s > 0.5, s == 0.0
    assert np.abs(dv[moving, 0]).max() < 1e-12
    t_move, t_rest = moving.sum() / 100, rest.sum() / 100
    assert t_move > 250 and t_rest > 25
    np.testing.assert_allclose(dv[moving, 1:].std(axis=0), SLIP, rtol=5 / np.sqrt(40 * t_move))
    np.testing.assert_allclose(dv[rest].std(axis=0), IDLE, rtol=5 / np.sqrt(40 * t_rest))
    assert np.abs(dv[moving, 1:].mean(axis=0)).max() < 0.1 * min(SLIP)
    ned = earth.lla_to_ned(tr.pos_lla, ORIGIN)
    first_stop = slice(0, int(np.argmin(rest)))
    assert np.ptp(ned[first_stop], axis=0).max() < 2 * 8 * IDLE / (2 * np.pi * 0.5)
    assert np.ptp(ned[first_stop], axis=0).max() > IDLE / (2 * np.pi * 10.5)  # it does move
    # seeded: the same draw again, another seed another one
    again, _ = _shaken(300, 100)
    other, _ = _shaken(300, 100, rng=2)
    assert np.array_equal(again.vel_ned, tr.vel_ned) and not np.allclose(other.vel_ned, tr.vel_ned, atol=1e-3)


def test_perturbed_derivatives_are_exact():
    """accel_ned is the derivative of the perturbed vel_ned: central differences agree to their truncation
    error, which falls 4x when the step halves (a missing or wrong term would not shrink); the perturbation's
    own acceleration is 10x larger than that residual."""
    err = []
    for fs in (200, 400):
        tr, ref = _shaken(120, fs)
        a = np.gradient(tr.vel_ned, tr.t, axis=0)
        err.append(np.abs(a - tr.accel_ned)[1:-1].max())
        assert np.abs(tr.accel_ned - ref.accel_ned).max() > 10 * err[-1]
    assert err[1] < err[0] / 3, err


def test_noise_free_imu_follows_the_shaken_truth():
    """With slip, suspension and idle vibration, the error-free IMU integrated by ins.strapdown_ned still follows
    the truth (200 s at 200 Hz: measured 1.0 mm horizontal, 0.02 mm vertical, 0.001 arcsec), as closely as on the
    same drive without them (1.0 mm: the mechanization's own residue, halving with the step): the fourth-order
    integration of the point samples leaves nothing of the vibration (the trapezoid left 14 mm, falling 4x per
    halving), no model mismatch."""
    tr, ref = _shaken(200, 200)
    hz, vt, ang = _strapdown_errors(tr, ideal_imu(tr))
    assert hz.max() < 2e-3 and vt.max() < 1e-4 and ang.max() < 0.01 * ARCSEC, (hz.max(), vt.max(), ang.max())
    hz0, _, _ = _strapdown_errors(ref, ideal_imu(ref))
    assert abs(hz.max() - hz0.max()) < 0.1 * hz0.max(), (hz.max(), hz0.max())


def test_odometer_reads_the_forward_speed_under_slip():
    """Side slip and suspension velocity are perpendicular to the wheel's forward axis: the odometer reads what it
    reads without them (to the transport-rate change, ~1e-8 m/s); at rest it reads the body's fore-aft idle
    velocity at the wheel."""
    tr, ref = _shaken(120, 100)
    lever = (0.0, 0.8, 0.3)
    a, b = simulate_odometer(tr, lever_arm=lever), simulate_odometer(ref, lever_arm=lever)
    s = np.linalg.norm(ref.vel_ned, axis=1)
    assert np.abs(a.speed - b.speed)[s > 0.5].max() < 1e-6
    rest = s == 0.0
    v_b = np.einsum("nji,nj->ni", dcm_from_quat(tr.q_nb), tr.vel_ned)
    np.testing.assert_allclose(a.speed[rest], v_b[rest, 0], atol=1e-6)  # + Earth rate x lever arm
    assert a.speed[rest].std() > 0.5 * IDLE


def test_zero_perturbation_is_the_plain_drive():
    d = demo_drive(120)
    plain = vehicle_trajectory(d, fs=50, origin_lla=ORIGIN)
    zero = vehicle_trajectory(d, fs=50, origin_lla=ORIGIN, slip_std=(0.0, 0.0), idle_vibration_std=0.0,
                              vibration_band_hz=(30.0, 40.0), rng=3)
    for f in ("t", "q_nb", "vel_ned", "pos_lla", "omega_nb_b", "accel_ned"):
        assert np.array_equal(getattr(plain, f), getattr(zero, f)), f


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"slip_std": (-0.1, 0.0)}, "slip_std"),
        ({"slip_std": (np.nan, 0.0)}, "slip_std"),
        ({"slip_std": 0.1}, "slip_std"),
        ({"idle_vibration_std": -0.01}, "idle_vibration_std"),
        ({"idle_vibration_std": np.inf}, "idle_vibration_std"),
        ({"idle_vibration_std": 0.01, "vibration_band_hz": (0.5, 60.0)}, "fs/2 = 50"),
        ({"slip_std": (0.1, 0.1), "vibration_band_hz": (0.0, 5.0)}, "vibration_band_hz"),
        ({"slip_std": (0.1, 0.1), "vibration_band_hz": (5.0, 2.0)}, "vibration_band_hz"),
    ],
)
def test_bad_perturbations_are_refused(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        vehicle_trajectory([stop(5), speed_change(5, 5)], fs=100, **kw)
