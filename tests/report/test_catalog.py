"""Parameter names for spec checks: estimates from calibrations / noise fits, axis-less limits, harvesting."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.calib import CalibrationResult, ImuCalibration
from imunav.lab.report import check_spec, load_spec
from imunav.lab.report.catalog import base_name, calibration_estimates, display_unit, expand_spec, to_display_value
from imunav.lab.runner import display_parameters, harvest_parameters
from imunav.units import DEG, G0


def _cal():
    T = np.eye(3) + np.diag([1e-3, 2e-3, 3e-3])
    T[0, 1] = 5e-3
    return ImuCalibration(accel_bias=[0.1, -0.2, 0.3], accel_matrix=T, gyro_bias=np.array([1, 2, 3]) * DEG / 3600,
                          g_sensitivity=np.diag([1e-5, 2e-5, 3e-5]))


def test_calibration_estimates_names_values_and_sigmas():
    se = {"accel_bias": np.full(3, 1e-3), "accel_matrix": np.full((3, 3), 1e-5), "gyro_bias": np.full(3, 1e-6),
          "g_sensitivity": np.full((3, 3), 1e-7)}
    est = calibration_estimates(_cal(), se)
    assert est["accel_bias_y"] == (-0.2, 1e-3)
    assert est["accel_scale_z"] == pytest.approx((3e-3, 1e-5))
    assert est["accel_misalignment_xy"] == pytest.approx((5e-3, 1e-5))
    assert est["gyro_g_sensitivity_z"] == pytest.approx((3e-5, 1e-7))
    # parameters without a standard error were not estimated: left out
    assert "gyro_scale_x" not in est and "gyro_misalignment_xy" not in est
    assert to_display_value("gyro_bias_z", est["gyro_bias_z"][0]) == pytest.approx(3.0)  # deg/h
    assert display_unit("accel_misalignment_zy") == "mrad" and base_name("gyro_arw_x") == "gyro_arw"


def test_axisless_spec_applies_to_every_axis_and_axis_entry_wins():
    spec = load_spec({"spec": {"accel_bias": {"max": 250, "unit": "mg"}, "accel_bias_z": {"max": 350, "unit": "mg"},
                               "gyro_arw": {"max": 0.1, "unit": "deg/sqrt(h)"}}})
    est = {"accel_bias_x": (0.2 * G0, None), "accel_bias_y": (-0.3 * G0, None), "accel_bias_z": (0.3 * G0, None)}
    lim = expand_spec(spec, list(est))
    assert lim["accel_bias_x"] is spec["accel_bias"] and lim["accel_bias_z"] is spec["accel_bias_z"]
    checks = {c.name: c.passed for c in check_spec(est, lim)}
    # |-300 mg| > 250 mg fails, z has its own 350 mg limit, gyro_arw specified but not measured fails
    assert checks == {"accel_bias_x": True, "accel_bias_y": False, "accel_bias_z": True, "gyro_arw": False}
    rows = display_parameters(est, spec, truth={"accel_bias_x": 0.21 * G0})
    assert rows[0].unit == "mg" and rows[0].value == pytest.approx(200.0) and rows[0].truth == pytest.approx(210.0)
    assert rows[1].limit == "≤ 250 mg" and rows[1].passed is False


def test_harvest_parameters_from_artifacts():
    se = {"accel_bias": np.full(3, 1e-3), "gyro_bias": np.full(3, 1e-6)}
    res = CalibrationResult(_cal(), se, {}, {})
    got = harvest_parameters({"calibration": {"static": res}, "other": [1, 2], "bare": _cal()})
    assert got["accel_bias_x"] == (0.1, 1e-3) and "gyro_bias_z" in got
    assert harvest_parameters({"x": np.zeros(3), "y": "text"}) == {}
