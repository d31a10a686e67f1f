"""Shared pieces of the GNSS/INS Monte Carlo consistency tests (tests/ins/gins/test_*.py).

``matched_run`` draws one run whose truth follows the filter's own model (:mod:`imunav.ins.gins.truth`), and
``mean_band`` gives the two-sided band of a mean of χ² values at a level corrected for the number of checks a
test makes on its fixed seeds (Bonferroni: the test fails by chance at most 5 % of the time over all its checks),
after asserting that the band is narrow enough for a covariance 1.5² times off either way to leave it.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from imunav.ins.gins import GinsFilter
from imunav.ins.gins.truth import initial_state_draw, matched_errors
from imunav.sim import apply_errors
from imunav.sim.gnss import simulate_gnss

LEVER = np.array([0.5, -0.3, -1.2])
POS_SD, VEL_SD = np.array([0.5, 0.5, 1.0]), np.array([0.05, 0.05, 0.1])


def matched_run(truth, cfg, seed, *, outages=None, smoother=False, **aids):
    """One seeded run on ``truth`` = (trajectory, ideal IMU): IMU errors and the initial state drawn from the model
    of ``cfg``, GNSS at 1 Hz with white POS_SD / VEL_SD noise and the LEVER arm.  Returns the result and the true
    final IMU errors (gyro bias, accel bias, gyro scale, accel scale)."""
    tr, ideal = truth
    rng = np.random.default_rng(seed)
    drawn = matched_errors(cfg, rng)
    imu, et = apply_errors(ideal, drawn.model, rng=seed, return_truth=True)
    gnss = simulate_gnss(tr, pos_noise=POS_SD, vel_noise=VEL_SD, lever_arm=LEVER, rng=seed + 10_000,
                         **({} if outages is None else {"outages": outages}))
    lla0, v0, q0 = initial_state_draw(tr.pos_lla[0], tr.vel_ned[0], tr.q_nb[0], cfg, rng)
    res = GinsFilter(cfg).run(imu, gnss, lla0=lla0, vel0=v0, q0=q0, smoother=smoother, **aids)
    return res, np.hstack([et.gyro.bias[-1], et.accel.bias[-1], drawn.gyro_scale, drawn.accel_scale])


def mean_band(dof_total, n, checks=1):
    """Two-sided band of the mean of n values whose sum is χ²(dof_total), at the level 0.05 / checks; asserts
    that hi / lo < 1.5², so that a covariance reported 1.5² times too large or too small (the mean divided or
    multiplied by 2.25) cannot stay inside it."""
    a = 0.05 / checks
    lo, hi = chi2.ppf([a / 2, 1 - a / 2], dof_total) / n
    assert hi / lo < 1.5**2, ("the check cannot see a 1.5x sigma error", lo, hi)
    return lo, hi
