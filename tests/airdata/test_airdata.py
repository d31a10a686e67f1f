"""Air-data computations against the digest's reference values."""

import numpy as np
import pytest

from imunav.airdata import airdata as ad
from imunav.atmosphere import RHO0, isa, pressure_altitude
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError


def test_flight_condition_reference_values():
    # digest §2.1 [REVIEWER CHECK] at 250 m/s, 12 200 m ISA
    s = isa(12200.0)
    assert s.pressure / 1000 == pytest.approx(18.73, abs=0.005)
    M = 250.0 / s.speed_of_sound
    assert M == pytest.approx(0.847, abs=5e-4)
    pt = s.pressure * ad.pitot_ratio(M)
    assert pt / 1000 == pytest.approx(29.95, abs=0.005)
    tat = ad.total_temperature(s.temperature, M)
    assert tat == pytest.approx(247.75, abs=0.005)
    out = ad.air_data(pt, s.pressure, tat)
    assert out.impact_pressure / 1000 == pytest.approx(11.22, abs=0.005)
    assert out.cas == pytest.approx(132.8, abs=0.05)
    assert out.tas == pytest.approx(250.0, abs=1e-9)
    assert out.mach == pytest.approx(M, abs=1e-12)
    assert out.pressure_altitude == pytest.approx(12200.0, abs=1e-6)
    assert out.density / RHO0 == pytest.approx(0.2459, abs=5e-5)
    assert ad.density_ratio(s.pressure, s.temperature) == pytest.approx(0.2459, abs=5e-5)
    assert 20.0468 * M * np.sqrt(216.65) == pytest.approx(250.0, rel=1e-4)  # Table 2.1 f


def test_supersonic_rayleigh_branch_and_continuity():
    assert ad.pitot_ratio(1.0) == pytest.approx(1.8929, abs=1e-4)
    assert ad.pitot_ratio(1.0 + 1e-9) == pytest.approx(ad.pitot_ratio(1.0), rel=1e-7)
    M = np.array([0.1, 0.5, 0.99, 1.0, 1.2, 2.0, 3.0])
    np.testing.assert_allclose(ad.mach_from_pressures(ad.pitot_ratio(M) * 5000.0, 5000.0), M, rtol=1e-11)
    # Rayleigh pitot formula at M = 2: p_t2/p_1 = 5.6404 (NACA 1135 table)
    assert ad.pitot_ratio(2.0) == pytest.approx(5.6404, abs=1e-4)
    v = np.array([50.0, 150.0, 340.0, 500.0])
    np.testing.assert_allclose(ad.calibrated_airspeed(ad.impact_pressure_from_cas(v)), v, rtol=1e-11)


def test_low_speed_tas_uses_rho0_over_rho():
    # eq. 2.6 corrected: at ρ/ρ₀ = 0.25, TAS = 2 × CAS
    assert ad.tas_from_cas_low_speed(100.0, 0.25) == pytest.approx(200.0)


def test_aoa_sideslip_and_body_decomposition_round_trip():
    v = np.array([[240.0, 12.0, 9.0], [100.0, -5.0, -3.0]])
    a, b = ad.aoa_sideslip(v)
    np.testing.assert_allclose(a, np.arctan(v[:, 2] / v[:, 0]))
    np.testing.assert_allclose(b, np.arctan(v[:, 1] / v[:, 0]))  # thesis definition (eq. 2.5)
    np.testing.assert_allclose(ad.tas_to_body(np.linalg.norm(v, axis=1), a, b), v, rtol=1e-12)
    a2, b2 = ad.aoa_sideslip(v, "standard")
    np.testing.assert_allclose(ad.tas_to_body(np.linalg.norm(v, axis=1), a2, b2, "standard"), v, rtol=1e-12)


def test_air_data_bad_inputs():
    with pytest.raises(InvalidInputError, match="total pressure below static"):
        ad.mach_from_pressures(900.0, 1000.0)
    with pytest.raises(InvalidInputError, match="must be > 0"):
        ad.air_data(-1.0, 1000.0, 250.0)
    with pytest.raises(NonFiniteError, match="p_total contains NaN"):
        ad.air_data(np.nan, 1000.0, 250.0)
    with pytest.raises(InvalidInputError, match="pass Pa, not kPa"):
        pressure_altitude(0.0)
    with pytest.raises(InvalidInputError, match="is the unit Pa"):
        pressure_altitude(101.325e3 * 1000)
    with pytest.raises(InvalidInputError, match="altitude must be within"):
        isa(60000.0)
    with pytest.raises(ShapeError, match=r"\(\.\.\., 3\)"):
        ad.aoa_sideslip(np.ones((2, 2)))
    with pytest.raises(InvalidInputError, match="forward air-velocity"):
        ad.aoa_sideslip([-1.0, 0.0, 0.0])
    with pytest.raises(InvalidInputError, match="recovery factor"):
        ad.static_temperature(250.0, 0.8, recovery=1.5)
