"""GNSS/INS filter: statistical consistency over seeded Monte Carlo runs (issue 15 acceptance).

The simulated IMU errors follow the filter's model exactly (white noise, first-order Gauss-Markov biases started
stationary, constant scale factors drawn from the filter's prior), the GNSS errors are white with the reported
sigma, and the initial state is drawn from the filter's initial covariance: then the normalised estimation error
squared (NEES) of position, velocity and attitude is chi^2(3) per run, its mean over R runs chi^2(3R)/R, and the
NIS of each aiding model chi^2(3) (Bar-Shalom, Li & Kirubarajan 2001, section 5.4).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import chi2

from imunav import earth
from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.io.gnss import GnssData
from imunav.rotation import quat_conjugate, quat_from_rotvec, quat_multiply, rotvec_from_quat
from imunav.sim import apply_errors, ideal_imu
from imunav.sim.error_model import GaussMarkov, ImuErrorModel, TriadErrors, scale_misalignment_matrix
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, vehicle_trajectory
from imunav.units import DEG, HOUR

RUNS = 50
FS = 50.0
LEVER = np.array([0.5, -0.3, -1.2])
ARW, VRW = 0.05 * DEG / 60, 0.05 / 60  # 0.05 deg/sqrt(h), 0.05 m/s/sqrt(h)
GB, AB, T = 1.0 * DEG / HOUR, 5e-3, 3600.0  # 1 deg/h, 0.5 mg, 1 h
SG = SA = 300e-6
POS_SD, VEL_SD = np.array([0.5, 0.5, 1.0]), np.array([0.05, 0.05, 0.1])
CFG = GinsConfig(arw=ARW, vrw=VRW, gyro_bias_std=GB, accel_bias_std=AB, gyro_scale_std=SG, accel_scale_std=SA,
                 corr_time=T, init_pos_std=1.0, init_vel_std=0.1, init_att_std=np.radians([0.05, 0.05, 0.5]),
                 lever_arm=LEVER)


@pytest.fixture(scope="module")
def truth():
    tr = vehicle_trajectory(demo_drive(300), fs=FS, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    return tr, ideal_imu(tr)


def _run(truth, seed):
    tr, ideal = truth
    rng = np.random.default_rng(seed)
    sg, sa = SG * rng.standard_normal(3), SA * rng.standard_normal(3)
    model = ImuErrorModel(
        gyro=TriadErrors(scale_misalignment=scale_misalignment_matrix(sg), noise_density=ARW,
                         bias_instability=GaussMarkov(GB, T)),
        accel=TriadErrors(scale_misalignment=scale_misalignment_matrix(sa), noise_density=VRW,
                          bias_instability=GaussMarkov(AB, T)),
        name="gm-consistency")
    imu, et = apply_errors(ideal, model, rng=seed, return_truth=True)
    gnss = simulate_gnss(tr, pos_noise=POS_SD, vel_noise=VEL_SD, lever_arm=LEVER, rng=seed + 10_000)
    # initial state drawn from the filter's prior
    dr = CFG.init_pos_std * rng.standard_normal(3)
    rn, re = earth.radii(tr.pos_lla[0, 0])
    lla0 = tr.pos_lla[0] - [dr[0] / (rn + tr.pos_lla[0, 2]), dr[1] / ((re + tr.pos_lla[0, 2]) * np.cos(tr.pos_lla[0, 0])),
                            -dr[2]]
    v0 = tr.vel_ned[0] - CFG.init_vel_std * rng.standard_normal(3)
    q0 = quat_multiply(quat_from_rotvec(-CFG.init_att_std * rng.standard_normal(3)), tr.q_nb[0])
    res = GinsFilter(CFG).run(imu, gnss, lla0=lla0, vel0=v0, q0=q0)
    return res, et, (sg, sa)


def _nav_errors(tr, res, idx):
    """true - estimate: NED position (m), velocity, navigation-frame attitude error phi (C = exp(phi) C_hat)."""
    ref, est = tr.pos_lla[idx], res.lla[idx]
    rn, re = earth.radii(ref[:, 0])
    dr = np.column_stack([(ref[:, 0] - est[:, 0]) * (rn + ref[:, 2]),
                          (ref[:, 1] - est[:, 1]) * (re + ref[:, 2]) * np.cos(ref[:, 0]), -(ref[:, 2] - est[:, 2])])
    dv = tr.vel_ned[idx] - res.vel_ned[idx]
    phi = rotvec_from_quat(quat_multiply(tr.q_nb[idx], quat_conjugate(res.q_nb[idx])))
    return np.hstack([dr, dv, phi])


@pytest.fixture(scope="module")
def monte_carlo(truth):
    tr, _ = truth
    nees = []
    nis = []
    bias_z = []
    for seed in range(RUNS):
        res, et, (sg, sa) = _run(truth, seed)
        keep = slice(10, None, 10)  # one record a second, after the first second
        ct = res.cov_t[keep]
        idx = np.searchsorted(tr.t, ct)
        e = _nav_errors(tr, res, idx)
        P = res.cov_nav[keep]
        row = []
        for blk in (slice(0, 3), slice(3, 6), slice(6, 9)):
            Pi = np.linalg.inv(P[:, blk, blk])
            row.append(np.einsum("ni,nij,nj->n", e[:, blk], Pi, e[:, blk]))
        nees.append(row)
        nis.append(res.nis[res.accepted[:, 0]])
        # IMU errors at the end: true - estimate against 3 sigma
        k = -1
        true = np.hstack([et.gyro.bias[k], et.accel.bias[k], sg, sa])
        est = np.hstack([res.gyro_bias[k], res.accel_bias[k], res.gyro_scale[k], res.accel_scale[k]])
        bias_z.append((true - est) / np.sqrt(res.cov_diag[-1, 9:21]))
    return np.array(nees), np.vstack(nis), np.array(bias_z)


def test_nees_of_position_velocity_attitude_in_the_95_band(monte_carlo):
    """Mean NEES over the runs at each second lies in the two-sided 95 % chi^2(3R)/R band for >= 90 % of the
    epochs (about 5 % outside is expected by construction; epochs are correlated, so the margin is generous),
    and its average over the drive lies within +-10 % of 3.  The bounds are tight enough to catch a filter
    whose reported sigma is 1.5 times too large: the same statistic on NEES / 1.5^2 fails."""
    nees, _, _ = monte_carlo
    lo, hi = chi2.ppf([0.025, 0.975], 3 * RUNS) / RUNS
    anees = nees.mean(axis=0)  # (3 blocks, epochs)
    for name, a in zip(("position", "velocity", "attitude"), anees):
        inside = np.mean((a >= lo) & (a <= hi))
        assert inside >= 0.9, (name, inside, a.mean())
        assert 2.7 <= a.mean() <= 3.3, (name, a.mean())
        wide = a / 1.5**2  # the covariance reported 1.5^2 times too large
        assert not (np.mean((wide >= lo) & (wide <= hi)) >= 0.9 and 2.7 <= wide.mean() <= 3.3), name


def test_nis_of_gnss_position_and_velocity(monte_carlo):
    """Every accepted GNSS epoch's NIS is chi^2(3): the mean over all epochs of all runs is within 5 standard
    errors of 3 (sd of one NIS sqrt(6); epochs close to independent)."""
    _, nis, _ = monte_carlo
    n = nis.shape[0]
    for j, name in enumerate(("position", "velocity")):
        m = nis[:, j].mean()
        assert abs(m - 3.0) < 5 * np.sqrt(6.0 / n), (name, m, n)


def test_biases_and_scale_factors_inside_3_sigma(monte_carlo):
    """At the end of each run the gyro / accel biases and scale factors are inside 3 sigma of the truth:
    >= 97 % of all the (runs x 12) normalised errors (99.7 % expected for a Gaussian), and their RMS near 1:
    below 1.5 per state, and pooled over all within [0.8, 1.25] (standard error 1/sqrt(2 x 600) = 0.03; the
    margin allows for the states' correlation), which a sigma reported 1.5 times too large (RMS 0.67) fails."""
    _, _, z = monte_carlo
    assert np.mean(np.abs(z) <= 3) >= 0.97, np.mean(np.abs(z) <= 3)
    rms = np.sqrt(np.mean(z**2, axis=0))
    assert np.all(rms < 1.5), rms
    pooled = float(np.sqrt(np.mean(z**2)))
    assert 0.8 <= pooled <= 1.25, pooled
    assert not 0.8 <= pooled / 1.5 <= 1.25


def test_the_nis_check_catches_a_model_error(truth):
    """The same statistics fail when the model is wrong: fixes that claim half their real sigma give a
    position NIS near 4 x 3 (the filter's own error adds a little), far outside 5 standard errors of 3."""
    tr, ideal = truth
    res, _, _ = _run(truth, 0)
    assert abs(np.nanmean(res.nis[:, 0]) - 3) < 1.0
    imu = apply_errors(ideal, ImuErrorModel(gyro=TriadErrors(noise_density=ARW), accel=TriadErrors(noise_density=VRW)),
                       rng=1)
    g = simulate_gnss(tr, pos_noise=POS_SD, vel_noise=VEL_SD, lever_arm=LEVER, rng=2)
    optimistic = GnssData(g.t, g.lla, g.pos_std / 2, g.vel_ned, g.vel_std, g.meta)
    bad = GinsFilter(replace(CFG, gate_alpha=0.0)).run(imu, optimistic, lla0=tr.pos_lla[0], vel0=tr.vel_ned[0],
                                                       q0=tr.q_nb[0])
    assert np.nanmean(bad.nis[:, 0]) > 6.0
