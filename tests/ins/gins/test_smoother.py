"""RTS smoother of the GNSS/INS filter: its covariance is calibrated over seeded Monte Carlo runs.

The IMU errors and the initial state follow the filter's model (:mod:`imunav.ins.gins.truth`), GNSS errors are
white with the reported sigma, and a 40 s GNSS outage makes the backward pass matter.  Then the smoothed normalised estimation
error squared of position, velocity and attitude is chi^2(3) at every epoch (Bar-Shalom, Li & Kirubarajan 2001,
section 5.4; the RTS covariance: Rauch, Tung & Striebel 1965).
"""

from __future__ import annotations

import numpy as np
import pytest
from gins_mc import LEVER, matched_run, mean_band

from imunav.ins.gins import GinsConfig
from imunav.ins.gins.truth import navigation_errors, nees_blocks
from imunav.sim import ideal_imu
from imunav.sim.vehicle import speed_change, stop, straight, turn, vehicle_trajectory
from imunav.units import DEG

RUNS, FS = 40, 20.0
OUTAGE = (50.0, 40.0)  # s from the start, length s


@pytest.fixture(scope="module")
def truth():
    drive = [stop(5.0), speed_change(12.0, 10.0), turn(90.0, 10.0), straight(15.0), turn(-60.0, 8.0),
             speed_change(18.0, 10.0), turn(-90.0, 12.0), straight(30.0), speed_change(8.0, 10.0), turn(45.0, 8.0),
             straight(12.0)]
    tr = vehicle_trajectory(drive, fs=FS, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    return tr, ideal_imu(tr)


def _smoothed_nees(truth, name):
    """(runs, 3 blocks, epochs) smoothed NEES of position, velocity and attitude, every 5 s."""
    tr, _ = truth
    cfg = GinsConfig.from_preset(name, lever_arm=LEVER, init_pos_std=1.0, init_vel_std=0.1,
                                 init_att_std=np.radians([0.05, 0.05, 0.5]))
    out = []
    for seed in range(RUNS):
        res, _ = matched_run(truth, cfg, seed, outages=[(tr.t[0] + OUTAGE[0], OUTAGE[1])], smoother=True)
        s = res.smoothed
        at = tr.t[0] + np.arange(5.0, tr.duration + 1e-9, 5.0)
        keep = np.searchsorted(s.cov_t, at - 1e-9)  # the smoother epoch at or just after
        keep = keep[keep < s.cov_t.size]
        idx = np.searchsorted(tr.t, s.cov_t[keep] - 1e-9)
        out.append(nees_blocks(navigation_errors(tr, idx, s), s.cov_nav[keep]))
    return np.array(out)


@pytest.mark.parametrize("name", ["navigation_a15", "mems_adis16465"])
def test_smoothed_nees_in_the_95_band(truth, name):
    """Per preset over RUNS runs: the mean smoothed NEES of position, velocity and attitude (over the runs and
    epochs 5 s apart, the outage included) lies in the two-sided band of chi^2(3 RUNS) / RUNS at 5 % over the six
    checks (Bonferroni), the band of one epoch's mean (the average of correlated means spreads at most as much);
    a covariance 1.5^2 times off either way leaves it."""
    nees = _smoothed_nees(truth, name)
    lo, hi = mean_band(3 * RUNS, RUNS, checks=6)
    for j, block in enumerate(("position", "velocity", "attitude")):
        m = float(nees[:, j].mean())
        assert lo <= m <= hi, (name, block, m, (lo, hi))


def test_rts_smooth_matches_the_interpolation_of_the_whole_error_state():
    """The smoothed trajectory interpolates only the navigation block of the smoothed error (speed: issue 33): it is
    the same, bit for bit, as interpolating the whole error state and then taking that block, and its gains, solved
    a block of epochs at a time, are those solved one epoch at a time (the textbook form, written out here), on
    random records with 12 states and epochs between the IMU samples."""
    from imunav.earth import ned_to_dlla
    from imunav.ins.gins.smoother import rts_smooth
    from imunav.rotation import quat_from_rotvec, quat_multiply, quat_normalize

    rng = np.random.default_rng(3)
    N, M, n = 4001, 601, 12  # more epochs than one block of gains
    t = np.arange(N) * 0.01
    rec_t = np.r_[t[0], np.sort(rng.choice(t[1:-1], M - 2, replace=False)), t[-1]]
    lla = np.column_stack([0.5 + 1e-6 * rng.standard_normal(N), 1.9 + 1e-6 * rng.standard_normal(N),
                           20.0 + rng.standard_normal(N)])
    vel, q = rng.standard_normal((N, 3)), quat_normalize(rng.standard_normal((N, 4)))
    phi = np.eye(n) + 0.01 * rng.standard_normal((M, n, n))
    B = rng.standard_normal((M, n, n))
    ppost = B @ B.transpose(0, 2, 1) * 1e-2 + np.eye(n) * 1e-3
    ppri = ppost + np.eye(n) * 1e-3
    inj, state = 1e-3 * rng.standard_normal((M, n)), np.zeros((M, 10))
    s = rts_smooth(t, lla, vel, q, rec_t, phi, ppri, ppost, inj, state)
    # the reference: the same backward pass, then every column interpolated
    ds, Ps, Pn = np.zeros((M, n)), np.empty((M, 9, 9)), ppost[M - 1].copy()
    Ps[M - 1] = Pn[:9, :9]
    for r in range(M - 2, -1, -1):
        A = np.linalg.solve(ppri[r + 1].T, (ppost[r] @ phi[r + 1].T).T).T
        ds[r] = A @ (ds[r + 1] + inj[r + 1])
        Pn = ppost[r] + A @ (Pn - ppri[r + 1]) @ A.T
        Ps[r] = Pn[:9, :9]
    before = ds + inj
    i = np.clip(np.searchsorted(rec_t, t, side="right") - 1, 0, M - 1)
    j = np.minimum(i + 1, M - 1)
    span = rec_t[j] - rec_t[i]
    w = np.where(span > 0, (t - rec_t[i]) / np.where(span > 0, span, 1.0), 0.0)[:, None]
    corr = (1 - w) * ds[i] + w * before[j]
    assert np.array_equal(s.lla, lla + ned_to_dlla(corr[:, 0:3], lla))
    assert np.array_equal(s.vel_ned, vel + corr[:, 3:6])
    assert np.array_equal(s.q_nb, quat_normalize(quat_multiply(quat_from_rotvec(corr[:, 6:9]), q)))
    assert np.array_equal(s.cov_nav, Ps)
    assert np.abs(corr[:, :9]).max() > 1e-4  # the corrections are not all zero: the test can fail
