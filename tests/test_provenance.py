"""Provenance travels with the data (issue 16, deliverable 3).

Compensation, resampling and unit conversion are recorded in ``ImuData.meta["provenance"]``;
every writer / reader keeps the record; a second compensation with the same calibration is
refused unless forced; one with another calibration warns.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from builders import static_imu
from typer.testing import CliRunner

from imunav.calib import ImuCalibration
from imunav.cli.main import app
from imunav.errors import ImunavWarning, InvalidInputError, ProvenanceError
from imunav.io import read_imu, write_imu
from imunav.provenance import steps
from imunav.timeseries import ImuData

G = 9.80665


def _raw():
    return static_imu(400, seed=3)


CAL = ImuCalibration(accel_bias=[0.1, -0.05, 0.02], accel_matrix=np.diag([1.01, 0.99, 1.0]),
                     gyro_bias=[1e-3, 0, -2e-3])
CAL2 = ImuCalibration(accel_bias=[0.2, 0.0, 0.0])


def test_unit_conversion_is_recorded():
    d = ImuData.from_arrays(None, np.zeros((10, 3)), np.tile([0, 0, -1.0], (10, 1)), fs=100, gyro_unit="deg/s",
                            accel_unit="g")
    (s,) = steps(d, "convert_units")
    assert s["parameters"]["from"] == {"time": "s", "gyro": "deg/s", "accel": "g"}
    assert s["parameters"]["to"]["accel"] == "m/s^2" and s["time"] and s["imunav"]
    assert steps(_raw(), "convert_units") == []  # SI in: nothing converted, nothing recorded


def test_reader_unit_option_is_recorded(tmp_path):
    p = tmp_path / "plain.csv"
    np.savetxt(p, np.column_stack([np.arange(20) / 100, np.zeros((20, 3)), np.tile([0, 0, -1.0], (20, 1))]),
               delimiter=",", header="t,gx,gy,gz,ax,ay,az", comments="")
    d = read_imu(p, units={"accel": "g"})
    assert d.accel[0, 2] == pytest.approx(-G)
    assert [s["parameters"]["from"]["accel"] for s in steps(d, "convert_units")] == ["g"]


def test_resample_is_recorded_and_absurd_rates_refused():
    d = _raw()
    r = d.resample(50.0)
    (s,) = steps(r, "resample")
    assert s["parameters"]["to_hz"] == 50.0 and s["parameters"]["from_hz"] == pytest.approx(100.0)
    assert r.meta["resampled_from_hz"] == pytest.approx(100.0)
    assert steps(d, "resample") == []  # the input is not changed
    with pytest.raises(InvalidInputError, match="samples"):
        d.resample(1e12)  # 4e12 samples: refused before any allocation
    with pytest.raises(InvalidInputError, match="fewer than 2 samples"):
        d.resample(0.1)


def test_compensation_recorded_and_a_second_one_refused_unless_forced():
    raw = _raw()
    once = CAL.apply(raw, source="cal.json")
    (s,) = steps(once, "compensate")
    assert s["calibration"]["sha256"] == CAL.sha256 and s["calibration"]["source"] == "cal.json"
    with pytest.raises(ProvenanceError, match=r"already compensated with calibration sha256:.*cal\.json.*force=True"):
        CAL.apply(once)
    twice = CAL.apply(once, force=True)
    assert len(steps(twice, "compensate")) == 2 and steps(twice, "compensate")[-1]["parameters"]["force"] is True
    # the values of the forced second compensation really are compensated twice (the record is not cosmetic)
    np.testing.assert_allclose(twice.accel, CAL.apply_arrays(once.accel, once.gyro)[0])


def test_a_different_calibration_on_compensated_data_warns():
    once = CAL.apply(_raw())
    with pytest.warns(ImunavWarning, match="another calibration"):
        both = CAL2.apply(once)
    assert [s["calibration"]["sha256"] for s in steps(both, "compensate")] == [CAL.sha256, CAL2.sha256]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        CAL.apply(_raw())  # raw data: no warning


def test_invert_undoes_a_compensation_in_the_record():
    once = CAL.apply(_raw())
    back = CAL.invert(once)
    assert [s["op"] for s in steps(back)] == ["compensate", "uncompensate"]
    again = CAL.apply(back)  # allowed: the compensation was undone
    np.testing.assert_allclose(again.accel, once.accel, atol=1e-12)


def test_hash_is_the_parameters_not_the_metadata(tmp_path):
    p = CAL.save(tmp_path / "cal.json")
    loaded = ImuCalibration.load(p)
    assert loaded.sha256 == CAL.sha256
    assert CAL.with_(meta={"comment": "x"}).sha256 == CAL.sha256
    assert CAL.with_(accel_bias=[0.1, -0.05, 0.0200001]).sha256 != CAL.sha256


@pytest.mark.parametrize("ext", ["csv", "parquet", "h5", "npz", "mat"])
def test_every_format_keeps_the_provenance(tmp_path, ext):
    d = CAL.apply(ImuData.from_arrays(None, np.zeros((50, 3)), np.tile([0, 0, -1.0], (50, 1)), fs=100,
                                      accel_unit="g").resample(50.0), source="cal.json")
    p = write_imu(d, tmp_path / f"rec.{ext}")
    back = read_imu(p)
    assert steps(back) == steps(d)
    assert [s["op"] for s in steps(back)] == ["convert_units", "resample", "compensate"]
    with pytest.raises(ProvenanceError):
        CAL.apply(back)


def _cli(*args):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_cli_compensate_twice_refused_force_and_other_calibration_warns(tmp_path):
    write_imu(_raw(), tmp_path / "raw.npz")
    CAL.save(tmp_path / "cal.json")
    CAL2.save(tmp_path / "cal2.json")
    r = _cli("compensate", tmp_path / "raw.npz", "--cal", tmp_path / "cal.json", "--out", tmp_path / "c1.npz")
    assert r.exit_code == 0, r.stderr
    assert steps(read_imu(tmp_path / "c1.npz"), "compensate")[0]["calibration"]["source"].endswith("cal.json")
    r = _cli("compensate", tmp_path / "c1.npz", "--cal", tmp_path / "cal.json", "--out", tmp_path / "c2.npz")
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and "--force" in r.stderr
    assert not (tmp_path / "c2.npz").exists()
    r = _cli("compensate", tmp_path / "c1.npz", "--cal", tmp_path / "cal.json", "--out", tmp_path / "c2.npz", "--force")
    assert r.exit_code == 0 and len(steps(read_imu(tmp_path / "c2.npz"), "compensate")) == 2
    r = _cli("compensate", tmp_path / "c1.npz", "--cal", tmp_path / "cal2.json", "--out", tmp_path / "c3.csv")
    assert r.exit_code == 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: ") and "another calibration" in lines[0]
