"""Magnetometer calibration: magcal example, random ellipsoids, thesis method, degenerate data."""

import numpy as np
import pytest
from builders import degenerate_mag_clouds

from imunav.calib import fit_ellipsoid, hard_iron_minmax, soft_iron_rotation_scale, sphere_coverage
from imunav.errors import DegenerateGeometryError, InsufficientDataError, InvalidInputError


def _sphere(n, rng):
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1)[:, None]


def _rot(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def test_magcal_documentation_example(rng):
    """MATLAB magcal: centre (-50, 20, 100), semi-axes (30, 20, 50) -> field 31.0723 = (30*20*50)^(1/3)."""
    h = _sphere(500, rng) * [30.0, 20.0, 50.0] + [-50.0, 20.0, 100.0]
    c = fit_ellipsoid(h)
    np.testing.assert_allclose(c.b, [-50, 20, 100], rtol=1e-6)
    assert c.field_norm == pytest.approx(31.0723, abs=1e-4)
    assert c.field_norm == pytest.approx((30 * 20 * 50) ** (1 / 3), rel=1e-6)
    np.testing.assert_allclose(c.A, np.diag([1 / 30, 1 / 20, 1 / 50]) * (30 * 20 * 50) ** (1 / 3), rtol=1e-6, atol=1e-9)
    assert np.linalg.det(c.A) == pytest.approx(1.0, rel=1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_random_ellipsoids_noise_free(seed):
    rng = np.random.default_rng(seed)
    R = _rot(rng)
    axes = rng.uniform(0.6, 1.4, 3)
    Ainv = R @ np.diag(axes) @ R.T * 50.0  # h_raw = Ainv h_true + b, |h_true| = 1
    b = rng.uniform(-80, 80, 3)
    h = _sphere(400, rng) @ Ainv.T + b
    c = fit_ellipsoid(h, field_norm=1.0)
    np.testing.assert_allclose(c.b, b, rtol=1e-6, atol=1e-6 * 50)
    np.testing.assert_allclose(c.A, np.linalg.inv(Ainv), rtol=1e-6, atol=1e-9)
    assert c.quality["residual_rms"] < 1e-9 and c.quality["coverage"] > 0.9


def test_random_ellipsoids_with_noise_within_reported_uncertainty():
    rng = np.random.default_rng(42)
    zs_b, zs_a = [], []
    for _ in range(40):
        R = _rot(rng)
        Ainv = R @ np.diag(rng.uniform(0.7, 1.3, 3)) @ R.T * 50.0
        b = rng.uniform(-80, 80, 3)
        h = _sphere(300, rng) @ Ainv.T + b + rng.normal(scale=0.5, size=(300, 3))
        c = fit_ellipsoid(h, field_norm=1.0)
        zs_b.append((c.b - b) / c.stderr["b"])
        zs_a.append(((c.A - np.linalg.inv(Ainv)) / c.stderr["A"]).ravel())
    zs_b, zs_a = np.abs(np.array(zs_b)), np.abs(np.array(zs_a))
    assert np.mean(zs_b <= 3) >= 0.95 and np.mean(zs_a <= 3) >= 0.95
    assert 0.5 < np.sqrt(np.mean(zs_b**2)) < 1.6  # z-scores of order 1: neither optimistic nor inflated


def test_thesis_rotation_scale_method(rng):
    """ahrs-sensor-errors §7.5: 480 mG sphere, scales (1.0150, 0.9393, 1.0455) in a frame rotated 11.3° about X."""
    c, s = np.cos(np.deg2rad(11.3)), np.sin(np.deg2rad(11.3))
    Rx = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    W = Rx @ np.diag([1.0150, 0.9393, 1.0455]) @ Rx.T
    hi = np.array([158.50, -37.49, 191.96])
    h = 480 * _sphere(3000, rng) @ W.T + hi + rng.normal(scale=1.0, size=(3000, 3))
    m = soft_iron_rotation_scale(h)
    assert np.all(np.abs(m.b - hi) < 5.0)  # mid-range: a few mG
    assert abs(np.rad2deg(m.extra["angles"][0]) - 11.3) < 0.5
    np.testing.assert_allclose(m.extra["alpha"], [1.0150, 0.9393, 1.0455], rtol=5e-3)
    assert m.quality["norm_spread_after"] < 0.2 * m.quality["norm_spread_centred_raw"]
    e = fit_ellipsoid(h, field_norm=480.0)
    assert np.all(np.abs(e.b - hi) < np.abs(m.b - hi) + 0.5)  # the ellipsoid fit does at least as well
    np.testing.assert_allclose(hard_iron_minmax(h), m.b)


def test_degenerate_data_refused(rng):
    t = np.linspace(0, 2 * np.pi, 400)
    circle = np.c_[40 * np.cos(t), 40 * np.sin(t), np.zeros_like(t)] + rng.normal(scale=0.05, size=(400, 3))
    with pytest.raises(DegenerateGeometryError, match="planar"):
        fit_ellipsoid(circle)
    u = _sphere(2000, rng)
    cap = 40 * u[u[:, 2] > 0.85]  # a 30-degree cap around +z
    with pytest.raises(DegenerateGeometryError, match="cover"):
        fit_ellipsoid(cap + rng.normal(scale=0.05, size=cap.shape))
    with pytest.raises(InsufficientDataError, match="at least 10"):
        fit_ellipsoid(u[:5])
    assert sphere_coverage(u) == 1.0


@pytest.mark.parametrize("kind", ["repeated", "zeros", "denormals"])
def test_fit_ellipsoid_refuses_degenerate_clouds(kind):
    h = {"repeated": np.tile([20.0, -5.0, 40.0], (200, 1)), "zeros": np.zeros((200, 3)),
         "denormals": _sphere(500, np.random.default_rng(1)) * 1e-310}[kind]
    with pytest.raises(DegenerateGeometryError):
        fit_ellipsoid(h)


def test_fit_ellipsoid_refuses_values_beyond_any_unit():
    with pytest.raises(InvalidInputError, match="no unit"):
        fit_ellipsoid(_sphere(500, np.random.default_rng(1)) * 1e200)


def test_fit_ellipsoid_fits_a_perfect_noise_free_sphere():
    for field_norm in (None, 50.0):
        c = fit_ellipsoid(50.0 * _sphere(500, np.random.default_rng(1)) + [10.0, -5.0, 3.0], field_norm=field_norm)
        np.testing.assert_allclose(c.b, [10.0, -5.0, 3.0], atol=1e-9)
        np.testing.assert_allclose(c.A, np.eye(3), atol=1e-9)
        assert c.field_norm == pytest.approx(50.0, rel=1e-12)


@pytest.mark.parametrize("kind", ["point", "line", "plane"])
def test_minmax_refuses_degenerate_geometry(kind):
    with pytest.raises(DegenerateGeometryError):
        hard_iron_minmax(degenerate_mag_clouds()[kind])


def test_minmax_accepts_a_sphere():
    u = _sphere(500, np.random.default_rng(1))
    assert np.allclose(hard_iron_minmax(30 * u + [5, -3, 2]), [5, -3, 2], atol=1.0)


def _cap(n=600, deg=16.0, seed=0):
    """A cap of the sphere (about 2 % of it for 16 deg) around +z: field 45, hard iron (10, -5, 3)."""
    rng = np.random.default_rng(seed)
    cz = rng.uniform(np.cos(np.deg2rad(deg)), 1.0, n)
    ph = rng.uniform(0.0, 2 * np.pi, n)
    d = np.c_[np.sqrt(1 - cz**2) * np.cos(ph), np.sqrt(1 - cz**2) * np.sin(ph), cz]
    return d * 45.0 + [10.0, -5.0, 3.0] + 0.3 * rng.standard_normal((n, 3))


def test_minmax_refuses_the_coverage_the_ellipsoid_refuses(tmp_path):
    """On a cap the mid-range is the field, not the hard iron (issue 26): refused, and no PX4 file written."""
    import warnings

    from typer.testing import CliRunner

    from imunav.calib.magnetometer import fit_ellipsoid, fit_minmax
    from imunav.cli.main import app
    from imunav.errors import DegenerateGeometryError

    h = _cap()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no leaked RuntimeWarning either
        for fit in (fit_ellipsoid, fit_minmax):
            with pytest.raises(DegenerateGeometryError, match="cover only"):
                fit(h)
    np.savez(tmp_path / "cap.npz", mag=h)
    r = CliRunner().invoke(app, ["calibrate", "mag", str(tmp_path / "cap.npz"), "--method", "minmax", "--out",
                                 str(tmp_path / "m.json"), "--px4-params", str(tmp_path / "m.params")])
    assert r.exit_code == 2 and "--min-coverage" in r.stderr and "min_coverage" not in r.stderr
    assert not (tmp_path / "m.json").exists() and not (tmp_path / "m.params").exists()
    # a whole sphere passes, and the mid-range finds the hard iron
    rng = np.random.default_rng(1)
    d = rng.standard_normal((800, 3))
    full = d / np.linalg.norm(d, axis=1, keepdims=True) * 45.0 + [10.0, -5.0, 3.0]
    np.testing.assert_allclose(fit_minmax(full).b, [10.0, -5.0, 3.0], atol=1.0)
