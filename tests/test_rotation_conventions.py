"""Converters to other conventions, checked against the peers themselves (vqf, ahrs, scipy)."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import rotation as R
from imunav.errors import InvalidInputError, ShapeError


def _motion(fs=100.0, duration=20.0):
    """Smooth attitude q_nb (NED, FRD) with consistent gyro / specific force / field."""
    t = np.arange(0, duration, 1 / fs)
    e = np.stack([0.4 * np.sin(0.3 * t), 0.3 * np.sin(0.23 * t + 1), 1.0 + 0.8 * np.sin(0.11 * t)], axis=1)
    q = R.quat_from_euler(e)
    w = R.rotvec_from_quat(R.quat_multiply(R.quat_conjugate(q[:-1]), q[1:])) * fs
    w = np.vstack([w, w[-1]])
    qbn = R.quat_conjugate(q)
    f = R.quat_rotate(qbn, np.tile([0, 0, -9.81], (t.size, 1)))
    m = R.quat_rotate(qbn, np.tile([20.0, 0.0, 40.0], (t.size, 1)))  # north and down, uT
    return t, q, w, f, m


def test_roundtrip_every_convention():
    q = R.quat_normalize(np.random.default_rng(3).normal(size=(30, 4)))
    for name in R.EXTERNAL_CONVENTIONS:
        for body in ("same", "flu"):
            back = R.from_convention(R.to_convention(q, name, body=body), name, body=body)
            assert np.max(R.quat_angle(back, q)) < 1e-12, (name, body)


def test_enu_worked_example():
    # Level, heading east (yaw = 90 deg) in NED is level with heading east in ENU:
    # body x maps to ENU (1, 0, 0) = east.
    q_ned = R.quat_from_euler(0.0, 0.0, np.pi / 2)
    q_enu = R.to_convention(q_ned, "enu")
    np.testing.assert_allclose(R.quat_rotate(q_enu, [1, 0, 0]), [1, 0, 0], atol=1e-15)
    # body z (down) maps to ENU -up
    np.testing.assert_allclose(R.quat_rotate(q_enu, [0, 0, 1]), [0, 0, -1], atol=1e-15)


def test_scipy_convention():
    from scipy.spatial.transform import Rotation

    q = R.quat_normalize(np.random.default_rng(4).normal(size=(10, 4)))
    v = np.array([1.0, -2.0, 0.5])
    np.testing.assert_allclose(
        Rotation.from_quat(R.to_convention(q, "scipy")).apply(v), R.quat_rotate(q, np.tile(v, (10, 1))), atol=1e-14
    )


def test_vqf_convention_matches_vqf():
    vqf = pytest.importorskip("vqf")
    t, q, w, f, m = _motion()
    out = vqf.VQF(0.01).updateBatch(np.ascontiguousarray(w), np.ascontiguousarray(f), np.ascontiguousarray(m))
    q_vqf = R.from_convention(out["quat9D"], "vqf")
    # First seconds (before vqf's slow heading filters wander on synthetic data): 0.2 deg.
    err = np.degrees(R.quat_angle(q_vqf[100:800], q[100:800]))
    assert np.median(err) < 0.2
    match = R.find_convention(out["quat9D"][:800], q[:800])
    np.testing.assert_array_equal(match.nav_dcm, R.C_ENU_NED.T)
    np.testing.assert_array_equal(match.body_dcm, np.eye(3))
    assert not match.scalar_last and not match.conjugate


def test_ahrs_convention_matches_ahrs():
    ahrs = pytest.importorskip("ahrs")
    t, q, w, f, m = _motion(duration=10.0)
    q_ahrs = ahrs.filters.Madgwick(gyr=w, acc=f, mag=m, frequency=100.0, q0=R.to_convention(q[0], "ahrs")).Q
    err = np.degrees(R.quat_angle(R.from_convention(q_ahrs, "ahrs"), q))
    assert np.median(err) < 0.5
    match = R.find_convention(q_ahrs, q)
    np.testing.assert_array_equal(match.nav_dcm, R.C_NED_NWU)
    np.testing.assert_array_equal(match.body_dcm, np.eye(3))


def test_find_convention_recovers_a_constructed_convention():
    q = R.quat_normalize(np.random.default_rng(5).normal(size=(100, 4)))
    L = R.quat_from_dcm(np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]]))
    B = R.quat_from_dcm(np.array([[1.0, 0, 0], [0, -1, 0], [0, 0, -1]]))
    q_ext = R.quat_multiply(R.quat_multiply(R.quat_conjugate(L), q), R.quat_conjugate(B))
    match = R.find_convention(q_ext, q)
    assert match.median_error_rad < 1e-12
    assert np.max(R.quat_angle(match.apply(q_ext), q)) < 1e-12


def test_convention_errors():
    with pytest.raises(InvalidInputError, match="unknown convention"):
        R.to_convention([1, 0, 0, 0], "nasa")
    with pytest.raises(InvalidInputError, match="body must be"):
        R.from_convention([1, 0, 0, 0], "enu", body="xyz")
    with pytest.raises(ShapeError):
        R.find_convention(np.ones((3, 4)), np.ones((4, 4)))
