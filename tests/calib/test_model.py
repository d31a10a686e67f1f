"""ImuCalibration: apply/invert, JSON, imucal conversion, thermal curves, errors."""

import json

import numpy as np
import pytest
from builders import thesis_truth

from imunav.calib import ImuCalibration, TempCurve, calibration_parameters, success_percentages
from imunav.errors import FileFormatError, InvalidInputError, NonFiniteError, ShapeError, UnitError


def test_apply_inverts_invert_exactly(rng):
    cal = thesis_truth()
    f = rng.normal(scale=9.8, size=(200, 3))
    w = rng.normal(scale=1.0, size=(200, 3))
    a, g = cal.invert_arrays(f, w)
    f2, w2 = cal.apply_arrays(a, g)
    np.testing.assert_allclose(f2, f, rtol=0, atol=1e-12)
    np.testing.assert_allclose(w2, w, rtol=0, atol=1e-12)


def test_gyro_uses_compensated_accel():
    # ω̃ = T ω + b + G f with f the *true* force: compensation must use f̂ = T_a⁻¹(ã − b_a)
    cal = ImuCalibration(accel_bias=[1.0, 0, 0], accel_matrix=np.diag([2.0, 1, 1]), g_sensitivity=np.eye(3))
    f, w = cal.apply_arrays(np.array([[3.0, 0, 0]]), np.array([[1.0, 0, 0]]))
    assert f[0, 0] == pytest.approx(1.0)
    assert w[0, 0] == pytest.approx(0.0)


def test_json_roundtrip_with_thermal(tmp_path):
    curve = TempCurve(np.array([0.1, 0.01, -0.002]), 10.0, 40.0, step_c=24.5, step_height=0.003)
    cal = thesis_truth().with_(
        thermal={"accel_bias": (curve, curve, curve)}, stderr={"accel_bias": np.array([1e-4, 2e-4, 3e-4])}
    )
    p = cal.save(tmp_path / "cal.json")
    d = json.loads(p.read_text())
    assert d["format_version"] == 1 and d["units"]["raw_accel"] == "m/s^2"
    back = ImuCalibration.load(p)
    np.testing.assert_array_equal(back.accel_matrix, cal.accel_matrix)
    np.testing.assert_array_equal(back.stderr["accel_bias"], cal.stderr["accel_bias"])
    temps = np.array([-30.0, 24.0, 25.0, 50.0])
    a = np.tile([[1.0, 2.0, -9.0]], (4, 1))
    np.testing.assert_allclose(back.apply_arrays(a, a, temps)[0], cal.apply_arrays(a, a, temps)[0], rtol=0, atol=0)


def test_thermal_bias_and_scale_replace_constants():
    bias = TempCurve(np.array([0.5, 0.1]), 20.0, 10.0)  # 0.5 + 0.1 (T-20)/10
    scale = TempCurve(np.array([1.01, 0.001]), 20.0, 10.0)
    cal = ImuCalibration(thermal={"accel_bias": (bias,) * 3, "accel_scale": (scale,) * 3})
    T = np.array([20.0, 40.0])
    a, _ = cal.invert_arrays(np.ones((2, 3)), np.zeros((2, 3)), T)
    np.testing.assert_allclose(a[:, 0], [1.01 + 0.5, 1.012 + 0.7])
    with pytest.raises(InvalidInputError, match="temp_c"):
        cal.apply_arrays(a, a)


def test_imucal_conversion_roundtrip():
    cal = thesis_truth().with_(g_sensitivity=np.full((3, 3), 1e-4))
    d = cal.to_imucal()
    np.testing.assert_allclose(np.linalg.norm(d["R_a"], axis=1), 1.0)
    back = ImuCalibration.from_imucal(d)
    np.testing.assert_allclose(back.gyro_matrix, cal.gyro_matrix, rtol=1e-14)
    np.testing.assert_allclose(back.accel_matrix, cal.accel_matrix, rtol=1e-14)
    np.testing.assert_allclose(back.g_sensitivity, cal.g_sensitivity)


def test_success_metric_definition():
    t = thesis_truth()
    assert success_percentages(t, t)["accel_mean"] == 100.0
    p = calibration_parameters(t)
    est = t.with_(accel_bias=t.accel_bias * 1.01)
    s = success_percentages(est, t)
    np.testing.assert_allclose(s["per_parameter"]["accel_B"], 99.0)
    assert s["accel_mean"] == pytest.approx((9 * 100 + 3 * 99) / 12)
    assert p["accel_M"][0] == pytest.approx(7.8824e-3)


def test_bad_inputs(tmp_path):
    with pytest.raises(ShapeError, match="accel_bias"):
        ImuCalibration(accel_bias=[1, 2])
    with pytest.raises(NonFiniteError, match="gyro_matrix"):
        ImuCalibration(gyro_matrix=np.full((3, 3), np.nan))
    with pytest.raises(InvalidInputError, match="singular"):
        ImuCalibration(accel_matrix=np.zeros((3, 3)))
    with pytest.raises(ShapeError, match=r"\(N, 3\)"):
        ImuCalibration().apply_arrays(np.zeros((4, 2)), np.zeros((4, 2)))
    p = tmp_path / "x.json"
    p.write_text(json.dumps({"format": "imunav.imu-calibration", "format_version": 99}))
    with pytest.raises(FileFormatError, match="format_version 99"):
        ImuCalibration.load(p)
    p.write_text("{not json")
    with pytest.raises(FileFormatError, match="invalid JSON"):
        ImuCalibration.load(p)
    with pytest.raises(FileFormatError, match="does not exist"):
        ImuCalibration.load(tmp_path / "missing.json")
    counts = ImuCalibration(raw_accel_unit="counts")

    class D:
        accel = np.zeros((2, 3))
        gyro = np.zeros((2, 3))

    with pytest.raises(UnitError, match="apply_arrays"):
        counts.apply(D())
