"""BROAD metric: closed-form cases and frame invariance."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.attitude.metrics import attitude_rmse, error_angles, euler_rmse
from imunav.errors import InsufficientDataError, ShapeError
from imunav.io.broad import from_enu, to_enu
from imunav.rotation import quat_from_rotvec, quat_multiply


def _rand_q(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def test_identity_and_equal(rng):
    q = _rand_q(rng, 50)
    r = attitude_rmse(q, q)
    assert r.total_rmse_deg == pytest.approx(0.0, abs=1e-5)
    r = attitude_rmse(-q, q)  # sign of a quaternion is irrelevant
    assert r.total_rmse_deg == pytest.approx(0.0, abs=1e-5)


def test_heading_only_and_tilt_only(rng):
    q = _rand_q(rng, 20)
    # Earth-frame error: q_est = q_err ⊗ q_ref
    e = error_angles(quat_multiply(quat_from_rotvec([0, 0, np.radians(10)]), q), q)
    assert np.allclose(np.degrees(e.heading), 10.0) and np.allclose(np.degrees(e.total), 10.0)
    assert np.allclose(e.inclination, 0.0, atol=1e-7)
    e = error_angles(quat_multiply(quat_from_rotvec([np.radians(4), 0, 0]), q), q)
    assert np.allclose(np.degrees(e.inclination), 4.0) and np.allclose(e.heading, 0.0, atol=1e-7)
    # a body-frame error about the body z axis is NOT a heading error in general
    e = error_angles(quat_multiply(q, quat_from_rotvec([0, 0, np.radians(10)])), q)
    assert np.allclose(np.degrees(e.total), 10.0)


def test_rmse_mask_and_nan(rng):
    q = _rand_q(rng, 10)
    qe = quat_multiply(quat_from_rotvec(np.tile([0, 0, np.radians(2.0)], (10, 1))), q)
    qe[:5] = quat_multiply(quat_from_rotvec([0, 0, np.radians(6.0)]), q[:5])
    ref = q.copy()
    ref[0] = np.nan
    r = attitude_rmse(qe, ref, np.ones(10, bool))
    assert r.n_used == 9
    assert r.total_rmse_deg == pytest.approx(np.sqrt((4 * 36 + 5 * 4) / 9), rel=1e-6)
    r = attitude_rmse(qe, ref, np.arange(10) >= 5)
    assert r.heading_rmse_deg == pytest.approx(2.0, rel=1e-6)


def test_enu_ned_invariance(rng):
    q = _rand_q(rng, 30)
    qe = quat_multiply(_rand_q(rng, 30) * 0.05 + [1, 0, 0, 0], q)
    a = attitude_rmse(qe, q)
    b = attitude_rmse(to_enu(qe), to_enu(q))
    assert a.total_rmse_deg == pytest.approx(b.total_rmse_deg)
    assert a.heading_rmse_deg == pytest.approx(b.heading_rmse_deg)
    assert a.inclination_rmse_deg == pytest.approx(b.inclination_rmse_deg)
    assert np.allclose(np.abs(np.sum(from_enu(to_enu(q)) * q, axis=1)), 1.0)


def test_euler_rmse_wraps():
    a = np.radians([[179.0, 0, 0], [-179.0, 0, 0]])
    b = np.radians([[-179.0, 0, 0], [179.0, 0, 0]])
    assert euler_rmse(a, b)[0] == pytest.approx(2.0)


def test_bad_inputs(rng):
    q = _rand_q(rng, 5)
    with pytest.raises(ShapeError, match=r"\(N, 4\)"):
        attitude_rmse(q[:, :3], q)
    with pytest.raises(ShapeError, match="same shape"):
        attitude_rmse(q, q[:3])
    with pytest.raises(ShapeError, match="mask"):
        attitude_rmse(q, q, np.ones(3, bool))
    with pytest.raises(InsufficientDataError, match="no sample"):
        attitude_rmse(q, q, np.zeros(5, bool))
