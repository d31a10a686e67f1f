"""``imunav noise`` end to end on a small simulated record and on the ADIS16405 npz."""

from __future__ import annotations

import json

import numpy as np
import pytest
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.noise import allan_deviation, fit_noise


def adis_welch_arw(path) -> np.ndarray:
    """Gyro white-noise density of the ADIS16405 record, deg/sqrt(h), from scipy's Welch PSD.

    Independent of imunav: the median one-sided PSD over 0.3-10 Hz, where it is flat within 1.5 % (below,
    bias instability lifts it; above 10 Hz the sensor's filter lowers it), and N = sqrt(PSD / 2).  The
    median over ~1460 bins of 122-segment averages has a relative error below 0.3 %."""
    from scipy.signal import welch

    d = np.load(path)
    g = np.deg2rad(d["gyro"])
    f, psd = welch(g - g.mean(axis=0), fs=float(d["fs"]), nperseg=2**14, axis=0)
    band = (f >= 0.3) & (f <= 10.0)
    return np.rad2deg(np.sqrt(np.median(psd[band], axis=0) / 2.0)) * 60.0


def _write_npz(path, rng, n=60_000, fs=100.0):
    g = rng.normal(scale=0.01 * np.sqrt(fs), size=(n, 3))  # N = 0.01 deg/s/sqrt(Hz)
    a = rng.normal(scale=1e-3 * np.sqrt(fs), size=(n, 3)) + [0, 0, -1]  # g
    np.savez(path, gyro=g, accel=a, fs=np.float64(fs))


def test_cli_noise_end_to_end(tmp_path, rng):
    f = tmp_path / "rec.npz"
    _write_npz(f, rng)
    out = tmp_path / "noise.json"
    r = CliRunner().invoke(app, ["noise", str(f), "--gyro-unit", "deg/s", "--accel-unit", "g", "--json", str(out),
                                 "--plot", str(tmp_path / "allan.png"), "--yaml", str(tmp_path / "imu.yaml"),
                                 "--openvins", str(tmp_path / "ov.yaml"), "--vins", str(tmp_path / "vins.yaml")])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    n_gyro = np.array(d["gyro"]["fit"]["terms"]["N"]["value"])
    np.testing.assert_allclose(n_gyro, 0.01 * np.pi / 180, rtol=0.03)
    assert (tmp_path / "allan_gyro.png").stat().st_size > 1000
    # the three estimator files carry the fitted gyro white noise (max over the axes), as written by the API
    nmax = float(n_gyro.max())
    for name, key in (("imu.yaml", "gyroscope_noise_density:"), ("ov.yaml", "gyroscope_noise_density:"),
                      ("vins.yaml", "gyr_n:")):
        line = next(ln for ln in (tmp_path / name).read_text().splitlines() if ln.strip().startswith(key))
        assert float(line.split(":")[1].split("#")[0]) == pytest.approx(nmax, rel=1e-12), name


def test_cli_noise_bad_channel(tmp_path, rng):
    f = tmp_path / "rec.npz"
    _write_npz(f, rng, n=2000)
    r = CliRunner().invoke(app, ["noise", str(f), "--channels", "gx,qq"])
    assert r.exit_code == 2 and "unknown" in r.output
    r = CliRunner().invoke(app, ["noise", str(f), "--channels", "gx,gy", "--kalibr", str(tmp_path / "k.yaml")])
    assert r.exit_code == 2 and "needs both gyro and accel" in r.output
    assert not (tmp_path / "k.yaml").exists()


@pytest.mark.data
def test_cli_noise_adis16405(tmp_path):
    p = data_path("adis16405", "adis16405_imu2.npz")
    out = tmp_path / "adis.json"
    r = CliRunner().invoke(app, ["noise", str(p), "--gyro-unit", "deg/s", "--accel-unit", "g", "--json", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    # ARW against an independent reference: the white-noise plateau of a scipy Welch PSD of the same record
    # (adis_welch_arw).  The CLI's default fit gives -1.2, -1.1 and -6.8 % (x, y, z): on z its automatic
    # tau_min keeps the 80 ms point, which the sensor's internal low-pass pulls down (chi^2 558 on 13 dof);
    # with tau >= 0.15 s the fit is within 1.3 % (test_adis16405_arw_against_welch_psd).  Deterministic: the
    # margin only covers numerics.
    arw = np.array(d["gyro"]["fit"]["terms"]["N"]["display_value"])
    np.testing.assert_allclose(arw, adis_welch_arw(p), rtol=0.08)
    for s in ("gyro", "accel"):
        assert np.all(np.abs(d[s]["psd_vs_allan"]["N"]) < 0.10)


@pytest.mark.data
def test_adis16405_arw_against_welch_psd():
    """fit_noise's N on the ADIS16405 record within 3 % of the Welch-PSD plateau on every axis (achieved
    -0.3, -0.4, +1.3 %), fitting tau >= 0.15 s (past the sensor's internal low-pass)."""
    p = data_path("adis16405", "adis16405_imu2.npz")
    d = np.load(p)
    f = fit_noise(allan_deviation(np.deg2rad(d["gyro"]), float(d["fs"]), units="rad/s"), tau_range=(0.15, 1e5))
    ref = adis_welch_arw(p)
    np.testing.assert_allclose(f.display("N"), ref, rtol=0.03)


def test_cli_noise_on_a_px4_log_with_dropouts_in_a_window(tmp_path):
    """sample.ulg has logger dropouts: a window of its static stretch is analysed, gaps reported (issue 26)."""
    ulg = data_path("px4_ulog", "sample.ulg")
    out = tmp_path / "n.json"
    r = CliRunner().invoke(app, ["noise", str(ulg), "--topic", "sensor_combined", "--start", "6", "--end", "68",
                            "--channels", "gx,gy,gz", "--json", str(out)])
    assert r.exit_code == 0, r.output
    assert "time gap(s)" in r.output
    d = json.loads(out.read_text())
    assert d["start_s"] == 6 and len(d["gaps"]) >= 1 and 15000 < d["n_samples"] < 15600
    assert "identifiability" in d and set(d["identifiability"]["gyro"]) <= {"B", "K", "R"}
