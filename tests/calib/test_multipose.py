"""Tedaldi multi-pose calibration: simulated truth recovery and the MPU-6050 session."""

import numpy as np
import pytest

from conftest_data import data_path
from imunav.calib import ImuCalibration, multipose
from imunav.calib.multipose import accel_tedaldi_matrix, gyro_tedaldi_matrix
from imunav.errors import DegenerateGeometryError, InsufficientDataError

from _simulate import multipose_session, random_poses

PA = np.array([0.004, -0.003, 0.006, 6.0e-4, 5.9e-4, 5.85e-4, -700, 350, 1800.0])
PG = np.array([-0.01, 0.009, -0.003, 0.007, -0.0098, 0.0058, 1.37e-4, 1.33e-4, 1.34e-4])
BG = np.array([-427, 148, -80.0])


def _truth():
    return ImuCalibration(
        accel_bias=-PA[6:], accel_matrix=np.linalg.inv(accel_tedaldi_matrix(PA)), gyro_bias=BG,
        gyro_matrix=np.linalg.inv(gyro_tedaldi_matrix(PG)), raw_accel_unit="counts", raw_gyro_unit="counts",
    )


def _session(n_poses, seed):
    rng = np.random.default_rng(seed)
    f, w = multipose_session(random_poses(n_poses, rng), 100.0, rest_s=20.0, static_s=3.0, move_s=1.5)
    a, g = _truth().invert_arrays(f, w)
    return a + rng.normal(scale=5, size=a.shape), g + rng.normal(scale=3, size=g.shape)


def test_recovers_truth_within_reported_uncertainty():
    a, g = _session(30, 3)
    r = multipose(a, g, 100.0, init_s=20.0, wait_s=2.0, gyro_scale_guess=1.3e-4)
    t = r.info["tedaldi"]
    assert r.info["n_poses"] == 30
    za = (np.array(t["accel"]) - PA) / np.array(t["accel_stderr"])
    zg = (np.array(t["gyro"]) - np.r_[PG, BG]) / np.array(t["gyro_stderr"])
    assert np.all(np.abs(za) < 4) and np.all(np.abs(zg) < 4), (za, zg)
    # compensated static poses: |f| = g to the noise level
    f, _ = r.calibration.apply_arrays(a[:2000], g[:2000])
    assert abs(np.linalg.norm(f.mean(0)) - 9.80665) < 0.01


def test_refuses_too_few_poses():
    a, g = _session(6, 4)
    with pytest.raises(InsufficientDataError, match="need at least 10"):
        multipose(a, g, 100.0, init_s=20.0, wait_s=2.0)


def test_refuses_poor_coverage():
    rng = np.random.default_rng(5)
    # all poses within ~10 deg of level: the gravity directions do not span the sphere
    q = np.tile([1.0, 0, 0, 0], (14, 1)) + np.c_[np.zeros(14), 0.08 * rng.normal(size=(14, 3))]
    q /= np.linalg.norm(q, axis=1)[:, None]
    f, w = multipose_session(q, 100.0, rest_s=20.0, static_s=3.0, move_s=1.5)
    a, g = _truth().invert_arrays(f, w)
    with pytest.raises(DegenerateGeometryError, match="do not cover"):
        multipose(a + rng.normal(scale=5, size=a.shape), g + rng.normal(scale=3, size=g.shape), 100.0,
                  init_s=20.0, wait_s=2.0)


def _mpu():
    return np.loadtxt(data_path("mpu6050_tedaldi", "example_data_calibration.csv"), delimiter=",", skiprows=5)


def test_mpu6050_session_refused_in_strict_mode():
    """10 poses, none tilted between x and y: accel m_yz is not determined (README: 'weakly determined')."""
    d = _mpu()
    with pytest.raises(DegenerateGeometryError, match="m_yz"):
        multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0, full_scale=(32767, 32767),
                  gyro_scale_guess=1.33e-4)


def _table(r, pub_a, pub_g, title):
    t = r.info["tedaldi"]
    rows = list(zip(["acc " + n for n in t["accel_names"]], pub_a, t["accel"], t["accel_stderr"]))
    rows += list(zip(["gyr " + n for n in t["gyro_names"]], pub_g, t["gyro"], t["gyro_stderr"]))
    print(f"\nMPU-6050 multi-pose, {title}: published vs imunav (± stderr, z = (imunav - published)/stderr)")
    for name, p, e, s in rows:
        z = (e - p) / s if s > 0 else float("nan")
        print(f"{name:10s} {p:14.6e} {e:14.6e} ±{s:10.3e}  z={z:7.2f}")
    return t


def test_mpu6050_session_compared_with_published():
    """Published parameters: shared/data/mpu6050_tedaldi/README (params_acc.csv, params_gyro.csv).

    The session's 10 poses cannot separate the accelerometer misalignments
    (no pose tilted between x and y); the full model is refused (test above).
    Fitted without them, every parameter is well determined and the gyro
    parameters agree with the published ones within the reported uncertainty.
    """
    d = _mpu()
    pub_a = np.loadtxt(data_path("mpu6050_tedaldi", "optmization_result_data", "params_acc.csv"))
    pub_g = np.loadtxt(data_path("mpu6050_tedaldi", "optmization_result_data", "params_gyro.csv"))
    full = multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0, gyro_scale_guess=1.33e-4, strict=False)
    _table(full, pub_a, pub_g, "full 9+9 model (strict=False)")
    assert "accel m_yz" in " ".join(full.info["weak_parameters"])
    r = multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0, gyro_scale_guess=1.33e-4,
                  accel_misalignment=False)
    t = _table(r, pub_a, pub_g, "accelerometer without misalignment")
    assert r.info["n_poses"] == 10 and r.info["weak_parameters"] == []
    e, s = np.array(t["accel"]), np.array(t["accel_stderr"])
    # accelerometer scales within 0.1 %, biases within 2 % of |b| (published fit is not converged:
    # its misalignments stayed at their 0 start within 1e-5)
    np.testing.assert_allclose(e[3:6], pub_a[3:6], rtol=1e-3)
    np.testing.assert_allclose(e[6:9], pub_a[6:9], atol=0.02 * np.abs(pub_a[6:9]).max())
    eg, sg = np.array(t["gyro"]), np.array(t["gyro_stderr"])
    assert np.all(np.abs(eg[:9] - pub_g[:9]) <= 3 * sg[:9]), (eg[:9] - pub_g[:9]) / sg[:9]
    np.testing.assert_allclose(eg[9:], pub_g[9:], atol=0.01)  # bias: mean over the same rest samples
