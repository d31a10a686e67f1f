"""Noise files for the next tool (issue 17): Kalibr, OpenVINS and VINS-Fusion (io/_noise and its three writers).

Each file is written, parsed back with a small parser of its own format (below, independent of the writers) and
checked against the values it came from and against the key names the target project documents.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from imunav.errors import InvalidInputError
from imunav.io.kalibr import write_kalibr_yaml
from imunav.io.openvins import write_openvins_yaml
from imunav.io.vins import write_vins_yaml
from imunav.noise import allan_deviation, fit_noise

# Kalibr: https://github.com/ethz-asl/kalibr/wiki/yaml-formats ("imu.yaml") and kalibr_common/ConfigReader.py
KALIBR_DOC_KEYS = {"accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
                   "gyroscope_random_walk", "rostopic", "update_rate"}
# OpenVINS: https://github.com/rpng/open_vins/blob/master/config/euroc_mav/kalibr_imu_chain.yaml (imu0 block)
OPENVINS_DOC_KEYS = {"T_i_b", "accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
                     "gyroscope_random_walk", "rostopic", "time_offset", "update_rate", "model", "Tw", "R_IMUtoGYRO",
                     "Ta", "R_IMUtoACC", "Tg"}
# VINS-Fusion: https://github.com/HKUST-Aerial-Robotics/VINS-Fusion/blob/master/config/euroc/euroc_mono_imu_config.yaml
VINS_DOC_KEYS = {"imu", "imu_topic", "acc_n", "gyr_n", "acc_w", "gyr_w", "g_norm"}


# ------------------------------------------------------------------ tiny parsers of the target formats
def parse_flat_yaml(text: str) -> dict[str, str]:
    """``key: value  # comment`` lines of one mapping level (the block under ``imu0:`` is read un-indented)."""
    out: dict[str, str] = {}
    for ln in text.splitlines():
        s = ln.split("#", 1)[0].rstrip()
        if not s.strip() or s.startswith("%") or s.strip().startswith("-"):
            continue
        key, _, val = s.strip().partition(":")
        out[key] = val.strip().strip('"')
    return out


# ------------------------------------------------------------------ noise configuration files
def _walk(N, K, fs, n, rng):
    return rng.normal(scale=N * np.sqrt(fs), size=n) + np.cumsum(rng.normal(scale=K / np.sqrt(fs), size=n))


@pytest.fixture(scope="module")
def fits():
    """Gyro and accel fits of 3 axes of white noise + random walk (K identified) and white-only ones."""
    rng = np.random.default_rng(7)
    fs, n = 100.0, 200_000
    g = np.stack([_walk(1e-3 * (1 + 0.2 * i), 2e-4, fs, n, rng) for i in range(3)], axis=1)
    a = np.stack([_walk(2e-3, 1e-4 * (1 + 0.3 * i), fs, n, rng) for i in range(3)], axis=1)
    fg = fit_noise(allan_deviation(g, fs, units="rad/s"))
    fa = fit_noise(allan_deviation(a, fs, units="m/s^2"))
    wg = fit_noise(allan_deviation(rng.normal(scale=1e-3 * np.sqrt(fs), size=(20_000, 3)), fs, units="rad/s"))
    wa = fit_noise(allan_deviation(rng.normal(scale=2e-3 * np.sqrt(fs), size=(20_000, 3)), fs, units="m/s^2"))
    return fs, fg, fa, wg, wa


def _term(fit, name):
    return fit.value[fit.names.index(name)]


def test_kalibr_round_trip_and_documented_keys(tmp_path, fits):
    fs, fg, fa, _, _ = fits
    assert fg.selected[fg.names.index("K")].all() and fa.selected[fa.names.index("K")].all()
    kv = parse_flat_yaml(write_kalibr_yaml(tmp_path / "imu.yaml", fg, fa, fs, rostopic="/imu").read_text())
    assert set(kv) == KALIBR_DOC_KEYS
    # written with every digit: the parsed numbers are the fitted ones exactly
    assert float(kv["gyroscope_noise_density"]) == _term(fg, "N").max()
    assert float(kv["gyroscope_random_walk"]) == _term(fg, "K").max()
    assert float(kv["accelerometer_noise_density"]) == _term(fa, "N").max()
    assert float(kv["accelerometer_random_walk"]) == _term(fa, "K").max()
    assert float(kv["update_rate"]) == fs and kv["rostopic"] == "/imu"
    mean = parse_flat_yaml(write_kalibr_yaml(tmp_path / "m.yaml", fg, fa, fs, combine="mean").read_text())
    assert float(mean["gyroscope_noise_density"]) == pytest.approx(_term(fg, "N").mean(), rel=1e-15)


def test_openvins_round_trip_and_documented_keys(tmp_path, fits):
    fs, fg, fa, _, _ = fits
    text = write_openvins_yaml(tmp_path / "kalibr_imu_chain.yaml", fg, fa, fs).read_text()
    assert text.startswith("%YAML:1.0\n")  # OpenCV FileStorage header, as OpenVINS's own files
    lines = text.splitlines()
    i0 = lines.index("imu0:")
    kv = parse_flat_yaml("\n".join(lines[i0 + 1:]))
    assert set(kv) == OPENVINS_DOC_KEYS
    assert float(kv["accelerometer_random_walk"]) == _term(fa, "K").max()
    assert float(kv["gyroscope_noise_density"]) == _term(fg, "N").max()
    assert float(kv["update_rate"]) == fs and kv["model"] == "kalibr"
    rows = [ln for ln in lines if ln.strip().startswith("- [")]
    assert len(rows) == 4 + 4 * 3 + 3  # T_i_b 4x4, Tw Ta R_IMUtoGYRO R_IMUtoACC identity, Tg zero


def test_vins_round_trip_keys_and_inflation_note(tmp_path, fits):
    fs, fg, fa, _, _ = fits
    text = write_vins_yaml(tmp_path / "vins.yaml", fg, fa, imu_topic="/imu0", g_norm=9.8017).read_text()
    kv = parse_flat_yaml(text)
    assert set(kv) == VINS_DOC_KEYS
    assert float(kv["acc_n"]) == _term(fa, "N").max() and float(kv["gyr_n"]) == _term(fg, "N").max()
    assert float(kv["acc_w"]) == _term(fa, "K").max() and float(kv["gyr_w"]) == _term(fg, "K").max()
    assert float(kv["g_norm"]) == 9.8017 and kv["imu"] == "1"
    assert "NOT inflated" in text
    with pytest.raises(InvalidInputError, match="g_norm"):
        write_vins_yaml(tmp_path / "v2.yaml", fg, fa, g_norm=1.0)


def test_unidentified_random_walk_is_its_upper_bound(tmp_path, fits):
    """White noise only: K is not selected, and Kalibr refuses K <= 0; the file holds the bound of the curve."""
    fs, _, _, wg, wa = fits
    assert not wg.selected[wg.names.index("K")].any()
    text = write_kalibr_yaml(tmp_path / "imu.yaml", wg, wa, fs).read_text()
    kv = parse_flat_yaml(text)
    tmax = wg.tau.max()
    bound = max(np.sqrt(3 * wg.model_avar([tmax], c)[0] / tmax) for c in range(3))
    assert float(kv["gyroscope_random_walk"]) == pytest.approx(bound, rel=1e-12) and bound > 0
    # AVAR(tau_max) of white noise N is N^2/tau_max, so the bound is sqrt(3) N / tau_max
    assert bound == pytest.approx(np.sqrt(3) * _term(wg, "N").max() / tmax, rel=1e-6)
    assert "upper bound" in text.split("gyroscope_random_walk")[1].splitlines()[0]


def test_noise_writer_bad_input(tmp_path, fits):
    fs, fg, fa, _, _ = fits
    with pytest.raises(InvalidInputError, match="gyro fit first"):
        write_kalibr_yaml(tmp_path / "x.yaml", fa, fg, fs)
    with pytest.raises(InvalidInputError, match="update_rate"):
        write_openvins_yaml(tmp_path / "x.yaml", fg, fa, 0.0)
    with pytest.raises(InvalidInputError, match="combine"):
        write_vins_yaml(tmp_path / "x.yaml", fg, fa, combine="median")
    no_n = dataclasses.replace(fg, selected=fg.selected & (np.array(fg.names) != "N")[:, None])
    with pytest.raises(InvalidInputError, match="white noise N was not identified"):
        write_kalibr_yaml(tmp_path / "x.yaml", no_n, fa, fs)
    assert not (tmp_path / "x.yaml").exists()
