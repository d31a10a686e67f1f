"""GNSS/INS filter: GNSS at its own time stamps, increments input, odometer + NHC, the outage protocol, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.ins.gins.config import misalignment_std
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.outage import outage_test
from imunav.io.kfgins import ImuIncrements
from imunav.rotation import quat_conjugate, quat_from_rotvec, quat_multiply, rotvec_from_quat
from imunav.sim import presets, simulate_imu
from imunav.sim.error_model import GaussMarkov, ImuErrorModel, TriadErrors
from imunav.sim.gnss import simulate_gnss, simulate_magnetometer
from imunav.sim.robot_log import simulate_robot_log
from imunav.sim.vehicle import OdometerData, demo_drive, simulate_baro, simulate_odometer, vehicle_trajectory
from imunav.timeseries import ImuData
from imunav.units import DEG

ORIGIN = (30.44 * DEG, 114.47 * DEG, 20.0)
LEVER = (0.136, -0.301, -0.184)
WHEEL = (0.0, 0.8, 0.3)


@pytest.fixture(scope="module")
def drive():
    truth = vehicle_trajectory(demo_drive(900), fs=50, origin_lla=ORIGIN)
    return truth, simulate_imu(truth, presets.get("mems_adis16465"), rng=1)


def _start(truth):
    return dict(lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])


def _hpos_err(truth, res):
    d = earth.lla_to_ned(res.lla, truth.pos_lla[0]) - earth.lla_to_ned(truth.pos_lla, truth.pos_lla[0])
    return np.hypot(d[:, 0], d[:, 1])


def test_gnss_is_used_at_its_own_time_stamp(drive):
    """RTK fixes (1 cm) stamped 7.3 ms after an IMU sample (20 m/s: 15 cm of travel): the filter integrates to
    the stamp, so the position NIS stays chi^2(3) (mean within 5 standard errors of 3)."""
    truth, imu = drive
    g = simulate_gnss(truth, pos_noise=(0.01, 0.01, 0.02), vel_noise=None, lever_arm=LEVER, t_offset=0.0073, rng=2)
    assert np.all(np.abs((g.t - truth.t[0]) * 50 - np.round((g.t - truth.t[0]) * 50)) > 0.3)  # between samples
    cfg = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, use_gnss_velocity=False, init_pos_std=0.05,
                                 init_vel_std=0.05, init_att_std=np.radians([0.1, 0.1, 0.5]))
    res = GinsFilter(cfg).run(imu, g, **_start(truth))
    nis = res.nis[res.accepted[:, 0], 0]
    assert nis.size >= 0.99 * g.n
    assert abs(nis[60:].mean() - 3.0) < 5 * np.sqrt(6.0 / nis[60:].size), nis[60:].mean()
    assert _hpos_err(truth, res)[truth.n // 2:].max() < 0.1


def test_increments_and_rates_give_the_same_navigation(drive):
    """The same IMU as rates (ImuData) or as trapezoid increments (ImuIncrements, as KF-GINS files hold them):
    the solutions agree within a small fraction of the GNSS sigma (0.5 m)."""
    truth, imu = drive
    g = simulate_gnss(truth, rng=3)
    cfg = GinsConfig.from_preset("mems_adis16465")
    a = GinsFilter(cfg).run(imu, g, **_start(truth))
    b = GinsFilter(cfg).run(ImuIncrements.from_imu_data(imu, 50.0), g, **_start(truth))
    d = earth.lla_to_ned(a.lla, truth.pos_lla[0]) - earth.lla_to_ned(b.lla, truth.pos_lla[0])
    assert np.abs(d).max() < 0.1


def test_odometer_and_nhc_shrink_mems_outage_drift(drive):
    """ADIS16465-class MEMS, 60 s outages every 180 s: odometer + NHC make the RMS of the per-outage maximum
    horizontal drift at least 3x smaller (measured ~19x on 20 min), and the drift stays inside 3 sigma."""
    truth, imu = drive
    g = simulate_gnss(truth, pos_noise=(0.02, 0.02, 0.04), vel_noise=None, lever_arm=LEVER, rng=4)
    odo = simulate_odometer(truth, lever_arm=WHEEL, scale_factor=0.005, noise_std=0.05, rng=5)
    base = dict(lever_arm=LEVER, use_gnss_velocity=False, init_pos_std=0.05, init_vel_std=0.05,
                init_att_std=np.radians([0.1, 0.1, 0.5]))
    plain = outage_test(imu, g, GinsConfig.from_preset("mems_adis16465", **base), truth, **_start(truth),
                        shifts_s=(0.0,))
    cfg = GinsConfig.from_preset("mems_adis16465", nhc_noise_std=0.1, odo_lever_arm=WHEEL, odo_noise_std=0.05, **base)
    aided = outage_test(imu, g, cfg, truth, **_start(truth), shifts_s=(0.0,), odometer=odo)
    p, q = plain.rms(), aided.rms()
    assert p["n_outages"] == q["n_outages"] == 4
    assert p["horizontal_m"] > 3 * q["horizontal_m"], (p, q)
    assert q["contained_3sigma"] == 1.0 and p["contained_3sigma"] == 1.0
    res = GinsFilter(cfg).run(imu, g, **_start(truth), odometer=odo)
    assert res.vehicle_t.size > 0 and np.all(res.vehicle_dof == 3)
    # the odometer scale (0.5 %) is estimated within 3 sigma
    assert abs(res.odo_scale[-1] - 0.005) < 3 * np.sqrt(res.cov_diag[-1, -1])


def test_each_aiding_model_has_its_own_nis_record(drive):
    """The odometer, NHC, ZUPT and ZARU NIS are recorded apart (the marginals of the joint updates' innovation):
    with the odometer alone the vehicle update has one row and its NIS is the odometer's; with the NHC alone, two
    rows and the NHC's; the ZUPT and ZARU records sit exactly where the joint rest update was applied, and there
    neither the NHC nor the odometer is applied."""
    truth, imu = drive
    g = simulate_gnss(truth, rng=7)
    odo = simulate_odometer(truth, lever_arm=WHEEL, noise_std=0.05, rng=8)
    static = np.linalg.norm(truth.vel_ned, axis=1) < 1e-9
    base = GinsConfig.from_preset("mems_adis16465", odo_lever_arm=WHEEL)
    only_odo = GinsFilter(base).run(imu, g, **_start(truth), odometer=odo, static=static)
    used = np.isin(truth.t, only_odo.vehicle_t)
    assert used.sum() > 1000 and np.all(only_odo.vehicle_dof == 1)
    np.testing.assert_allclose(only_odo.odo_nis[used], only_odo.vehicle_nis, rtol=1e-9)
    assert np.all(np.isnan(only_odo.odo_nis[~used])) and np.all(np.isnan(only_odo.nhc_nis))
    rest = ~np.isnan(only_odo.zupt_nis)
    assert not np.any(used & rest)  # at rest the ZUPT replaces the odometer too
    assert rest.sum() > 100 and np.array_equal(rest, ~np.isnan(only_odo.zupt_vel_nis))
    assert np.array_equal(rest, ~np.isnan(only_odo.zaru_nis))
    only_nhc = GinsFilter(GinsConfig.from_preset("mems_adis16465", odo_lever_arm=WHEEL, nhc_noise_std=0.1)).run(
        imu, g, **_start(truth))
    used = np.isin(truth.t, only_nhc.vehicle_t)
    assert np.all(only_nhc.vehicle_dof == 2) and np.all(np.isnan(only_nhc.odo_nis))
    np.testing.assert_allclose(only_nhc.nhc_nis[used], only_nhc.vehicle_nis, rtol=1e-9)
    # at rest the ZUPT replaces the NHC (the same velocity is not used twice)
    rest_nhc = GinsFilter(GinsConfig.from_preset("mems_adis16465", odo_lever_arm=WHEEL, nhc_noise_std=0.1)).run(
        imu, g, **_start(truth), static=static)
    nhc = ~np.isnan(rest_nhc.nhc_nis)
    assert not np.any(nhc & static) and np.array_equal(nhc, used & ~static)
    assert np.array_equal(~np.isnan(rest_nhc.zupt_nis), used & static)


def test_nhc_interval_applies_the_constraint_once_per_interval(drive):
    """With ``nhc_interval_s`` the NHC is applied at the first sample of each interval since the start (0.7 s: off
    the 0.2 s covariance grid, so those samples become covariance epochs), only while the vehicle moves and GNSS
    fixes arrive; in an outage at every covariance step again; the odometer stays at every step; an interval that
    is not > 0 is refused."""
    truth, imu = drive
    g = simulate_gnss(truth, rng=7)
    odo = simulate_odometer(truth, lever_arm=WHEEL, noise_std=0.05, rng=8)
    static = np.linalg.norm(truth.vel_ned, axis=1) < 1e-9
    kw = dict(odo_lever_arm=WHEEL, nhc_noise_std=0.1)
    every = GinsFilter(GinsConfig.from_preset("mems_adis16465", **kw)).run(imu, g, **_start(truth), odometer=odo,
                                                                           static=static)
    spaced = GinsFilter(GinsConfig.from_preset("mems_adis16465", nhc_interval_s=0.7, **kw)).run(
        imu, g, **_start(truth), odometer=odo, static=static)
    b = np.floor((truth.t - truth.t[0]) / 0.7 + 1e-9)
    first = np.r_[False, b[1:] != b[:-1]]
    np.testing.assert_array_equal(~np.isnan(spaced.nhc_nis), first & ~static)
    assert np.count_nonzero(~np.isnan(every.nhc_nis)) > 3 * np.count_nonzero(~np.isnan(spaced.nhc_nis))
    assert np.count_nonzero(~np.isnan(spaced.odo_nis)) >= np.count_nonzero(~np.isnan(every.odo_nis))
    # a 30 s GNSS outage: 1.4 s (two intervals) after its last fix the NHC is back at every 0.2 s step
    t_a, t_b = 100.0, 130.0
    cut = GinsFilter(GinsConfig.from_preset("mems_adis16465", nhc_interval_s=0.7, **kw)).run(
        imu, g.select((g.t <= t_a) | (g.t >= t_b), "outage"), **_start(truth), odometer=odo, static=static)
    inside = (truth.t > t_a + 1.5) & (truth.t < t_b) & ~static
    used = ~np.isnan(cut.nhc_nis)
    assert inside.sum() > 20 * 50 and abs(np.count_nonzero(used & inside) - inside.sum() / 10) <= 2  # 5 Hz of 50 Hz
    np.testing.assert_array_equal(used[truth.t < t_a], (first & ~static)[truth.t < t_a])
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InvalidInputError, match="nhc_interval_s"):
            GinsConfig.from_preset("mems_adis16465", nhc_interval_s=bad)


def test_bad_inputs_are_refused(drive):
    truth, imu = drive
    g = simulate_gnss(truth, rng=6)
    cfg = GinsConfig.from_preset("mems_adis16465")
    far = OdometerData(truth.t + 1e5, np.zeros(truth.n))
    with pytest.raises(InvalidInputError, match="outside the IMU span"):
        GinsFilter(cfg).run(imu, g, **_start(truth), odometer=far)
    late = type(g)(g.t + 1e5, g.lla, g.pos_std, g.vel_ned, g.vel_std)
    with pytest.raises(InvalidInputError, match="outside the IMU span"):
        GinsFilter(cfg).run(imu, late, **_start(truth))
    with pytest.raises(InvalidInputError, match="> 0"):
        GinsConfig.from_preset("mems_adis16465", init_pos_std=0.0)
    with pytest.raises(InvalidInputError, match="lat"):
        GinsFilter(cfg).run(imu, g, lla0=(30.0, 114.0, 0.0), vel0=(0, 0, 0), q0=(1, 0, 0, 0))


def test_rts_smoother_bridges_an_outage(drive):
    """A 60 s outage on the MEMS drive: the RTS pass shrinks the maximum horizontal error inside it at least 5x
    (measured 8.7 m -> 0.43 m), every smoothed position error lies inside its smoothed 3 sigma, and at the
    last epoch the smoothed and filtered solutions coincide (nothing after it to smooth with)."""
    truth, imu = drive
    g = simulate_gnss(truth, rng=7, outages=[(420.0, 60.0)])
    res = GinsFilter(GinsConfig.from_preset("mems_adis16465")).run(imu, g, **_start(truth), smoother=True)
    s = res.smoothed
    m = (truth.t >= 420) & (truth.t <= 480)
    hf = _hpos_err(truth, res)[m].max()
    hs = np.hypot(*(earth.lla_to_ned(s.lla, truth.pos_lla[0]) - earth.lla_to_ned(truth.pos_lla, truth.pos_lla[0]))[m, :2].T).max()
    assert hs < hf / 5, (hf, hs)
    idx = np.searchsorted(truth.t, s.cov_t)
    e = (earth.lla_to_ned(s.lla, truth.pos_lla[0]) - earth.lla_to_ned(truth.pos_lla, truth.pos_lla[0]))[idx]
    sd = np.sqrt(np.einsum("nii->ni", s.cov_nav[:, :3, :3]))
    assert np.mean(np.abs(e) <= 3 * sd) >= 0.99
    np.testing.assert_allclose(s.lla[-1], res.lla[-1], rtol=0, atol=1e-12)
    assert res.smoothed is not None and GinsFilter(res.config).run(imu, g, **_start(truth)).smoothed is None


def test_zupt_zaru_and_barometer_updates(drive):
    """While the vehicle stands still (the drive's stops, from the truth) ZUPT + ZARU hold the velocity near zero
    without GNSS; a barometer with white noise (sigma 0.5 m) brings the height error below the GNSS-only one.
    The barometer's NIS is chi^2(1): its mean within 5 standard errors of 1 (it was 0.71 when the samples were
    interpolated to the IMU stamps, which averages the white noise of two samples)."""
    truth, _ = drive
    gyro_noise_density, accel_noise_density, gb, ab, tc = 0.15 * DEG / 60, 0.012 / 60, 10 * DEG / 3600, 2e-3, 1000.0
    model = ImuErrorModel(gyro=TriadErrors(noise_density=gyro_noise_density, bias_instability=GaussMarkov(gb, tc)),
                          accel=TriadErrors(noise_density=accel_noise_density, bias_instability=GaussMarkov(ab, tc)))
    imu = simulate_imu(truth, model, rng=10)
    cfg = GinsConfig(gyro_noise_density=gyro_noise_density, accel_noise_density=accel_noise_density, gyro_bias_std=gb, accel_bias_std=ab, corr_time=tc, scale_factors=False,
                     baro_noise_std=0.5)
    static = np.linalg.norm(truth.vel_ned, axis=1) < 1e-9
    assert static[: 20 * 50].all()  # the 20 s stop at the start
    g = simulate_gnss(truth, rng=8, outages=[(0.0, 20.0)])
    baro = simulate_baro(truth, noise_std=0.5, bias_std=0.0, rate_hz=10, rng=9)
    res = GinsFilter(cfg).run(imu, g, **_start(truth), static=static, baro=baro)
    z = res.zupt_nis[~np.isnan(res.zupt_nis)]
    b = res.baro_nis[~np.isnan(res.baro_nis)]
    assert z.size > 100 and b.size > 1000
    assert abs(b.mean() - 1.0) < 5 * np.sqrt(2.0 / b.size), b.mean()
    plain = GinsFilter(cfg).run(imu, g, **_start(truth))
    hb = np.abs(res.lla[:, 2] - truth.pos_lla[:, 2])[50 * 60:]
    hp = np.abs(plain.lla[:, 2] - truth.pos_lla[:, 2])[50 * 60:]
    assert np.sqrt(np.mean(hb**2)) < np.sqrt(np.mean(hp**2)), (np.sqrt(np.mean(hb**2)), np.sqrt(np.mean(hp**2)))
    still = np.abs(res.vel_ned[: 20 * 50]).max()
    assert still < 0.05 and np.abs(plain.vel_ned[: 20 * 50]).max() > 2 * still


@pytest.mark.parametrize("nhc_interval", [None, 0.6])
def test_step_by_step_equals_run(drive, nhc_interval):
    """GinsFilter.step over the increments, with each fix handed to the step whose interval holds it, the
    wheel speed at each sample and the NHC (at every covariance step, or every 0.6 s: 30 samples, on the 0.2 s grid,
    so that the last sample stays a covariance step as :meth:`run` makes it), reproduces GinsFilter.run (same kernel, carried state) to 1e-9 on a 60 s drive: position (rad / m), velocity,
    attitude, IMU errors and the final covariance."""
    truth, imu = drive
    n = 3001  # 60 s at 50 Hz: the last sample is a covariance step (0.2 s = 10 samples)
    inc = ImuIncrements.from_imu_data(imu, 50.0)
    inc = ImuIncrements(inc.t[:n], inc.dtheta[:n], inc.dvel[:n], inc.dt[:n])
    g = simulate_gnss(truth, lever_arm=LEVER, t_offset=0.0073, rng=7).within(inc.t[0], inc.t[-1])
    odo = simulate_odometer(truth, lever_arm=WHEEL, scale_factor=0.005, noise_std=0.05, rng=8)
    cfg = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, nhc_noise_std=0.1, odo_lever_arm=WHEEL,
                                 nhc_interval_s=nhc_interval)
    f = GinsFilter(cfg)
    ref = f.run(inc, g, **_start(truth), odometer=odo)
    f.reset(**_start(truth), t0=inc.t[0], fs=50.0, odometer=True, dtheta0=inc.dtheta[0], dvel0=inc.dvel[0])
    lla, nis = [], []
    speed = np.interp(inc.t, odo.t, odo.speed)
    for k in range(1, n):
        f.step(inc.t[k], inc.dtheta[k], inc.dvel[k], gnss=g, odometer_speed=speed[k])
        lla.append(f.lla.copy())
        nis.append(f.last_nis["gnss"])
    lla = np.array(lla)
    assert np.max(np.abs(lla[:, :2] - ref.lla[1:, :2])) < 1e-9 / 6.4e6  # 1e-9 m
    assert np.max(np.abs(lla[:, 2] - ref.lla[1:, 2])) < 1e-9
    assert np.max(np.abs(f.vel_ned - ref.vel_ned[-1])) < 1e-9
    assert np.max(np.abs(f.q_nb - ref.q_nb[-1])) < 1e-9
    assert np.max(np.abs(f.imu_errors[:12] - np.hstack([ref.gyro_bias[-1], ref.accel_bias[-1], ref.gyro_scale[-1],
                                                         ref.accel_scale[-1]]))) < 1e-9
    assert np.allclose(np.diag(f.P), ref.cov_diag[-1], rtol=1e-9, atol=0)
    nis = np.vstack([x for x in nis if x.size])
    assert nis.shape == ref.nis.shape and np.allclose(nis, ref.nis, rtol=1e-9, atol=1e-12, equal_nan=True)
    with pytest.raises(InvalidInputError, match="not after"):
        f.step(inc.t[-1], inc.dtheta[-1], inc.dvel[-1])
    with pytest.raises(InvalidInputError, match="reset"):
        GinsFilter(cfg).step(1.0, (0, 0, 0), (0, 0, 0))


def test_magnetometer_heading_aiding(drive):
    """A calibrated magnetometer (declination 6 deg, inclination 60 deg, 0.2 uT on 50 uT: heading sigma
    0.46 deg) fixes a 3 deg initial heading error during the first 20 s stop, where position-only GNSS cannot:
    the heading error at the end of the stop is below 3 x its predicted sigma (itself < 0.5 deg: the z gyro bias
    of 0.04 deg/s is learnt in 20 s only in part) with the magnetometer and stays above 2 deg without; the magnetometer NIS is chi^2(1) (mean within 5 standard errors of 1)."""
    truth, imu = drive
    decl, incl = np.radians(6.0), np.radians(60.0)
    mag = simulate_magnetometer(truth, declination=decl, inclination=incl, strength=50.0, noise_std=0.2, rng=11)
    g = simulate_gnss(truth, vel_noise=None, rng=12)
    sd = 0.2 / (50.0 * np.cos(incl))
    cfg = GinsConfig.from_preset("mems_adis16465", use_gnss_velocity=False, declination=decl, mag_heading_noise_std=sd,
                                 init_att_std=np.radians([0.1, 0.1, 5.0]))
    start = _start(truth)
    start["q0"] = quat_multiply(quat_from_rotvec(np.radians([0.0, 0.0, 3.0])), truth.q_nb[0])
    with_mag = GinsFilter(cfg).run(imu, g, **start, mag=mag)
    plain = GinsFilter(cfg).run(imu, g, **start)
    k = 20 * 50 - 1  # end of the stop

    def yaw_err(res):
        return abs(rotvec_from_quat(quat_multiply(truth.q_nb[k], quat_conjugate(res.q_nb[k])))[2])

    sig = np.sqrt(with_mag.cov_nav[np.searchsorted(with_mag.cov_t, truth.t[k]), 8, 8])
    assert yaw_err(with_mag) < 3 * sig and sig < np.radians(0.5)  # prior 5 deg
    assert yaw_err(plain) > np.radians(2.0)
    nis = with_mag.mag_nis[~np.isnan(with_mag.mag_nis)]
    assert nis.size > 0.99 * mag.t.size
    assert abs(nis.mean() - 1.0) < 5 * np.sqrt(2.0 / nis.size), nis.mean()
    with pytest.raises(InvalidInputError, match="declination"):
        GinsConfig.from_preset("mems_adis16465", declination=4.0)


def test_covariance_records_cover_the_whole_run_with_fast_aiding(drive):
    """Barometer (10 Hz) and magnetometer (10 Hz) samples are covariance epochs besides the 0.2 s steps: the
    records still reach the last IMU sample (none dropped for lack of room: 9001 records, twice the room the
    0.2 s steps alone need)."""
    truth, imu = drive
    g = simulate_gnss(truth, rng=13)
    res = GinsFilter(GinsConfig.from_preset("mems_adis16465")).run(
        imu, g, **_start(truth), baro=simulate_baro(truth, rate_hz=10, rng=14),
        mag=simulate_magnetometer(truth, rate_hz=10, rng=15))
    assert res.cov_t[-1] == truth.t[-1] and np.all(np.diff(res.cov_t) > 0)
    assert res.cov_t.size == 10 * 900 + 1  # every 0.1 s (the aiding stamps, the 0.2 s steps among them) and t0


def test_aiding_samples_are_checked():
    """Aiding data types refuse what the kernel would read as 'no sample' or crash on (review finding)."""
    from imunav.errors import NonFiniteError, ShapeError
    from imunav.sim.gnss import MagnetometerData
    from imunav.sim.vehicle import BaroData

    with pytest.raises(ShapeError, match="field_b"):
        MagnetometerData(np.arange(3.0), np.zeros(3))
    with pytest.raises(ShapeError, match="height"):
        BaroData(np.arange(3.0), np.zeros(4))
    with pytest.raises(NonFiniteError, match=r"rows \[1\]"):
        OdometerData(np.arange(3.0), np.array([1.0, np.nan, 1.0]))
    with pytest.raises(InvalidInputError, match="strictly increase"):
        BaroData(np.array([0.0, 1.0, 1.0]), np.zeros(3))


def test_progress_goes_through_chunks_with_the_same_result_bit_for_bit(drive, monkeypatch):
    """With ``progress`` the filter runs in chunks of ``PROGRESS_CHUNK`` samples (997 here: chunk boundaries fall
    between covariance epochs, GNSS fixes and forced NHC epochs) and reports each; the trajectory, covariance records,
    NIS of every aid and the smoother's output are those of one call, bit for bit."""
    from imunav.ins.gins import filter as gins_filter

    truth, imu = drive
    g = simulate_gnss(truth, lever_arm=LEVER, t_offset=0.0073, rng=7)
    odo = simulate_odometer(truth, lever_arm=WHEEL, noise_std=0.05, rng=8)
    static = np.linalg.norm(truth.vel_ned, axis=1) < 1e-9
    cfg = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, nhc_noise_std=0.1, odo_lever_arm=WHEEL,
                                 nhc_interval_s=0.7, gnss_delay_std=0.05)
    kw = dict(**_start(truth), odometer=odo, static=static, smoother=True)
    plain = GinsFilter(cfg).run(imu, g, **kw)
    monkeypatch.setattr(gins_filter, "PROGRESS_CHUNK", 997)
    seen = []
    chunked = GinsFilter(cfg).run(imu, g, **kw, progress=lambda done, total: seen.append((done, total)))
    n = truth.t.size
    assert len(seen) == -(-(n - 1) // 997) + 1 and seen[-1] == (2 * n, 2 * n)
    assert all(b[0] > a[0] for a, b in zip(seen, seen[1:])) and seen[-2] == (n, 2 * n)
    for name in ("lla", "vel_ned", "q_nb", "gyro_bias", "accel_bias", "odo_scale", "gnss_delay", "cov_t", "cov_diag",
                 "cov_nav", "nis", "vehicle_nis", "vehicle_t", "nhc_nis", "odo_nis", "zupt_nis"):
        np.testing.assert_array_equal(getattr(chunked, name), getattr(plain, name), err_msg=name)
    for name in ("lla", "vel_ned", "q_nb", "cov_t", "cov_nav"):
        np.testing.assert_array_equal(getattr(chunked.smoothed, name), getattr(plain.smoothed, name), err_msg=name)
    assert chunked.aids.keys() == plain.aids.keys()
    for a in plain.aids:
        np.testing.assert_array_equal(chunked.aids[a].sample, plain.aids[a].sample, err_msg=a)
        np.testing.assert_array_equal(chunked.aids[a].nis, plain.aids[a].nis, err_msg=a)


@pytest.mark.parametrize("model", ["constant_and_gauss_markov", "gauss_markov"])
def test_bias_variance_without_aiding_follows_its_model(model):
    """A still IMU, no aid, 500 s = 5 T: the filter's variance of each whole bias is its closed form.  A random
    constant plus a stationary Gauss-Markov part keeps var(c) + var(g) = init^2 at every time (the two-block model:
    d/dt P_bb = -2 P_bg / T + q = 0 with P_bg = P_gg = sigma_GM^2, q = 2 sigma_GM^2 / T); a Gauss-Markov bias decays
    from init^2 to sigma_GM^2, sigma_GM^2 + (init^2 - sigma_GM^2) exp(-2 t / T).  A random walk of the Gauss-Markov's
    noise (the earlier form) grows by 2 sigma_GM^2 t / T: for the accelerometer 9e-4 + 1e-4 * 10 m^2/s^4 at 500 s,
    twice the closed form."""
    T, gm_g, gm_a, init_g, init_a = 100.0, 1e-4, 1e-2, 1e-3, 3e-2
    cfg = GinsConfig(gyro_noise_density=1e-4, accel_noise_density=1e-3, gyro_bias_std=gm_g, accel_bias_std=gm_a,
                     init_gyro_bias_std=init_g, init_accel_bias_std=init_a, corr_time=T, scale_factors=False,
                     bias_model=model, gate_alpha=0.0)
    lat, h = 0.5, 100.0
    g = float(earth.normal_gravity(lat, h))
    t = np.arange(0.0, 500.0 + 1e-9, 0.01)
    gyro = np.tile([earth.OMEGA_E * np.cos(lat), 0.0, -earth.OMEGA_E * np.sin(lat)], (t.size, 1))
    res = GinsFilter(cfg).run(ImuData(t, gyro, np.tile([0.0, 0.0, -g], (t.size, 1))), None,
                              lla0=np.array([lat, 0.2, h]), vel0=np.zeros(3), q0=np.array([1.0, 0.0, 0.0, 0.0]))
    i = 9  # the gyro biases, then the accelerometer's (pos, vel, att first)
    tk = res.cov_t - res.cov_t[0]
    for j0, gm, init in ((i, gm_g, init_g), (i + 3, gm_a, init_a)):
        if model == "gauss_markov":
            want = gm**2 + (init**2 - gm**2) * np.exp(-2 * tk / T)
        else:
            want = np.full(tk.size, init**2)
        for j in range(3):
            np.testing.assert_allclose(res.cov_diag[:, j0 + j], want, rtol=1e-3)


def test_the_accelerometers_misalignment_tilt_reaches_the_reported_covariance(drive):
    """``accel_misalignment_std`` adds its variance to the attitude errors of every covariance record, forward and
    smoothed, and (with wheel aids) the velocity it turns, and nothing else: the estimate is the same to the bit.  ``misalignment_std`` is
    the RMS of a preset's off-diagonal accelerometer misalignment (what a log run takes); ``from_preset`` leaves
    it at 0."""
    truth, imu = drive
    m = presets.get("consumer_mems").accel.scale_misalignment
    off = m[~np.eye(3, dtype=bool)]
    sd = misalignment_std(m)
    assert sd == pytest.approx(np.sqrt(np.mean(off[off != 0] ** 2)), rel=1e-12) and 0.1 * DEG < sd < 0.3 * DEG
    assert misalignment_std(np.eye(3)) == 0.0 and GinsConfig.from_preset("consumer_mems").accel_misalignment_std == 0
    g = simulate_gnss(truth, rng=7).within(0.0, 120.0)
    short = ImuData(imu.t[:6001], imu.gyro[:6001], imu.accel[:6001])
    a, b = (GinsFilter(GinsConfig.from_preset("mems_adis16465", accel_misalignment_std=s)).run(
        short, g, **_start(truth), smoother=True) for s in (0.0, 0.2 * DEG))
    np.testing.assert_array_equal(a.lla, b.lla)
    expect = np.zeros((9, 9))
    expect[6, 6] = expect[7, 7] = expect[8, 8] = (0.2 * DEG) ** 2
    np.testing.assert_allclose(b.cov_nav - a.cov_nav, np.broadcast_to(expect, a.cov_nav.shape), rtol=0, atol=1e-15)
    np.testing.assert_allclose((b.cov_diag - a.cov_diag)[:, :9], np.broadcast_to(np.diag(expect), (a.cov_t.size, 9)),
                               rtol=0, atol=1e-15)
    np.testing.assert_array_equal((b.cov_diag - a.cov_diag)[:, 9:], 0.0)
    np.testing.assert_allclose(b.smoothed.cov_nav - a.smoothed.cov_nav, np.broadcast_to(
        expect, a.smoothed.cov_nav.shape), rtol=0, atol=1e-15)
    with pytest.raises(InvalidInputError, match="accel_misalignment_std"):
        GinsConfig.from_preset("consumer_mems", accel_misalignment_std=-1e-3)
    # a log run (a real IMU whose axes nobody calibrated) takes its preset's
    log = simulate_robot_log(3, distance_m=80.0)
    assert run_log(log.sources, LogRunOptions()).config.accel_misalignment_std == sd
    # with wheel aids (here the NHC) the velocity is measured in the body's axes, and the misalignment turns it:
    # δv = φ × v adds [v×] Σ [v×]ᵀ to the velocity and −[v×] Σ to its covariance with the attitude
    a, b = (GinsFilter(GinsConfig.from_preset("mems_adis16465", accel_misalignment_std=s, nhc_noise_std=0.5)).run(
        short, g, **_start(truth), smoother=True) for s in (0.0, 0.2 * DEG))
    np.testing.assert_array_equal(a.vel_ned, b.vel_ned)
    for cov_t, t_grid, vel, da in ((a.cov_t, a.t, a.vel_ned, b.cov_nav - a.cov_nav),
                                   (a.smoothed.cov_t, a.smoothed.t, a.smoothed.vel_ned,
                                    b.smoothed.cov_nav - a.smoothed.cov_nav)):
        v = vel[np.clip(np.searchsorted(t_grid, cov_t), 0, t_grid.size - 1)]
        s2 = (0.2 * DEG) ** 2
        # δv = φ × v = J φ with J = −[v×]
        J = np.zeros((v.shape[0], 3, 3))
        J[:, 0, 1], J[:, 0, 2], J[:, 1, 2] = v[:, 2], -v[:, 1], v[:, 0]
        J -= np.transpose(J, (0, 2, 1))
        np.testing.assert_allclose(da[:, 3:6, 3:6], s2 * J @ np.transpose(J, (0, 2, 1)), rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(da[:, 3:6, 6:9], s2 * J, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(da[:, 6:9, 6:9], np.broadcast_to(s2 * np.eye(3), (v.shape[0], 3, 3)), atol=1e-15)
        assert np.abs(da[:, :3]).max() == 0
