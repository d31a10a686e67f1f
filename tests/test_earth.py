"""WGS84 Earth model against published values (NIMA TR8350.2) and round trips."""

import numpy as np
import pytest

from imunav import earth
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError


def test_constants_match_tr8350():
    # TR8350.2 (2000) Tables 3.1, 3.3, 3.4
    assert earth.A == 6378137.0
    assert 1 / earth.F == pytest.approx(298.257223563, abs=1e-9)
    assert earth.E2 == pytest.approx(6.69437999014e-3, abs=1e-14)
    assert earth.B == pytest.approx(6356752.3142, abs=1e-4)
    assert earth._K_SOMIGLIANA == pytest.approx(0.00193185265241, abs=1e-14)
    assert earth._M == pytest.approx(0.00344978650684, abs=1e-13)
    assert earth.OMEGA_E == 7.292115e-5


def test_normal_gravity_published_values():
    # TR8350.2 Table 3.4: gamma_e, gamma_p
    assert earth.normal_gravity(0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert earth.normal_gravity(np.pi / 2) == pytest.approx(9.8321849379, abs=1e-10)
    assert earth.normal_gravity(-np.pi / 2) == pytest.approx(9.8321849379, abs=1e-10)
    # batch form, and symmetric in latitude
    lat = np.deg2rad([-60.0, -10.0, 10.0, 60.0])
    g = earth.normal_gravity(lat, 0.0)
    assert g.shape == (4,)
    np.testing.assert_allclose(g[:2], g[:-3:-1], rtol=0, atol=1e-15)


def test_normal_gravity_height_gradient():
    # free-air gradient dgamma/dh = -2 gamma/a (1 + f + m - 2 f sin^2 phi): -0.3086 mGal/m at the equator
    for lat in (0.0, 0.6, 1.2):
        s2 = np.sin(lat) ** 2
        g0 = earth.normal_gravity(lat)
        grad = -2 * g0 / earth.A * (1 + earth.F + earth._M - 2 * earth.F * s2)
        dh = 1.0
        num = (earth.normal_gravity(lat, dh) - earth.normal_gravity(lat, -dh)) / (2 * dh)
        assert num == pytest.approx(grad, rel=1e-9)
    assert (earth.normal_gravity(0, 1.0) - earth.normal_gravity(0.0)) == pytest.approx(-3.0877e-6, abs=1e-9)
    # second-order term: 3 gamma h^2/a^2 at 10 km is 2.2e-5 m/s^2
    g10 = earth.normal_gravity(0.0, 1e4)
    lin = earth.normal_gravity(0.0) * (1 - 2 / earth.A * (1 + earth.F + earth._M) * 1e4)
    assert g10 - lin == pytest.approx(3 * earth.GAMMA_E * 1e8 / earth.A**2, rel=1e-9)


def test_gravity_and_earth_rate_vectors():
    lat = np.deg2rad(39.9)
    g = earth.gravity_ned(lat, 900.0)
    assert g.shape == (3,) and g[0] == 0 and g[1] == 0
    assert g[2] == earth.normal_gravity(lat, 900.0)
    w = earth.earth_rate_ned(lat)
    np.testing.assert_allclose(w, earth.OMEGA_E * np.array([np.cos(lat), 0, -np.sin(lat)]), rtol=0, atol=1e-20)
    assert np.linalg.norm(w) == pytest.approx(earth.OMEGA_E, rel=1e-15)
    assert earth.earth_rate_ned(np.zeros(5)).shape == (5, 3)
    assert earth.gravity_ned(np.zeros(5), np.zeros(5)).shape == (5, 3)


def test_radii_published_and_geometric():
    rn, re = earth.radii(0.0)
    assert re == pytest.approx(earth.A, abs=1e-9)
    assert rn == pytest.approx(earth.A * (1 - earth.E2), abs=1e-8)  # 6335439.327 m
    assert rn == pytest.approx(6335439.327, abs=1e-3)
    rn, re = earth.radii(np.pi / 2)
    assert rn == pytest.approx(re, abs=1e-6)
    assert rn == pytest.approx(earth.A**2 / earth.B, abs=1e-6)  # 6399593.626 m
    # geometric meaning: |dr/dlat| = R_N and |dr/dlon| = R_E cos(lat) on the ellipsoid
    lat, lon, d = 0.8, 0.3, 1e-6
    def r(la, lo):
        return earth.lla_to_ecef([la, lo, 0.0])

    rn, re = earth.radii(lat)
    assert np.linalg.norm(r(lat + d, lon) - r(lat - d, lon)) / (2 * d) == pytest.approx(rn, rel=1e-9)
    assert np.linalg.norm(r(lat, lon + d) - r(lat, lon - d)) / (2 * d) == pytest.approx(re * np.cos(lat), rel=1e-9)


def test_transport_rate():
    v = 250.0
    w = earth.transport_rate_ned(0.0, 0.0, [0.0, v, 0.0])
    np.testing.assert_allclose(w, [v / earth.A, 0, 0], atol=1e-20)
    lat, h = 0.7, 1000.0
    rn, re = earth.radii(lat)
    w = earth.transport_rate_ned(lat, h, [[10.0, 20.0, 3.0]] * 2)
    assert w.shape == (2, 3)
    np.testing.assert_allclose(w[0], [20 / (re + h), -10 / (rn + h), -20 * np.tan(lat) / (re + h)], rtol=1e-15)


def test_ecef_special_points():
    np.testing.assert_allclose(earth.lla_to_ecef([0, 0, 0]), [earth.A, 0, 0], atol=1e-9)
    np.testing.assert_allclose(earth.lla_to_ecef([0, np.pi / 2, 100.0]), [0, earth.A + 100, 0], atol=1e-8)
    np.testing.assert_allclose(earth.lla_to_ecef([np.pi / 2, 0, 0]), [0, 0, earth.B], atol=1e-8)
    np.testing.assert_allclose(earth.ecef_to_lla([0, 0, -earth.B - 50]), [-np.pi / 2, 0, 50], atol=1e-8)
    # 45 deg: x = z / (1 - e^2) at h = 0 (normal meets the axis below the centre)
    x = earth.lla_to_ecef([np.pi / 4, 0, 0])
    assert x[0] * (1 - earth.E2) == pytest.approx(x[2], rel=1e-15)
    assert x[0] == pytest.approx(earth.A / np.sqrt(2 - earth.E2), rel=1e-15)


def test_geodetic_ecef_round_trip():
    rng = np.random.default_rng(3)
    n = 20000
    lla = np.c_[rng.uniform(-np.pi / 2, np.pi / 2, n), rng.uniform(-np.pi, np.pi, n), rng.uniform(-1e4, 1e5, n)]
    back = earth.ecef_to_lla(earth.lla_to_ecef(lla))
    d = back - lla
    d[:, 1] = (d[:, 1] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(d[:, :2]).max() < 1e-12
    # extended precision makes 1e-9 m reachable; with plain float64 long double the
    # float64 rounding of ECEF (ulp 9.3e-10 m at 6.4e6 m) allows a few ulp
    tol_h = 1e-9 if np.finfo(np.longdouble).eps < 1e-17 else 5e-9
    assert np.abs(d[:, 2]).max() < tol_h
    # far above (satellite altitudes) and inside the crust
    far = np.array([[0.3, 1.0, 2.02e7], [-1.2, -2.0, -3e4], [1e-9, 0.0, 0.0]])
    np.testing.assert_allclose(earth.ecef_to_lla(earth.lla_to_ecef(far)), far, rtol=0, atol=2e-8)


def test_ned_round_trips_and_directions():
    ref = np.array([np.deg2rad(39.87), np.deg2rad(32.73), 938.0])
    ned = np.array([[1000.0, -2000.0, 30.0], [0, 0, 0], [-5e4, 3e4, -1e3]])
    np.testing.assert_allclose(earth.lla_to_ned(earth.ned_to_lla(ned, ref), ref), ned, atol=1e-8)
    np.testing.assert_allclose(earth.ned_to_ecef(earth.ecef_to_ned(earth.lla_to_ecef(ref), ref), ref),
                               earth.lla_to_ecef(ref), atol=1e-8)
    # straight up along the normal: only the height changes
    up = earth.ned_to_lla([0, 0, -123.25], ref)
    np.testing.assert_allclose(up, ref + [0, 0, 123.25], atol=1e-9)
    # a small step north raises the latitude by dN / (R_N + h)
    rn, _ = earth.radii(ref[0])
    p = earth.ned_to_lla([1.0, 0, 0], ref)
    assert p[0] - ref[0] == pytest.approx(1.0 / (rn + ref[2]), rel=1e-6)
    C = earth.dcm_en(ref[0], ref[1])
    np.testing.assert_allclose(C @ C.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(C) == pytest.approx(1.0)


def test_bad_inputs():
    with pytest.raises(ShapeError, match=r"lla must have shape \(3,\) or \(N, 3\)"):
        earth.lla_to_ecef([1.0, 2.0])
    with pytest.raises(NonFiniteError, match="rows \\[1\\]"):
        earth.ecef_to_lla([[earth.A, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(NonFiniteError, match="finite"):
        earth.normal_gravity(np.nan)
    with pytest.raises(ShapeError, match="ref_lla must be one point"):
        earth.lla_to_ned([0, 0, 0], [[0, 0, 0]])


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=200, deadline=None)
@given(
    lat=st.floats(-np.pi / 2, np.pi / 2),
    lon=st.floats(-np.pi, np.pi),
    h=st.floats(-1e4, 1e6),
    dn=st.floats(-1e5, 1e5),
    de=st.floats(-1e5, 1e5),
    dd=st.floats(-1e4, 1e4),
)
def test_round_trips_property(lat, lon, h, dn, de, dd):
    lla = np.array([lat, lon, h])
    back = earth.ecef_to_lla(earth.lla_to_ecef(lla))
    assert abs(back[0] - lat) < 1e-12
    if abs(lat) < np.pi / 2 - 1e-6:  # longitude is undefined at the poles
        assert abs((back[1] - lon + np.pi) % (2 * np.pi) - np.pi) < 1e-12
    assert abs(back[2] - h) < 1e-8  # 1e-8 m up to 1000 km altitude (ulp of ECEF there is 1.9e-9 m)
    ned = np.array([dn, de, dd])
    np.testing.assert_allclose(earth.lla_to_ned(earth.ned_to_lla(ned, lla), lla), ned, rtol=0, atol=1e-7)


def test_small_differences_in_local_metres_agree_with_the_exact_ned():
    """dlla_to_ned / ned_to_dlla (curvilinear radii) against the exact ECEF route for offsets of ~10 m: the same
    to second order (within 2 |d|^2 / R, ~3e-4 m here), and each the inverse of the other to the rounding of
    geodetic coordinates (1e-16 x 6.4e6 m, a few 1e-9 m)."""
    from imunav.earth import dlla_to_ned, lla_to_ned, ned_to_dlla

    rng = np.random.default_rng(3)
    lla = np.column_stack([rng.uniform(-1.4, 1.4, 50), rng.uniform(-3, 3, 50), rng.uniform(-100, 3000, 50)])
    d = 10.0 * rng.standard_normal((50, 3))
    moved = lla + ned_to_dlla(d, lla)
    np.testing.assert_allclose(dlla_to_ned(moved - lla, lla), d, rtol=0, atol=5e-9)
    exact = np.array([lla_to_ned(m, p) for m, p in zip(moved, lla)])
    np.testing.assert_allclose(exact, d, rtol=0, atol=2 * np.max(np.sum(d**2, axis=1)) / 6.3e6)


@pytest.mark.parametrize("lat_deg,h", [(100.0, 0.0), (-90.5, 0.0), (45.0, 1e12), (45.0, -2e4), (45.0, 1.5e5)])
def test_earth_refuses_out_of_range_lat_h(lat_deg, h):
    with pytest.raises(InvalidInputError):
        earth.normal_gravity(np.radians(lat_deg), h)
    with pytest.raises(InvalidInputError):
        earth.gravity_ned(np.radians(lat_deg), h)


def test_earth_rate_refuses_latitude_beyond_pole():
    with pytest.raises(InvalidInputError, match="latitude"):
        earth.earth_rate_ned(np.radians(100.0))


@pytest.mark.parametrize("lat_deg,h", [(90.0, 0.0), (-90.0, 0.0), (0.0, -1e4), (45.0, 1e5)])
def test_earth_accepts_the_range_ends(lat_deg, h):
    assert 9.0 < earth.normal_gravity(np.radians(lat_deg), h) < 10.0
