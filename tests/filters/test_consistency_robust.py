"""NIS / NEES χ² consistency on seeded Monte Carlo; robust updates."""

import numpy as np
import pytest
from scipy.stats import chi2

from imunav.errors import InvalidInputError, ShapeError
from imunav.filters import (
    KalmanFilter,
    batch_kalman_filter,
    chi2_bounds,
    consistency_test,
    gate_channels,
    huber_update,
    isolate_channels,
    kalman_filter,
    nees,
    nis,
    robust_update,
)


def test_chi2_bounds_published_example():
    # Bar-Shalom, Li & Kirubarajan (2001) §5.4.2: 50 runs, 2 dof, 95 % -> [1.5, 2.6] (two decimals)
    lo, hi = chi2_bounds(2, 50, 0.95)
    assert lo == pytest.approx(chi2.ppf(0.025, 100) / 50) and lo == pytest.approx(1.48, abs=0.01)
    assert hi == pytest.approx(2.59, abs=0.01)


def _mc(r_filter, runs=60, steps=80, seed=1):
    rng = np.random.default_rng(seed)
    dt = 0.1
    F = np.array([[1, dt], [0, 1]])
    Q = 0.1 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    H = np.array([[1.0, 0.0]])
    R = 0.25
    Lq = np.linalg.cholesky(Q)
    x = rng.multivariate_normal([0, 1], np.eye(2), size=runs)
    xs = np.empty((runs, steps, 2))
    for k in range(steps):
        x = x @ F.T + rng.standard_normal((runs, 2)) @ Lq.T
        xs[:, k] = x
    z = xs[:, :, :1] + np.sqrt(R) * rng.standard_normal((runs, steps, 1))
    run = batch_kalman_filter([0, 1], np.eye(2), F, Q, H, [[r_filter]], z)
    # P is deterministic (same for every run): take it from one sequence run
    P = kalman_filter([0, 1], np.eye(2), F, Q, H, [[r_filter]], z[0]).P
    ne = nees(xs - run.x, np.broadcast_to(P, (runs, steps, 2, 2)))
    ni = run.normalized[..., 0] ** 2
    np.testing.assert_allclose(run.cov_diag[0], np.einsum("kii->ki", P), rtol=1e-12)
    return ne, ni


def test_nees_nis_consistent_for_true_model_and_not_for_wrong_r():
    ne, ni = _mc(0.25)
    res_nis = consistency_test(ni, 1)
    assert res_nis.passed and res_nis.fraction_inside > 0.85
    res_nees = consistency_test(ne, 2)
    assert res_nees.fraction_inside > 0.85  # NEES is time-correlated; per-step check only
    assert res_nees.lower < res_nees.time_average < res_nees.upper
    _, ni_bad = _mc(0.25 / 6)  # R under-stated 6x: NIS far too large
    bad = consistency_test(ni_bad, 1)
    assert not bad.passed and bad.time_average > bad.time_bounds[1]
    assert isinstance(bad.to_dict()["mean_per_step"], list)


def test_nis_nees_shapes():
    assert nis(np.array([1.0, 2.0]), np.eye(2)) == pytest.approx(5.0)
    assert nees(np.ones((3, 2)), np.broadcast_to(2 * np.eye(2), (3, 2, 2))) == pytest.approx([1.0] * 3)
    with pytest.raises(ShapeError, match="do not match"):
        nis(np.ones(3), np.eye(2))
    with pytest.raises(InvalidInputError, match="dof and n_samples"):
        chi2_bounds(0)


def test_huber_equals_kf_without_outliers_and_downweights_outlier():
    P = np.diag([1.0, 2.0])
    H = np.eye(2)
    R = np.eye(2) * 0.5
    x, Pn, w, _ = huber_update([0.0, 0.0], P, [0.3, -0.2], H, R)
    kf = KalmanFilter([0.0, 0.0], P, H=H, R=R)
    kf.update([0.3, -0.2])
    np.testing.assert_allclose(x, kf.x, atol=1e-12)
    np.testing.assert_allclose(Pn, kf.P, atol=1e-12)
    assert np.all(w == 1)
    x2, _, w2, _ = huber_update([0.0, 0.0], P, [0.3, 50.0], H, R)
    assert w2[1] < 0.1 and w2[0] == 1.0
    assert abs(x2[1]) < 5.0  # the KF would move to 50*2/2.5 = 40


def test_gate_and_isolation():
    assert gate_channels([0.5, -2.5, 1.99], 2.0).tolist() == [True, False, True]
    S = np.eye(3)
    assert isolate_channels([0.3, 30.0, -0.5], S).tolist() == [True, False, True]
    assert isolate_channels([30.0, 25.0, -40.0], S).tolist() == [False, False, False]
    assert isolate_channels([0.3, 1.0, -0.5], S).all()
    kf = KalmanFilter([0.0, 0.0, 0.0], np.eye(3), H=np.eye(3), R=np.eye(3))
    r = robust_update(kf, [0.1, 100.0, 0.2], "isolate")
    assert r.accepted.tolist() == [True, False, True] and kf.x[1] == 0.0
    kf2 = KalmanFilter([0.0, 0.0, 0.0], np.eye(3), H=np.eye(3), R=np.eye(3))
    robust_update(kf2, [0.1, 100.0, 0.2], "huber")
    assert kf2.x[1] < 5
    with pytest.raises(InvalidInputError, match="method must be"):
        robust_update(kf2, [0.0, 0.0, 0.0], "median")
    with pytest.raises(InvalidInputError, match="gate m must be"):
        gate_channels([1.0], 0.0)
