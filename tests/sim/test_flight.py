"""Flight simulator (thesis aircraft, Dryden, multi-rate sensors)."""

import numpy as np
import pytest

from imunav.airdata.filter import LongHorizonConfig, LongHorizonFilter
from imunav.errors import InvalidInputError, ShapeError
from imunav.sim.flight import (
    FlightConfig,
    charlie_model,
    dryden_gusts,
    simulate_flight,
    simulate_linear_aircraft,
)


def test_thesis_aircraft_kinematics():
    A, Ad = charlie_model(0.001)
    np.testing.assert_allclose(Ad, np.eye(12) + 0.001 * A)
    assert Ad[1, 2] == pytest.approx(0.25)  # U0 T in the w row (printed 0.2499)
    assert Ad[10, 4] == pytest.approx(0.25)  # Y row: U0 β T
    f = simulate_linear_aircraft()
    assert f.velocity.shape == (500, 3)
    assert f.velocity[0, 0] == pytest.approx(250.0, abs=0.1) and f.velocity[0, 1] == pytest.approx(25.0, rel=0.01)
    # positions are the running sum of the kinematic velocity
    np.testing.assert_allclose(f.position[-1] - f.position[0], 0.001 * f.velocity[1:].sum(axis=0), rtol=1e-12)


def test_dryden_gust_statistics():
    g = dryden_gusts(100_000, 0.01, 200.0, (1.5, 2.0, 3.0), rng=0)
    # std within ±10 % (correlation time 1.3-2.7 s, 1000 s of data: ~400 independent samples)
    np.testing.assert_allclose(g.std(axis=0), [1.5, 2.0, 3.0], rtol=0.1)
    # longitudinal autocorrelation at lag τ_u = L_u / V = 2.665 s is e^-1 (first-order Dryden)
    u = g[:, 0] - g[:, 0].mean()
    lag = int(round(533.0 / 200.0 / 0.01))
    rho = np.mean(u[:-lag] * u[lag:]) / np.var(u)
    assert rho == pytest.approx(np.exp(-1), abs=0.1)


def test_flight_sensors_consistent_with_truth():
    cfg = FlightConfig(profile="manoeuvre", duration=120.0, turbulence="moderate")
    f = simulate_flight(cfg, rng=3)
    assert f.t_ads.size == 6001 and f.t_doppler.size == 1201  # 50 Hz and 10 Hz
    # wind triangle on the truth: V_G = V_air + W
    C = f.C_nb("truth")
    np.testing.assert_allclose(np.einsum("kij,kj->ki", C, f.v_air_body) + f.wind_ned, f.velocity_ned, atol=1e-9)
    ia = np.searchsorted(f.t, f.t_ads)
    err = f.v_ads_body - f.v_air_body[ia]
    assert np.all(np.abs(err.mean(axis=0)) < 0.05) and np.all(err.std(axis=0) < 0.5)
    idd = np.searchsorted(f.t, f.t_doppler)
    vgb = np.einsum("kji,kj->ki", C[idd], f.velocity_ned[idd])
    assert np.all((f.v_doppler_body - vgb).std(axis=0) < 0.25)
    # coordinated turns at 1.5°/s: bank = atan(V ψ̇ / g) ≈ 28° at 200 m/s (up to 220 m/s here)
    assert 26.0 < np.rad2deg(np.abs(f.euler[:, 0])).max() < 32.0
    assert np.rad2deg(np.ptp(f.euler[:, 2])) > 85.0
    assert f.tas.max() > 210 and f.altitude.max() - f.altitude.min() > 200


def test_flight_bad_inputs():
    with pytest.raises(InvalidInputError, match="profile must be"):
        FlightConfig(profile="loop")
    with pytest.raises(InvalidInputError, match="integer multiple"):
        FlightConfig(rate_truth=100.0, rate_ads=30.0)
    with pytest.raises(InvalidInputError, match="turbulence must be one of"):
        FlightConfig(turbulence="extreme")
    with pytest.raises(ShapeError, match="ADS arrays must be"):
        LongHorizonFilter().run(np.arange(3.0), np.zeros((2, 3)), np.arange(2.0), np.zeros((2, 3)),
                                np.tile(np.eye(3), (2, 1, 1)), np.tile(np.eye(3), (3, 1, 1)))
    with pytest.raises(InvalidInputError, match="strictly increasing"):
        LongHorizonFilter().run(np.zeros(3), np.zeros((3, 3)), np.arange(2.0), np.zeros((2, 3)),
                                np.tile(np.eye(3), (2, 1, 1)), np.tile(np.eye(3), (3, 1, 1)))
    with pytest.raises(InvalidInputError, match="robust must be"):
        LongHorizonConfig(robust="median")
