"""Presets of the virtual IMU: published figures converted to SI, valid models."""

from __future__ import annotations

import numpy as np
import pytest
from shared_data import ROOT

from imunav.errors import InvalidInputError
from imunav.sim import presets
from imunav.sim.error_model import BIAS_INSTABILITY_FLOOR, Flicker, GaussMarkov, ImuErrorModel, apply_errors
from imunav.timeseries import ImuData
from imunav.units import DEG, G0, to_display

REQUIRED = ("thesis_sim", "consumer_mems", "tactical", "navigation")


def test_names_and_sources():
    assert set(REQUIRED) <= set(presets.names())
    for name in presets.names():
        m = presets.get(name)
        assert isinstance(m, ImuErrorModel)
        assert m.name == name
        assert len(m.source) > 40  # the published source is stated
        assert presets.get(name) is not m  # a fresh object each call


def test_thesis_sim_is_tables_5_1_and_5_2_in_si():
    m = presets.get("thesis_sim")
    # Table 5.1 (accelerometer): S ppm, B g, M mrad, dB 0.001 g, n 0.00043 g/sqrt(Hz)
    np.testing.assert_allclose(m.accel.scale_factor, np.array([21283, 17592, 18409]) * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(m.accel.bias, np.array([0.3945, 0.2899, -0.3371]) * G0, rtol=1e-12)
    mis = m.accel.misalignment
    np.testing.assert_allclose(
        [mis[0, 1], mis[0, 2], mis[1, 0], mis[1, 2], mis[2, 0], mis[2, 1]],
        np.array([7.8824, 4.1317, 5.5272, 4.8791, 6.2235, 8.9376]) * 1e-3,
        rtol=1e-12,
    )
    np.testing.assert_allclose(m.accel.noise_density, 0.00043 * G0, rtol=1e-12)
    assert isinstance(m.accel.bias_instability, GaussMarkov)
    np.testing.assert_allclose(m.accel.bias_instability.sigma, 0.001 * G0, rtol=1e-12)
    np.testing.assert_allclose(m.accel.bias_instability.tau, presets.THESIS_TC_S)
    assert presets.THESIS_TC_S == 5.0  # digest §9: the reading under which the thesis targets hold
    # Table 5.2 (gyro): S ppm, B deg/s, B_G deg/s/g (diagonal), M mrad, dB 0.01 deg/s, n 0.0057 deg/s/sqrt(Hz)
    np.testing.assert_allclose(m.gyro.scale_factor, np.array([19872, 32650, 14883]) * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(m.gyro.bias, np.array([1.4402, -0.7611, 1.5269]) * DEG, rtol=1e-12)
    np.testing.assert_allclose(m.g_sensitivity, np.diag([0.0485, 0.0617, 0.0432]) * DEG / G0, rtol=1e-12)
    mis = m.gyro.misalignment
    np.testing.assert_allclose(
        [mis[0, 1], mis[0, 2], mis[1, 0], mis[1, 2], mis[2, 0], mis[2, 1]],
        np.array([8.4814, 3.9864, 5.1457, 6.5572, 6.1988, 7.3812]) * 1e-3,
        rtol=1e-12,
    )
    np.testing.assert_allclose(m.gyro.noise_density, 0.0057 * DEG, rtol=1e-12)
    np.testing.assert_allclose(m.gyro.bias_instability.sigma, 0.01 * DEG, rtol=1e-12)


def test_datasheet_figures_survive_conversion():
    c = presets.get("consumer_mems")  # MPU-6050 PS rev. 3.4
    assert to_display(c.gyro.noise_density[0], "deg/s/sqrt(Hz)") == pytest.approx(0.005)
    assert to_display(c.accel.noise_density[0], "ug/sqrt(Hz)") == pytest.approx(400.0)
    assert c.gyro.quantization[0] == pytest.approx(DEG / 131.0)
    assert c.accel.quantization[0] == pytest.approx(G0 / 16384.0)
    assert c.gyro.full_scale[0] == pytest.approx(250 * DEG)
    assert np.all(np.abs(c.gyro.bias) <= 20 * DEG) and np.all(np.abs(c.accel.bias[:2]) <= 0.05 * G0)
    assert np.all(np.abs(c.gyro.scale_factor) <= 0.03)
    t = presets.get("tactical")  # ADIS16495-1: 0.8 deg/h in-run stability = Allan minimum
    assert to_display(t.gyro.noise_density[0], "deg/sqrt(h)") == pytest.approx(0.09)
    assert isinstance(t.gyro.bias_instability, Flicker)
    taus = np.logspace(0.5, 2.5, 9)
    adev = np.sqrt(t.gyro.bias_instability.allan_variance(taus)[0])
    np.testing.assert_allclose(to_display(adev, "deg/h"), 0.8, rtol=0.005)
    adev_a = np.sqrt(t.accel.bias_instability.allan_variance(taus)[0])
    np.testing.assert_allclose(to_display(adev_a, "ug"), 3.2, rtol=0.005)
    assert t.gyro.bias_instability.b[0] == pytest.approx(0.8 / BIAS_INSTABILITY_FLOOR * DEG / 3600)
    n = presets.get("navigation")  # HG9900 brochure
    assert to_display(n.gyro.noise_density[0], "deg/sqrt(h)") == pytest.approx(0.002)
    assert to_display(abs(n.gyro.bias[0]), "deg/h") == pytest.approx(0.0035)
    assert to_display(n.accel.bias[0], "ug") == pytest.approx(25.0)
    assert n.gyro.scale_factor[0] == pytest.approx(5e-6)
    assert n.accel.scale_factor[0] == pytest.approx(100e-6)


@pytest.mark.parametrize("name", presets.names())
def test_roundtrip_and_simulation(name, tmp_path):
    m = presets.get(name)
    assert ImuErrorModel.from_dict(m.to_dict()) == m
    assert ImuErrorModel.from_toml(m.to_toml(tmp_path / f"{name}.toml")) == m
    n, fs = 2000, 100.0
    ideal = ImuData(np.arange(n) / fs, np.zeros((n, 3)), np.tile([0.0, 0.0, -G0], (n, 1)))
    out, truth = apply_errors(ideal, m, rng=0, return_truth=True)
    assert np.all(np.isfinite(out.gyro)) and np.all(np.isfinite(out.accel))
    assert truth.accel.n_saturated.sum() == 0  # 1 g is inside every range
    # mean static output is T f + b + G f within the noise (5 sigma of the mean plus the bias-instability sigma)
    f = np.array([0.0, 0.0, -G0])
    expected_a = m.accel.scale_misalignment @ f + m.accel.bias
    spread = np.std(out.accel - truth.accel.bias, axis=0) / np.sqrt(n) * 5 + np.max(np.abs(truth.accel.bias - m.accel.bias), axis=0)
    q = m.accel.quantization
    assert np.all(np.abs(out.accel.mean(0) - expected_a) <= spread + q + 1e-12)


def test_unknown_preset():
    with pytest.raises(InvalidInputError, match="unknown IMU preset 'hg1700'.*thesis_sim"):
        presets.get("hg1700")
    assert presets.get("Thesis-Sim").name == "thesis_sim"


def test_example_toml_loads_with_display_units():
    from imunav.units import from_display

    p = ROOT / "examples" / "imu_error_model.toml"
    m = ImuErrorModel.from_toml(p)
    assert m.name == "example_mems"
    assert m.gyro.noise_density[0] == pytest.approx(from_display(0.15, "deg/sqrt(h)"))
    assert m.gyro.random_walk[0] == pytest.approx(from_display(3.0, "deg/h/sqrt(h)"))
    assert m.gyro.bias_instability.b[0] == pytest.approx(from_display(5.0, "deg/h"))
    assert m.gyro.misalignment[0, 2] == pytest.approx(-0.5e-3)
    assert m.gyro.full_scale[0] == pytest.approx(250 * DEG)
    assert m.accel.full_scale[0] == pytest.approx(16 * G0)
    assert m.accel.bias[2] == pytest.approx(20e-3 * G0)
    assert m.accel.bias_instability.tau[0] == pytest.approx(120.0)
    assert m.g_sensitivity[2, 2] == pytest.approx(0.02 * DEG / G0)
    assert m.gyro.bias_temp_poly[0, 2] == pytest.approx(0.02 * DEG)


def test_gnss_ins_presets_carry_their_published_figures():
    """ADIS16465 data sheet (rev. C) and KF-GINS's Leador-A15 imunoise, back in display units."""
    m = presets.get("mems_adis16465")
    assert to_display(m.gyro.noise_density[0], "deg/sqrt(h)") == pytest.approx(0.15)
    assert to_display(m.accel.noise_density[0], "m/s/sqrt(h)") == pytest.approx(0.012)
    assert to_display(m.gyro.bias_instability.b[0] * BIAS_INSTABILITY_FLOOR, "deg/h") == pytest.approx(2.0)
    assert m.accel.bias_instability.b[0] * BIAS_INSTABILITY_FLOOR / (1e-6 * G0) == pytest.approx(3.6)
    a = presets.get("navigation_a15")
    assert to_display(a.gyro.noise_density[0], "deg/sqrt(h)") == pytest.approx(0.003)
    assert to_display(a.accel.noise_density[0], "m/s/sqrt(h)") == pytest.approx(0.03)
    assert isinstance(a.gyro.bias_instability, GaussMarkov)
    assert to_display(a.gyro.bias_instability.sigma[0], "deg/h") == pytest.approx(0.027)
    assert a.accel.bias_instability.sigma[0] == pytest.approx(15e-5)  # 15 mGal
    np.testing.assert_allclose(a.gyro.bias_instability.tau, 4 * 3600.0)
    np.testing.assert_array_equal(a.gyro.bias, 0.0)  # the whole bias is the Gauss-Markov process
