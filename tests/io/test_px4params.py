"""PX4 calibration parameters for the next tool (issue 17).

The file is written, parsed back with a small parser of QGroundControl's parameter format (below, independent of
the writer) and checked against the values it came from, the PX4 correction formulas, and the parameter names PX4
documents.
"""

from __future__ import annotations

import numpy as np
import pytest

from imunav.calib import ImuCalibration
from imunav.calib.magnetometer import MagCalibration
from imunav.calib.model import TempCurve
from imunav.errors import InvalidInputError, UnitError
from imunav.io.px4params import px4_parameters, write_px4_params

# PX4 parameter reference, group "Sensor Calibration", instance 0:
# https://docs.px4.io/main/en/advanced_config/parameter_reference.html
PX4_DOC_NAMES = {
    "CAL_ACC0_ID", "CAL_ACC0_PRIO", "CAL_ACC0_XOFF", "CAL_ACC0_YOFF", "CAL_ACC0_ZOFF",
    "CAL_ACC0_XSCALE", "CAL_ACC0_YSCALE", "CAL_ACC0_ZSCALE",
    "CAL_GYRO0_ID", "CAL_GYRO0_PRIO", "CAL_GYRO0_XOFF", "CAL_GYRO0_YOFF", "CAL_GYRO0_ZOFF",
    "CAL_MAG0_ID", "CAL_MAG0_PRIO", "CAL_MAG0_XOFF", "CAL_MAG0_YOFF", "CAL_MAG0_ZOFF",
    "CAL_MAG0_XSCALE", "CAL_MAG0_YSCALE", "CAL_MAG0_ZSCALE", "CAL_MAG0_XODIAG", "CAL_MAG0_YODIAG", "CAL_MAG0_ZODIAG",
}


def parse_qgc_params(text: str) -> dict[str, tuple[int, int, float, int]]:
    """QGroundControl parameter file: ``{name: (vehicle, component, value, type)}``."""
    out = {}
    for ln in text.splitlines():
        if not ln.strip() or ln.startswith("#"):
            continue
        veh, comp, name, value, typ = ln.split("\t")
        assert int(typ) in (6, 9), ln  # MAV_PARAM_TYPE_INT32 / REAL32
        out[name] = (int(veh), int(comp), int(value) if int(typ) == 6 else float(value), int(typ))
    return out


def _px4_accel(p, raw):
    off = np.array([p[f"CAL_ACC0_{a}OFF"][2] for a in "XYZ"])
    scale = np.array([p[f"CAL_ACC0_{a}SCALE"][2] for a in "XYZ"])
    return (raw - off) * scale  # PX4 Accelerometer::Correct (rotation: none)


def _px4_gyro(p, raw):
    return raw - np.array([p[f"CAL_GYRO0_{a}OFF"][2] for a in "XYZ"])  # PX4 Gyroscope::Correct


def _px4_mag(p, raw_gauss):
    d = [p[f"CAL_MAG0_{a}SCALE"][2] for a in "XYZ"]
    o = [p[f"CAL_MAG0_{a}ODIAG"][2] for a in "XYZ"]
    S = np.array([[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]])  # PX4 Magnetometer scale matrix
    off = np.array([p[f"CAL_MAG0_{a}OFF"][2] for a in "XYZ"])
    return (raw_gauss - off) @ S.T


def _mag(A, b, field_norm=48.0):
    return MagCalibration(b=np.asarray(b, float), A=np.asarray(A, float), field_norm=field_norm, method="test")


def test_px4_reproduces_imunav_compensation(tmp_path):
    """A model PX4 can express: the PX4 formulas with the parsed parameters give imunav's compensation."""
    rng = np.random.default_rng(3)
    cal = ImuCalibration(accel_bias=[0.12, -0.05, 0.31], accel_matrix=np.diag([1.01, 0.985, 1.004]),
                         gyro_bias=[0.004, -0.002, 0.0011])
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    A = R @ np.diag([1.1, 0.93, 0.98]) @ R.T  # symmetric soft iron
    mag = _mag(A, [12.0, -30.0, 5.5])  # uT
    res = write_px4_params(tmp_path / "cal.params", cal, mag, mag_unit="uT", accel_id=1310988, gyro_id=1310989,
                           mag_id=396825)
    assert res.dropped == ()
    p = parse_qgc_params((tmp_path / "cal.params").read_text())
    assert set(p) == PX4_DOC_NAMES
    assert {v[:2] for v in p.values()} == {(1, 1)}
    assert p["CAL_ACC0_ID"] == (1, 1, 1310988, 6) and p["CAL_MAG0_PRIO"] == (1, 1, 50, 6)
    assert p["CAL_ACC0_XOFF"][3] == 9
    a_raw = rng.normal([0, 0, -9.8], 3.0, (500, 3))
    w_raw = rng.normal(0, 1.0, (500, 3))
    f_ref, w_ref = cal.apply_arrays(a_raw, w_raw)
    np.testing.assert_allclose(_px4_accel(p, a_raw), f_ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(_px4_gyro(p, w_raw), w_ref, rtol=0, atol=1e-9)
    h_raw = rng.normal(0, 50.0, (500, 3))  # uT
    np.testing.assert_allclose(_px4_mag(p, h_raw * 0.01), mag.apply(h_raw) * 0.01, rtol=0, atol=1e-9)


def test_px4_drops_what_it_cannot_express(tmp_path):
    rng = np.random.default_rng(4)
    Ta = np.diag([1.01, 0.99, 1.0]) + np.array([[0, 2e-3, -1e-3], [0, 0, 5e-4], [0, 0, 0]])
    cal = ImuCalibration(accel_bias=[0.1, 0, 0], accel_matrix=Ta, gyro_matrix=np.eye(3) * 1.002,
                         g_sensitivity=np.diag([1e-4, 0, 0]))
    th = np.radians(5.0)
    U = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    P = np.diag([1.05, 0.95, 1.0])
    mag = _mag(U @ P, [0.1, 0.2, 0.3], 0.48)  # gauss; not symmetric: a 5 deg rotation PX4 cannot hold
    res = write_px4_params(tmp_path / "c.params", cal, mag)
    text = (tmp_path / "c.params").read_text()
    assert len(res.dropped) == 4 and all(d in text for d in res.dropped)
    assert "accelerometer cross-axis" in res.dropped[0] and "g-sensitivity" in res.dropped[2]
    assert "rotation of 5 deg" in res.dropped[3]
    p = parse_qgc_params(text)
    # the accel scales are the diagonal of T_a^-1; the soft-iron matrix is the symmetric factor P of A = U P
    np.testing.assert_allclose([p[f"CAL_ACC0_{a}SCALE"][2] for a in "XYZ"], np.diag(np.linalg.inv(Ta)), rtol=1e-15)
    h = rng.normal(0, 0.5, (200, 3))
    np.testing.assert_allclose(_px4_mag(p, h), (h - mag.b) @ P.T, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(_px4_mag(p, h), axis=1), np.linalg.norm(mag.apply(h), axis=1),
                               atol=1e-12)
    with pytest.raises(InvalidInputError, match="PX4 cannot express accelerometer cross-axis"):
        px4_parameters(cal, strict=True)


def test_px4_bad_input(tmp_path):
    cal = ImuCalibration()
    with pytest.raises(InvalidInputError, match="nothing to export"):
        px4_parameters()
    thermal = cal.with_(thermal={"accel_bias": tuple(TempCurve(np.array([0.0, 1e-3]), 20.0, 10.0)
                                                     for _ in range(3))})
    with pytest.raises(InvalidInputError, match="temperature model"):
        px4_parameters(thermal)
    with pytest.raises(UnitError, match="m/s\\^2 and rad/s"):
        px4_parameters(cal.with_(raw_accel_unit="counts"))
    with pytest.raises(InvalidInputError, match="outside PX4's range"):
        px4_parameters(cal.with_(accel_matrix=np.eye(3) * 20.0))
    with pytest.raises(InvalidInputError, match="slot 0-3"):
        px4_parameters(cal, instance=4)
    with pytest.raises(InvalidInputError, match="device id"):
        px4_parameters(cal, accel_id=-3)
    with pytest.raises(UnitError, match="mag_unit"):
        px4_parameters(mag=_mag(np.eye(3), [0, 0, 0]), mag_unit="furlong")
    with pytest.raises(UnitError, match="magnitude 48 gauss is outside"):  # µT data taken for gauss
        px4_parameters(mag=_mag(np.eye(3), [0, 0, 0]), mag_unit="gauss")
    assert px4_parameters(mag=_mag(np.eye(3), [0, 0, 0]), mag_unit="uT").converted == (
        "CAL_MAG0_{X,Y,Z}OFF: the offsets converted from uT to PX4's gauss (x 0.01); the scales are unitless",)
    assert not list(tmp_path.iterdir())
    p = px4_parameters(cal, instance=2)
    assert set(p.values) == {f"CAL_{s}2_{a}{k}" for s, k in (("ACC", "OFF"), ("ACC", "SCALE"), ("GYRO", "OFF"))
                             for a in "XYZ"}
