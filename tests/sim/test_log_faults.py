"""The faults of real logs (imunav.sim.log_faults) and the hard robot / hard car (imunav.sim.hard_log): each switch
does what it says, everything off reproduces the robot of before to the bit, and the log run takes both."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from imunav.earth import dlla_to_ned
from imunav.errors import InvalidInputError
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.io.navlog import read_nav_sources
from imunav.rotation import euler_from_quat
from imunav.sim import presets
from imunav.sim.gnss import truth_at
from imunav.sim.hard_log import simulate_hard_car_log, simulate_hard_robot_log
from imunav.sim.log_faults import LogFaults
from imunav.sim.robot_log import robot_loops, simulate_robot_log, write_robot_log
from imunav.sim.trajectory import body_rate_from_attitude
from imunav.sim.vehicle import lever_arm_velocity_body, omega_eb_b, vehicle_trajectory


def _fingerprint(log) -> str:
    h = hashlib.sha256()
    tr = log.truth.trajectory
    for a in (log.imu.t, log.imu.gyro, log.imu.accel, log.gnss.t, log.gnss.lla, log.gnss.pos_std, log.odometer.t,
              log.odometer.speed, tr.t, tr.q_nb, tr.vel_ned, tr.pos_lla, tr.omega_nb_b, tr.accel_ned):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()


def test_everything_off_is_the_robot_of_before_to_the_bit():
    """Every fault off (``LogFaults()``) draws what the robot drew before the faults existed (``faults=None``), bit
    for bit, plain and with its body perturbations.  (Digests recorded at 8c8bfc6 held this against the code of
    before; they also fixed the versions of numpy and numba, and a fresh install of them moved every digest, both
    calls alike.)"""
    for seed, perturbed in ((3, False), (5, True)):
        kw = {"slip_std": (0.05, 0.05), "idle_vibration_std": 0.01} if perturbed else {}
        a = _fingerprint(simulate_robot_log(seed, distance_m=80.0, faults=None, **kw))
        assert _fingerprint(simulate_robot_log(seed, distance_m=80.0, faults=LogFaults(), **kw)) == a
        some = LogFaults(imu_stamp_jitter_s=0.003)
        assert _fingerprint(simulate_robot_log(seed, distance_m=80.0, faults=some, **kw)) != a  # can fail


def _fix_errors(log):
    """NED error of each fix against the truth of the antenna at its stamp less the latency, m."""
    tr = log.truth.trajectory
    lla, _ = truth_at(tr, log.gnss.t - log.truth.gnss_latency_s, log.truth.gnss_lever_arm_base)
    return dlla_to_ned(log.gnss.lla - lla, lla)


def test_correlated_gnss_error_has_the_gauss_markov_autocorrelation():
    tau, rate = 4.0, 2.5
    log = simulate_robot_log(11, gnss_std_m=0.01, outlier_fraction=0.0,
                             faults=LogFaults(gnss_corr_sigma_m=(1.0, 1.0, 1.0), gnss_corr_tau_s=tau))
    e = _fix_errors(log)
    n, lag = e.shape[0], int(round(tau * rate))
    e = e - e.mean(axis=0)
    rho = np.mean([np.sum(e[lag:, j] * e[:-lag, j]) / np.sum(e[:, j] ** 2) for j in range(3)])
    # Bartlett's variance of an AR(1) autocorrelation estimate at lag k, phi = exp(-1 / (tau rate)); three axes
    phi = math.exp(-1.0 / (tau * rate))
    var = ((1 + phi**2) * (1 - phi ** (2 * lag)) / (1 - phi**2) - 2 * lag * phi ** (2 * lag)) / n / 3
    assert abs(rho - math.exp(-1.0)) < 4.0 * math.sqrt(var)
    assert abs(rho - math.exp(-1.0)) < 0.3  # the margin itself is not vacuous
    # the fixes report the marginal sigma, sqrt(white^2 + correlated^2)
    np.testing.assert_allclose(log.gnss.pos_std, math.sqrt(1.0 + 0.01**2), rtol=1e-12)


def test_reported_sigma_is_the_true_one_times_the_factor():
    for factor in (0.4, 2.0):
        log = simulate_robot_log(2, distance_m=80.0, faults=LogFaults(gnss_std_factor=factor))
        np.testing.assert_allclose(log.gnss.pos_std, 0.8 * factor, rtol=1e-12)
        np.testing.assert_allclose(log.truth.faults["gnss_true_std"], 0.8, rtol=1e-12)
        # the positions are those without the fault
        np.testing.assert_array_equal(log.gnss.lla, simulate_robot_log(2, distance_m=80.0).gnss.lla)


def test_repeated_fixes_copy_the_fix_before():
    p, m = 0.1, 3
    log = simulate_robot_log(3, outlier_fraction=0.0, faults=LogFaults(gnss_repeat_prob=p, gnss_repeat_max=m))
    rep = log.truth.faults["gnss_repeated"]
    g = log.gnss
    k = np.flatnonzero(rep)
    np.testing.assert_array_equal(g.lla[k], g.lla[k - 1])  # a repeat holds the position before it
    assert np.all(np.diff(g.t) > 0)  # under new stamps
    assert not np.any(np.all(g.lla[1:] == g.lla[:-1], axis=1) & ~rep[1:])  # and nothing else repeats
    # share: a fix starts a run with probability p; runs average (1 + m) / 2 repeats
    mean_run = (1 + m) / 2
    expect = p * mean_run / (1 + p * mean_run)
    n_runs = p * g.n / (1 + p * mean_run)
    assert abs(rep.mean() - expect) < 4.0 * math.sqrt(n_runs * (1 + mean_run**2)) / g.n + 0.01


def test_jumps_and_drifts_at_rest_fade_once_moving():
    f = LogFaults(gnss_rest_jump_m=5.0, gnss_rest_jump_prob=1.0, gnss_rest_drift_mps=0.01, gnss_rest_relax_s=2.0)
    log = simulate_robot_log(4, distance_m=160.0, faults=f)
    clean = simulate_robot_log(4, distance_m=160.0)
    off = log.truth.faults["gnss_rest_offset_ned"]
    d = dlla_to_ned(log.gnss.lla - clean.gnss.lla, clean.gnss.lla)
    np.testing.assert_allclose(d, off, atol=1e-6)  # the fixes moved by the recorded offset, nothing else
    tr = log.truth.trajectory
    speed = np.interp(log.gnss.t - 0.15, tr.t, np.linalg.norm(tr.vel_ned, axis=1))
    h = np.hypot(off[:, 0], off[:, 1])
    rest = speed < 0.02
    # every stop (the first, one after each of the 2 loops, the last) jumped by 2.5-5 m, plus a drift of at most
    # a few cm over its 5-10 s
    edges = np.diff(np.concatenate([[0], rest.astype(int), [0]]))
    runs = list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))
    assert len(runs) == 3
    for _, e in runs:
        assert 2.4 < h[e - 1] < 5.0 + 0.5
    # 20 s (ten relax times) after a stop, nothing is left
    t_moving_since = np.maximum.accumulate(np.where(rest, log.gnss.t, -np.inf))
    far = ~rest & (log.gnss.t - t_moving_since > 20.0)
    assert far.sum() > 100 and np.max(h[far]) < 5.0 * math.exp(-20.0 / 2.0) * 1.01 + 1e-9


def test_imu_stamp_jitter_has_its_sigma_and_keeps_the_samples():
    sd = 0.002
    log = simulate_robot_log(5, distance_m=80.0, faults=LogFaults(imu_stamp_jitter_s=sd))
    clean = simulate_robot_log(5, distance_m=80.0)
    e = log.imu.t - clean.imu.t
    np.testing.assert_allclose(e, log.truth.faults["imu_stamp_error_s"])
    assert e[0] == e[-1] == 0.0 and np.all(np.diff(log.imu.t) > 0)  # the log spans the drive
    n = e.size - 2
    # sample sd against sigma: chi^2(n) / n has sd sqrt(2 / n); the cut at 0.4 of 1/30 s is 6.7 sigma away
    assert abs(np.sqrt(np.mean(e[1:-1] ** 2)) / sd - 1.0) < 4.0 * math.sqrt(0.5 / n)
    np.testing.assert_array_equal(log.imu.gyro, clean.imu.gyro)


def test_warm_up_moves_the_gyro_bias_by_its_temperature_coefficient():
    rise, tau = 20.0, 100.0
    log = simulate_robot_log(6, distance_m=80.0, faults=LogFaults(imu_temp_rise_c=rise, imu_temp_tau_s=tau))
    clean = simulate_robot_log(6, distance_m=80.0)
    temp = log.truth.faults["imu_temp_c"]
    t = log.imu.t
    np.testing.assert_allclose(temp, 25.0 + rise * (1 - np.exp(-t / tau)), rtol=1e-12)
    last = t > t[-1] - 8.0  # the final stop
    coef = presets.get("consumer_mems").gyro.bias_temp_poly[0]
    diff = (log.imu.gyro - clean.imu.gyro)[last].mean(axis=0)
    lsb = math.radians(1.0) / 131.0
    np.testing.assert_allclose(diff, coef * (temp[last].mean() - 25.0), atol=lsb)
    assert np.all(np.abs(coef * rise * 0.5) > 3 * lsb)  # the shift is resolved


def test_wheels_change_radius_read_late_and_quantised():
    f = LogFaults(odometer_scale_change=0.05, odometer_scale_tau_s=50.0, odometer_latency_s=0.1,
                  odometer_resolution=0.001)
    log = simulate_robot_log(7, distance_m=80.0, odometer_noise_std=1e-9, faults=f)
    tr, o = log.truth.trajectory, log.odometer
    v = lever_arm_velocity_body(tr, (0.0, 0.0, 0.0))[:, 0]
    k = 0.91 * (1.0 + 0.05 * (1.0 - np.exp(-o.t / 50.0)))
    late = k * np.interp(o.t - 0.1, tr.t, v)
    np.testing.assert_allclose(o.speed, late, atol=0.0005 + 1e-8)  # half a quantum
    np.testing.assert_allclose(o.speed / 0.001, np.round(o.speed / 0.001), atol=1e-6)
    assert np.max(np.abs(o.speed - k * np.interp(o.t, tr.t, v))) > 0.01  # lateness shows in the ramps


def test_terrain_moves_the_wheels_scale_as_a_gauss_markov_process():
    # the same draws with and without the terrain: the ratio of the readings is 1 + g(t), g first-order Gauss-Markov
    clean = simulate_robot_log(9, distance_m=200.0, faults=LogFaults())
    rough = simulate_robot_log(9, distance_m=200.0, faults=LogFaults(odometer_terrain_std=0.1,
                                                                     odometer_terrain_tau_s=0.5))
    moving = np.abs(clean.odometer.speed) > 0.3
    g = rough.odometer.speed[moving] / clean.odometer.speed[moving] - 1.0
    t = clean.odometer.t[moving]
    # about T / (2 tau) independent values: the sample sigma's relative standard error is 1 / sqrt(2 N_eff)
    n_eff = (t[-1] - t[0]) / (2 * 0.5)
    assert abs(np.std(g) / 0.1 - 1.0) < 3.0 / math.sqrt(2.0 * n_eff)
    step = np.diff(t) < 0.15  # consecutive 10 Hz readings: correlation e^{-0.1 / 0.5}
    rho = np.corrcoef(g[:-1][step], g[1:][step])[0, 1]
    assert abs(rho - math.exp(-0.2)) < 0.05
    for bad in ({"odometer_terrain_std": -0.1}, {"odometer_terrain_tau_s": 0.0}):
        with pytest.raises(InvalidInputError, match="odometer_terrain"):
            LogFaults(**bad)


def test_turns_slip_sideways_and_the_wheels_over_read():
    f = LogFaults(turn_slip=0.2, odometer_turn_overread=0.3)
    log = simulate_robot_log(8, distance_m=80.0, odometer_noise_std=1e-9, faults=f)
    tr = log.truth.trajectory
    vb = lever_arm_velocity_body(tr, (0.0, 0.0, 0.0))
    s = vb[:, 0]
    wz = tr.omega_nb_b[:, 2]
    np.testing.assert_allclose(vb[:, 1], -0.2 * s * s * wz, atol=2e-5)
    assert np.max(np.abs(vb[:, 1])) > 0.04  # 0.2 x 1 m/s x 0.25 rad/s in the 4 m turns
    # the truth stays a trajectory: its acceleration is the derivative of its velocity
    acc = np.gradient(tr.vel_ned, tr.t, axis=0)
    np.testing.assert_allclose(acc[1:-1], tr.accel_ned[1:-1], atol=2e-3)
    o = log.odometer
    i = np.searchsorted(tr.t, o.t)
    np.testing.assert_allclose(o.speed, 0.91 * (1 + 0.3 * np.abs(omega_eb_b(tr)[i, 2])) * s[i], atol=1e-7)


def test_bank_hill_and_bump_give_a_consistent_rough_drive():
    tr = vehicle_trajectory(robot_loops(80.0, bank_deg=5.0, grade_deg=4.0, bump_deg=4.0), fs=100.0)
    e = np.degrees(euler_from_quat(tr.q_nb))
    assert abs(np.max(e[:, 0]) - 5.0) < 1e-6 and np.max(e[:, 1]) > 3.99 and np.min(e[:, 1]) < -3.99
    w = body_rate_from_attitude(tr.t, tr.q_nb)
    assert np.max(np.abs(tr.omega_nb_b)) > 0.5  # the bump is sharp
    np.testing.assert_allclose(w[1:-1], tr.omega_nb_b[1:-1], atol=5e-3)  # central differences at 0.7 rad/s
    assert abs(tr.pos_lla[-1, 2] - tr.pos_lla[0, 2]) < 1e-6  # each loop climbs and comes back down
    with pytest.raises(InvalidInputError):
        LogFaults(gnss_std_factor=0.0)


def test_log_run_takes_the_hard_robot_and_the_hard_car(tmp_path):
    robot = simulate_hard_robot_log(0, distance_m=80.0)
    run = run_log(robot.sources, LogRunOptions(gnss_lever_arm=tuple(robot.truth.gnss_lever_arm_base)))
    assert run.result.t.size == robot.imu.n and np.all(np.isfinite(run.result.lla))
    car = simulate_hard_car_log(0, duration_s=60.0)
    sp = np.linalg.norm(car.truth.trajectory.vel_ned, axis=1)
    assert sp.min() > 7.0 and sp.max() < 31.0  # a highway that never stops
    run = run_log(car.sources, LogRunOptions(mounting=car.truth.q_base_imu,
                                             gnss_lever_arm=tuple(car.truth.gnss_lever_arm_base)))
    assert run.result.t.size == car.imu.n and np.all(np.isfinite(run.result.lla))
    # its bag holds the same sources (imunav gins run robot.bag)
    bag = write_robot_log(car, tmp_path, formats=("ros1",))["ros1"]
    src, mem = read_nav_sources(bag), car.sources
    np.testing.assert_allclose(src.imu.t, mem.imu.t, atol=1e-9)
    np.testing.assert_allclose(src.imu.gyro, mem.imu.gyro, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(src.gnss.lla, mem.gnss.lla, rtol=1e-12)
    np.testing.assert_allclose(src.gnss.pos_std, mem.gnss.pos_std, rtol=1e-9)
    np.testing.assert_allclose(src.odometer.speed, mem.odometer.speed, rtol=1e-12, atol=1e-12)
