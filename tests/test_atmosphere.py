"""ISA against its tables."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.atmosphere import A0, RHO0, geopotential_altitude, isa, pressure_altitude, speed_of_sound


@pytest.mark.parametrize(
    "h, T, p, rho",
    [  # ICAO Doc 7488 / ISO 2533 table values
        (0.0, 288.15, 101325.0, 1.2250),
        (5000.0, 255.65, 54019.9, 0.73612),
        (11000.0, 216.65, 22632.1, 0.36392),
        (20000.0, 216.65, 5474.89, 0.088035),
        (32000.0, 228.65, 868.019, 0.013225),
    ],
)
def test_isa_table_values(h, T, p, rho):
    s = isa(h)
    assert s.temperature == pytest.approx(T, abs=1e-9)
    assert s.pressure == pytest.approx(p, rel=5e-6)  # tables give 6 significant figures
    assert s.density == pytest.approx(rho, rel=2e-4)
    assert pressure_altitude(s.pressure) == pytest.approx(h, abs=1e-6)


def test_isa_constants_and_thesis_formula():
    assert A0 == pytest.approx(340.294, abs=1e-3) and RHO0 == pytest.approx(1.225, abs=1e-6)
    h = np.linspace(0, 11000, 12)
    thesis = 101325.0 * (1 - 2.25577e-5 * h) ** 5.255879  # Table 2.1(a)
    np.testing.assert_allclose(isa(h).pressure, thesis, rtol=2e-6)
    hs = np.linspace(11000, 20000, 10)
    np.testing.assert_allclose(isa(hs).pressure, 22632.0 * np.exp(-1.576885e-4 * (hs - 11000)), rtol=2e-5)
    assert speed_of_sound(216.65) == pytest.approx(295.07, abs=0.01)
    assert geopotential_altitude(11019.0) == pytest.approx(11000.0, abs=1.0)
