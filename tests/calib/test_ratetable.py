"""Rate-table least squares and the combined static + rate calibration."""

import numpy as np
import pytest
from builders import G, rate_table_steps, thesis_truth

from imunav.calib import combine, multiposition, ratetable, ratetable_from_means, success_percentages
from imunav.errors import DegenerateGeometryError, InsufficientDataError


def test_rate_steps_noise_free_exact():
    truth = thesis_truth()
    W, U = rate_table_steps()
    f = G * U
    _, g = truth.invert_arrays(f, W)
    r = ratetable_from_means(W, g, f, base=truth.with_(gyro_matrix=np.eye(3)))
    np.testing.assert_allclose(r.calibration.gyro_matrix, truth.gyro_matrix, atol=1e-14)
    assert r.condition["gyro_rate"] < 2


def test_intercept_absorbs_turn_on_bias(rng):
    truth = thesis_truth()
    W, U = rate_table_steps()
    f = G * U
    _, g = truth.invert_arrays(f, W)
    g = g + np.array([1e-3, -2e-3, 5e-4])  # a different power-up
    base = truth.with_(gyro_matrix=np.eye(3))
    r = ratetable_from_means(W, g, f, base=base, intercept=True)
    np.testing.assert_allclose(r.calibration.gyro_bias, truth.gyro_bias + [1e-3, -2e-3, 5e-4], atol=1e-13)
    np.testing.assert_allclose(r.calibration.gyro_matrix, truth.gyro_matrix, atol=1e-13)


def test_vertical_earth_rate_is_handled():
    truth = thesis_truth()
    W, U = rate_table_steps()
    # positive rates only: with the symmetric thesis list the Earth rate cancels from T_g anyway
    keep = W.sum(1) > 0
    W, U = W[keep], U[keep]
    lat = np.deg2rad(45.0)
    w_true = W + 7.292115e-5 * np.sin(lat) * U
    _, g = truth.invert_arrays(G * U, w_true)
    base = truth.with_(gyro_matrix=np.eye(3))
    ok = ratetable_from_means(W, g, G * U, base=base, latitude=lat, up=U).calibration.gyro_matrix
    ignored = ratetable_from_means(W, g, G * U, base=base).calibration.gyro_matrix
    np.testing.assert_allclose(ok, truth.gyro_matrix, atol=1e-14)
    assert np.abs(ignored - truth.gyro_matrix).max() > 1e-6  # the thesis's neglect is visible


def test_rate_uncertainty_covers_truth():
    truth = thesis_truth()
    W, U = rate_table_steps()
    rng = np.random.default_rng(11)
    base = truth.with_(gyro_matrix=np.eye(3))
    _, g0 = truth.invert_arrays(G * U, W)
    hits, n = np.zeros((3, 3)), 300
    for _ in range(n):
        g = g0 + rng.normal(scale=1.2e-4, size=g0.shape)
        r = ratetable_from_means(W, g, G * U, base=base)
        hits += np.abs(r.calibration.gyro_matrix - truth.gyro_matrix) <= 3 * r.stderr["gyro_matrix"]
    assert np.all(hits / n >= 0.95), hits / n


def test_full_pipeline_on_sim_profiles_noise_free():
    """imunav.sim profiles (transitions, Earth rate, normal gravity) through the estimators."""
    from imunav.sim import hundred_position_profile, ideal_imu, rate_table_step_profile

    truth = thesis_truth()
    lat = np.deg2rad(40.0)
    sp = hundred_position_profile(fs=10.0, dwell_s=4.0, transition_s=1.0, lat=lat)
    rp = rate_table_step_profile(fs=10.0, dwell_s=4.0, transition_s=1.0, remount_s=2.0, lat=lat)
    out = []
    for p in (sp, rp):
        d = ideal_imu(p.trajectory)
        a, g = truth.invert_arrays(d.accel, d.gyro)
        out.append(d.with_(accel=a, gyro=g))
    st = multiposition(out[0], sp.segments, latitude=lat, window_s=0.5, trim_s=0.0, min_duration_s=1.0)
    rt = ratetable(out[1], rp.segments, base=st.calibration, latitude=lat, window_s=0.5, trim_s=0.0, min_duration_s=1.0)
    c = combine(st, rt).calibration
    np.testing.assert_allclose(c.accel_matrix, truth.accel_matrix, atol=1e-10)
    np.testing.assert_allclose(c.accel_bias, truth.accel_bias, atol=1e-10)
    np.testing.assert_allclose(c.gyro_bias, truth.gyro_bias, atol=1e-12)
    np.testing.assert_allclose(c.g_sensitivity, truth.g_sensitivity, atol=1e-12)
    # horizontal Earth rate on a turning table is not modelled: 1e-7-level on T_g
    np.testing.assert_allclose(c.gyro_matrix, truth.gyro_matrix, atol=1e-7)
    s = success_percentages(c, truth)
    assert s["accel_mean"] > 99.99999 and s["gyro_mean"] > 99.999


def test_refusals():
    W, U = rate_table_steps()
    x_only = W[:40]
    with pytest.raises(DegenerateGeometryError, match="ill-conditioned"):
        ratetable_from_means(x_only, x_only, G * U[:40])
    with pytest.raises(InsufficientDataError, match="3 positions/steps for 3 unknowns"):
        ratetable_from_means(np.eye(3), np.eye(3))
    with pytest.raises(InsufficientDataError, match="up vector"):
        ratetable_from_means(W, W, latitude=0.5)
