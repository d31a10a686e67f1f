"""The MEKF's generalisation features, each against a closed form or a constructed case.

Rate-dependent gyro noise, the low-pass rest test, the magnetometer's
minimum undisturbed time and the consider (Schmidt) heading update; all
through the public ``MEKF`` / ``AdaptiveMEKF`` ``run`` on an ``ImuData``.
"""

from dataclasses import replace

import numpy as np
import pytest
from builders import MAG_NED, angle_err_deg, rotating_imu

from imunav.attitude import AdaptiveMEKF
from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS
from imunav.attitude.mekf import MEKF, MekfConfig
from imunav.errors import ConfigError, InvalidInputError
from imunav.rotation import quat_conjugate, quat_exp, quat_from_euler, quat_rotate
from imunav.timeseries import ImuData


def _static(n, fs, *, q=None, bias=(0.0, 0.0, 0.0), sg=0.0, sa=0.0, sm=0.0, acc_scale=1.0, seed=0):
    r = np.random.default_rng(seed)
    q = quat_from_euler(0.1, -0.05, 0.7) if q is None else q
    qc = np.tile(quat_conjugate(q), (n, 1))
    f = acc_scale * quat_rotate(qc, np.tile([0, 0, -9.81], (n, 1))) + r.normal(0, sa, (n, 3))
    m = quat_rotate(qc, np.tile(MAG_NED, (n, 1))) + r.normal(0, sm, (n, 3))
    w = np.asarray(bias) + r.normal(0, sg, (n, 3))
    return ImuData(t=np.arange(n) / fs, gyro=w, accel=f, mag=m), q


def test_rate_dependent_gyro_noise_matches_closed_form():
    """No aiding, constant rate ω about z: P_zz(t) = p0² + (σ_g² + k² ω²) t + p0_b² t² + σ_b² t³ / 3."""
    fs, n, w = 100.0, 1000, 2.0
    sg, k, p0, p0b, sb = 0.002, 0.004, 0.01, 0.001, 1e-4
    data = ImuData(t=np.arange(n) / fs, gyro=np.tile([0.0, 0.0, w], (n, 1)),
                   accel=np.tile([0.0, 0.0, -9.81], (n, 1)))
    prm = MekfConfig(gyro_noise_density=sg, k_gyro_rate=k, gyro_bias_random_walk=sb, accel_reject_threshold=0.0, use_mag=False,
                     init_att_std=p0, init_gyro_bias_std=p0b)
    r = MEKF(prm).run(data, q0=[1.0, 0, 0, 0])
    # the discrete z-axis recursion of δθ_{k+1} = δθ_k − Δt δb_k + w_k, δb_{k+1} = δb_k + w_b,k
    # (rotation about z leaves the z row alone), Var w_k = (σ_g² + k² ω²) Δt, Var w_b = σ_b² Δt
    dt = 1.0 / fs
    a, c, b = p0**2, 0.0, p0b**2
    expected = np.empty(n)
    for i in range(n):
        a, c, b = a - 2 * dt * c + dt**2 * b + (sg**2 + k**2 * w**2) * dt, c - dt * b, b + sb**2 * dt
        expected[i] = a
    np.testing.assert_allclose(r.cov_diag[:, 2], expected, rtol=1e-12)
    # its continuous limit: p0² + (σ_g² + k² ω²) t + p0_b² t² + σ_b² t³ / 3
    t = np.arange(1, n + 1) * dt
    np.testing.assert_allclose(expected, p0**2 + (sg**2 + k**2 * w**2) * t + p0b**2 * t**2 + sb**2 * t**3 / 3,
                               rtol=1e-4)
    # without the rate term the z variance grows by σ_g² only: the k term is what changed it
    r0 = MEKF(replace(prm, k_gyro_rate=0.0)).run(data, q0=[1.0, 0, 0, 0])
    assert r.cov_diag[-1, 2] - r0.cov_diag[-1, 2] == pytest.approx(k**2 * w**2 * t[-1], rel=1e-9)


def test_lowpass_rest_test_ignores_accel_scale_and_noise():
    """A still sensor whose accelerometer reads 3 % high and whose gyro is noisy with a 0.5 °/s bias.

    The plain test (| |f| − g | < 0.2 m/s² on every sample, |ω − b̂| < 0.02 rad/s) misses the rest;
    the low-pass test finds it, and the bias then converges inside its reported σ.
    """
    fs, n = 200.0, 4000
    bias = np.radians([0.5, -0.3, 0.45])
    data, q = _static(n, fs, bias=bias, sg=0.005, sa=0.02, sm=0.1, acc_scale=1.03, seed=3)
    plain = MEKF(MekfConfig(rest_gyro_threshold=0.02, rest_accel_threshold=0.2, rest_time=1.5, gyro_noise_density=0.003)).run(data)
    # zaru_noise_std is the gyro's per-sample noise: the zero-rate measurement is then modelled correctly
    lp = MEKF(MekfConfig(rest_gyro_threshold=0.035, rest_accel_threshold=0.5, rest_time=1.5, rest_lpf_time_constant=0.5, lpf_gyro_threshold=0.035,
                         gyro_noise_density=0.003, zaru_noise_std=0.005)).run(data)
    assert plain.flags["rest"].mean() < 0.05
    assert lp.flags["rest"][int(2.5 * fs):].all()
    z = (lp.bias[-1] - bias) / np.sqrt(lp.cov_diag[-1, 3:])
    assert np.all(np.abs(z) < 3.5), z
    # a rotation as slow as a bias but above lpf_gyro_threshold is not rest
    fast = replace(data, gyro=data.gyro + [0.0, 0.0, 0.05])
    clip = MekfConfig(rest_gyro_threshold=0.035, rest_accel_threshold=0.5, rest_lpf_time_constant=0.5, lpf_gyro_threshold=0.035, use_mag=False)
    assert not MEKF(clip).run(fast).flags["rest"].any()
    # the same steady 0.05 rad/s without the clip passes the deviation test: the clip is what refused it
    assert MEKF(replace(clip, lpf_gyro_threshold=1e9)).run(fast).flags["rest"][int(2.5 * fs):].all()


def _flicker_disturbance(n, fs, seed):
    """Still sensor; from 10 s to 40 s the field is disturbed (norm x 1.6), except for 0.2 s in every second, when it
    is a field of the right norm and dip turned 40° in heading: it passes the norm / dip test by chance."""
    data, q = _static(n, fs, sg=0.002, sa=0.02, sm=0.1, seed=seed)
    m = data.mag.copy()
    qc = quat_conjugate(q)
    turned = quat_rotate(qc, quat_rotate(quat_exp(np.array([0, 0, np.radians(40.0)])), MAG_NED))
    i0, i1 = int(10 * fs), int(40 * fs)
    m[i0:i1] *= 1.6
    for k in range(i0 + int(0.5 * fs), i1, int(fs)):
        m[k:k + int(0.2 * fs)] = turned
    return replace(data, mag=m), q


def test_min_undisturbed_time_rejects_chance_passes():
    fs, n = 100.0, 5000
    data, q = _flicker_disturbance(n, fs, 1)
    base = replace(ADAPTIVE_DEFAULTS, mag_min_undisturbed=0.0, heading_time_constant=2.0)  # a fast heading shows it best
    e0 = angle_err_deg(AdaptiveMEKF(base).run(data).q_nb, np.tile(q, (n, 1)))
    e1 = angle_err_deg(AdaptiveMEKF(replace(base, mag_min_undisturbed=0.5)).run(data).q_nb, np.tile(q, (n, 1)))
    seg = slice(int(15 * fs), int(40 * fs))
    assert e0[seg].max() > 2.0  # the chance passes pull the heading
    assert e1[seg].max() < 0.2  # with 0.5 s of continuous undisturbed field required they are never used


def test_consider_heading_update_leaves_the_bias_alone():
    """A field turned by 20° after 20 s (passes the tests once the reference re-adapts): with mag_bias=False the
    heading moves but the z-bias estimate stays put; with mag_bias=True the heading step leaks into the bias."""
    fs, n = 100.0, 6000
    data, q = _static(n, fs, sg=0.002, sa=0.02, sm=0.05, seed=2)
    qc = quat_conjugate(q)
    m = data.mag.copy()
    m[2000:] = quat_rotate(qc, quat_rotate(quat_exp(np.array([0, 0, np.radians(20.0)])), MAG_NED))
    d = replace(data, mag=m)
    prm = MekfConfig(gyro_noise_density=0.003, gyro_bias_random_walk=1e-4, accel_direction_noise_std=0.05, heading_noise_std=0.3)
    b_on = MEKF(prm).run(d).bias[:, 2]
    b_off = MEKF(replace(prm, mag_bias=False)).run(d).bias[:, 2]
    moved_on = np.max(np.abs(b_on[2000:] - b_on[1999]))
    moved_off = np.max(np.abs(b_off[2000:] - b_off[1999]))  # only the accelerometer's tiny share is left
    assert moved_on > 5e-3 and moved_off < 1e-3 * moved_on, (moved_on, moved_off)


def test_new_parameters_validated():
    with pytest.raises(ConfigError, match="k_gyro_rate"):
        MekfConfig(k_gyro_rate=-1.0)
    with pytest.raises(ConfigError, match="mag_min_undisturbed"):
        MekfConfig(mag_min_undisturbed=float("nan"))


def test_defaults_track_a_moving_sensor():
    """The shipped adaptive defaults on the shared simulated motion: converge and stay within 1.5°."""
    data, q = rotating_imu(5, duration=60.0, fs=100.0)
    e = angle_err_deg(AdaptiveMEKF().run(data).q_nb, q)
    assert np.sqrt(np.mean(e[2000:] ** 2)) < 1.5


def test_time_constants_give_rate_independent_steady_state():
    """Random walk of density σ_g seen through white noise of density τ σ_g: P_ss = σ_g² τ (continuous Riccati),
    whatever the sampling rate.  The heading adds the tilt error that leaks into the measured heading through the
    dip (tan δ φ_N, a slowly varying error the heading update carries as consider states): P_ss = σ_g² τ_m where the
    field is nearly horizontal, larger at a steep dip, and the same at every rate.  (That the larger heading
    variance is the true one is checked by the calibration tests in test_nees.py.)"""
    sg, ta, tm = 0.003, 2.0, 10.0
    prm = MekfConfig(gyro_noise_density=sg, tilt_time_constant=ta, heading_time_constant=tm, gyro_bias_random_walk=0.0, init_gyro_bias_std=1e-12)
    heading = {}
    for fs in (50.0, 400.0):
        n = int(12 * tm * fs)
        for dip_deg in (2.0, 70.0):
            d = np.radians(dip_deg)
            mag = np.array([np.cos(d), 0.0, np.sin(d)]) * 50.0
            data = ImuData(t=np.arange(n) / fs, gyro=np.zeros((n, 3)), accel=np.tile([0.0, 0.0, -9.81], (n, 1)),
                           mag=np.tile(mag, (n, 1)))
            P = MEKF(prm).run(data, q0=[1.0, 0, 0, 0]).cov_diag[-1]
            # discrete steady state differs from the continuous one by O(Δt/τ)
            np.testing.assert_allclose(P[:2], sg**2 * ta, rtol=2.0 / (fs * ta) + 1e-3)
            heading[fs, dip_deg] = P[2] / (sg**2 * tm)
    # nearly horizontal field: the leak tan²δ P_tilt is 0.1 % of the heading variance
    for fs in (50.0, 400.0):
        np.testing.assert_allclose(heading[fs, 2.0], 1.0, rtol=2.0 / (fs * tm) + 2e-3)
    # steep dip: larger, and rate-independent to O(Δt/τ)
    assert heading[50.0, 70.0] > 1.05
    np.testing.assert_allclose(heading[50.0, 70.0], heading[400.0, 70.0], rtol=2.0 / (50.0 * tm) + 1e-3)


@pytest.mark.parametrize("make", [
    lambda: MEKF(), lambda: AdaptiveMEKF(),
])
@pytest.mark.parametrize("dt", [float("nan"), -0.01, 0.0, float("inf"), "x"])
def test_step_refuses_a_bad_time_step(make, dt):
    f = make()
    f.step([0.0, 0.0, 0.1], [0.0, 0.0, -9.81], [20.0, 0.0, 40.0], 0.01)
    q = f.q.copy()
    with pytest.raises(InvalidInputError, match="dt"):
        f.step([0.0, 0.0, 0.1], [0.0, 0.0, -9.81], [20.0, 0.0, 40.0], dt)
    np.testing.assert_array_equal(f.q, q)  # the state is untouched: later samples stay valid


def test_impossible_rates_refused_in_step_and_run():
    from imunav.attitude import UKF, Complementary, GravityKF, Madgwick, Mahony

    for f in (MEKF(), Madgwick(), Mahony(), Complementary(), UKF()):
        with pytest.raises(InvalidInputError, match="exceeds"):
            f.step([1e300, 0.0, 0.0], [0.0, 0.0, -9.81], None, 0.01)
    with pytest.raises(InvalidInputError, match="exceeds"):
        GravityKF().step([1e300, 0.0, 0.0], [0.0, 0.0, -9.81], 0.01)
    data, _ = _static(200, 100.0)
    g = data.gyro.copy()
    g[57] = [0.0, 2e4, 0.0]
    with pytest.raises(InvalidInputError, match="sample 57"):
        AdaptiveMEKF().run(replace(data, gyro=g))
