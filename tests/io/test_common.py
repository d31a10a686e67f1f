"""Units declared in a file win over reader options (issue 16): a contradicting option is an error naming both."""

import json

import numpy as np
import pytest
from builders import static_imu
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import UnitError
from imunav.io import read_imu, write_imu


def _rec():
    return static_imu(200, accel=(0.0, 0.0, -9.81), mag=(20.0, 0.0, 40.0), mag_unit="uT")


@pytest.mark.parametrize("ext", ["csv", "parquet", "h5", "npz", "mat"])
def test_contradicting_unit_refused_matching_accepted(tmp_path, ext):
    p = write_imu(_rec(), tmp_path / f"rec.{ext}")
    with pytest.raises(UnitError, match=r"declares gyro in 'rad/s'.*'deg/s'"):
        read_imu(p, units={"gyro": "deg/s"})
    with pytest.raises(UnitError, match=r"declares t in 's'.*'ms'"):
        read_imu(p, units={"t": "ms"})
    # the same unit, however spelled, is not a contradiction: values unchanged
    got = read_imu(p, units={"gyro": "rad/s", "accel": "m/s^2"})
    np.testing.assert_array_equal(got.gyro, _rec().gyro)


def test_option_fills_in_an_undeclared_unit(tmp_path):
    p = tmp_path / "plain.csv"
    d = _rec()
    np.savetxt(p, np.column_stack([d.t, np.degrees(d.gyro), d.accel]), delimiter=",",
               header="t,gx,gy,gz,ax,ay,az", comments="")
    got = read_imu(p, units={"gyro": "deg/s"})
    np.testing.assert_allclose(got.gyro, d.gyro, rtol=1e-12)


def test_cli_info_refuses_a_contradicting_flag(tmp_path):
    p = write_imu(_rec(), tmp_path / "rec.csv")
    r = CliRunner().invoke(app, ["info", str(p), "--gyro-unit", "deg/s"])
    assert r.exit_code == 2
    err = r.stderr if hasattr(r, "stderr") else r.output
    assert "declares gyro in 'rad/s'" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    ok = CliRunner().invoke(app, ["info", str(p), "--json", str(tmp_path / "i.json")])
    assert ok.exit_code == 0, ok.output
    json.loads((tmp_path / "i.json").read_text())
