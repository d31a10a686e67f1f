"""Magnetometer calibration: magcal example, random ellipsoids, thesis method, degenerate data."""

import numpy as np
import pytest

from imunav.calib import (
    calibrate_magnetometer,
    fit_ellipsoid,
    hard_iron_minmax,
    minmax_calibration,
    soft_iron_rotation_scale,
    sphere_coverage,
)
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


def test_minmax_calibration_and_the_method_dispatch(rng):
    """Min-max: the mid-range hard iron, no soft iron; its norm spread shows the soft iron it leaves."""
    u = _sphere(4000, rng)
    sphere = 40.0 * u + [5.0, -3.0, 2.0]
    c = minmax_calibration(sphere)
    # the mid-range of 4000 points on a sphere misses the extremes by < 1 % of the radius
    np.testing.assert_allclose(c.b, [5, -3, 2], atol=0.4)
    assert c.method == "minmax" and np.array_equal(c.A, np.eye(3))
    assert c.field_norm == pytest.approx(40.0, rel=0.01) and c.quality["norm_spread_after"] < 0.01
    squashed = u * [40.0, 40.0, 20.0]  # soft iron (a z axis half as long): the spread stays
    assert minmax_calibration(squashed).quality["norm_spread_after"] > 0.1
    assert calibrate_magnetometer(sphere, "minmax").to_dict() == c.to_dict()
    np.testing.assert_allclose(calibrate_magnetometer(sphere).b, [5, -3, 2], atol=1e-9)
    with pytest.raises(InvalidInputError, match="ellipsoid, rotation-scale or minmax"):
        calibrate_magnetometer(sphere, "median")
