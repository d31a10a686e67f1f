"""Temperature calibration: order choice, Table 6.1-style metrics, piecewise steps, run-time compensation."""

import numpy as np
import pytest

from imunav.calib import ImuCalibration, fit_temperature_curve, thermal_calibration
from imunav.errors import InsufficientDataError, InvalidInputError, ShapeError

T10 = np.linspace(-30.0, 50.0, 10)  # the thesis: 10 points from -30 to +50 °C
X10 = (T10 - 10.0) / 40.0
COEF = np.array([0.3, 0.5, -0.8, 0.6, 0.4, -0.5])


def test_chosen_order_equals_truth():
    """Simulated B(T) of every order 1-5 at the thesis's 10 temperatures (one seeded noise stream)."""
    rng = np.random.default_rng(0)
    for true_order in range(1, 6):
        y = 1e-2 * np.polynomial.polynomial.polyval(X10, COEF[: true_order + 1]) + rng.normal(scale=1e-5, size=10)
        assert fit_temperature_curve(T10, y).chosen_order == true_order


def test_order_choice_rate_over_seeds():
    """LOO with the parsimony rule picks the true (cubic) order in most seeded runs."""
    rng = np.random.default_rng(1)
    hits = 0
    for _ in range(100):
        y = 1e-2 * np.polynomial.polynomial.polyval(X10, COEF[:4]) + rng.normal(scale=1e-5, size=10)
        hits += fit_temperature_curve(T10, y).chosen_order == 3
    assert hits >= 80


def test_residuals_fall_with_order_like_table_6_1():
    """In-sample MSE non-increasing 1 -> 5, MSE <= max|r|^2 (the consistency used to read Table 6.1)."""
    rng = np.random.default_rng(3)
    y = 5e-3 * np.tanh(1.5 * X10) + 1e-3 * X10**2 + rng.normal(scale=2e-5, size=10)
    f = fit_temperature_curve(T10, y)
    tab = f.table()
    assert all(np.diff(tab["mse"]) <= 1e-18)
    for m, mx, mn in zip(tab["mse"], tab["max_residual"], tab["min_residual_abs"]):
        assert m <= max(mx, mn) ** 2 + 1e-30 and mx >= 0 and mn >= 0
    assert tab["mse"][0] > 10 * tab["mse"][-1]


def test_loo_matches_brute_force():
    rng = np.random.default_rng(4)
    y = rng.normal(size=10)
    f = fit_temperature_curve(T10, y, orders=[2])
    brute = []
    for i in range(10):
        m = np.arange(10) != i
        c = np.polynomial.polynomial.polyfit(X10[m] * 40 / 40, y[m], 2)
        brute.append(y[i] - np.polynomial.polynomial.polyval(X10[i], c))
    assert f.fits[0].loo_mse == pytest.approx(np.mean(np.square(brute)), rel=1e-9)


def test_piecewise_removes_a_step():
    """ahrs-sensor-errors §7.5: cubic + step at 24.5 °C; polynomials leave the residual at the step."""
    T = np.linspace(-10, 50, 25)
    y = 1e-3 * (0.2 * ((T - 20) / 30) ** 3 - 0.5 * (T - 20) / 30) + 2e-4 * (T >= 24.5)
    poly = fit_temperature_curve(T, y, orders=[3])
    pw = fit_temperature_curve(T, y, orders=[3], model="piecewise")
    r = np.abs(poly.best.residuals)
    assert np.argmax(r) in (np.searchsorted(T, 24.5) - 1, np.searchsorted(T, 24.5))
    assert pw.best.mse < 1e-6 * poly.best.mse
    assert 22.5 < pw.curve.step_c <= 25.0 and pw.curve.step_height == pytest.approx(2e-4, rel=1e-6)


def test_thermal_calibration_and_runtime_compensation():
    """Calibrations at 10 temperatures -> B(T), S(T); compensation removes the thermal error."""
    rng = np.random.default_rng(5)
    bias_true = lambda t: 0.05 + 1e-3 * (t - 10) - 2e-5 * (t - 10) ** 2  # noqa: E731
    scale_true = lambda t: 1.01 + 2e-5 * (t - 10)  # noqa: E731
    cals = []
    for t in T10:
        Ta = np.diag([scale_true(t)] * 3)
        cals.append(ImuCalibration(accel_bias=[bias_true(t)] * 3, accel_matrix=Ta))
    res = thermal_calibration(T10, cals, params=("accel_bias", "accel_scale"))
    assert [f.chosen_order for f in res.fits["accel_bias"]] == [2, 2, 2]
    assert [f.chosen_order for f in res.fits["accel_scale"]] == [1, 1, 1]
    tt = rng.uniform(-30, 50, 200)
    f = rng.normal(scale=9.8, size=(200, 3))
    raw = f * scale_true(tt)[:, None] + bias_true(tt)[:, None]
    comp, _ = res.calibration.apply_arrays(raw, np.zeros_like(raw), temp_c=tt)
    np.testing.assert_allclose(comp, f, atol=1e-9)


def test_bad_inputs():
    with pytest.raises(InsufficientDataError, match="at least 7 distinct temperatures"):
        fit_temperature_curve(T10[:6], np.ones(6))
    with pytest.raises(ShapeError, match="equal-length"):
        fit_temperature_curve(T10, np.ones(9))
    with pytest.raises(InvalidInputError, match="model"):
        fit_temperature_curve(T10, np.ones(10), model="spline9")
    with pytest.raises(InsufficientDataError, match="2 distinct temperatures, got 1"):
        fit_temperature_curve(np.full(10, 20.0), np.ones(10), orders=[0])
    with pytest.raises(InvalidInputError, match="scale_c"):
        fit_temperature_curve(T10, np.ones(10), scale_c=0.0)


def test_plots_render(tmp_path):
    from imunav.calib import multiposition_from_means
    from imunav.calib.plot import plot_residuals, plot_temperature_fit, save_figure

    rng = np.random.default_rng(9)
    f = fit_temperature_curve(T10, rng.normal(size=10), orders=[1, 2])
    p = save_figure(plot_temperature_fit(f), tmp_path / "t.png")
    u = rng.normal(size=(12, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    r = multiposition_from_means(9.8 * u, 9.8 * u + rng.normal(scale=1e-3, size=u.shape), serial=False)
    q = save_figure(plot_residuals(r), tmp_path / "r.png")
    assert p.stat().st_size > 1000 and q.stat().st_size > 1000
