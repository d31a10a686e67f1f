"""Trajectory, ideal IMU and trajectory builders: closed-form oracles."""

import numpy as np
import pytest

from imunav import earth
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError, TimeOrderError
from imunav.rotation import (
    dcm_from_quat,
    integrate_rate,
    quat_conjugate,
    quat_from_euler,
    quat_from_rotvec,
    quat_multiply,
    rotvec_from_quat,
)
from imunav.sim import (
    Trajectory,
    body_rate_from_attitude,
    ideal_imu,
    rate_table_profile,
    static_profile,
    trajectory_from_attitude,
    trajectory_from_functions,
    trajectory_from_waypoints,
)
from imunav.units import G0

LAT = np.deg2rad(39.87)


def angle_between(q1, q2):
    """Rotation angle between attitudes via the log map (rotation.quat_angle uses
    arccos, which cannot resolve angles below ~2e-8 rad)."""
    return np.linalg.norm(rotvec_from_quat(quat_multiply(quat_conjugate(q1), q2)), axis=-1)


@pytest.mark.parametrize("h", [0.0, 938.0])
def test_static_level_gives_gravity_and_earth_rate(h):
    traj = static_profile(5.0, 50.0, lat=LAT, lon=0.5, h=h).trajectory
    imu = ideal_imu(traj)
    g = earth.normal_gravity(LAT, h)
    np.testing.assert_allclose(imu.accel, np.tile([0, 0, -g], (traj.n, 1)), rtol=0, atol=1e-14)
    w = earth.OMEGA_E * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
    np.testing.assert_allclose(imu.gyro, np.tile(w, (traj.n, 1)), rtol=0, atol=1e-19)


def test_static_tilted_resolves_in_body_axes():
    q = quat_from_euler(0.3, -0.4, 2.0)
    traj = static_profile(2.0, 10.0, orientation=q, lat=LAT).trajectory
    imu = ideal_imu(traj)
    C_bn = dcm_from_quat(q).T
    np.testing.assert_allclose(imu.accel[0], C_bn @ [0, 0, -earth.normal_gravity(LAT)], atol=1e-14)
    np.testing.assert_allclose(imu.gyro[-1], C_bn @ earth.earth_rate_ned(LAT), atol=1e-19)
    # switches: constant gravity, explicit number, no Earth rate
    np.testing.assert_allclose(np.linalg.norm(ideal_imu(traj, gravity="constant").accel, axis=1), G0, rtol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(ideal_imu(traj, gravity=9.81).accel, axis=1), 9.81, rtol=1e-15)
    assert np.all(ideal_imu(traj, earth_rate=False).gyro == 0)


def test_constant_rate_integrates_back_to_attitude():
    # a constant-rate step of a rate-table profile about an oblique body axis
    axis = np.array([[1.0, -2.0, 0.5]])
    prof = rate_table_profile([np.deg2rad(123.0)], axis, dwell_s=20.0, fs=200.0, transition_s=1.0)
    traj, seg = prof
    imu = ideal_imu(traj, earth_rate=False, gravity="constant")
    rate = seg.select("rate")
    i0, i1 = rate.i_start[0], rate.i_stop[0]
    for method in ("zoh", "trapezoid"):
        q = integrate_rate(traj.q_nb[i0], traj.t[i0:i1], imu.gyro[i0:i1], method=method)
        assert np.max(angle_between(q, traj.q_nb[i0:i1])) < 1e-9
    # through the minimum-jerk ramp too: exact rates, so the only error is the
    # trapezoid rule's dt^2/12 * theta'' (<= 1.875 * rate / T_ramp), gone at the ramp's end
    q = integrate_rate(traj.q_nb[0], traj.t, imu.gyro, method="trapezoid")
    err = angle_between(q, traj.q_nb)
    assert err.max() < 1.1 * (1 / 200.0) ** 2 / 12 * 1.875 * np.deg2rad(123.0) / 1.0 * 2
    assert err[-1] < 1e-9


def test_moving_east_on_equator_coriolis_and_centripetal():
    # v east along the equator: f_D = -g + 2 Omega v + v^2 / a, gyro_x = Omega + v/a
    v, fs = 200.0, 10.0
    t = np.arange(0, 20, 1 / fs)
    n = t.size
    lla = np.c_[np.zeros(n), v * t / earth.A, np.zeros(n)]
    vel = np.tile([0.0, v, 0.0], (n, 1))
    q = np.tile([1.0, 0, 0, 0], (n, 1))
    exact = ideal_imu(Trajectory(t, q, vel_ned=vel, pos_lla=lla, omega_nb_b=np.zeros((n, 3)), accel_ned=np.zeros((n, 3))))
    g = earth.GAMMA_E
    np.testing.assert_allclose(exact.accel, np.tile([0, 0, -g + 2 * earth.OMEGA_E * v + v * v / earth.A], (n, 1)), atol=1e-13)
    np.testing.assert_allclose(exact.gyro, np.tile([earth.OMEGA_E + v / earth.A, 0, 0], (n, 1)), atol=1e-18)
    # the same from positions only (velocity and acceleration by differentiation)
    derived = ideal_imu(Trajectory(t, q, pos_lla=lla))
    np.testing.assert_allclose(derived.accel, exact.accel, atol=1e-9)
    np.testing.assert_allclose(derived.gyro, exact.gyro, atol=1e-15)
    # transport rate off: gyro is Earth rate only
    assert ideal_imu(Trajectory(t, q, vel_ned=vel, pos_lla=lla), transport_rate=False).gyro[0, 0] == earth.OMEGA_E


def test_derived_rates_second_order():
    # rotation about a fixed axis with angle A sin(2 pi f t): error <= dt^2/6 |w''| + tiny
    fs, A, f = 100.0, 0.8, 0.5
    t = np.arange(0, 4, 1 / fs)
    ax = np.array([0.6, 0.0, 0.8])
    th = A * np.sin(2 * np.pi * f * t)
    q = quat_from_rotvec(ax[None] * th[:, None])
    w_true = ax[None] * (A * 2 * np.pi * f * np.cos(2 * np.pi * f * t))[:, None]
    w = body_rate_from_attitude(t, q)
    bound = (1 / fs) ** 2 / 6 * A * (2 * np.pi * f) ** 3
    assert np.abs(w - w_true)[1:-1].max() <= 1.01 * bound
    tr = trajectory_from_attitude(t, q, lat=LAT)
    np.testing.assert_allclose(tr.omega_nb_b, w)
    assert tr.pos_lla[0, 0] == LAT


def test_functions_builder_matches_closed_form():
    # level, yaw spinning at 0.2 rad/s, constant acceleration 0.5 m/s^2 north from rest
    def att(t):
        return np.c_[np.zeros_like(t), np.zeros_like(t), 0.2 * t]

    def pos(t):
        return np.c_[0.25 * t**2, np.zeros_like(t), np.zeros_like(t)]

    o = np.array([LAT, 0.1, 100.0])
    tr = trajectory_from_functions(att, pos, duration_s=10.0, fs=20.0, origin_lla=o)
    np.testing.assert_allclose(tr.omega_nb_b, np.tile([0, 0, 0.2], (tr.n, 1)), atol=1e-9)
    np.testing.assert_allclose(tr.vel_ned[:, 0], 0.5 * tr.t, atol=1e-6)
    # kinematic accel 0.5 north; a straight tangent-plane track climbs away from the
    # curved Earth: v_D = -v x / R, so dv_D/dt = -(a x + v^2) / R
    np.testing.assert_allclose(tr.accel_ned[:, 0], 0.5, atol=1e-6)
    rn, _ = earth.radii(LAT)
    x, v = 0.25 * tr.t**2, 0.5 * tr.t
    np.testing.assert_allclose(tr.accel_ned[:, 2], -(0.5 * x + v**2) / (rn + o[2]), atol=1e-7)
    imu = ideal_imu(tr, earth_rate=False, transport_rate=False, gravity="constant")
    yaw = 0.2 * tr.t
    np.testing.assert_allclose(imu.accel[:, 0], 0.5 * np.cos(yaw), atol=2e-5)
    np.testing.assert_allclose(imu.accel[:, 1], -0.5 * np.sin(yaw), atol=2e-5)


def test_waypoint_spline_rates_are_body_rates():
    tk = np.array([0.0, 1.0, 2.5, 4.0])
    e = np.array([[0, 0, 0], [0.3, -0.2, 1.0], [1.0, 0.5, -1.0], [0.1, 0.1, 0.1]])
    pk = np.array([[0, 0, 0], [10, 2, 0], [20, 10, -1], [25, 30, -2.0]])
    tr = trajectory_from_waypoints(tk, e, pk, fs=1000.0, origin_lla=[LAT, 0, 0])
    np.testing.assert_allclose(angle_between(tr.q_nb[[0, 1000, 2500, 4000]], quat_from_euler(e)), 0, atol=1e-9)
    w = body_rate_from_attitude(tr.t, tr.q_nb)
    assert np.abs(w - tr.omega_nb_b)[5:-5].max() < 1e-5
    away = np.min(np.abs(tr.t[:, None] - tk[None]), axis=1) > 0.005  # acceleration has kinks at knots
    np.testing.assert_allclose(np.gradient(tr.vel_ned, tr.t, axis=0)[away], tr.accel_ned[away], atol=1e-4)
    assert tr.n == 4001


def test_bad_inputs():
    q = np.tile([1.0, 0, 0, 0], (3, 1))
    with pytest.raises(TimeOrderError, match="rows \\[2\\]"):
        Trajectory([0.0, 1.0, 1.0], q)
    with pytest.raises(ShapeError, match="q_nb must have shape \\(3, 4\\)"):
        Trajectory([0.0, 1.0, 2.0], q[:2])
    with pytest.raises(ShapeError, match="vel_ned"):
        Trajectory([0.0, 1.0, 2.0], q, vel_ned=np.zeros((3, 2)))
    with pytest.raises(NonFiniteError, match="omega_nb_b"):
        Trajectory([0.0, 1.0, 2.0], q, omega_nb_b=np.full((3, 3), np.nan))
    traj = Trajectory([0.0, 1.0, 2.0], q)
    with pytest.raises(InvalidInputError, match="needs a latitude"):
        ideal_imu(traj)
    with pytest.raises(InvalidInputError, match="gravity must be"):
        ideal_imu(traj, earth_rate=False, gravity="moon")
    with pytest.raises(InvalidInputError, match="within"):
        ideal_imu(traj, lat=3.0)
    with pytest.raises(InvalidInputError, match="duration_s and fs"):
        trajectory_from_functions(lambda t: np.zeros((t.size, 3)))
    # no location needed when nothing asks for it
    imu = ideal_imu(traj, earth_rate=False, gravity="constant")
    assert imu.accel[0, 2] == -G0
