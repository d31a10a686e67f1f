"""Doppler beam geometry and least squares."""

import numpy as np
import pytest

from imunav.airdata import doppler as dp
from imunav.errors import DegenerateGeometryError, InvalidInputError, ShapeError


@pytest.mark.parametrize("n", [3, 4])
def test_beams_and_exact_least_squares(n):
    B = dp.janus_beams(n, 65.0)
    np.testing.assert_allclose(np.linalg.norm(B, axis=1), 1.0)
    assert np.all(B[:, 2] > 0)  # pointing down (FRD)
    v = np.array([[220.0, -8.0, 3.0], [150.0, 20.0, -5.0]])
    np.testing.assert_allclose(dp.velocity_from_beams(dp.beam_velocities(v, B), B), v, rtol=1e-12)
    lam = 299792458.0 / 13.325e9
    np.testing.assert_allclose(dp.doppler_shift(v, B, lam), 2 * (v @ B.T) / lam)


def test_doppler_shift_order_of_magnitude():
    # Chapter 3: about 30 Hz per 2 m/s at 13.3 GHz along a beam at γ ≈ 70°... 2 V cosγ/λ per m/s
    lam = 299792458.0 / 13.325e9
    per_2ms = 2 * 2.0 * np.cos(np.deg2rad(70.0)) / lam
    assert 40 < per_2ms < 70  # same order as the thesis's "≈ 30 Hz per 2 m/s"


def test_least_squares_covariance_matches_monte_carlo():
    B = dp.janus_beams(4, 60.0)
    C = dp.velocity_covariance(B, 0.1)
    rng = np.random.default_rng(3)
    v = np.array([200.0, 5.0, 1.0])
    est = dp.velocity_from_beams(dp.beam_velocities(v, B) + 0.1 * rng.standard_normal((20000, 4)), B)
    emp = np.cov(est.T)
    np.testing.assert_allclose(np.diag(emp), np.diag(C), rtol=0.05)  # 20000 samples: 2 % sd of a variance
    # Janus 4-beam at 45° azimuths: x and y equally observed, cross terms zero
    assert C[0, 0] == pytest.approx(C[1, 1]) and abs(C[0, 1]) < 1e-15


def test_error_model_bias_scale_and_over_water():
    B = dp.janus_beams(4, 65.0)
    v = np.tile([200.0, 0.0, 0.0], (4000, 1))
    e = dp.DopplerErrors(bias=0.0, scale=0.002, noise=0.0, water_scale=-0.005, water_velocity_body=(1.0, 0.5, 0.0))
    land = dp.simulate_doppler(v, B, e, np.zeros(4000), rng=0)
    np.testing.assert_allclose(land.velocity[:, 0], 200.0 * 1.002)
    sea = dp.simulate_doppler(v, B, e, np.ones(4000), rng=0)
    np.testing.assert_allclose(sea.velocity[0], (1.002 - 0.005) * (v[0] - [1.0, 0.5, 0.0]), atol=1e-9)
    # a common bias on all beams appears on the vertical axis only (beams symmetric in x, y)
    bias = dp.simulate_doppler(v[:1], B, dp.DopplerErrors(bias=0.1, noise=0.0), None, rng=0)
    np.testing.assert_allclose(bias.velocity[0], [200.0, 0.0, 0.1 / np.sin(np.deg2rad(65.0))], atol=1e-9)
    thesis = dp.doppler_additive(v, 0.1, rng=1)
    assert np.std(thesis - v) == pytest.approx(0.1, rel=0.03)


def test_beam_angle_error_example():
    # eq. 3.4: γ₀ = 70°, 1° → tan(70°)·1° = 4.8 % (the thesis rounds to 4.7 %)
    assert dp.beam_angle_error(np.deg2rad(70.0), np.deg2rad(1.0)) == pytest.approx(0.0479, abs=2e-4)


def test_doppler_bad_inputs():
    with pytest.raises(DegenerateGeometryError, match="fewer than 3"):
        dp.velocity_from_beams(np.zeros(3), dp.janus_beams(azimuths_deg=[0, 0, 0]))
    with pytest.raises(InvalidInputError, match="n_beams must be 3 or 4"):
        dp.janus_beams(5)
    with pytest.raises(ShapeError, match="beam_vel has 3 beams"):
        dp.velocity_from_beams(np.zeros(3), dp.janus_beams(4))
    with pytest.raises(InvalidInputError, match="unit vectors"):
        dp.beam_velocities([1.0, 0, 0], np.eye(3) * 2)
