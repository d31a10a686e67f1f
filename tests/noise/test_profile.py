"""The noise profile: TOML / JSON round trip, validation on read, and the configurations built from it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from shared_data import data_path

from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS
from imunav.attitude.gravity_kf import GravityKfConfig
from imunav.attitude.mekf import MekfConfig
from imunav.attitude.ukf import UkfConfig
from imunav.errors import ConfigError, InvalidInputError
from imunav.ins import ZuptConfig, ZuptFilter, error_2d
from imunav.ins.gins import GinsConfig
from imunav.io.foot import read_pyshoe_mat
from imunav.noise import NoiseProfile, NoiseTerm, SensorNoise, allan_deviation, fit_noise, read_noise_profile

NAN = float("nan")


def hand_profile(fs: float = 100.0) -> NoiseProfile:
    """A profile with round numbers, to check the configurations against values computed by hand."""
    gyro = SensorNoise("rad/s", NoiseTerm([1e-4, 2e-4, 3e-4], [1e-6, 2e-6, 3e-6], [True] * 3),
                       NoiseTerm([0.0, 5e-5, 4e-5], [NAN, 1e-6, 1e-6], [False, True, True]),
                       NoiseTerm([1e-6, 2e-6, 4e-6], [NAN] * 3, [False] * 3))
    accel = SensorNoise("m/s^2", NoiseTerm([2e-3, 1e-3, 3e-3], [1e-5] * 3, [True] * 3),
                        NoiseTerm([1e-3, 1e-3, 2e-3], [1e-4] * 3, [True] * 3),
                        NoiseTerm([1e-4, 3e-4, 2e-4], [1e-5] * 3, [True] * 3))
    return NoiseProfile(fs=fs, duration_s=1000.0, gyro=gyro, accel=accel, source="by hand")


def fitted_profile(rng) -> NoiseProfile:
    """A profile of Allan fits of simulated white noise (N = 0.01 rad/s/√Hz gyro, 0.002 m/s²/√Hz accel)."""
    fs, n = 100.0, 40_000
    fits = {}
    for s, nd, unit in (("gyro", 0.01, "rad/s"), ("accel", 0.002, "m/s^2")):
        r = allan_deviation(rng.normal(scale=nd * math.sqrt(fs), size=(n, 3)), fs, units=unit)
        fits[s] = fit_noise(r, terms=("N", "B", "K"), quantity=s)
    return NoiseProfile.from_fits(fs=fs, duration_s=n / fs, source="simulated", **fits)


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_round_trip_is_exact(tmp_path, rng, suffix):
    p = fitted_profile(rng)
    # white noise only: N identified to a few % on every axis, K (too short to show) the curve's bound
    np.testing.assert_allclose(p.gyro.noise_density.value, 0.01, rtol=0.05)
    np.testing.assert_allclose(p.accel.noise_density.value, 0.002, rtol=0.05)
    assert p.gyro.noise_density.identified.all() and np.all(p.gyro.noise_density.se > 0)
    assert not p.gyro.bias_random_walk.identified.any() and np.all(p.gyro.bias_random_walk.value > 0)
    assert np.all(np.isnan(p.gyro.bias_random_walk.se))
    f = p.write(tmp_path / f"profile{suffix}")
    q = read_noise_profile(f)
    assert q == p
    for s in ("gyro", "accel"):
        for t in ("noise_density", "bias_instability", "bias_random_walk"):
            a, b = getattr(getattr(p, s), t), getattr(getattr(q, s), t)
            assert np.array_equal(a.value, b.value) and np.array_equal(a.se, b.se, equal_nan=True)
    text = f.read_text()
    assert "NaN" not in text
    if suffix == ".json":
        json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON token {c}"))
        assert "null" in text
    assert 'unit = "rad/s/sqrt(Hz)"' in text or '"unit": "rad/s/sqrt(Hz)"' in text


def test_hand_profile_round_trip_both_formats(tmp_path):
    p = hand_profile()
    with_mag = NoiseProfile(fs=p.fs, duration_s=p.duration_s, gyro=p.gyro, accel=p.accel, source="with a magnetometer",
                            mag=SensorNoise("uT", NoiseTerm([0.07, 0.08, 0.06], [1e-3] * 3, [True] * 3),
                                            NoiseTerm([0.1, 0.0, 0.0], [0.02, NAN, NAN], [True, False, False]),
                                            NoiseTerm([0.02] * 3, [NAN] * 3, [False] * 3)))
    assert read_noise_profile(with_mag.write(tmp_path / "m.toml")) == with_mag
    assert 'unit = "uT/sqrt(s)"' in (tmp_path / "m.toml").read_text()
    with pytest.raises(InvalidInputError, match="mag is in uT"):
        NoiseProfile(fs=1.0, duration_s=1.0, mag=SensorNoise("a.u.", p.gyro.noise_density, p.gyro.bias_instability,
                                                             p.gyro.bias_random_walk))
    assert read_noise_profile(p.write(tmp_path / "a.toml")) == p
    assert read_noise_profile(p.write(tmp_path / "a.json")) == p
    with pytest.raises(InvalidInputError, match=r"\.toml or \.json"):
        p.write(tmp_path / "a.yaml")


def _doc(tmp_path, edit) -> str:
    f = hand_profile().write(tmp_path / "p.json")
    d = json.loads(f.read_text())
    edit(d)
    f.write_text(json.dumps(d))
    return str(f)


@pytest.mark.parametrize("edit, words", [
    (lambda d: d.update(gyro_arw=1.0), ["unknown key gyro_arw", "the keys there are"]),
    (lambda d: d["gyro"]["noise_density"].update(sigma=1.0), ["unknown key gyro.noise_density.sigma"]),
    (lambda d: d["gyro"]["noise_density"].update(unit="deg/sqrt(h)"), ["gyro.noise_density.unit", "rad/s/sqrt(Hz)"]),
    (lambda d: d["accel"].update(unit="g"), ["accel.unit", "m/s^2"]),
    (lambda d: d["accel"]["bias_random_walk"].update(value=[1e-4, -1e-4, 0.0]), ["bias_random_walk.value[1]", ">= 0"]),
    (lambda d: d["gyro"]["bias_instability"].update(se=[1.0, 2.0]), ["list of three values"]),
    (lambda d: d.update(fs=0), ["fs", "> 0"]),
    (lambda d: d.pop("format"), ["lacks format"]),
    (lambda d: d["gyro"].pop("bias_random_walk"), ["lacks gyro.bias_random_walk"]),
    # the white noise the filters take: a profile holds it on every axis (from_fits refuses one without it)
    (lambda d: d["gyro"]["noise_density"].update(identified=[True, False, True]),
     ["gyro.noise_density is not identified (or 0) on axis y"]),
    (lambda d: d["accel"]["noise_density"].update(value=[0.0, 1e-3, 0.0]),
     ["accel.noise_density is not identified (or 0) on axis x, z"]),
])
def test_bad_profile_is_refused_naming_file_and_key(tmp_path, edit, words):
    path = _doc(tmp_path, edit)
    with pytest.raises(ConfigError) as e:
        read_noise_profile(path)
    msg = str(e.value)
    assert msg.startswith(path) and msg.count(path) == 1, msg  # fs = 0 named the file twice
    for w in words:
        assert w in msg, msg


def test_nan_value_in_toml_is_refused(tmp_path):
    f = hand_profile().write(tmp_path / "p.toml")
    text = f.read_text().replace("value = [0.0001, 0.0002, 0.0003]", "value = [nan, 0.0002, 0.0003]")
    assert "nan, 0.0002" in text
    f.write_text(text)
    with pytest.raises(ConfigError, match=r"gyro.noise_density.value\[0\]"):
        read_noise_profile(f)


def test_missing_and_misnamed_files(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        read_noise_profile(tmp_path / "none.toml")
    (tmp_path / "p.yaml").write_text("x")
    with pytest.raises(ConfigError, match=r"\.toml or \.json"):
        read_noise_profile(tmp_path / "p.yaml")
    (tmp_path / "p.json").write_text("{")
    with pytest.raises(ConfigError, match="p.json"):
        read_noise_profile(tmp_path / "p.json")


# ------------------------------------------------------------------ configurations, field by field (hand values)
FS = 200.0
SQ = math.sqrt(FS)  # 14.142135...: white noise of density N sampled at 200 Hz has σ = N √200 per sample


def test_mekf_config_from_profile():
    c = MekfConfig.from_noise_profile(hand_profile(), fs=FS)
    assert c.gyro_noise_density == 3e-4  # rad/s/√Hz, continuous time: the largest axis
    assert c.gyro_bias_random_walk == 4e-6  # rad/s/√s
    assert c.zaru_noise_std == pytest.approx(4.242640687e-3, rel=1e-9)  # 3e-4 · √200 rad/s per sample
    assert c.accel_direction_noise_std == pytest.approx(3e-3 * SQ / 9.81, rel=1e-12)  # 4.3248e-3 (unit vector)
    assert c.accel_direction_noise_std == pytest.approx(4.32481e-3, rel=1e-5)
    base = MekfConfig()
    for f in ("heading_noise_std", "init_att_std", "tilt_time_constant", "rest_gyro_threshold"):
        assert getattr(c, f) == getattr(base, f)
    # the adaptive filter's base: its gates and time constants stay; the mean over the axes on request
    a = MekfConfig.from_noise_profile(hand_profile(), base=ADAPTIVE_DEFAULTS, fs=FS, combine="mean")
    assert a.gyro_noise_density == pytest.approx(2e-4, rel=1e-12)
    assert a.gyro_bias_random_walk == pytest.approx(7e-6 / 3, rel=1e-12)
    assert a.tilt_time_constant == ADAPTIVE_DEFAULTS.tilt_time_constant
    assert a.heading_time_constant == ADAPTIVE_DEFAULTS.heading_time_constant
    # the profile's own rate by default
    assert MekfConfig.from_noise_profile(hand_profile(fs=100.0)).zaru_noise_std == pytest.approx(3e-3, rel=1e-12)


def test_ukf_and_gravity_kf_configs_from_profile():
    u = UkfConfig.from_noise_profile(hand_profile(), fs=FS)
    assert (u.gyro_noise_density, u.gyro_bias_random_walk) == (3e-4, 4e-6)
    assert u.accel_direction_noise_std == pytest.approx(3e-3 * SQ / 9.81, rel=1e-12)
    assert u.mag_direction_noise_std == UkfConfig().mag_direction_noise_std
    g = GravityKfConfig.from_noise_profile(hand_profile(), fs=FS)
    assert g.gyro_noise_std == pytest.approx(4.242640687e-3, rel=1e-9)  # rad/s per sample
    assert g.accel_noise_std == pytest.approx(4.242640687e-2, rel=1e-9)  # m/s² per sample: 3e-3 · √200
    assert g.gyro_bias_random_walk == 4e-6


def test_zupt_config_from_profile():
    z = ZuptConfig.from_noise_profile(hand_profile(), base=ZuptConfig(states=15, zaru=True), fs=FS)
    assert z.accel_noise_std == pytest.approx(4.242640687e-2, rel=1e-9)  # m/s² per sample
    assert z.gyro_noise_std == pytest.approx(4.242640687e-3, rel=1e-9)  # rad/s per sample
    assert z.accel_bias_random_walk == 3e-4  # m/s²/√s
    assert z.gyro_bias_random_walk == 4e-6  # rad/s/√s
    assert (z.states, z.zaru, z.zupt_noise_std) == (15, True, ZuptConfig().zupt_noise_std)


def test_gins_config_from_profile():
    g = GinsConfig.from_noise_profile(hand_profile(), corr_time=1000.0)
    np.testing.assert_array_equal(g.gyro_noise_density, [1e-4, 2e-4, 3e-4])  # per axis, rad/s/√Hz
    np.testing.assert_array_equal(g.accel_noise_density, [2e-3, 1e-3, 3e-3])
    # Gauss–Markov σ² = B² + K² T / 2, T = 1000 s
    np.testing.assert_allclose(g.gyro_bias_std, [math.sqrt(0 + 1e-12 * 500), math.sqrt(25e-10 + 4e-12 * 500),
                                                 math.sqrt(16e-10 + 16e-12 * 500)], rtol=1e-12)
    np.testing.assert_allclose(g.gyro_bias_std, [2.236068e-5, 6.708204e-5, 9.797959e-5], rtol=1e-6)
    np.testing.assert_allclose(g.accel_bias_std, [math.sqrt(1e-6 + 1e-8 * 500), math.sqrt(1e-6 + 9e-8 * 500),
                                                  math.sqrt(4e-6 + 4e-8 * 500)], rtol=1e-12)
    assert g.corr_time == 1000.0
    # from a base: its corr_time and its other fields stay; overrides win
    base = GinsConfig.from_preset("mems_adis16465")
    h = GinsConfig.from_noise_profile(hand_profile(), base=base, odo_noise_std=0.2)
    assert h.corr_time == base.corr_time and h.odo_noise_std == 0.2
    np.testing.assert_array_equal(h.init_gyro_bias_std, base.init_gyro_bias_std)
    with pytest.raises(InvalidInputError, match="corr_time"):
        GinsConfig.from_noise_profile(hand_profile(), corr_time=-1.0)


def test_a_config_refuses_a_profile_without_its_sensor():
    p = NoiseProfile(fs=100.0, duration_s=10.0, gyro=hand_profile().gyro)
    assert MekfConfig.from_noise_profile(p).accel_direction_noise_std == MekfConfig().accel_direction_noise_std
    with pytest.raises(ConfigError, match="needs the accel noise"):
        ZuptConfig.from_noise_profile(p)
    with pytest.raises(ConfigError, match="needs the accel noise"):
        GinsConfig.from_noise_profile(p)
    with pytest.raises(InvalidInputError, match="fs"):
        MekfConfig.from_noise_profile(p, fs=float("nan"))


@pytest.mark.data
@pytest.mark.parametrize("trial", ["2017-11-22-11-22-03", "2017-11-22-11-22-46", "2017-11-22-11-23-25"])
def test_a_foot_trials_first_stance_profile_reaches_the_zupt_ins(trial):
    """The profile of a foot trial's first stance (1.8-3.1 s standing before the walk; N and K, the stance is too
    short for B) gives the ZUPT INS per-sample σ in rad/s and m/s² at the trial's 200 Hz: against the σ of the
    raw samples' first differences / √2 (white noise, independent of the Allan fit), gyro 0.82-1.23, accelerometer
    0.93-1.67 (a standing foot is not a bench: it sways).  A unit slip (deg, g, a missing √fs) is a factor 10 or
    more.  The INS run with it ends where the pyshoe defaults do (2-D error 0.033 / 0.050 / 0.023 m against
    0.029 / 0.048 / 0.025 m)."""
    tr = read_pyshoe_mat(data_path("foot", "pyshoe_vicon", f"{trial}.mat"))
    zv = tr.labels["shoe"].astype(bool)
    n = int(np.argmax(~zv))
    fs = tr.imu.fs
    fits = {s: fit_noise(allan_deviation(x[:n], fs, units=u), terms=("N", "K"), quantity=s)
            for s, x, u in (("gyro", tr.imu.gyro, "rad/s"), ("accel", tr.imu.accel, "m/s^2"))}
    p = NoiseProfile.from_fits(fs=fs, duration_s=n / fs, source=f"{trial} first stance", **fits)
    z = ZuptConfig.from_noise_profile(p)
    diff_g = float(np.max(np.std(np.diff(tr.imu.gyro[:n], axis=0), axis=0))) / math.sqrt(2)
    diff_a = float(np.max(np.std(np.diff(tr.imu.accel[:n], axis=0), axis=0))) / math.sqrt(2)
    assert 0.75 < z.gyro_noise_std / diff_g < 1.35
    assert 0.85 < z.accel_noise_std / diff_a < 1.8
    np.testing.assert_array_equal(GinsConfig.from_noise_profile(p).gyro_noise_density, p.gyro.noise_density.value)
    e_default = error_2d(ZuptFilter(ZuptConfig()).run(tr.imu, zv).position, tr.position)
    e_profile = error_2d(ZuptFilter(z).run(tr.imu, zv).position, tr.position)
    assert e_profile < 1.3 * e_default
