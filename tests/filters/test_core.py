"""The numba estimation core (imunav.filters._core, _core_models) against dense numpy references.

Each primitive is compared with the textbook formula written out in numpy (Joseph form, Van Loan block
exponential with scipy, quaternion products of imunav.rotation).  Tolerances: the kernels and the references do
the same O(n³) arithmetic in another order, so they agree to a few ulps of the largest entry (≤ 1e-12 relative
for the well-conditioned, n ≤ 15 problems drawn here); the strapdown and expm checks carry their own bound.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm as scipy_expm

from imunav.filters import _core as core
from imunav.filters import _core_models as models
from imunav.rotation import quat_exp, quat_multiply, quat_normalize, quat_rotate

RTOL = 1e-12


def _spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


def _joseph_ref(P, dx, H, R, nu, n_est=None):
    n = P.shape[0]
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    if n_est is not None:
        K[n_est:] = 0.0
    y = nu - H @ dx
    A = np.eye(n) - K @ H
    return A @ P @ A.T + K @ R @ K.T, dx + K @ y, y, S


@pytest.mark.parametrize("n_est", [6, 4, 1])
def test_scalar_update_is_the_joseph_form_with_consider_states(rng, n_est):
    P = _spd(rng, 6, 1e-3)
    dx = rng.normal(size=6) * 1e-2
    h = rng.normal(size=6)
    r, nu = 0.3, 0.7
    Pref, dxref, yref, Sref = _joseph_ref(P, dx, h[None], np.array([[r]]), np.array([nu]), n_est)
    P1, dx1, PH = P.copy(), dx.copy(), np.empty(6)
    y, s = core.scalar_update(P1, dx1, h, r, nu, PH, n_est)
    np.testing.assert_allclose(P1, Pref, rtol=0, atol=RTOL * np.abs(P).max())
    np.testing.assert_allclose(dx1, dxref, rtol=0, atol=RTOL * np.abs(dx).max() * 10)
    assert y == pytest.approx(yref[0], rel=RTOL) and s == pytest.approx(Sref[0, 0], rel=RTOL)
    assert np.array_equal(P1, P1.T)  # bit-symmetric
    # the consider-consider block is untouched, the consider gain is zero
    np.testing.assert_array_equal(P1[n_est:, n_est:], P[n_est:, n_est:])
    np.testing.assert_array_equal(dx1[n_est:], dx[n_est:])


def test_scalar_update_sparse_equals_the_dense_row(rng):
    P = _spd(rng, 15)
    dx = rng.normal(size=15)
    idx = np.array([2, 7, 11])
    hv = np.array([0.5, -1.0, 2.0])
    h = np.zeros(15)
    h[idx] = hv
    Pa, dxa, Pb, dxb = P.copy(), dx.copy(), P.copy(), dx.copy()
    ya, sa = core.scalar_update(Pa, dxa, h, 0.1, 0.2, np.empty(15), 12)
    yb, sb = core.scalar_update_sparse(Pb, dxb, idx, hv, 0.1, 0.2, np.empty(15), 12)
    np.testing.assert_allclose(Pb, Pa, rtol=0, atol=RTOL * np.abs(P).max())
    np.testing.assert_allclose(dxb, dxa, rtol=0, atol=RTOL * np.abs(dx).max())
    assert (yb, sb) == pytest.approx((ya, sa), rel=RTOL)


@pytest.mark.parametrize("m", [1, 3, 6])
def test_vector_joseph_update_matches_numpy(rng, m):
    n = 15
    P = _spd(rng, n, 0.1)
    dx = rng.normal(size=n) * 0.1
    H = rng.normal(size=(m, n))
    R = _spd(rng, m, 0.05)
    nu = rng.normal(size=m)
    Pref, dxref, yref, Sref = _joseph_ref(P, dx, H, R, nu)
    innov, S = np.empty(m), np.empty((m, m))
    d = core.joseph_update(P, dx, H, R, nu, innov, S)
    np.testing.assert_allclose(P, Pref, rtol=0, atol=1e-11 * np.abs(Pref).max())
    np.testing.assert_allclose(dx, dxref, rtol=0, atol=1e-11 * np.abs(dxref).max())
    np.testing.assert_allclose(innov, yref, rtol=RTOL)
    np.testing.assert_allclose(S, Sref, rtol=RTOL)
    assert d == pytest.approx(yref @ np.linalg.solve(Sref, yref), rel=1e-10)
    assert np.array_equal(P, P.T)


def test_joseph_update_gain_is_joseph_update_and_returns_the_gain(rng):
    n, m = 6, 3
    P = _spd(rng, n, 0.1)
    dx = rng.normal(size=n) * 0.1
    H = rng.normal(size=(m, n))
    R = _spd(rng, m, 0.05)
    nu = rng.normal(size=m)
    Pa, dxa, Pb, dxb = P.copy(), dx.copy(), P.copy(), dx.copy()
    da = core.joseph_update(Pa, dxa, H, R, nu, np.empty(m), np.empty((m, m)))
    K = np.empty((n, m))
    db = core.joseph_update_gain(Pb, dxb, H, R, nu, np.empty(m), np.empty((m, m)), K)
    assert np.array_equal(Pa, Pb) and np.array_equal(dxa, dxb) and da == db  # one arithmetic
    np.testing.assert_allclose(K, P @ H.T @ np.linalg.inv(H @ P @ H.T + R), rtol=1e-10)


@pytest.mark.parametrize("n", [1, 3, 6])
def test_cholesky_and_spd_inverse_match_numpy(rng, n):
    A = _spd(rng, n)
    L = core.cholesky_small(A)
    np.testing.assert_allclose(L, np.linalg.cholesky(A), rtol=1e-12, atol=1e-14 * np.abs(A).max())
    Ai = core.inv_spd_cholesky(A)
    np.testing.assert_allclose(Ai, np.linalg.inv(A), rtol=1e-10)
    assert np.array_equal(Ai, Ai.T)


def test_unscented_transform_of_a_linear_map_is_exact(rng):
    # sigma points of (x, P) through z = H x: mean H x, covariance H P Hᵀ, cross-covariance P Hᵀ; the update is
    # then the Kalman update P − K S Kᵀ with K = P Hᵀ S⁻¹
    n, m = 4, 2
    P = _spd(rng, n, 0.1)
    H = rng.normal(size=(m, n))
    R = _spd(rng, m, 0.05)
    x = rng.normal(size=n)
    lam, wm0, wc0, wi = core.unscented_weights(n, 0.5, 2.0, 1.0)
    assert wm0 + 2 * n * wi == pytest.approx(1.0, abs=1e-12)
    X = np.empty((2 * n + 1, n))
    core.sigma_offsets(P, lam, X)
    Z = (x + X) @ H.T
    zm = core.unscented_mean(Z, wm0, wi)
    np.testing.assert_allclose(zm, H @ x, rtol=1e-12, atol=1e-12)
    Dz = Z - zm
    S = core.unscented_cov(Dz, Dz, wc0, wi) + R
    Pxz = core.unscented_cov(X, Dz, wc0, wi)
    np.testing.assert_allclose(S, H @ P @ H.T + R, rtol=1e-10)
    np.testing.assert_allclose(Pxz, P @ H.T, rtol=1e-10, atol=1e-12)
    nu = rng.normal(size=m)
    Pu, dx, K = P.copy(), np.empty(n), np.empty((n, m))
    d = core.unscented_update(Pu, Pxz, S, nu, dx, K)
    Pref, dxref, _, _ = _joseph_ref(P, np.zeros(n), H, R, nu)
    np.testing.assert_allclose(Pu, Pref, rtol=0, atol=1e-10 * np.abs(Pref).max())
    np.testing.assert_allclose(dx, dxref, rtol=1e-10)
    assert d == pytest.approx(nu @ np.linalg.solve(H @ P @ H.T + R, nu), rel=1e-10)


def test_unit_row_joseph_update_matches_numpy(rng):
    n = 15
    P = _spd(rng, n, 0.1)
    idx = np.array([3, 4, 5])
    r = np.array([1e-4, 2e-4, 3e-4])
    z = rng.normal(size=3)
    H = np.zeros((3, n))
    H[np.arange(3), idx] = 1.0
    Pref, dxref, _, Sref = _joseph_ref(P, np.zeros(n), H, np.diag(r), z)
    dx, innov, s = np.full(n, 7.0), np.empty(3), np.empty(3)
    core.joseph_update_rows(P, dx, idx, z, r, innov, s)
    np.testing.assert_allclose(P, Pref, rtol=0, atol=1e-11 * np.abs(Pref).max())
    np.testing.assert_allclose(dx, dxref, rtol=0, atol=1e-11 * np.abs(dxref).max())  # dx overwritten, not added
    np.testing.assert_array_equal(innov, z)
    np.testing.assert_allclose(s, np.diag(Sref), rtol=RTOL)


def test_chi2_gate_and_nis(rng):
    S = _spd(rng, 3)
    nu = rng.normal(size=3)
    d = nu @ np.linalg.solve(S, nu)
    assert core.nis(nu, S) == pytest.approx(d, rel=1e-12)
    ok, d1 = core.chi2_gate(nu, S, d * (1 + 1e-9))
    assert ok and d1 == pytest.approx(d, rel=1e-12)
    ok, _ = core.chi2_gate(nu, S, d * (1 - 1e-9))
    assert not ok


def test_inv_small_inverts_an_spd_matrix(rng):
    S = _spd(rng, 6)
    Si = np.empty((6, 6))
    core.inv_small(S, Si)
    np.testing.assert_allclose(Si @ S, np.eye(6), rtol=0, atol=1e-13)


def test_attitude_injection_local_and_global(rng):
    q = quat_normalize(rng.normal(size=4))
    dx = np.zeros(9)
    dx[6:9] = rng.normal(size=3) * 0.1
    np.testing.assert_allclose(core.inject_attitude_local(q, dx, 6), quat_multiply(q, quat_exp(dx[6:9])), atol=1e-15)
    np.testing.assert_allclose(core.inject_attitude_global(q, dx, 6), quat_multiply(quat_exp(dx[6:9]), q),
                               atol=1e-15)
    x = np.arange(3.0)
    core.inject_additive(x, dx, 6, 3)
    np.testing.assert_array_equal(x, np.arange(3.0) + dx[6:9])


def test_attitude_covariance_reset_is_G_P_Gt(rng):
    P = _spd(rng, 9)
    dx = np.zeros(9)
    dx[3:6] = rng.normal(size=3) * 0.2
    a = 0.5 * dx[3:6]
    G = np.eye(9)
    G[3:6, 3:6] -= np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    ref = G @ P @ G.T
    core.reset_attitude_cov(P, dx, 3)
    np.testing.assert_allclose(P, ref, rtol=0, atol=RTOL * np.abs(ref).max())


@pytest.mark.parametrize("scale", [1e-3, 0.3, 5.0, 80.0])
def test_expm_matches_scipy(rng, scale):
    A = rng.normal(size=(6, 6)) * scale / 6
    ref = scipy_expm(A)
    # Padé(6,6) with ‖A/2^j‖ ≤ 1/2: truncation ~3e-16 relative, plus roundoff growing with the j squarings
    tol = 1e-13 * max(1.0, math.log2(max(np.abs(A).sum(axis=1).max(), 1.0)) + 1)
    np.testing.assert_allclose(core.expm(A), ref, rtol=0, atol=tol * np.abs(ref).max())


def test_van_loan_matches_the_closed_form_of_a_first_order_gauss_markov():
    # ẋ = −x/τ + w, E[w w] = 2σ²/τ: Φ = e^{−dt/τ}, Q_d = σ² (1 − e^{−2 dt/τ})  (Gelb 1974, table 4.1)
    tau, sigma, dt = 3.0, 0.7, 0.25
    Phi, Qd = core.van_loan(np.array([[-1.0 / tau]]), np.array([[2 * sigma**2 / tau]]), dt)
    assert Phi[0, 0] == pytest.approx(math.exp(-dt / tau), rel=1e-14)
    assert Qd[0, 0] == pytest.approx(sigma**2 * (1 - math.exp(-2 * dt / tau)), rel=1e-13)


def test_van_loan_matches_the_scipy_block_exponential(rng):
    F = rng.normal(size=(3, 3))
    L = rng.normal(size=(3, 3))
    Qc = L @ L.T
    dt = 0.1
    M = np.zeros((6, 6))
    M[:3, :3], M[:3, 3:], M[3:, 3:] = -F, Qc, F.T
    E = scipy_expm(M * dt)
    Phi_ref = E[3:, 3:].T
    Q_ref = Phi_ref @ E[:3, 3:]
    Phi, Qd = core.van_loan(F, Qc, dt)
    np.testing.assert_allclose(Phi, Phi_ref, rtol=0, atol=1e-14)
    np.testing.assert_allclose(Qd, 0.5 * (Q_ref + Q_ref.T), rtol=0, atol=1e-14 * np.abs(Q_ref).max())


@pytest.mark.parametrize("att", [core.ATT_START, core.ATT_MID, core.ATT_END])
def test_strapdown_step_local_matches_numpy(rng, att):
    q = quat_normalize(rng.normal(size=4))
    v, p = rng.normal(size=3), rng.normal(size=3)
    dth, dv, h, g = rng.normal(size=3) * 0.01, rng.normal(size=3) * 0.1, 0.01, 9.81
    q1 = quat_normalize(quat_multiply(q, quat_exp(dth)))
    qa = {core.ATT_START: q, core.ATT_MID: quat_multiply(q, quat_exp(0.5 * dth)), core.ATT_END: q1}[att]
    dvn_ref = quat_rotate(qa, dv)
    v1 = v + dvn_ref + np.array([0, 0, g * h])
    qo, vo, po = np.empty(4), np.empty(3), np.empty(3)
    dvn = core.strapdown_step_local(q, v, p, dth, dv, h, g, att, qo, vo, po)
    np.testing.assert_allclose(qo, q1, atol=1e-15)
    np.testing.assert_allclose(dvn, dvn_ref, atol=1e-15)
    np.testing.assert_allclose(vo, v1, atol=1e-14)
    np.testing.assert_allclose(po, p + 0.5 * (v + v1) * h, atol=1e-14)


def test_strapdown_step_ned_keeps_a_body_at_rest_on_the_rotating_earth():
    # a sensor at rest measures -g up and the Earth rate: one step leaves v ≈ 0 and lla unchanged
    from imunav.earth import OMEGA_E, normal_gravity

    lat, h_e = 0.7, 200.0
    g = float(normal_gravity(lat, h_e))
    w_ie = OMEGA_E * np.array([math.cos(lat), 0.0, -math.sin(lat)])  # NED, body = NED (q = 1)
    q = np.array([1.0, 0, 0, 0])
    dt = 0.01
    qo, vo, llao = np.empty(4), np.empty(3), np.empty(3)
    core.strapdown_step_ned(q, np.zeros(3), np.array([lat, 0.2, h_e]), w_ie * dt, np.array([0, 0, -g]) * dt,
                            dt, OMEGA_E, core.ATT_START, qo, vo, llao)
    # residual: the increment rotates the sensed gravity by ω dt (≈ g ω_ie dt² ≈ 1e-8 m/s)
    assert np.abs(vo).max() < 1e-7
    np.testing.assert_allclose(llao, [lat, 0.2, h_e], atol=1e-9)
    np.testing.assert_allclose(qo, q, atol=1e-12)


def test_gravity_direction_row_is_the_jacobian_of_the_model(rng):
    q = quat_normalize(rng.normal(size=4))

    def h(qq):
        return quat_rotate(np.array([qq[0], -qq[1], -qq[2], -qq[3]]), np.array([0, 0, -1.0]))

    h0 = h(q)
    eps = 1e-6
    J = np.empty((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = eps
        J[:, j] = (h(quat_multiply(q, quat_exp(e))) - h(quat_multiply(q, quat_exp(-e)))) / (2 * eps)
    a = rng.normal(size=3)
    H = np.empty(6)
    for i in range(3):
        nu = models.gravity_direction_row(q[0], q[1], q[2], q[3], a[i], i, H)
        assert nu == pytest.approx(a[i] - h0[i], abs=1e-15)
        np.testing.assert_allclose(H[:3], J[i], atol=1e-9)  # central difference: O(eps²) ≈ 1e-12
        np.testing.assert_array_equal(H[3:], 0.0)


def test_heading_hold_innovation_is_minus_the_vertical_rotation(rng):
    from imunav.rotation import quat_from_euler

    q_ref = quat_from_euler(0.1, -0.2, 0.3)
    q = quat_multiply(quat_exp(np.array([0.0, 0.0, 0.05])), q_ref)  # 0.05 rad about nav down
    nu, r = np.empty(1), np.empty(1)
    models.heading_hold(q, q_ref, 0.01, nu, r)
    assert nu[0] == pytest.approx(-0.05, abs=1e-15) and r[0] == pytest.approx(1e-4)


def test_zero_velocity_zero_rate_and_height_models():
    nu, r = np.empty(3), np.empty(3)
    models.zero_velocity(np.array([0.1, -0.2, 0.3]), 0.01, nu, r)
    np.testing.assert_array_equal(nu, [-0.1, 0.2, -0.3])
    np.testing.assert_allclose(r, 1e-4)
    models.zero_rate(np.array([0.1, 0.2, 0.3]), np.array([0.1, 0.0, 0.1]), 0.02, nu, r)
    np.testing.assert_allclose(nu, [0.0, 0.2, 0.2])
    n1, r1 = np.empty(1), np.empty(1)
    models.height(-1.5, -1.0, 0.1, n1, r1)
    assert n1[0] == pytest.approx(0.5) and r1[0] == pytest.approx(0.01)


def test_sparse_covariance_propagation_matches_numpy(rng):
    n = 15
    P = _spd(rng, n)
    Phi = np.eye(n)
    Phi[0:3, 3:6] = 0.01 * np.eye(3)
    Phi[3:6, 6:9] = rng.normal(size=(3, 3)) * 0.01
    Q = np.diag(rng.uniform(0.1, 1.0, n))
    Q[0, 1] = 0.05  # not symmetric: the kernel uses its symmetric part
    ref = Phi @ P @ Phi.T + 0.5 * (Q + Q.T)
    core.propagate_cov_sparse(Phi, P, Q, np.empty((n, n)), np.empty((n, n), np.int64), np.empty(n, np.int64))
    np.testing.assert_allclose(P, ref, rtol=0, atol=RTOL * np.abs(ref).max())
    assert np.array_equal(P, P.T)


def test_consider_update_covariance_is_the_error_covariance_of_its_estimate():
    """Schmidt consider states (``joseph_update_consider``): the consider states do not move, the others take the
    gain's rows, and the covariance written is the actual error covariance of that estimate: over 20,000 draws
    ``x ~ N(0, P)``, ``z = H x + v``, the sample covariance of ``x − dx`` equals the updated ``P`` within 4 % (its
    standard error at 20,000 draws is about 1 %; the optimal filter's covariance, which ignores that the consider
    rows are not applied, is smaller and fails)."""
    rng = np.random.default_rng(3)
    n, m = 5, 2
    A = rng.normal(size=(n, n))
    P0 = A @ A.T + n * np.eye(n)
    H = rng.normal(size=(m, n))
    R = np.diag([0.5, 2.0])
    consider = np.array([False, False, True, False, True])
    P = P0.copy()
    dx0 = np.zeros(n)
    K = np.empty((n, m))
    core.joseph_update_consider(P, dx0, H, R, np.zeros(m), np.empty(m), np.empty((m, m)), K, consider)
    assert np.all(K[consider] == 0.0)
    L = np.linalg.cholesky(P0)
    errs = np.empty((20000, n))
    for k in range(errs.shape[0]):
        x = L @ rng.normal(size=n)
        z = H @ x + np.sqrt(np.diag(R)) * rng.normal(size=m)
        dx = np.zeros(n)
        Pk = P0.copy()
        core.joseph_update_consider(Pk, dx, H, R, z, np.empty(m), np.empty((m, m)), np.empty((n, m)), consider)
        assert np.all(dx[consider] == 0.0)
        errs[k] = x - dx
    C = np.cov(errs.T)
    np.testing.assert_allclose(np.diag(C), np.diag(P), rtol=0.04)
    Popt = P0.copy()
    core.joseph_update(Popt, np.zeros(n), H, R, np.zeros(m), np.empty(m), np.empty((m, m)))
    assert np.any(np.abs(np.diag(C) / np.diag(Popt) - 1) > 0.1)
