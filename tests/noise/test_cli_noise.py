"""``imunav noise`` end to end on a small simulated record and on the ADIS16405 npz."""

from __future__ import annotations

import json

import numpy as np
import pytest
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli.main import app


def _write_npz(path, rng, n=60_000, fs=100.0):
    g = rng.normal(scale=0.01 * np.sqrt(fs), size=(n, 3))  # N = 0.01 deg/s/sqrt(Hz)
    a = rng.normal(scale=1e-3 * np.sqrt(fs), size=(n, 3)) + [0, 0, -1]  # g
    np.savez(path, gyro=g, accel=a, fs=np.float64(fs))


def test_cli_noise_end_to_end(tmp_path, rng):
    f = tmp_path / "rec.npz"
    _write_npz(f, rng)
    out = tmp_path / "noise.json"
    r = CliRunner().invoke(app, ["noise", str(f), "--gyro-unit", "deg/s", "--accel-unit", "g", "--json", str(out),
                                 "--plot", str(tmp_path / "allan.png"), "--yaml", str(tmp_path / "imu.yaml")])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    n_gyro = np.array(d["gyro"]["fit"]["terms"]["N"]["value"])
    np.testing.assert_allclose(n_gyro, 0.01 * np.pi / 180, rtol=0.03)
    assert (tmp_path / "allan_gyro.png").stat().st_size > 1000
    assert "gyroscope_noise_density" in (tmp_path / "imu.yaml").read_text()


def test_cli_noise_bad_channel(tmp_path, rng):
    f = tmp_path / "rec.npz"
    _write_npz(f, rng, n=2000)
    r = CliRunner().invoke(app, ["noise", str(f), "--channels", "gx,qq"])
    assert r.exit_code == 2 and "unknown" in r.output


@pytest.mark.data
def test_cli_noise_adis16405(tmp_path):
    p = data_path("adis16405", "adis16405_imu2.npz")
    out = tmp_path / "adis.json"
    r = CliRunner().invoke(app, ["noise", str(p), "--gyro-unit", "deg/s", "--accel-unit", "g", "--json", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    # datasheet ARW of the ADIS16405 is 2.0 deg/sqrt(h) (typ.); PSD and Allan N within 10 %
    arw = np.array(d["gyro"]["fit"]["terms"]["N"]["display_value"])
    assert np.all((arw > 1.5) & (arw < 3.0))
    for s in ("gyro", "accel"):
        assert np.all(np.abs(d[s]["psd_vs_allan"]["N"]) < 0.10)
