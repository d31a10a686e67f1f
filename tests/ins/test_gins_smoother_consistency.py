"""RTS smoother of the GNSS/INS filter: its covariance is calibrated over seeded Monte Carlo runs.

The IMU errors follow the filter's model (as in ``test_gins_consistency``: white noise of the configured ARW /
VRW, biases a random constant plus a Gauss-Markov process of the configured sigma, scale factors random
constants), GNSS errors are white with the reported sigma, the initial state is drawn from the initial
covariance, and a 40 s GNSS outage makes the backward pass matter.  Then the smoothed normalised estimation
error squared of position, velocity and attitude is chi^2(3) at every epoch (Bar-Shalom, Li & Kirubarajan 2001,
section 5.4; the RTS covariance: Rauch, Tung & Striebel 1965).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from imunav import earth
from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.rotation import quat_conjugate, quat_from_rotvec, quat_multiply, rotvec_from_quat
from imunav.sim import apply_errors, ideal_imu
from imunav.sim.error_model import GaussMarkov, ImuErrorModel, TriadErrors, scale_misalignment_matrix
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import speed_change, stop, straight, turn, vehicle_trajectory
from imunav.units import DEG

RUNS, FS = 40, 20.0
LEVER = np.array([0.5, -0.3, -1.2])
OUTAGE = (50.0, 40.0)  # s from the start, length s


@pytest.fixture(scope="module")
def truth():
    drive = [stop(5.0), speed_change(12.0, 10.0), turn(90.0, 10.0), straight(15.0), turn(-60.0, 8.0),
             speed_change(18.0, 10.0), turn(-90.0, 12.0), straight(30.0), speed_change(8.0, 10.0), turn(45.0, 8.0),
             straight(12.0)]
    tr = vehicle_trajectory(drive, fs=FS, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    return tr, ideal_imu(tr)


def _triad(white, gm_sd, init_sd, scale_sd, tc, rng):
    const = np.sqrt(np.maximum(init_sd**2 - gm_sd**2, 0.0)) * rng.standard_normal(3)
    return TriadErrors(bias=const, scale_misalignment=scale_misalignment_matrix(scale_sd * rng.standard_normal(3)),
                       noise_density=white, bias_instability=GaussMarkov(gm_sd, tc))


def _smoothed_nees(truth, name):
    """(runs, 3 blocks, epochs) smoothed NEES of position, velocity and attitude, every 5 s."""
    tr, ideal = truth
    cfg = GinsConfig.from_preset(name, lever_arm=LEVER, init_pos_std=1.0, init_vel_std=0.1,
                                 init_att_std=np.radians([0.05, 0.05, 0.5]))
    out = []
    for seed in range(RUNS):
        rng = np.random.default_rng(seed)
        model = ImuErrorModel(
            gyro=_triad(cfg.arw, cfg.gyro_bias_std, cfg.init_gyro_bias_std, cfg.init_gyro_scale_std, cfg.corr_time, rng),
            accel=_triad(cfg.vrw, cfg.accel_bias_std, cfg.init_accel_bias_std, cfg.init_accel_scale_std,
                         cfg.corr_time, rng), name="matched")
        imu = apply_errors(ideal, model, rng=seed)
        gnss = simulate_gnss(tr, pos_noise=(0.5, 0.5, 1.0), vel_noise=(0.05, 0.05, 0.1), lever_arm=LEVER,
                             rng=seed + 10_000, outages=[(tr.t[0] + OUTAGE[0], OUTAGE[1])])
        dr = cfg.init_pos_std * rng.standard_normal(3)
        lat, h = tr.pos_lla[0, 0], tr.pos_lla[0, 2]
        rn, re = earth.radii(lat)
        lla0 = tr.pos_lla[0] - [dr[0] / (rn + h), dr[1] / ((re + h) * np.cos(lat)), -dr[2]]
        v0 = tr.vel_ned[0] - cfg.init_vel_std * rng.standard_normal(3)
        q0 = quat_multiply(quat_from_rotvec(-cfg.init_att_std * rng.standard_normal(3)), tr.q_nb[0])
        s = GinsFilter(cfg).run(imu, gnss, lla0=lla0, vel0=v0, q0=q0, smoother=True).smoothed
        at = tr.t[0] + np.arange(5.0, tr.duration + 1e-9, 5.0)
        keep = np.searchsorted(s.cov_t, at - 1e-9)  # the smoother epoch at or just after
        keep = keep[keep < s.cov_t.size]
        idx = np.searchsorted(tr.t, s.cov_t[keep] - 1e-9)
        ref = tr.pos_lla[idx]
        rn, re = earth.radii(ref[:, 0])
        est = s.lla[idx]
        e = np.hstack([np.column_stack([(ref[:, 0] - est[:, 0]) * (rn + ref[:, 2]),
                                        (ref[:, 1] - est[:, 1]) * (re + ref[:, 2]) * np.cos(ref[:, 0]),
                                        -(ref[:, 2] - est[:, 2])]),
                       tr.vel_ned[idx] - s.vel_ned[idx],
                       rotvec_from_quat(quat_multiply(tr.q_nb[idx], quat_conjugate(s.q_nb[idx])))])
        P = s.cov_nav[keep]
        out.append([np.einsum("ni,nij,nj->n", e[:, b], np.linalg.inv(P[:, b, b]), e[:, b])
                    for b in (slice(0, 3), slice(3, 6), slice(6, 9))])
    return np.array(out)


@pytest.mark.parametrize("name", ["navigation_a15", "mems_adis16465"])
def test_smoothed_nees_in_the_95_band(truth, name):
    """Per preset over RUNS runs: the mean smoothed NEES of position, velocity and attitude (over the runs and
    epochs 5 s apart, the outage included) lies in the two-sided 95 % band of chi^2(3 RUNS) / RUNS, the band of
    one epoch's mean (the average of correlated means spreads at most as much); a covariance 1.5^2 times off
    either way leaves it."""
    nees = _smoothed_nees(truth, name)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * RUNS) / RUNS
    for j, block in enumerate(("position", "velocity", "attitude")):
        m = float(nees[:, j].mean())
        assert lo <= m <= hi, (name, block, m, (lo, hi))
        assert not lo <= m / 1.5**2 <= hi and not lo <= m * 1.5**2 <= hi, (name, block, m)
