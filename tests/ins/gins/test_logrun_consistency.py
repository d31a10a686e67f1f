"""GNSS/INS on a robot's log: the innovations of every aid are consistent over seeded drives (issue 24).

Each drive is the simulated robot (:func:`~imunav.sim.robot_log.simulate_robot_log`, 400 m of loops) with a truth
that follows the filter's model: IMU errors drawn from ``GinsConfig.from_preset("consumer_mems")``
(:func:`~imunav.ins.gins.truth.matched_errors`), wheel slip and body bounce of σ 0.05 m/s (the NHC's σ) and an
odometer noise of 0.05 m/s (its σ floor); written as a ROS 1 bag and run by ``imunav gins run``'s library
function with the antenna's lever arm.  The 30-drive NEES and the preset-IMU figures are in
``benchmarks/bench_gins_robot_consistency.py``.

The NIS bands are three standard errors of the mean of 8 drives, from the spread of the per-drive means over 100
drives (``bench_gins_robot_consistency.py --drives 100 --first-seed 500``: 0.022 for GNSS, 0.032 for the odometer,
0.065 for the NHC, whose drives differ most: the slip's realised variance over a drive's ~450 NHC epochs scatters
by ±7 %, and a drive whose levelling took a large accelerometer bias for a 5° tilt, as 302 and 307 here, meets
NHC innovations of NIS up to 30 in its first turns); the χ² band of the pooled updates (±1 % for 10⁴ of them)
ignores both.  The NHC's mean NIS sat at 0.87 while rest was decided on each noisy odometer sample: a standing robot
declared moving gave the NHC measurements of a slip that was not there.  A σ 1.5 times off moves a mean NIS by a
factor 2.25 or 0.44, far outside every band.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import chi2

from imunav.ins.gins import GinsConfig
from imunav.ins.gins.layout import LAY
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.truth import matched_errors, navigation_errors, nees_blocks
from imunav.io.navlog import read_nav_sources
from imunav.rotation import quat_multiply
from imunav.sim.robot_log import simulate_robot_log, write_robot_log

DRIVES = 8
#: aid -> (degrees of freedom, spread of the per-drive mean NIS per degree of freedom over 100 drives)
_SPREAD = {"gnss_position": (3, 0.022), "odometer": (1, 0.032), "nhc": (2, 0.065)}
#: aid -> (degrees of freedom, band of the mean NIS per degree of freedom over the drives: 3 standard errors)
AIDS = {a: (dof, (1 - 3 * sd / np.sqrt(DRIVES), 1 + 3 * sd / np.sqrt(DRIVES))) for a, (dof, sd) in _SPREAD.items()}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = []
    cfg = GinsConfig.from_preset("consumer_mems")
    for seed in range(300, 300 + DRIVES):
        model = matched_errors(cfg, np.random.default_rng(seed)).model
        log = simulate_robot_log(seed, imu_model=model, slip_std=(0.05, 0.05),
                                 odometer_noise_std=0.05)
        d = tmp_path_factory.mktemp(f"drive{seed}")
        write_robot_log(log, d, formats=("ros1",))
        # the truth follows the filter's model: no accelerometer misalignment, so none in the attitude σ either
        run = run_log(read_nav_sources(d / "robot.bag"), LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3),
                                                                       overrides={"accel_misalignment_std": 0.0}))
        out.append((log, run))
    return out


def test_nis_of_gnss_odometer_and_nhc_in_their_bands(runs):
    """Mean NIS / dof of the accepted GNSS position, odometer and NHC updates over the drives in their bands."""
    for aid, (dof, (lo, hi)) in AIDS.items():
        x = np.concatenate([(r.result.aids[aid].nis / dof)[r.result.aids[aid].accepted.astype(bool)]
                            for _, r in runs])
        m = float(x.mean())
        print(f"{aid}: mean NIS/dof {m:.3f} over {x.size} updates")
        assert x.size > 1000 and lo <= m <= hi, (aid, m, (lo, hi))


def test_nees_of_position_velocity_and_attitude_in_the_chi2_band(runs):
    """The NEES of the IMU's position, velocity and attitude (each 3 dof, its own 3×3 block of ``cov_nav``) against
    the truth every 10 s from 10 s after the start, averaged over the drives and the epochs, inside the two-sided
    95 % band of χ²(3R)/R for R drives (one epoch's mean; the epochs' average scatters less).  A σ 1.5 times off
    multiplies the NEES by 2.25 or 0.44: 6.8 or 1.3 against a band of [1.6, 4.9] for 8 drives.  The attitude's
    was 4.7 (30 drives, after 60 s) before the NHC was spaced 1 s apart with GNSS and the initial heading's σ
    counted the dead reckoning's drift (``logrun.NHC_INTERVAL``, ``logrun._heading_fit_std``)."""
    R = len(runs)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * R) / R
    nees = []
    for log, run in runs:
        r, tr = run.result, log.truth.trajectory
        q_imu = quat_multiply(tr.q_nb, np.broadcast_to(log.truth.q_base_imu, (tr.t.size, 4)))
        k = np.searchsorted(r.cov_t, np.arange(tr.t[0] + 10.0, tr.t[-1], 10.0), side="right") - 1
        it, ir = np.searchsorted(tr.t, r.cov_t[k] - 1e-9), np.searchsorted(r.t, r.cov_t[k] - 1e-9)
        e = navigation_errors(SimpleNamespace(pos_lla=tr.pos_lla[it], vel_ned=tr.vel_ned[it], q_nb=q_imu[it]),
                              np.arange(k.size), SimpleNamespace(lla=r.lla[ir], vel_ned=r.vel_ned[ir], q_nb=r.q_nb[ir]))
        nees.append(nees_blocks(e, r.cov_nav[k]).mean(axis=1))
    m = np.mean(nees, axis=0)
    print(f"mean NEES position / velocity / attitude {m.round(3)} over {R} drives, band [{lo:.2f}, {hi:.2f}]")
    assert np.all((lo <= m) & (m <= hi)), (m, (lo, hi))


def test_latency_and_mounting_inside_their_3_sigma(runs):
    """The GNSS latency (truth 0.15 s) and the mounting (each axis) inside the reported 3σ on every drive."""
    for log, run in runs:
        r = run.result
        i = int(run.state_layout()[LAY.gnss_delay])
        sd = float(np.sqrt(r.cov_diag[-1, i]))
        assert abs(float(r.gnss_delay[-1]) - log.truth.gnss_latency_s) < 3 * sd, (float(r.gnss_delay[-1]), sd)
        e, s = run.mounting_euler()
        err = np.degrees(e) - np.asarray(log.truth.mounting_euler_deg)
        err = np.remainder(err + 180.0, 360.0) - 180.0
        assert np.all(np.abs(err) < 3 * np.degrees(s)), (err, np.degrees(s))


def test_bias_model_is_checked_and_changes_only_the_bias_dynamics():
    """An unknown bias model is refused, naming the choices; the constant-and-Gauss-Markov model keeps the bias
    states' variance from decaying (no measurement: the gyro bias sigma stays at its initial value instead of
    falling to the stationary one)."""
    from imunav.errors import InvalidInputError
    from imunav.ins.gins import GinsFilter
    from imunav.timeseries import ImuData

    with pytest.raises(InvalidInputError, match="constant_and_gauss_markov"):
        GinsConfig.from_preset("consumer_mems", bias_model="constant")
    n = 3001  # 300 s at 10 Hz, three correlation times of the preset's 100 s
    imu = ImuData(np.arange(n) / 10.0, np.zeros((n, 3)), np.tile([0.0, 0.0, -9.80], (n, 1)))
    sd = {}
    for model in ("gauss_markov", "constant_and_gauss_markov"):
        cfg = GinsConfig.from_preset("consumer_mems", bias_model=model)
        res = GinsFilter(cfg).run(imu, None, lla0=np.array([0.8, 0.2, 100.0]), vel0=np.zeros(3),
                                  q0=np.array([1.0, 0.0, 0.0, 0.0]))
        sd[model] = np.sqrt(res.cov_diag[-1, 9:12])
    init = GinsConfig.from_preset("consumer_mems").init_gyro_bias_std
    assert np.all(sd["constant_and_gauss_markov"] >= init * (1 - 1e-9))
    assert np.all(sd["gauss_markov"] < 0.2 * init)
