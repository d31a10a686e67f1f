"""Tedaldi multi-pose calibration: simulated truth recovery and the MPU-6050 session."""

import time

import numpy as np
import pytest
from builders import BG_U, PA_U, PG_U, multipose_session, random_poses, unsigned_count_session
from scipy.stats import chi2, norm
from scipy.stats import t as student_t
from shared_data import data_path

from imunav.calib import ImuCalibration, multipose
from imunav.calib.multipose import accel_tedaldi_matrix, gyro_tedaldi_matrix
from imunav.errors import DegenerateGeometryError, InsufficientDataError

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


def _poor_coverage_session():
    rng = np.random.default_rng(5)
    # all poses within ~10 deg of level: the gravity directions do not span the sphere
    q = np.tile([1.0, 0, 0, 0], (14, 1)) + np.c_[np.zeros(14), 0.08 * rng.normal(size=(14, 3))]
    q /= np.linalg.norm(q, axis=1)[:, None]
    f, w = multipose_session(q, 100.0, rest_s=20.0, static_s=3.0, move_s=1.5)
    a, g = _truth().invert_arrays(f, w)
    return a + rng.normal(scale=5, size=a.shape), g + rng.normal(scale=3, size=g.shape)


def test_refuses_poor_coverage():
    a, g = _poor_coverage_session()
    with pytest.raises(DegenerateGeometryError, match="do not cover"):
        multipose(a, g, 100.0, init_s=20.0, wait_s=2.0)


def _mpu():
    return np.loadtxt(data_path("mpu6050_tedaldi", "example_data_calibration.csv"), delimiter=",", skiprows=5)


def test_mpu6050_session_refused_in_strict_mode():
    """10 poses, none tilted between x and y: accel m_yz is not determined (README: 'weakly determined')."""
    d = _mpu()
    with pytest.raises(DegenerateGeometryError, match="m_yz"):
        multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0, full_scale=(32767, 32767),
                  gyro_scale_guess=1.33e-4)


def test_mpu6050_refusal_through_the_cli_names_the_flags(tmp_path):
    """The README's documented refusal (the MPU-6050 session without --no-accel-misalignment): one line, exit 2,
    and the ways out named as the command's flags, not as Python keyword arguments (issue 16, item 7)."""
    from typer.testing import CliRunner

    from imunav.cli.main import app

    out = tmp_path / "mpu_cal.json"
    csv = data_path("mpu6050_tedaldi", "example_data_calibration.csv")
    r = CliRunner().invoke(app, ["calibrate", "multipose", str(csv), "--skiprows", "4", "--fs", "100",
                                 "--accel-unit", "counts", "--accel-scale", "5.9855e-4", "--gyro-unit", "counts",
                                 "--gyro-scale", "1.3323e-4", "--init-s", "36.5", "--out", str(out)])
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "accel m_yz" in lines[0] and "--no-accel-misalignment" in lines[0] and "--no-strict" in lines[0], lines[0]
    assert "=False" not in lines[0], lines[0]
    assert not out.exists()


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
    e = np.array(t["accel"])
    # accelerometer scales within 0.1 %, biases within 2 % of |b| (published fit is not converged:
    # its misalignments stayed at their 0 start within 1e-5)
    np.testing.assert_allclose(e[3:6], pub_a[3:6], rtol=1e-3)
    np.testing.assert_allclose(e[6:9], pub_a[6:9], atol=0.02 * np.abs(pub_a[6:9]).max())
    eg, sg = np.array(t["gyro"]), np.array(t["gyro_stderr"])
    assert np.all(np.abs(eg[:9] - pub_g[:9]) <= 3 * sg[:9]), (eg[:9] - pub_g[:9]) / sg[:9]
    np.testing.assert_allclose(eg[9:], pub_g[9:], atol=0.01)  # bias: mean over the same rest samples


# ---------------------------------------------------------------- raw unsigned counts, default options
def _z(r):
    """Errors of scales and misalignments (accel 6, gyro 9) in units of the reported stderr, and their dof."""
    t = r.info["tedaldi"]
    za = (np.array(t["accel"]) - PA_U)[:6] / np.array(t["accel_stderr"])[:6]
    zg = (np.array(t["gyro"])[:9] - PG_U) / np.array(t["gyro_stderr"])[:9]
    return za, zg, r.info["n_poses"] - 9, 2 * r.info["gyro_pairs_used"] - 9


def test_unsigned_counts_with_default_options():
    a, g = unsigned_count_session(11)
    assert 48_000 < len(a) < 54_000 and a.min() > 20_000  # unsigned: every raw value far from 0
    t0 = time.perf_counter()
    r = multipose(a, g, 100.0, init_s=50)
    dt = time.perf_counter() - t0
    t = r.info["tedaldi"]
    ea, eg = np.array(t["accel"]), np.array(t["gyro"])
    err_a, err_g = ea[3:6] / PA_U[3:6] - 1, eg[6:9] / PG_U[6:9] - 1
    za, zg, _, _ = _z(r)
    print(f"\nunsigned counts, {len(a)} samples, {r.info['n_poses']} poses: {dt:.2f} s; scale errors accel "
          f"{np.round(100 * err_a, 4)} %, gyro {np.round(100 * err_g, 4)} %; misalignment z accel "
          f"{np.round(za[:3], 2)}, gyro {np.round(zg[:6], 2)}")
    assert r.info["n_poses"] == 40 and r.info["weak_parameters"] == []
    assert dt < 5.0
    assert np.all(np.abs(err_a) < 3e-3) and np.all(np.abs(err_g) < 3e-3)
    assert np.all(np.abs(za[:3]) < 3) and np.all(np.abs(zg[:6]) < 3)
    # offsets estimated, not assumed: within 3 sigma of the truth
    assert np.all(np.abs(ea[6:9] - PA_U[6:9]) < 3 * np.array(t["accel_stderr"])[6:9])
    assert np.all(np.abs(eg[9:] - BG_U) < 3 * np.array(t["gyro_stderr"])[9:])
    # the calibration maps raw counts to SI: a static pose has |f| = g
    f, w = r.calibration.apply_arrays(a[:4000], g[:4000])
    assert abs(np.linalg.norm(f.mean(0)) - 9.80665) < 0.005 and np.linalg.norm(w.mean(0)) < 1e-3


def test_offset_of_32768_counts_changes_nothing():
    """Signed and unsigned versions of the same sessions: same coverage verdict, same result."""
    a, g = unsigned_count_session(12)
    ru = multipose(a, g, 100.0, init_s=50)
    rs = multipose(a - 32768, g - 32768, 100.0, init_s=50)
    tu, ts = ru.info["tedaldi"], rs.info["tedaldi"]
    # tolerances ~30x the differences seen (rounding of the centred data: params 3e-9 relative, biases 1e-7 counts)
    assert ru.info["coverage"] == pytest.approx(rs.info["coverage"], rel=1e-12)
    assert ru.info["n_poses"] == rs.info["n_poses"] and ru.info["threshold_factor"] == rs.info["threshold_factor"]
    for k in ("accel", "gyro"):
        eu, es = np.array(tu[k]), np.array(ts[k])
        n = 6 if k == "accel" else 9  # misalignments and scales
        np.testing.assert_allclose(es[:n], eu[:n], rtol=1e-7, atol=0)
        np.testing.assert_allclose(np.array(ts[k + "_stderr"]), np.array(tu[k + "_stderr"]), rtol=3e-6)
    # biases shift by exactly the offset (Tedaldi b_a is added to the raw vector, b_g subtracted)
    np.testing.assert_allclose(np.array(ts["accel"])[6:9], np.array(tu["accel"])[6:9] + 32768, rtol=0, atol=3e-6)
    np.testing.assert_allclose(np.array(ts["gyro"])[9:], np.array(tu["gyro"])[9:] - 32768, rtol=0, atol=3e-6)
    np.testing.assert_allclose(rs.calibration.accel_matrix, ru.calibration.accel_matrix, rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(rs.calibration.gyro_matrix, ru.calibration.gyro_matrix, rtol=1e-7, atol=1e-7)
    # the poor-coverage session is refused with the same message, with or without the offset
    a, g = _poor_coverage_session()
    msgs = []
    for off in (0.0, 32768.0):
        with pytest.raises(DegenerateGeometryError, match="do not cover") as e:
            multipose(a + off, g + off, 100.0, init_s=20.0, wait_s=2.0)
        msgs.append(str(e.value))
    assert msgs[0] == msgs[1]


def test_reported_uncertainty_is_calibrated_on_unsigned_sessions():
    """20 sessions: the z-scores of the 15 scales and misalignments have RMS 1 within sampling bounds.

    The stderr comes from the residual variance, so z follows Student's t with the fit's residual
    degrees of freedom; each z is mapped to the normal quantile of the same probability before the
    chi-square test of sum(z²) (99 % two-sided bounds).
    """
    zs = []
    for seed in range(100, 120):
        za, zg, dof_a, dof_g = _z(multipose(*unsigned_count_session(seed), 100.0, init_s=50))
        zs += [norm.ppf(student_t.cdf(za, dof_a)), norm.ppf(student_t.cdf(zg, dof_g))]
    z = np.concatenate(zs)
    lo, hi = np.sqrt(chi2.ppf([0.005, 0.995], z.size) / z.size)
    rms = float(np.sqrt(np.mean(z**2)))
    print(f"\nRMS z over {z.size} scale/misalignment estimates: {rms:.3f} (99 % bounds {lo:.3f}..{hi:.3f})")
    assert lo < rms < hi


def test_mpu6050_session_with_default_scale_guesses():
    """No gyro_scale_guess: the gyro parameters still agree with the published ones within 3 stderr."""
    d = _mpu()
    pub_a = np.loadtxt(data_path("mpu6050_tedaldi", "optmization_result_data", "params_acc.csv"))
    pub_g = np.loadtxt(data_path("mpu6050_tedaldi", "optmization_result_data", "params_gyro.csv"))
    r = multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0, accel_misalignment=False)
    t = _table(r, pub_a, pub_g, "default scale guesses, accelerometer without misalignment")
    assert r.info["n_poses"] == 10 and r.info["weak_parameters"] == []
    np.testing.assert_allclose(np.array(t["accel"])[3:6], pub_a[3:6], rtol=1e-3)
    eg, sg = np.array(t["gyro"]), np.array(t["gyro_stderr"])
    assert np.all(np.abs(eg[:9] - pub_g[:9]) <= 3 * sg[:9]), (eg[:9] - pub_g[:9]) / sg[:9]
    # the full model is still refused, naming m_yz
    with pytest.raises(DegenerateGeometryError, match="m_yz"):
        multipose(d[:, :3], d[:, 3:], 100.0, init_s=36.5, wait_s=3.0)
