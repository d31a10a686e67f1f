"""GNSS dual-antenna heading aid: NIS and attitude NEES in their bands over seeded drives, the heading it makes
observable on a straight drive, and its refusals."""

from __future__ import annotations

import numpy as np
import pytest
from gins_mc import LEVER, matched_run, mean_band

from imunav.errors import InvalidInputError
from imunav.ins.gins import GinsConfig
from imunav.ins.gins.truth import navigation_errors, nees_blocks
from imunav.io.gnss_heading import DualAntennaData
from imunav.sim import ideal_imu
from imunav.sim.gnss import simulate_dual_antenna
from imunav.sim.vehicle import speed_change, stop, straight, turn, vehicle_trajectory
from imunav.units import DEG

FS = 20.0
RUNS = 10
BASELINE = np.array([1.5, -0.2, 0.1])  # secondary antenna from the primary, body FRD, m
SIGMA = np.radians([0.3, 0.8])  # heading, pitch


def _config(**kw):
    return GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, init_pos_std=1.0, init_vel_std=0.1,
                                  init_att_std=np.radians([0.5, 0.5, 5.0]), dual_antenna_baseline=BASELINE, **kw)


@pytest.fixture(scope="module")
def truth():
    drive = [stop(5.0), speed_change(10.0, 8.0), turn(90.0, 10.0), straight(15.0), turn(-120.0, 12.0),
             speed_change(15.0, 8.0), straight(20.0), turn(60.0, 8.0), straight(10.0)]
    tr = vehicle_trajectory(drive, fs=FS, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    return tr, ideal_imu(tr)


def test_dual_antenna_nis_and_attitude_nees_are_in_their_bands(truth):
    """Over RUNS seeded drives (IMU errors and initial state drawn from the filter's own model, the baseline's
    heading and pitch with white noise of the reported σ): the mean NIS of the aid is χ²(2) and the mean attitude
    NEES χ²(3), epochs 3 s apart pooled over the runs, inside their two-sided bands (Bonferroni over the 2 checks; each band narrower than 1.5²)."""
    tr, _ = truth
    cfg = _config()
    nis, nees = [], []
    for seed in range(RUNS):
        dual = simulate_dual_antenna(tr, BASELINE, heading_std=SIGMA[0], pitch_std=SIGMA[1], rng=seed + 500)
        res, _ = matched_run(truth, cfg, seed, dual_antenna=dual)
        rec = res.aids["dual_antenna"]
        assert rec.t.size == dual.t.size and rec.accepted.all() and np.all(rec.dof == 2)
        nis.append(rec.nis)
        keep = np.searchsorted(res.cov_t, np.arange(3.0, tr.t[-1], 3.0), side="right") - 1
        e = navigation_errors(tr, np.searchsorted(tr.t, res.cov_t[keep] - 1e-9), res)
        nees.append(nees_blocks(e, res.cov_nav[keep])[2])
    nis, nees = np.concatenate(nis), np.concatenate(nees)
    lo, hi = mean_band(2 * nis.size, nis.size, checks=2)
    print(f"dual-antenna NIS mean {nis.mean():.3f} (band {lo:.3f}-{hi:.3f}, {nis.size} epochs)")
    assert lo < nis.mean() < hi
    # epochs 3 s apart: the attitude error decorrelates within a few of the aid's 0.2 s epochs
    lo, hi = mean_band(3 * nees.size, nees.size, checks=2)
    print(f"attitude NEES mean {nees.mean():.3f} (band {lo:.3f}-{hi:.3f}, {nees.size} run-epochs)")
    assert lo < nees.mean() < hi


def test_dual_antenna_makes_the_heading_observable_on_a_straight_drive():
    """A straight drive at constant speed leaves the heading unobservable from GNSS alone (its σ stays near its
    initial 5°); with the dual-antenna aid it converges to the order of the measurement σ averaged over the
    epochs, and the error stays inside 3σ."""
    tr = vehicle_trajectory([speed_change(10.0, 5.0), straight(60.0)], fs=FS,
                            origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    truth = (tr, ideal_imu(tr))
    cfg = _config()
    plain, _ = matched_run(truth, cfg, 3)
    dual = simulate_dual_antenna(tr, BASELINE, heading_std=SIGMA[0], pitch_std=SIGMA[1], rng=7)
    aided, _ = matched_run(truth, cfg, 3, dual_antenna=dual)
    sd_plain = np.degrees(np.sqrt(plain.cov_nav[-1, 8, 8]))
    sd_aided = np.degrees(np.sqrt(aided.cov_nav[-1, 8, 8]))
    err = np.degrees(navigation_errors(tr, [tr.n - 1], aided)[0, 8])
    print(f"heading sigma without / with the aid: {sd_plain:.3f} / {sd_aided:.3f} deg, error {err:.3f} deg")
    assert sd_plain > 1.0 and sd_aided < 0.1 and abs(err) < 3 * sd_aided


def test_dual_antenna_refusals():
    with pytest.raises(InvalidInputError, match="dual_antenna_baseline"):
        DualAntennaData(np.arange(3.0), np.zeros(3), np.zeros(3), 0.01, 0.01).measurements(None)
    with pytest.raises(InvalidInputError, match="degrees"):
        DualAntennaData(np.arange(3.0), np.zeros(3), np.full(3, 5.0), 0.01, 0.01)
    with pytest.raises(InvalidInputError, match="> 0"):
        DualAntennaData(np.arange(3.0), np.zeros(3), np.zeros(3), 0.0, 0.01)
    with pytest.raises(InvalidInputError, match="increasing"):
        DualAntennaData(np.array([0.0, 2.0, 1.0]), np.zeros(3), np.zeros(3), 0.01, 0.01)
