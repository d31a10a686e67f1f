"""Calibration of the reported uncertainties of the calibration estimators.

Over independent seeded runs the z-scores (estimate - truth) / stderr of each
parameter group must have an RMS inside the 99 % chi-square interval for their
number (tests/_calibration.py); that interval rejects a stderr wrong by 1.5 or
1/1.5.  Components of one group (e.g. the three biases) are pooled: the
designs are symmetric, so they are close to independent.  Everything goes
through the public API and reads the stderr a user reads
(``CalibrationResult.stderr``, ``MagCalibration.stderr``, ``OrderMetrics.stderr``).

Set IMUNAV_SIGMA_SCALE=1.5 (or 0.6667) to see these tests fail.
"""

from __future__ import annotations

import numpy as np
import pytest
from _calibration import assert_rms_calibrated, z_scores
from builders import (
    G,
    hundred_positions,
    multipose_session,
    random_poses,
    thesis_truth,
)

from imunav.calib import (
    calibration_parameters,
    ferraris,
    fit_ellipsoid,
    multipose,
    multiposition_from_means,
    parameter_stderr,
    ratetable_from_means,
)
from imunav.calib.multipose import accel_tedaldi_matrix, gyro_tedaldi_matrix
from imunav.calib.temperature import fit_temperature_curve


def _collect(zs: dict, key: str, est, truth, se) -> None:
    zs.setdefault(key, []).append(z_scores(est, truth, se))


def _check(zs: dict, where: str) -> None:
    for k, v in zs.items():
        assert_rms_calibrated(np.concatenate(v), f"{where} {k}")


def test_static_multiposition_stderr_calibrated():
    """100 positions, white noise on the position means, 60 runs: S, B, M, gyro B and G."""
    truth, u = thesis_truth(), hundred_positions()
    pt = calibration_parameters(truth)
    f = G * u
    a0, g0 = truth.invert_arrays(f, np.zeros_like(f))
    zs: dict = {}
    for seed in range(60):
        rng = np.random.default_rng(seed)
        a = a0 + rng.normal(scale=6.7e-4 * G, size=a0.shape)
        g = g0 + rng.normal(scale=6.7e-3 * np.pi / 180, size=g0.shape)
        r = multiposition_from_means(f, a, g, serial=False)
        pe, se = calibration_parameters(r.calibration), parameter_stderr(r.stderr)
        for k in ("accel_S", "accel_B", "accel_M", "gyro_B", "gyro_BG"):
            _collect(zs, k, pe[k], pt[k], se[k])
    _check(zs, "multiposition")


def _rate_design():
    rates = []
    for i in range(3):
        for w in (-1.0, -0.5, 0.5, 1.0):
            e = np.zeros(3)
            e[i] = w
            rates.append(e)
    return np.array(rates * 2)


def test_ratetable_stderr_calibrated():
    """24 table steps with a separate power-up bias, 60 runs: gyro matrix and bias."""
    truth = thesis_truth()
    rates = _rate_design()
    fref = np.tile([0.0, 0.0, -G], (len(rates), 1))
    _, g0 = truth.invert_arrays(fref, rates)
    zs: dict = {}
    for seed in range(60):
        rng = np.random.default_rng(100 + seed)
        g = g0 + rng.normal(scale=1e-4, size=g0.shape)
        r = ratetable_from_means(rates, g, fref, base=truth, intercept=True, serial=False)
        for k in ("gyro_matrix", "gyro_bias"):
            _collect(zs, k, getattr(r.calibration, k), getattr(truth, k), r.stderr[k])
    _check(zs, "ratetable")


def _ferraris_sections(truth, rng, fs, g0, n_static=100, n_rot=1000, sa=0.02, sg=0.005):
    secs = {}
    for i, ax in enumerate("xyz"):
        for sgn, tag in ((1, "p"), (-1, "a")):
            f = np.zeros((n_static, 3))
            f[:, i] = sgn * g0
            a, w = truth.invert_arrays(f, np.zeros_like(f))
            secs[f"{ax}_{tag}"] = (a + rng.normal(scale=sa, size=a.shape), w + rng.normal(scale=sg, size=w.shape))
        wt = np.zeros((n_rot, 3))
        wt[:, i] = -2 * np.pi / n_rot * fs  # one turn, measured as -360 deg
        f = np.zeros((n_rot, 3))
        f[:, i] = g0
        a, w = truth.invert_arrays(f, wt)
        secs[f"{ax}_rot"] = (a + rng.normal(scale=sa, size=a.shape), w + rng.normal(scale=sg, size=w.shape))
    return secs


def test_ferraris_stderr_calibrated():
    """Simulated Ferraris sessions, 60 runs: every parameter group, the gyro matrix included
    (its stderr carries the bias and g-sensitivity estimates removed from the turns)."""
    truth, fs, g0 = thesis_truth(), 100.0, 9.81
    zs: dict = {}
    for seed in range(60):
        r = ferraris(_ferraris_sections(truth, np.random.default_rng(200 + seed), fs, g0), fs, gravity=g0)
        for k in ("accel_matrix", "accel_bias", "gyro_matrix", "gyro_bias", "g_sensitivity"):
            _collect(zs, k, getattr(r.calibration, k), getattr(truth, k), r.stderr[k])
    _check(zs, "ferraris")


def test_temperature_curve_stderr_calibrated():
    """Quadratic drift over 41 temperatures (36 residual dof: Student-t z have RMS 1.03), 80 runs."""
    temp = np.linspace(-20.0, 60.0, 41)
    c_true = np.array([0.1, 2e-3, -3e-5])  # in degC
    y0 = c_true[0] + c_true[1] * temp + c_true[2] * temp**2
    zs: dict = {}
    for seed in range(80):
        rng = np.random.default_rng(300 + seed)
        fit = fit_temperature_curve(temp, y0 + rng.normal(scale=1e-3, size=temp.size), order=2)
        cv = fit.curve
        # the true coefficients in the fit's normalised variable x = (t - centre) / scale
        c, s = cv.center_c, cv.scale_c
        truth_x = np.array([c_true[0] + c_true[1] * c + c_true[2] * c * c, (c_true[1] + 2 * c_true[2] * c) * s,
                            c_true[2] * s * s])
        _collect(zs, "poly", cv.coeffs, truth_x, fit.best.stderr)
    _check(zs, "temperature")


def test_thermal_calibration_stderr_calibrated():
    """thermal_calibration from calibrations repeated at 41 temperatures (39 residual dof, so Student-t z have RMS
    1.03): every parameter's linear drift curve (order fixed at 1) against its ThermalResult stderr, 30 runs x 4
    parameters x 3 axes x 2 coefficients."""
    from imunav.calib import ImuCalibration
    from imunav.calib.temperature import thermal_calibration

    temp = np.linspace(-20.0, 60.0, 41)
    slope = {"accel_bias": 2e-3, "gyro_bias": -1e-5, "accel_scale": 4e-5, "gyro_scale": -6e-5}
    noise = {"accel_bias": 5e-3, "gyro_bias": 2e-5, "accel_scale": 1e-4, "gyro_scale": 1e-4}
    zs: dict = {}
    for seed in range(30):
        rng = np.random.default_rng(700 + seed)
        true = {k: (rng.normal(scale=0.1, size=3) if "bias" in k else 1 + rng.normal(scale=0.01, size=3),
                    slope[k] * (1 + 0.5 * rng.random(3))) for k in slope}
        cals = []
        for t in temp:
            v = {k: c0 + c1 * t + rng.normal(scale=noise[k], size=3) for k, (c0, c1) in true.items()}
            cals.append(ImuCalibration(accel_bias=v["accel_bias"], accel_matrix=np.diag(v["accel_scale"]),
                                       gyro_bias=v["gyro_bias"], gyro_matrix=np.diag(v["gyro_scale"])))
        res = thermal_calibration(temp, cals, order=1)
        for k, (c0, c1) in true.items():
            for i in range(3):
                fit = res.fits[k][i]
                c, sc = fit.curve.center_c, fit.curve.scale_c
                _collect(zs, k, fit.curve.coeffs, np.array([c0[i] + c1[i] * c, c1[i] * sc]), fit.best.stderr)
    _check(zs, "thermal_calibration")


def _random_ellipsoid(rng, shortest):
    """Soft-iron inverse A⁻¹ (random axes, semi-axes shortest..1.3 x 50) and hard iron b."""
    q, _r = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q * np.sign(np.linalg.det(q))
    return R @ np.diag(rng.uniform(shortest, 1.3, 3)) @ R.T * 50.0, rng.uniform(-80, 80, 3)


def test_magnetometer_b_and_A_stderr_calibrated():
    """Random ellipsoids with noise, 60 runs: b (3) and A (9) against MagCalibration.stderr."""
    rng = np.random.default_rng(42)
    zs: dict = {}
    for _ in range(60):
        Ainv, b = _random_ellipsoid(rng, 0.7)
        u = rng.normal(size=(300, 3))
        u /= np.linalg.norm(u, axis=1)[:, None]
        h = u @ Ainv.T + b + rng.normal(scale=0.5, size=(300, 3))
        c = fit_ellipsoid(h, field_norm=1.0)
        _collect(zs, "b", c.b, b, c.stderr["b"])
        _collect(zs, "A", c.A, np.linalg.inv(Ainv), c.stderr["A"])
    _check(zs, "fit_ellipsoid")


def test_li_griffiths_algebraic_fit_exact_without_refinement():
    """refine=False returns the algebraic Li-Griffiths solution: exact on noise-free ellipsoids whose
    shortest axis is at least half the longest (where the k = 4 constraint holds for the true quadric)."""
    rng = np.random.default_rng(5)
    for _ in range(3):
        Ainv, b = _random_ellipsoid(rng, 0.75)
        u = rng.normal(size=(400, 3))
        h = (u / np.linalg.norm(u, axis=1)[:, None]) @ Ainv.T + b
        c = fit_ellipsoid(h, field_norm=1.0, refine=False)
        np.testing.assert_allclose(c.b, b, atol=1e-8)
        np.testing.assert_allclose(c.A, np.linalg.inv(Ainv), atol=1e-10)
        assert c.stderr == {}


PA = np.array([0.004, -0.003, 0.006, 6.0e-4, 5.9e-4, 5.85e-4, -700, 350, 1800.0])
PG = np.array([-0.01, 0.009, -0.003, 0.007, -0.0098, 0.0058, 1.37e-4, 1.33e-4, 1.34e-4])
BG = np.array([-427, 148, -80.0])


@pytest.mark.slow
def test_multipose_stderr_calibrated():
    """Tedaldi multi-pose on simulated sessions (30 poses): z of the 9 accel and 12 gyro parameters."""
    from imunav.calib import ImuCalibration

    truth = ImuCalibration(
        accel_bias=-PA[6:], accel_matrix=np.linalg.inv(accel_tedaldi_matrix(PA)), gyro_bias=BG,
        gyro_matrix=np.linalg.inv(gyro_tedaldi_matrix(PG)), raw_accel_unit="counts", raw_gyro_unit="counts")
    zs: dict = {}
    for seed in range(8):
        rng = np.random.default_rng(400 + seed)
        f, w = multipose_session(random_poses(30, rng), 100.0, rest_s=20.0, static_s=3.0, move_s=1.5)
        a, g = truth.invert_arrays(f, w)
        a, g = a + rng.normal(scale=5, size=a.shape), g + rng.normal(scale=3, size=g.shape)
        t = multipose(a, g, 100.0, init_s=20.0, wait_s=2.0, gyro_scale_guess=1.3e-4).info["tedaldi"]
        _collect(zs, "accel", t["accel"], PA, t["accel_stderr"])
        _collect(zs, "gyro", t["gyro"], np.r_[PG, BG], t["gyro_stderr"])
    _check(zs, "multipose")
