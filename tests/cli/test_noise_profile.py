"""``imunav noise --profile`` and ``--noise PROFILE`` on ``attitude run``, ``zupt run``: the profile from a record's
rest reaches the filters' configurations in their units."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_contract import invoke, one_error_line
from shared_data import data_path

from imunav.ins import ZuptConfig
from imunav.ins.gins import GinsConfig
from imunav.noise import NoiseProfile, NoiseTerm, SensorNoise, read_noise_profile

NAN = float("nan")

BROAD05 = "05_undisturbed_slow_rotation_with_breaks_B.mat"


def _npz(path, rng, n=3000, fs=100.0):
    np.savez(path, gyro=rng.normal(scale=0.1, size=(n, 3)), accel=rng.normal(scale=0.01, size=(n, 3)) + [0, 0, -9.81],
             fs=np.float64(fs))
    return path


def test_bad_profile_exits_2_with_one_line(tmp_path, rng):
    rec = _npz(tmp_path / "rec.npz", rng)
    bad = tmp_path / "p.toml"
    bad.write_text('format = "imunav noise profile"\nversion = 1\nfs = 100.0\nduration_s = 10.0\n'
                   '[gyro]\nunit = "deg/s"\n')
    line = one_error_line(invoke("attitude", "run", rec, "--filter", "mekf", "--noise", bad))
    assert str(bad) in line and "lacks gyro.noise_density" in line
    line = one_error_line(invoke("attitude", "run", rec, "--filter", "mekf", "--noise", tmp_path / "none.toml"))
    assert "none.toml" in line
    # a filter with fixed gains takes no noise parameters
    ok = tmp_path / "ok.toml"
    r = invoke("noise", rec, "--profile", ok, "--force")
    assert r.exit_code == 0, r.output
    line = one_error_line(invoke("attitude", "run", rec, "--filter", "madgwick", "--noise", ok))
    assert "--noise" in line and "mekf" in line


def test_profile_option_checks(tmp_path, rng):
    rec = _npz(tmp_path / "rec.npz", rng)
    line = one_error_line(invoke("noise", rec, "--profile", tmp_path / "p.yaml", "--force"))
    assert "--profile" in line and ".toml" in line
    line = one_error_line(invoke("noise", rec, "--channels", "gx,gy", "--profile", tmp_path / "p.toml", "--force"))
    assert "three axes" in line
    line = one_error_line(invoke("noise", rec, "--profile", rec))  # an output never overwrites an input
    assert "rec.npz" in line
    assert not (tmp_path / "p.toml").exists()


@pytest.mark.data
def test_attitude_run_with_a_profile_of_the_trials_rest(tmp_path):
    trial = data_path("broad", BROAD05)
    prof = tmp_path / "rest.toml"
    r = invoke("noise", trial, "--end", 25, "--profile", prof, "-q")
    assert r.exit_code == 0, r.output
    p = read_noise_profile(prof)
    assert p.fs == pytest.approx(2000 / 7, rel=1e-9) and p.duration_s == pytest.approx(25.0, abs=0.01)
    assert "[:25 s]" in p.source
    assert read_noise_profile(p.write(tmp_path / "rest.json")) == p  # and back through JSON, exactly
    # the trial's magnetometer (µT) comes along: about 0.07 µT/√Hz on each axis
    assert p.sensors() == ("gyro", "accel", "mag") and p.mag.unit == "uT"
    assert p.mag.units()["noise_density"] == "uT/sqrt(Hz)"
    assert np.all((p.mag.noise_density.value > 0.03) & (p.mag.noise_density.value < 0.15))
    # a MEMS gyro at rest: N about 1e-4 rad/s/√Hz (0.3 °/√h) on every axis
    assert np.all((p.gyro.noise_density.value > 5e-5) & (p.gyro.noise_density.value < 2e-4))
    out = tmp_path / "run.json"
    r = invoke("attitude", "run", trial, "--noise", prof, "--param", "heading_time_constant=20", "--json", out)
    assert r.exit_code == 0, r.output
    assert "noise from" in r.stdout and "BROAD RMSE" in r.stdout
    params = json.loads(out.read_text())["params"]
    n_g = float(np.max(p.gyro.noise_density.value))
    assert params["gyro_noise_density"] == pytest.approx(n_g, rel=1e-12)
    assert params["gyro_bias_random_walk"] == pytest.approx(float(np.max(p.gyro.bias_random_walk.value)), rel=1e-12)
    assert params["zaru_noise_std"] == pytest.approx(n_g * math.sqrt(2000 / 7), rel=1e-9)  # rad/s per sample
    assert params["heading_time_constant"] == 20  # --param wins over the defaults


def adis_welch_density(x: np.ndarray, fs: float) -> np.ndarray:
    """White-noise density of each column, unit/√Hz, from scipy's Welch PSD (independent of imunav): the median
    one-sided PSD over 0.3-10 Hz, N = sqrt(PSD / 2) (the method of tests/cli/test_noise.py::adis_welch_arw)."""
    from scipy.signal import welch

    f, psd = welch(x - x.mean(axis=0), fs=fs, nperseg=2**14, axis=0)
    band = (f >= 0.3) & (f <= 10.0)
    return np.sqrt(np.median(psd[band], axis=0) / 2.0)


@pytest.mark.data
def test_adis16405_profile_reaches_zupt_and_gins_in_their_units(tmp_path):
    src = data_path("adis16405", "adis16405_imu2.npz")
    prof = tmp_path / "adis.json"
    r = invoke("noise", src, "--gyro-unit", "deg/s", "--accel-unit", "g", "--end", 2000, "--profile", prof, "-q")
    assert r.exit_code == 0, r.output
    p = read_noise_profile(prof)
    assert read_noise_profile(p.write(tmp_path / "adis.toml")) == p  # and back through TOML, exactly
    assert p.gyro.noise_density.identified.all() and np.all(p.gyro.noise_density.se < 0.01 * p.gyro.noise_density.value)
    d = np.load(src)
    n = 200_000  # the 2000 s the profile saw
    n_gyro = adis_welch_density(np.deg2rad(d["gyro"][:n]), 100.0)  # rad/s/√Hz
    n_accel = adis_welch_density(d["accel"][:n] * 9.80665, 100.0)  # m/s²/√Hz
    # the Allan N of the profile against the Welch plateau: gyro within 8 % (as the CLI's ARW test), the
    # accelerometer, quantised at 3.3 mg (a third of its noise), within 25 %.  A unit slip (deg, g, a missing √fs)
    # is a factor 10 or more.
    np.testing.assert_allclose(p.gyro.noise_density.value, n_gyro, rtol=0.08)
    np.testing.assert_allclose(p.accel.noise_density.value, n_accel, rtol=0.25)
    z = ZuptConfig.from_noise_profile(p, fs=100.0)
    assert z.gyro_noise_std == pytest.approx(float(np.max(n_gyro)) * 10.0, rel=0.08)  # rad/s per sample at 100 Hz
    assert z.accel_noise_std == pytest.approx(float(np.max(n_accel)) * 10.0, rel=0.25)  # m/s² per sample
    assert z.gyro_bias_random_walk == float(np.max(p.gyro.bias_random_walk.value))
    g = GinsConfig.from_noise_profile(p, corr_time=3600.0)
    np.testing.assert_allclose(g.gyro_noise_density, n_gyro, rtol=0.08)
    np.testing.assert_allclose(g.accel_noise_density, n_accel, rtol=0.25)
    B, K = p.gyro.bias_instability.value, p.gyro.bias_random_walk.value
    np.testing.assert_allclose(g.gyro_bias_std, np.sqrt(B**2 + K**2 * 1800.0), rtol=1e-12)
    # the record is 100 Hz: the per-sample σ of the ZUPT INS at a 200 Hz foot IMU is √2 larger
    assert ZuptConfig.from_noise_profile(p, fs=200.0).gyro_noise_std == pytest.approx(z.gyro_noise_std * math.sqrt(2))


@pytest.mark.data
def test_zupt_run_with_a_profile(tmp_path):
    trial = data_path("foot", "pyshoe_vicon", "2017-11-22-11-22-03.mat")
    prof = NoiseProfile(fs=100.0, duration_s=600.0, source="a foot IMU's data sheet, by hand",
                        gyro=SensorNoise("rad/s", NoiseTerm([1e-3, 2e-3, 1e-3], [NAN] * 3, [True] * 3),
                                         NoiseTerm([0.0] * 3, [NAN] * 3, [False] * 3),
                                         NoiseTerm([1e-5] * 3, [NAN] * 3, [False] * 3)),
                        accel=SensorNoise("m/s^2", NoiseTerm([0.01, 0.02, 0.03], [NAN] * 3, [True] * 3),
                                          NoiseTerm([0.0] * 3, [NAN] * 3, [False] * 3),
                                          NoiseTerm([1e-4] * 3, [NAN] * 3, [False] * 3))).write(tmp_path / "foot.toml")
    out = tmp_path / "z.json"
    r = invoke("zupt", "run", trial, "--noise", prof, "--json", out)
    assert r.exit_code == 0, r.output
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("noise from"))
    fs = float(line.split(" at ")[1].split()[0])
    assert fs == pytest.approx(200.0, rel=1e-3)  # the trial's rate, not the profile's
    assert float(line.split("accel_noise_std ")[1].split()[0]) == pytest.approx(0.03 * math.sqrt(fs), rel=1e-3)
    assert float(line.split("gyro_noise_std ")[1].split()[0]) == pytest.approx(2e-3 * math.sqrt(fs), rel=1e-3)
    assert "error_2d_m" in json.loads(out.read_text())
