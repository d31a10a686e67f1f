"""Rotation maths: property tests for every conversion pair and closed-form oracles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imunav import rotation as R
from imunav.errors import NonFiniteError, ShapeError, TimeOrderError

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
quat_raw = arrays(np.float64, 4, elements=st.floats(-1, 1, allow_nan=False)).filter(
    lambda q: np.linalg.norm(q) > 1e-3
)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
half = st.floats(-math.pi / 2, math.pi / 2, allow_nan=False)
rotvec = arrays(np.float64, 3, elements=st.floats(-3.0, 3.0, allow_nan=False)).filter(
    lambda r: np.linalg.norm(r) < math.pi - 1e-6
)
vec = arrays(np.float64, 3, elements=st.floats(-100, 100, allow_nan=False))


def Rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def same_rotation(q1, q2, atol=1e-12):
    return R.quat_angle(q1, q2) < atol


# ---- closed-form oracles ----------------------------------------------------
def test_euler_matches_elementary_rotations():
    roll, pitch, yaw = 0.3, -0.5, 2.0
    C = Rz(yaw) @ Ry(pitch) @ Rx(roll)
    np.testing.assert_allclose(R.dcm_from_euler(roll, pitch, yaw), C, atol=1e-15)
    np.testing.assert_allclose(R.euler_from_dcm(C), [roll, pitch, yaw], atol=1e-14)


def test_quaternion_of_elementary_rotation():
    # rotation of 90 deg about z: [cos45, 0, 0, sin45]; maps body x to nav y
    q = R.quat_from_rotvec([0, 0, math.pi / 2])
    np.testing.assert_allclose(q, [math.sqrt(0.5), 0, 0, math.sqrt(0.5)], atol=1e-15)
    np.testing.assert_allclose(R.quat_rotate(q, [1, 0, 0]), [0, 1, 0], atol=1e-15)


def test_hamilton_product_table():
    i, j, k = np.eye(4)[1], np.eye(4)[2], np.eye(4)[3]
    np.testing.assert_allclose(R.quat_multiply(i, j), k)
    np.testing.assert_allclose(R.quat_multiply(j, k), i)
    np.testing.assert_allclose(R.quat_multiply(k, i), j)
    np.testing.assert_allclose(R.quat_multiply(i, i), [-1, 0, 0, 0])


def test_composition_order():
    # q_ac = q_ab ⊗ q_bc  <=>  C_ac = C_ab C_bc
    q_ab = R.quat_from_euler(0.1, 0.2, 0.3)
    q_bc = R.quat_from_euler(-0.4, 0.5, -0.6)
    np.testing.assert_allclose(
        R.dcm_from_quat(R.quat_multiply(q_ab, q_bc)), R.dcm_from_quat(q_ab) @ R.dcm_from_quat(q_bc), atol=1e-15
    )


def test_level_specific_force_convention():
    # A level, north-facing body at rest measures f_b = (0, 0, -g); rotated to NED it stays (0, 0, -g).
    q = R.quat_from_euler(0.0, 0.0, 0.0)
    np.testing.assert_allclose(R.quat_rotate(q, [0, 0, -9.81]), [0, 0, -9.81])
    # pitch up 90 deg: body x points up (-z in NED)
    q = R.quat_from_euler(0.0, math.pi / 2, 0.0)
    np.testing.assert_allclose(R.quat_rotate(q, [1, 0, 0]), [0, 0, -1], atol=1e-15)


@pytest.mark.parametrize("method", ["zoh", "trapezoid"])
def test_constant_rate_integrates_exactly(method):
    # w constant in body: q(t) = q0 ⊗ exp(w t), closed form, 1e-9 rad over 10 s at 100 Hz
    w = np.array([0.1, -0.2, 0.05])
    t = np.arange(1001) * 0.01
    q0 = R.quat_from_euler(0.2, -0.1, 1.0)
    q = R.integrate_rate(q0, t, np.tile(w, (t.size, 1)), method=method)
    expected = R.quat_multiply(q0, R.quat_from_rotvec(w[None, :] * t[:, None]))
    err = R.quat_angle(q, expected)
    assert np.max(err) < 1e-9


def test_integration_order_of_accuracy():
    # Smooth rate with a turning axis; reference from a very fine trapezoid run.
    # zoh is first order (error halves with h), trapezoid + coning second order (quarter).
    def w_of(t):
        return np.stack([np.sin(3 * t), np.cos(2 * t), 0.5 + 0 * t], axis=1)

    tf = np.linspace(0, 1, 200001)
    q_ref = R.integrate_rate([1, 0, 0, 0], tf, w_of(tf), method="trapezoid")[-1]
    errs = {}
    for method in ("zoh", "trapezoid"):
        e = []
        for n in (101, 201):
            t = np.linspace(0, 1, n)
            e.append(R.quat_angle(R.integrate_rate([1, 0, 0, 0], t, w_of(t), method=method)[-1], q_ref))
        errs[method] = e
    assert 1.7 < errs["zoh"][0] / errs["zoh"][1] < 2.3
    assert errs["trapezoid"][0] / errs["trapezoid"][1] > 3.5
    assert errs["trapezoid"][1] < errs["zoh"][1] / 100


# ---- property tests -----------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(quat_raw)
def test_quat_dcm_roundtrip(q):
    q = R.quat_normalize(q)
    C = R.dcm_from_quat(q)
    np.testing.assert_allclose(C @ C.T, np.eye(3), atol=1e-12)
    assert abs(np.linalg.det(C) - 1) < 1e-12
    assert same_rotation(R.quat_from_dcm(C), q, 1e-7)
    np.testing.assert_allclose(R.dcm_from_quat(R.quat_from_dcm(C)), C, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(quat_raw)
def test_q_and_minus_q_are_the_same_rotation(q):
    q = R.quat_normalize(q)
    np.testing.assert_allclose(R.dcm_from_quat(q), R.dcm_from_quat(-q), atol=1e-15)
    np.testing.assert_allclose(R.rotvec_from_quat(q), R.rotvec_from_quat(-q), atol=1e-12)
    np.testing.assert_allclose(R.euler_from_quat(q), R.euler_from_quat(-q), atol=1e-12)
    assert R.quat_canonical(-q)[0] >= 0
    assert R.quat_angle(q, -q) < 1e-7


@settings(max_examples=200, deadline=None)
@given(angle, st.floats(-math.pi / 2 + 1e-3, math.pi / 2 - 1e-3), angle)
def test_euler_roundtrip(roll, pitch, yaw):
    e = R.euler_from_quat(R.quat_from_euler(roll, pitch, yaw))
    q1 = R.quat_from_euler(roll, pitch, yaw)
    q2 = R.quat_from_euler(e)
    assert same_rotation(q1, q2, 1e-7)
    np.testing.assert_allclose(e[1], pitch, atol=1e-9)
    np.testing.assert_allclose(R.dcm_from_euler(e), R.dcm_from_euler(roll, pitch, yaw), atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(angle, st.sampled_from([-1.0, 1.0]), st.floats(0, 1e-7), angle)
def test_euler_near_gimbal_lock(roll, sign, eps, yaw):
    # The rotation is preserved exactly even when roll and yaw are not separable.
    pitch = sign * (math.pi / 2 - eps)
    C = R.dcm_from_euler(roll, pitch, yaw)
    e = R.euler_from_dcm(C)
    np.testing.assert_allclose(R.dcm_from_euler(e), C, atol=1e-6)
    assert abs(abs(e[1]) - math.pi / 2) < 1e-6


@settings(max_examples=200, deadline=None)
@given(rotvec)
def test_exp_log_roundtrip(r):
    q = R.quat_from_rotvec(r)
    assert abs(np.linalg.norm(q) - 1) < 1e-14
    np.testing.assert_allclose(R.rotvec_from_quat(q), r, atol=1e-12)
    np.testing.assert_allclose(R.rotvec_from_dcm(R.dcm_from_rotvec(r)), r, atol=1e-8)


def test_exp_log_small_angles_are_accurate():
    for th in [0.0, 1e-12, 1e-8, 1e-5, 9.9e-5, 1.01e-4, 1e-3]:
        r = np.array([th, -0.5 * th, 0.25 * th])
        np.testing.assert_allclose(R.rotvec_from_quat(R.quat_from_rotvec(r)), r, rtol=1e-13, atol=1e-300)


@settings(max_examples=100, deadline=None)
@given(quat_raw, vec)
def test_rotate_matches_dcm_and_inverse(q, v):
    q = R.quat_normalize(q)
    np.testing.assert_allclose(R.quat_rotate(q, v), R.dcm_from_quat(q) @ v, atol=1e-11)
    back = R.quat_rotate(R.quat_conjugate(q), R.quat_rotate(q, v))
    np.testing.assert_allclose(back, v, atol=1e-11)
    np.testing.assert_allclose(R.quat_multiply(q, R.quat_inverse(q)), [1, 0, 0, 0], atol=1e-14)


@settings(max_examples=100, deadline=None)
@given(quat_raw, quat_raw, st.floats(0, 1))
def test_slerp_endpoints_and_constant_speed(a, b, s):
    a, b = R.quat_normalize(a), R.quat_normalize(b)
    assert same_rotation(R.quat_slerp(a, b, 0.0), a, 1e-7)
    assert same_rotation(R.quat_slerp(a, b, 1.0), b, 1e-7)
    total = R.quat_angle(a, b)
    np.testing.assert_allclose(R.quat_angle(a, R.quat_slerp(a, b, s)), s * total, atol=1e-7)


def test_batch_and_single_agree():
    rng = np.random.default_rng(1)
    q = R.quat_normalize(rng.normal(size=(50, 4)))
    v = rng.normal(size=(50, 3))
    batch = R.quat_rotate(q, v)
    single = np.array([R.quat_rotate(q[i], v[i]) for i in range(50)])
    np.testing.assert_array_equal(batch, single)
    e = R.euler_from_quat(q)
    assert e.shape == (50, 3)
    np.testing.assert_allclose(R.dcm_from_quat(R.quat_from_euler(e)), R.dcm_from_quat(q), atol=1e-12)


def test_quat_interp_between_samples():
    t = np.array([0.0, 1.0, 2.0])
    q = R.quat_from_rotvec(np.array([[0, 0, 0], [0, 0, 0.5], [0, 0, 1.0]]))
    out = R.quat_interp(t, q, [0.5, 1.5])
    np.testing.assert_allclose(R.rotvec_from_quat(out), [[0, 0, 0.25], [0, 0, 0.75]], atol=1e-14)


def test_skew_is_cross_product():
    a, b = np.array([1.0, -2.0, 3.0]), np.array([0.5, 4.0, -1.0])
    np.testing.assert_allclose(R.skew(a) @ b, np.cross(a, b))


# ---- frame-convention constants -------------------------------------------
def test_enu_ned_constants():
    v_ned = np.array([1.0, 2.0, 3.0])  # north, east, down
    np.testing.assert_allclose(R.C_ENU_NED @ v_ned, [2.0, 1.0, -3.0])
    np.testing.assert_allclose(R.quat_rotate(R.Q_ENU_NED, v_ned), [2.0, 1.0, -3.0], atol=1e-15)
    np.testing.assert_allclose(R.quat_rotate(R.Q_FRD_FLU, [1.0, 2.0, 3.0]), [1.0, -2.0, -3.0], atol=1e-15)


# ---- bad input ---------------------------------------------------------------
def test_bad_inputs_raise():
    with pytest.raises(ShapeError, match=r"shape \(4,\) or \(N, 4\)"):
        R.quat_multiply(np.zeros(3), np.zeros(4))
    with pytest.raises(NonFiniteError, match="rows \\[1\\]"):
        R.quat_normalize([[1, 0, 0, 0], [np.nan, 0, 0, 0]])
    with pytest.raises(NonFiniteError, match="zero quaternion"):
        R.quat_normalize([0, 0, 0, 0])
    with pytest.raises(TimeOrderError):
        R.integrate_rate([1, 0, 0, 0], [0.0, 0.1, 0.1], np.zeros((3, 3)))
    with pytest.raises(ShapeError, match="same number of rows"):
        R.integrate_rate([1, 0, 0, 0], [0.0, 0.1], np.zeros((3, 3)))
    with pytest.raises(ShapeError, match="must match"):
        R.quat_multiply(np.ones((2, 4)), np.ones((3, 4)))


def test_frame_constants_are_the_quaternions_of_their_matrices():
    """Q_ENU_NED / Q_FRD_FLU are written out (no kernel runs at import): they equal quat_from_dcm of their
    matrices bit for bit."""
    np.testing.assert_array_equal(R.Q_ENU_NED, R.quat_from_dcm(R.C_ENU_NED))
    np.testing.assert_array_equal(R.Q_FRD_FLU, R.quat_from_dcm(R.C_FLU_FRD.T))


def test_quat_from_dcm_takes_each_of_shepperds_pivots():
    """The four branches of Shepperd's method (largest of trace, C00, C11, C22; the first of equal ones): the
    identity and the half turns about x, y and z give their quaternions exactly, and a half turn about (x + y)/√2
    (C00 = C11 = 0, the largest) the x pivot, to rounding."""
    for C, q in ((np.eye(3), [1, 0, 0, 0]), (np.diag([1.0, -1, -1]), [0, 1, 0, 0]),
                 (np.diag([-1.0, 1, -1]), [0, 0, 1, 0]), (np.diag([-1.0, -1, 1]), [0, 0, 0, 1])):
        np.testing.assert_array_equal(R.quat_from_dcm(C), q)
    C = np.array([[0.0, 1, 0], [1, 0, 0], [0, 0, -1]])
    np.testing.assert_allclose(R.quat_from_dcm(C), [0, math.sqrt(0.5), math.sqrt(0.5), 0], rtol=0, atol=2e-16)
    np.testing.assert_array_equal(R.quat_from_dcm(np.stack([C, np.eye(3)]))[0], R.quat_from_dcm(C))
