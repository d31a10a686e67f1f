"""Gait simulator truth, 15-state bias recovery, strapdown convergence and NED static oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imunav.earth import radii_gravity_1
from imunav.errors import InvalidInputError
from imunav.ins import ZuptConfig, ZuptFilter, coning_sculling_increments, strapdown_local, strapdown_ned
from imunav.sim.gait import simulate_gait
from imunav.timeseries import ImuData


def test_fifteen_state_biases_inside_3sigma():
    """Simulated walk/run/stairs with MEMS errors: estimated biases within 3 sigma of the truth."""
    for seed in (0, 1):
        sim = simulate_gait(["walk", "run", "stairs"], 30, error_model="foot_mems", rng=seed, turn_deg=12)
        res = ZuptFilter(ZuptConfig(g=9.80665, states=15, zaru=True, integration="coning")).run(sim.imu, sim.stance)
        sd = np.sqrt(res.cov_diag[-1])
        np.testing.assert_array_less(np.abs(res.gyro_bias[-1] - sim.gyro_bias[-1]), 3 * sd[12:15])
        np.testing.assert_array_less(np.abs(res.accel_bias[-1] - sim.accel_bias[-1]), 3 * sd[9:12])
        # the position is good to a few cm over ~40 m
        assert np.linalg.norm(res.position[-1] - sim.position[-1]) < 0.05


def test_ideal_gait_zupt_exact_and_stairs_height():
    sim = simulate_gait("stairs", 10, error_model=None, rng=3)
    assert sim.position[-1, 2] == pytest.approx(-10 * 0.34)  # NED: up is negative
    assert np.all(np.linalg.norm(sim.velocity[sim.stance], axis=1) == 0)
    res = ZuptFilter(ZuptConfig(g=9.80665, integration="coning")).run(sim.imu, sim.stance)
    np.testing.assert_allclose(res.position[-1], sim.position[-1], atol=5e-3)
    with pytest.raises(InvalidInputError, match="gait mode"):
        simulate_gait("crawl")


def test_strapdown_second_order_convergence():
    """Free inertial integration of the ideal run: error / 25 when the rate x5 (trapezoid + corrections)."""
    errs = []
    for fs in (200.0, 1000.0):
        sim = simulate_gait("run", 4, error_model=None, rng=1, fs=fs)
        st = strapdown_local(sim.imu, sim.q_nb[0], g=9.80665)
        errs.append(np.linalg.norm(st.velocity[-1] - sim.velocity[-1]))
    assert errs[0] < 0.1
    assert errs[1] < errs[0] / 10


def test_coning_correction_closed_form():
    """Two-sample coning/sculling terms equal the cross-product formulas."""
    n = 4
    t = np.arange(n) * 0.01
    w = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 1.0, 0], [0, 0, 1.0]])
    a = np.array([[0.0, 0, -9.8], [0, 1.0, -9.8], [1.0, 0, -9.8], [0, 0, -9.8]])
    data = ImuData(t, w, a)
    th0, v0 = coning_sculling_increments(data, corrected=False)
    np.testing.assert_allclose(th0[2], w[2] * 0.01)
    th, v = coning_sculling_increments(data, corrected=True)
    # raw increments: the cubic rule inside, the quadratic through samples 0-2 on the first interval
    a1 = (-w[0] + 13 * w[1] + 13 * w[2] - w[3]) * 0.01 / 24
    a0 = (5 * w[0] + 8 * w[1] - w[2]) * 0.01 / 12
    np.testing.assert_allclose(th[2], a1 + np.cross(a0, a1) / 12)
    b1 = (-a[0] + 13 * a[1] + 13 * a[2] - a[3]) * 0.01 / 24
    b0 = (5 * a[0] + 8 * a[1] - a[2]) * 0.01 / 12
    np.testing.assert_allclose(v[2], b1 + 0.5 * np.cross(a1, b1) + (np.cross(a0, b1) + np.cross(b0, a1)) / 12)


def _one_axis(t, x):
    """Rates along x only: the coning, rotation and sculling terms vanish, the increments are the raw integrals."""
    z = np.zeros((t.size, 3))
    z[:, 0] = x
    return coning_sculling_increments(ImuData(t, z, z.copy()), corrected=True)[0][:, 0]


def test_increments_integrate_cubics_exactly_on_a_jittered_grid():
    """The increments of point samples integrate any cubic exactly where the interval has a sample on each side
    within 1.5 of its step (jitter of +-15 %), and any quadratic at the ends and beside a 0.5 s gap (one side
    left out): oracle, the polynomial's own integral, to rounding."""
    rng = np.random.default_rng(0)
    h = 1 / 30
    t = np.cumsum(h * (1 + rng.uniform(-0.15, 0.15, 200)))
    t[120:] += 0.5  # a gap: interval 120 spans 0.53 s; its neighbours have no usable sample on that side
    for deg, coef in ((3, [0.3, -1.2, 0.7, 2.0]), (2, [0.0, -1.2, 0.7, 2.0])):
        p = np.polynomial.Polynomial(coef[::-1] if deg == 3 else coef[1:][::-1])
        got = _one_axis(t, p(t))
        exact = np.diff(p.integ()(t))
        err = np.abs(got[1:] - exact)
        edge = np.zeros(t.size - 1, dtype=bool)
        edge[[0, 118, 119, 120, 121, t.size - 2]] = True  # the ends and the gap: quadratics or the trapezoid
        assert err[~edge].max() < 1e-11, (deg, err[~edge].max())
        if deg == 2:
            assert err[edge & (np.arange(t.size - 1) != 119)].max() < 1e-11  # quadratics at the ends
    assert got[0] == 0.0


def test_increments_keep_a_sinusoid_at_30_hz():
    """A 2.6 Hz sinusoid sampled at 30 Hz (x = 2 pi f h = 0.545 rad per step): its angle increments equal the
    exact ones within 11 x^4 / 720 = 0.13 % of their amplitude (the cubic rule's error), where the trapezoid's
    (x/2) cot(x/2) shrinks them by 2.5 %."""
    f, fs = 2.6, 30.0
    t = np.arange(600) / fs
    w = 2 * math.pi * f
    got = _one_axis(t, np.cos(w * t))[2:-1]
    exact = np.diff(np.sin(w * t))[1:-1] / w
    amp = 2 * math.sin(w / fs / 2) / w  # amplitude of the exact increments
    x = w / fs
    rel = np.abs(got - exact).max() / amp
    assert 0.9 * 11 * x**4 / 720 < rel < 1.05 * 11 * x**4 / 720, rel


def test_ned_static_on_rotating_earth():
    """A static IMU measuring Earth rate and normal gravity stays put for 10 min (Coriolis/transport consistent)."""
    lat, h = math.radians(45.0), 100.0
    RN, RE, g = radii_gravity_1(lat, h)
    # Somigliana normal gravity at 45 deg, sea level: 9.806199 m/s^2 (WGS84 closed form); free-air -3.086e-6/m
    assert radii_gravity_1(lat, 0.0)[2] == pytest.approx(9.806199, abs=2e-6)
    assert g == pytest.approx(9.806199 - 3.086e-4, abs=2e-6)
    we = 7.292115e-5
    n = 6001
    t = np.arange(n) * 0.1
    gyro = np.tile([we * math.cos(lat), 0.0, -we * math.sin(lat)], (n, 1))
    accel = np.tile([0.0, 0.0, -g], (n, 1))
    st = strapdown_ned(ImuData(t, gyro, accel), [1, 0, 0, 0], [lat, 0.3, h])
    dn = (st.lla[-1, 0] - lat) * (RN + h)
    de = (st.lla[-1, 1] - 0.3) * (RE + h) * math.cos(lat)
    assert abs(dn) < 1e-3 and abs(de) < 1e-3 and abs(st.lla[-1, 2] - h) < 1e-3
    np.testing.assert_allclose(st.q_nb[-1], [1, 0, 0, 0], atol=1e-9)
    with pytest.raises(InvalidInputError, match="pole"):
        strapdown_ned(ImuData(t[:5], gyro[:5], accel[:5]), [1, 0, 0, 0], [math.pi / 2, 0, 0])
    with pytest.raises(InvalidInputError, match="unit quaternion"):
        strapdown_local(ImuData(t[:5], gyro[:5], accel[:5]), [1, 1, 0, 0])


def test_plots_run(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from imunav.ins import detect_zero_velocity
    from imunav.ins.zupt.plot import plot_trajectory, plot_zero_velocity

    sim = simulate_gait("walk", 4, error_model=None, rng=0)
    res = ZuptFilter().run(sim.imu, sim.stance)
    ax = plot_trajectory(res, sim.position)
    assert len(ax.lines) == 3
    ax = plot_zero_velocity(sim.imu, {"truth": sim.stance, "shoe": detect_zero_velocity(sim.imu, "shoe")})
    ax.figure.savefig(tmp_path / "zv.png")
    assert (tmp_path / "zv.png").stat().st_size > 0
