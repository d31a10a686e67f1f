"""GNSS simulator: lever arm, latency, noise statistics, Gauss-Markov correlation, dropouts and outages."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.sim.gnss import outage_schedule, simulate_gnss, truth_at
from imunav.sim.vehicle import demo_drive, speed_change, straight, turn, vehicle_trajectory
from imunav.units import DEG

ORIGIN = np.array([30.4 * DEG, 114.5 * DEG, 20.0])
TINY = 1e-9  # white noise small enough to read the geometry


@pytest.fixture(scope="module")
def drive():
    return vehicle_trajectory(demo_drive(400), fs=100, origin_lla=ORIGIN)


def _ned(lla):
    return earth.lla_to_ned(lla, ORIGIN)


def test_fixes_on_the_grid_are_the_truth_and_between_samples_interpolate(drive):
    g = simulate_gnss(drive, pos_noise=TINY, vel_noise=TINY, rng=0)
    idx = np.searchsorted(drive.t, g.t)
    assert np.abs(_ned(g.lla) - _ned(drive.pos_lla[idx])).max() < 1e-6
    assert np.abs(g.vel_ned - drive.vel_ned[idx]).max() < 1e-6
    # half-way between samples: within the cubic Hermite error h^4/384 |p''''| of the mean of the neighbours
    # corrected by the curvature term h^2/8 |a| (a <= 3 m/s^2, h = 10 ms: 4e-5 m)
    tm = drive.t[1000:3000:7] + 0.005
    lla, _ = truth_at(drive, tm)
    i = np.arange(1000, 3000, 7)
    mean = 0.5 * (_ned(drive.pos_lla[i]) + _ned(drive.pos_lla[i + 1]))
    assert np.abs(_ned(lla) - mean).max() < 5e-5


def test_lever_arm_moves_position_and_velocity():
    """Antenna 1 m ahead and 1.5 m up: north of the IMU by 1 m on a northward straight, 1.5 m higher, and
    in a right turn at yaw rate r its velocity gains r x l = r * 1 m to the east-ish (body y)."""
    tr = vehicle_trajectory([speed_change(10, 10), straight(5), turn(90, 10), straight(5)], fs=100, origin_lla=ORIGIN)
    la = (1.0, 0.0, -1.5)
    g0 = simulate_gnss(tr, pos_noise=TINY, vel_noise=TINY, rng=0)
    g1 = simulate_gnss(tr, pos_noise=TINY, vel_noise=TINY, lever_arm=la, rng=0)
    k = 12  # t = 12 s: straight north
    d = earth.lla_to_ned(g1.lla[k], g0.lla[k])  # in the local NED frame of the IMU
    np.testing.assert_allclose(d, [1.0, 0.0, -1.5], atol=1e-6)
    k = 20  # mid-turn, yaw 45 deg, yaw rate 2 * 90 deg / 10 s = 0.314 rad/s
    yaw_rate = tr.omega_nb_b[np.searchsorted(tr.t, g1.t[k]), 2]
    dv = g1.vel_ned[k] - g0.vel_ned[k]
    np.testing.assert_allclose(np.linalg.norm(dv[:2]), abs(yaw_rate) * 1.0, rtol=1e-4)
    head = np.arctan2(g0.vel_ned[k, 1], g0.vel_ned[k, 0])
    np.testing.assert_allclose(np.arctan2(dv[1], dv[0]), head + np.pi / 2, atol=1e-4)  # body +y


def test_latency_shifts_the_content_not_the_stamps(drive):
    g = simulate_gnss(drive, pos_noise=TINY, vel_noise=TINY, latency_s=0.13, rng=0)
    lla, vel = truth_at(drive, g.t - 0.13)
    assert np.abs(_ned(g.lla) - _ned(lla)).max() < 1e-6
    assert np.abs(g.vel_ned - vel).max() < 1e-6
    lla_now, _ = truth_at(drive, g.t)
    assert np.abs(_ned(g.lla) - _ned(lla_now)).max() > 1.0  # 0.13 s at 15-22 m/s


def test_noise_statistics_and_reported_sigma(drive):
    """White: sample std within 5 chi^2 sigmas of the setting; Gauss-Markov: lag-1 autocorrelation e^(-1/T)
    within 5 / sqrt(n); the reported sigma is sqrt(white^2 + correlated^2)."""
    g = simulate_gnss(drive, pos_noise=(0.5, 0.6, 1.0), vel_noise=(0.05, 0.05, 0.1), rng=7)
    lla, vel = truth_at(drive, g.t)
    e = _ned(g.lla) - _ned(lla)
    n = g.n
    tol = 5 * np.sqrt(1 / (2 * n))
    np.testing.assert_allclose(e.std(axis=0) / [0.5, 0.6, 1.0], 1.0, atol=tol)
    np.testing.assert_allclose((g.vel_ned - vel).std(axis=0) / [0.05, 0.05, 0.1], 1.0, atol=tol)
    gm = simulate_gnss(drive, pos_noise=1e-3, pos_corr_sigma=2.0, pos_corr_tau=5.0, vel_noise=None, rng=8)
    e = _ned(gm.lla) - _ned(truth_at(drive, gm.t)[0])
    rho = [np.corrcoef(e[:-1, j], e[1:, j])[0, 1] for j in range(3)]
    np.testing.assert_allclose(rho, np.exp(-1 / 5.0), atol=5 / np.sqrt(gm.n))
    np.testing.assert_allclose(gm.pos_std[0], np.sqrt(1e-6 + 4.0))
    assert gm.vel_ned is None


def test_outages_and_dropouts_are_removed_and_recorded(drive):
    out = outage_schedule(drive.t[0] + 100, drive.t[-1], every_s=180, length_s=60, first_s=0)
    assert out == [(100.0, 60.0), (280.0, 60.0)]
    g = simulate_gnss(drive, dropout_prob=0.1, outages=out, rng=3)
    for s, d in out:
        assert not np.any((g.t >= s) & (g.t < s + d))
    removed = {r["reason"]: r["epochs"] for r in g.meta["removed"]}
    full = 401
    assert removed["random dropout"] + removed["scheduled outage"] + g.n == full
    # dropouts: binomial(401, 0.1), 5 sigma
    assert abs(removed["random dropout"] - 40.1) < 5 * np.sqrt(401 * 0.1 * 0.9)
    again = simulate_gnss(drive, dropout_prob=0.1, outages=out, rng=3)
    np.testing.assert_array_equal(again.lla, g.lla)  # seeded


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"pos_noise": 0.0}, "pos_noise"),
        ({"vel_noise": (0.1, 0.0, 0.1)}, "vel_noise"),
        ({"latency_s": -0.1}, "latency"),
        ({"dropout_prob": 1.0}, "dropout"),
        ({"rate_hz": 1000.0}, "rate_hz"),
    ],
)
def test_bad_settings_are_refused(drive, kw, match):
    with pytest.raises(InvalidInputError, match=match):
        simulate_gnss(drive, **kw)
