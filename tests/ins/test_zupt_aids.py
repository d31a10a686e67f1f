"""ZUPT-INS aids: nav-frame heading hold, level-floor constraint, ZARU in long stances only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imunav.errors import ConfigError
from imunav.ins import ZuptConfig, ZuptFilter, long_stances
from imunav.rotation import dcm_from_quat, quat_error_angle, quat_from_euler, quat_multiply
from imunav.sim.gait import simulate_gait
from imunav.timeseries import ImuData

G = 9.80665


def _pitching_tilted_sensor(fs=200.0, T=6.0, amp_deg=25.0, mount_deg=(30.0, -20.0, 50.0)):
    """A still foot rocking heel to toe (pitch about the nav y axis) with a tilted sensor.

    C_nb(t) = R_y(theta(t)) C_mount, theta = amp sin(pi t / 2): no translation and
    no rotation about the vertical, so both the ZUPT and the heading hold are exact.
    The gyro sample k is the mean rate over (t_{k-1}, t_k] (single-axis rotation:
    the first-order integration is then exact).
    """
    t = np.arange(int(T * fs) + 1) / fs
    amp = math.radians(amp_deg)
    theta = amp * np.sin(0.5 * math.pi * t)
    q_m = quat_from_euler(*np.radians(mount_deg))
    q_p = np.column_stack([np.cos(theta / 2), np.zeros_like(t), np.sin(theta / 2), np.zeros_like(t)])
    q = quat_multiply(q_p, q_m)
    axis_b = dcm_from_quat(q_m).T @ np.array([0.0, 1.0, 0.0])
    rate = np.zeros_like(t)
    rate[1:] = np.diff(theta) * fs
    gyr = rate[:, None] * axis_b[None, :]
    C = dcm_from_quat(q)
    acc = np.einsum("nji,j->ni", C, np.array([0.0, 0.0, -G]))
    return ImuData(t, gyr, acc), q


def test_heading_hold_exact_for_tilted_sensor_rocking_in_stance():
    """The hold measures the rotation about the vertical, not a ZYX-yaw difference.

    The yaw angle of the tilted sensor swings by tens of degrees while the foot
    only pitches; holding that angle would twist the attitude.  The nav-frame
    rotation about the vertical is 0, so the held filter stays on the truth.
    """
    data, q_true = _pitching_tilted_sensor()
    from imunav.rotation import euler_from_quat

    yaw_swing = np.ptp(np.unwrap(euler_from_quat(q_true)[:, 2]))
    assert yaw_swing > math.radians(10)  # a yaw-angle hold would be badly wrong here
    cfg = ZuptConfig(heading_hold=True, heading_noise_std=math.radians(0.1), g=G)
    res = ZuptFilter(cfg).run(data, np.ones(data.n, bool), initial_quaternion=q_true[0])
    err = np.degrees(quat_error_angle(res.q_nb, q_true))
    # integration is exact for this motion; what is left is the rounding of 1200 steps
    assert err.max() < 1e-6
    np.testing.assert_allclose(res.position, 0.0, atol=1e-9)


def test_heading_hold_removes_gyro_bias_heading_drift():
    """A vertical-gyro bias turns a standing foot; the hold stops the drift.

    Level and static, the yaw error decouples: a random walk with
    q = (gyro_noise_std h)^2 per step, measured with r = heading_noise_std^2.  The
    steady-state prior variance solves P^2 - q P - q r = 0, K = P / (P + r),
    and a ramp of d = b h per step settles at the lag e = (1 - K) d / K.
    """
    fs, n = 200.0, 2001
    b = math.radians(0.5)  # °/s about body z (= nav down for a level foot)
    data = ImuData(np.arange(n) / fs, np.tile([0.0, 0.0, b], (n, 1)), np.tile([0.0, 0.0, -G], (n, 1)))
    free = ZuptFilter(ZuptConfig(g=G)).run(data, np.ones(n, bool), initial_quaternion=[1, 0, 0, 0])
    held = ZuptFilter(ZuptConfig(g=G, heading_hold=True)).run(data, np.ones(n, bool), initial_quaternion=[1, 0, 0, 0])
    from imunav.rotation import euler_from_quat

    yaw_free = euler_from_quat(free.q_nb[-1])[2]
    yaw_held = euler_from_quat(held.q_nb[-1])[2]
    assert yaw_free == pytest.approx(b * data.t[-1], rel=1e-6)  # 5°
    cfg = ZuptConfig()
    h = 1.0 / fs
    q, r = (cfg.gyro_noise_std * h) ** 2, cfg.heading_noise_std**2
    P = 0.5 * (q + math.sqrt(q * q + 4 * q * r))
    K = P / (P + r)
    lag = (1 - K) * b * h / K
    assert yaw_held == pytest.approx(lag, rel=0.01)  # 0.5° against 5° free


def test_level_floor_removes_vertical_drift_on_flat_walk():
    """Flat simulated walk, MEMS errors: stance heights stay at 0 within a few floor_noise_std."""
    worst_free, worst_floor = [], []
    for seed in (0, 1, 2):
        sim = simulate_gait("walk", 30, error_model="foot_mems", rng=seed, turn_deg=12)
        free = ZuptFilter(ZuptConfig(g=G, integration="coning")).run(sim.imu, sim.stance)
        cfg = ZuptConfig(g=G, integration="coning", level_floor=True, floor_noise_std=0.01)
        floor = ZuptFilter(cfg).run(sim.imu, sim.stance)
        worst_free.append(np.abs(free.position[sim.stance, 2]).max())
        worst_floor.append(np.abs(floor.position[sim.stance, 2]).max())
        # the constraint does not harm the horizontal solution
        h_free = np.linalg.norm(free.position[-1, :2] - sim.position[-1, :2])
        h_floor = np.linalg.norm(floor.position[-1, :2] - sim.position[-1, :2])
        assert h_floor < h_free + 0.02
    assert max(worst_floor) < 3 * 0.01
    assert max(worst_floor) < 0.5 * max(worst_free)


def test_long_stances_mask():
    t = np.arange(12) * 0.5
    zv = np.array([1, 1, 1, 1, 0, 1, 1, 0, 0, 1, 1, 1], bool)
    # stances: 0-3 (1.5 s), 5-6 (0.5 s), 9-11 (1.0 s)
    np.testing.assert_array_equal(long_stances(t, zv, 1.0), [1, 1, 1, 1, 0, 0, 0, 0, 0, 1, 1, 1])
    np.testing.assert_array_equal(long_stances(t, zv, 0.0), zv)
    assert not long_stances(t, zv, 2.0).any()
    with pytest.raises(ConfigError, match="zaru_min_s"):
        ZuptConfig(states=15, zaru=True, zaru_min_s=-1.0)


def test_zaru_in_long_stances_recovers_gyro_bias():
    """ZARU only while standing (initial / final stance of 4 s): biases inside 3 sigma."""
    for seed in (0, 1):
        sim = simulate_gait("walk", 20, error_model="foot_mems", rng=seed, turn_deg=18,
                            initial_stance_s=4.0, final_stance_s=4.0)
        cfg = ZuptConfig(g=G, states=15, zaru=True, zaru_min_s=1.0, integration="coning")
        res = ZuptFilter(cfg).run(sim.imu, sim.stance)
        sd = np.sqrt(res.cov_diag[-1])
        np.testing.assert_array_less(np.abs(res.gyro_bias[-1] - sim.gyro_bias[-1]), 3 * sd[12:15])
        assert np.linalg.norm(res.position[-1] - sim.position[-1]) < 0.1


def test_free_acceleration_detector_on_simulated_walk():
    """x-io's rule on an ideal walk: every true stance sample is stationary; most swing is not.

    In stance the free acceleration is |tilt error| g only (the Mahony tilt
    re-converges after each swing), far below 3 m/s²; the minimum-jerk swing
    dips below it only for a few samples at toe-off and heel-strike.
    """
    from imunav.errors import InvalidInputError
    from imunav.ins import detect_zero_velocity, free_acceleration

    sim = simulate_gait("walk", 12, error_model=None, rng=4, turn_deg=20)
    det = detect_zero_velocity(sim.imu, "freeacc", g=G)
    assert det.detector == "freeacc" and det.params["threshold"] == 3.0
    assert det.zv[sim.stance].all()
    assert det.statistic[sim.stance].max() < 1.0
    assert det.zv[~sim.stance].mean() < 0.05
    # widening the moving periods by 0.1 s (x-io) removes the swing ends
    wide = detect_zero_velocity(sim.imu, "freeacc", g=G, margin_s=0.1).zv
    assert not wide[~sim.stance].any()
    with pytest.raises(InvalidInputError, match="threshold"):
        free_acceleration(sim.imu, threshold=-1.0)
