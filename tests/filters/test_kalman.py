"""The public filters (on the numba core) against closed forms: scalar and 2-state Riccati steady states, the
Kalman update of a Gaussian prior, EKF = KF and UKF = KF on a linear model, sigma-point moments."""

import numpy as np
import pytest

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError
from imunav.filters import (
    ExtendedKalmanFilter,
    KalmanFilter,
    UnscentedKalmanFilter,
    kalman_filter,
    riccati_steady_state,
    sigma_points,
)


def test_scalar_random_walk_steady_state_matches_closed_form():
    # x(k+1) = x(k) + w, z = x + v: posterior steady state P = (-Q + sqrt(Q^2 + 4QR)) / 2
    Q, R = 0.001, 4.01
    closed = (-Q + np.sqrt(Q * Q + 4 * Q * R)) / 2
    assert closed == pytest.approx(0.06283, abs=5e-6)  # Akgün 2002 steady state, digest §2.5
    kf = KalmanFilter([0.0], [[10.0]], F=[[1.0]], Q=[[Q]], H=[[1.0]], R=[[R]])
    for _ in range(3000):
        kf.predict()
        kf.update([0.0])
    assert kf.P[0, 0] == pytest.approx(closed, rel=1e-9)
    assert riccati_steady_state([[1.0]], [[Q]], [[1.0]], [[R]])[0, 0] == pytest.approx(closed, rel=1e-9)


def test_update_is_the_gaussian_conditional_and_keeps_p_symmetric(rng):
    # one update = the conditional of the joint Gaussian (x, z): x + P Hᵀ S⁻¹ ν, P − P Hᵀ S⁻¹ H P
    n, m = 4, 2
    A = rng.standard_normal((n, n))
    P = A @ A.T + np.eye(n)
    H = rng.standard_normal((m, n))
    R = np.diag([0.5, 2.0])
    x0 = rng.standard_normal(n)
    z = rng.standard_normal(m)
    kf = KalmanFilter(x0, P, H=H, R=R)
    r = kf.update(z)
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    nu = z - H @ x0
    np.testing.assert_allclose(kf.x, x0 + K @ nu, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(kf.P, P - K @ S @ K.T, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(r.K, K, rtol=1e-10, atol=1e-12)
    assert r.nis == pytest.approx(nu @ np.linalg.solve(S, nu), rel=1e-12)
    np.testing.assert_allclose(r.normalized @ r.normalized, r.nis, rtol=1e-12)
    assert np.array_equal(kf.P, kf.P.T)


def test_two_state_steady_state_matches_the_riccati_equation():
    # constant-velocity model: the recursion converges to the DARE solution (scipy, independent of the core)
    F, Q, H, R = _cv_model()
    kf = KalmanFilter([0.0, 0.0], np.eye(2) * 100.0, F=F, Q=Q, H=H, R=R)
    for _ in range(2000):
        kf.predict()
        kf.update([0.0])
    np.testing.assert_allclose(kf.P, riccati_steady_state(F, Q, H, R), rtol=1e-9)


def _cv_model(dt=0.1, q=0.05, r=0.3):
    F = np.array([[1, dt], [0, 1]])
    Q = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    H = np.array([[1.0, 0.0]])
    return F, Q, H, np.array([[r]])


def test_ukf_and_ekf_equal_kf_on_linear_model(rng):
    F, Q, H, R = _cv_model()
    x0, P0 = np.array([0.0, 1.0]), np.diag([1.0, 0.5])
    kf = KalmanFilter(x0, P0, F=F, Q=Q, H=H, R=R)
    ukf = UnscentedKalmanFilter(x0, P0, lambda x, u: F @ x, lambda x: H @ x, Q, R, alpha=0.5, beta=2.0, kappa=1.0)
    ukf3 = UnscentedKalmanFilter(x0, P0, lambda x, u: F @ x, lambda x: H @ x, Q, R)  # alpha = 1e-3
    ekf = ExtendedKalmanFilter(x0, P0, lambda x, u: F @ x, lambda x: H @ x, Q, R)
    for k in range(50):
        z = np.array([0.1 * k + rng.standard_normal() * 0.5])
        for f in (kf, ukf, ukf3, ekf):
            f.predict()
            f.update(z)
        np.testing.assert_allclose(ukf.x, kf.x, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(ukf.P, kf.P, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ukf3.x, kf.x, rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(ekf.x, kf.x, rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(ekf.P, kf.P, rtol=1e-7, atol=1e-10)


def test_ekf_with_analytic_jacobians_is_the_kf_on_a_linear_model(rng):
    # same model, same core steps: EKF and KF agree to rounding
    F, Q, H, R = _cv_model()
    x0, P0 = np.array([0.0, 1.0]), np.diag([1.0, 0.5])
    kf = KalmanFilter(x0, P0, F=F, Q=Q, H=H, R=R)
    ekf = ExtendedKalmanFilter(x0, P0, lambda x, u: F @ x, lambda x: H @ x, Q, R, F_jac=lambda x, u: F,
                               H_jac=lambda x: H)
    for k in range(50):
        z = np.array([0.1 * k + rng.standard_normal() * 0.5])
        kf.predict()
        ekf.predict()
        rk, re = kf.update(z), ekf.update(z)
        np.testing.assert_allclose(ekf.x, kf.x, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(ekf.P, kf.P, rtol=1e-12, atol=1e-16)
        assert re.nis == pytest.approx(rk.nis, rel=1e-12)


def test_sigma_points_reproduce_mean_and_covariance(rng):
    A = rng.standard_normal((3, 3))
    P = A @ A.T + 0.1 * np.eye(3)
    x = rng.standard_normal(3)
    for alpha, kappa in ((1e-3, 0.0), (0.5, 1.0), (1.0, 2.0)):
        chi, Wm, Wc = sigma_points(x, P, alpha, 2.0, kappa)
        assert chi.shape == (7, 3) and Wm.sum() == pytest.approx(1.0, abs=1e-9)
        np.testing.assert_allclose(Wm @ chi, x, atol=1e-9)
        D = chi - x
        np.testing.assert_allclose((D * Wc[:, None]).T @ D, P, rtol=1e-9, atol=1e-9 * np.abs(P).max())
    with pytest.raises(InvalidInputError, match="not positive definite"):
        sigma_points(x, -np.eye(3), 0.5, 2.0, 0.0)


def test_ekf_nonlinear_range_measurement_converges(rng):
    # static 2-D position observed by ranges to three beacons: EKF converges to truth within 3 sigma
    beacons = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    truth = np.array([3.0, 4.0])

    def h(x):
        return np.linalg.norm(beacons - x, axis=1)

    ekf = ExtendedKalmanFilter([5.0, 5.0], np.eye(2) * 4.0, lambda x, u: x, h, np.eye(2) * 1e-9, np.eye(3) * 0.01)
    for _ in range(30):
        ekf.predict()
        ekf.update(h(truth) + 0.1 * rng.standard_normal(3))
    err = ekf.x - truth
    assert err @ np.linalg.solve(ekf.P, err) < 13.8  # chi2(2) 0.999


def test_kalman_filter_sequence_matches_class_and_skips_nan_rows(rng):
    F, Q, H, R = _cv_model()
    z = rng.standard_normal((40, 1))
    z[5] = np.nan
    run = kalman_filter([0.0, 0.0], np.eye(2), F, Q, H, R, z)
    kf = KalmanFilter([0.0, 0.0], np.eye(2), F=F, Q=Q, H=H, R=R)
    for k in range(40):
        kf.predict()
        np.testing.assert_allclose(run.x_pred[k], kf.x, atol=1e-12)
        if k != 5:
            kf.update(z[k])
        np.testing.assert_allclose(run.x[k], kf.x, atol=1e-12)
        np.testing.assert_allclose(run.P[k], kf.P, atol=1e-12)
    assert np.isnan(run.nis[5]) and np.isfinite(run.nis[6])
    d = run.to_dict()
    assert d["nis"][5] is None


def test_partial_update_rejects_channel():
    kf = KalmanFilter([0.0, 0.0], np.eye(2), H=np.eye(2), R=np.eye(2))
    r = kf.update([1.0, 100.0], accept=[True, False])
    assert kf.x[1] == 0.0 and kf.P[1, 1] == 1.0 and kf.x[0] == pytest.approx(0.5)
    assert r.K[1, 1] == 0.0 and not r.accepted[1]


def test_bad_inputs_raise():
    with pytest.raises(ShapeError, match="P0 must have shape"):
        KalmanFilter([0.0, 0.0], np.eye(3))
    with pytest.raises(NonFiniteError, match="x0 contains NaN"):
        KalmanFilter([np.nan], [[1.0]])
    with pytest.raises(InvalidInputError, match="not positive semi-definite"):
        KalmanFilter([0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]])
    kf = KalmanFilter([0.0], [[1.0]])
    with pytest.raises(InvalidInputError, match="predict needs F"):
        kf.predict()
    with pytest.raises(ShapeError, match="z must have length 1"):
        kf.update([1.0, 2.0], H=[[1.0]], R=[[1.0]])
    with pytest.raises(InvalidInputError, match="alpha must be > 0"):
        UnscentedKalmanFilter([0.0], [[1.0]], lambda x, u: x, lambda x: x, [[1.0]], [[1.0]], alpha=0.0)
