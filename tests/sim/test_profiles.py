"""Calibration test profiles (imu-error-calibration.md §5)."""

import numpy as np
import pytest

from imunav.errors import InvalidInputError, ShapeError
from imunav.rotation import integrate_rate, quat_conjugate, quat_multiply, rotvec_from_quat
from imunav.sim import (
    ferraris_profile,
    hundred_position_orientations,
    hundred_position_profile,
    hundred_position_up_vectors,
    ideal_imu,
    multiposition_profile,
    orientations_from_up,
    rate_table_profile,
    rate_table_step_profile,
    rate_table_steps,
    six_position_profile,
    static_profile,
    up_from_orientations,
)
from imunav.units import G0


def _check_cover(seg, n):
    assert seg.i_start[0] == 0 and seg.i_stop[-1] == n
    np.testing.assert_array_equal(seg.i_start[1:], seg.i_stop[:-1])
    np.testing.assert_allclose(seg.t_start[1:], seg.t_stop[:-1])


def test_hundred_position_design():
    up = hundred_position_up_vectors()
    assert up.shape == (100, 3)
    np.testing.assert_allclose(np.linalg.norm(up, axis=1), 1.0, rtol=1e-15)
    # consecutive positions all differ (by one 22.5 deg step inside an axis block)
    ang = np.degrees(np.arccos(np.clip(np.sum(up[1:] * up[:-1], axis=1), -1, 1)))
    assert np.all(ang > 1.0)
    np.testing.assert_allclose(ang[:32], 22.5, atol=1e-9)
    # both signs, full +-1 g, on every axis; the projections are g cos(theta) on the 22.5 deg grid
    for i in range(3):
        assert up[:, i].max() == pytest.approx(1.0) and up[:, i].min() == pytest.approx(-1.0)
        block = up[33 * i : 33 * (i + 1), i]
        grid = np.cos(np.deg2rad(np.arange(9) * 22.5))
        assert np.all(np.min(np.abs(block[:, None] - grid[None]), axis=1) < 1e-12)
        assert block[0] == -1.0 and block[8] == 1.0 and block[-1] == -1.0
    np.testing.assert_array_equal(up[-1], [0, 0, 1])
    # the attitudes realise these vertical directions
    q = hundred_position_orientations()
    np.testing.assert_allclose(up_from_orientations(q), up, atol=1e-12)


def test_hundred_position_profile_and_ideal_accel():
    prof = hundred_position_profile(fs=10.0, dwell_s=3.0, transition_s=1.0)
    traj, seg = prof
    st = seg.select("static")
    assert len(st) == 100 and len(seg.select("transition")) == 99
    np.testing.assert_array_equal(st.step, np.arange(100))
    _check_cover(seg, traj.n)
    assert traj.duration == pytest.approx(100 * 3.0 + 99 * 1.0)
    imu = ideal_imu(traj, earth_rate=False, gravity="constant")
    for k in range(100):
        sl = slice(st.i_start[k], st.i_stop[k])
        np.testing.assert_allclose(imu.accel[sl], np.tile(G0 * st.up_b[k], (st.i_stop[k] - st.i_start[k], 1)), atol=1e-12)
        assert np.all(imu.gyro[sl] == 0)
    assert prof.summary()["segments"] == {"static": 100, "transition": 99}


def test_rate_table_steps_exact():
    rates, axes = rate_table_steps()
    assert rates.shape == (120,) and axes.shape == (120,)
    digest = (
        list(range(0, 251, 25)) + list(range(225, 0, -25)) + [0] + list(range(-25, -251, -25)) + list(range(-225, 0, 25))
    )
    assert len(digest) == 40
    for i in range(3):
        np.testing.assert_allclose(np.rad2deg(rates[axes == i]), digest, atol=1e-12)
        assert np.sum(axes == i) == 40
    np.testing.assert_array_equal(axes, np.repeat([0, 1, 2], 40))


def test_rate_table_profile_exact_commanded_rates():
    prof = rate_table_step_profile(fs=10.0, dwell_s=2.0, transition_s=0.5, remount_s=1.0)
    traj, seg = prof
    _check_cover(seg, traj.n)
    rs = seg.select("rate")
    rates, axes = rate_table_steps()
    assert len(rs) == 120
    np.testing.assert_array_equal(rs.rate, rates)
    np.testing.assert_array_equal(rs.axis_b, np.eye(3)[axes])
    imu = ideal_imu(traj, earth_rate=False, gravity="constant")
    for k in range(120):
        sl = slice(rs.i_start[k], rs.i_stop[k])
        m = rs.i_stop[k] - rs.i_start[k]
        assert m == 20 + (k == 119)  # the last segment also holds the final sample
        np.testing.assert_array_equal(imu.gyro[sl], np.tile(rates[k] * np.eye(3)[axes[k]], (m, 1)))
        # rotated axis vertical, pointing up: that accelerometer reads +g, the others 0
        np.testing.assert_allclose(imu.accel[sl], np.tile(G0 * np.eye(3)[axes[k]], (m, 1)), atol=1e-12)
    down = rate_table_profile(rates[:3], axes[:3], 1.0, 10.0, 0.5, mounting="down")
    assert ideal_imu(down.trajectory, earth_rate=False, gravity="constant").accel[0, 0] == pytest.approx(-G0)


def test_profiles_integrate_consistently():
    # exact rates through transitions: attitude from integrating the gyro matches at
    # the end of each move (trapezoid + coning error vanishes for rest-to-rest moves)
    prof = six_position_profile(fs=200.0, dwell_s=1.0, transition_s=2.0)
    traj, seg = prof
    q = integrate_rate(traj.q_nb[0], traj.t, traj.omega_nb_b, method="trapezoid")
    st = seg.select("static")
    err = np.linalg.norm(rotvec_from_quat(quat_multiply(quat_conjugate(q[st.i_start]), traj.q_nb[st.i_start])), axis=1)
    assert err.max() < 1e-6
    np.testing.assert_allclose(np.abs(st.up_b).max(axis=1), 1.0)


def test_ferraris_rotation_angles():
    prof = ferraris_profile(fs=100.0, dwell_s=1.0, transition_s=2.0, rotation_s=4.0)
    traj, seg = prof
    _check_cover(seg, traj.n)
    assert len(seg.select("static")) == 12
    rot = seg.select("rotation")
    assert len(rot) == 3
    np.testing.assert_allclose(rot.angle, 2 * np.pi)
    for k in range(3):
        sl = slice(rot.i_start[k], rot.i_stop[k] + 1)
        area = np.trapezoid(traj.omega_nb_b[sl], traj.t[sl], axis=0)
        np.testing.assert_allclose(area, 2 * np.pi * np.eye(3)[k], atol=1e-4)
        np.testing.assert_allclose(rot.up_b[k], np.eye(3)[k], atol=1e-12)


def test_static_and_generic_multiposition():
    p = static_profile(10.0, 100.0, lat=0.7, h=50.0)
    assert p.trajectory.n == 1001 and len(p.segments) == 1
    assert p.trajectory.pos_lla[0, 2] == 50.0
    up = np.array([[0, 0, -1.0], [1, 0, 0], [0, 1, 1]])
    q = orientations_from_up(up)
    prof = multiposition_profile(q, [2.0, 3.0, 4.0], 50.0, 1.5)
    st = prof.segments.select("static")
    np.testing.assert_allclose(st.t_stop - st.t_start, [2, 3, 4])
    np.testing.assert_allclose(st.up_b, up / np.linalg.norm(up, axis=1)[:, None], atol=1e-12)
    assert prof.to_dict()["segment_table"]["kind"][1] == "transition"
    tr = st.trim(0.5)
    np.testing.assert_array_equal(tr.i_start - st.i_start, 25)
    np.testing.assert_array_equal(st.i_stop - tr.i_stop, 25)
    np.testing.assert_allclose(prof.trajectory.t[tr.i_start], tr.t_start)
    with pytest.raises(InvalidInputError, match=r"empties segments \[0\]"):
        st.trim(1.0)


def test_bad_inputs():
    q = orientations_from_up(np.array([[0, 0, -1.0], [1, 0, 0]]))
    with pytest.raises(InvalidInputError, match="transition_s must be positive"):
        multiposition_profile(q, 1.0, 10.0, 0.0)
    with pytest.raises(ShapeError, match="orientations must be \\(K, 4\\)"):
        multiposition_profile(np.zeros((2, 3)), 1.0, 10.0)
    with pytest.raises(ShapeError, match="dwell_s must be a scalar or have one entry"):
        multiposition_profile(q, [1.0, 2.0, 3.0], 10.0)
    with pytest.raises(InvalidInputError, match="fs must be a positive"):
        multiposition_profile(q, 1.0, -10.0)
    with pytest.raises(InvalidInputError, match="axes must be 0"):
        rate_table_profile([1.0], [3], 1.0, 10.0)
    with pytest.raises(InvalidInputError, match="mounting"):
        rate_table_profile([1.0], [0], 1.0, 10.0, mounting="side")
    with pytest.raises(InvalidInputError, match="zero or non-finite"):
        orientations_from_up(np.zeros((1, 3)))
    with pytest.raises(InvalidInputError, match="step_deg"):
        hundred_position_up_vectors(25.0)
