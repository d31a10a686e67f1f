"""Calibration of the covariance that :meth:`imunav.ins.ZuptFilter.run` reports (``ZuptResult.P`` / ``cov_diag``).

One gait trajectory is simulated without sensor errors (:func:`imunav.sim.gait.simulate_gait`);
each run adds what the filter's model assumes and nothing else: white noise of the
configured per-sample standard deviation on every accelerometer and gyro sample, an
initial attitude error drawn from ``init_att_std`` (the filter is started from the perturbed
quaternion through the public ``initial_quaternion``) and, with 15 states, constant
biases drawn from ``init_accel_bias_std`` / ``init_gyro_bias_std`` (bias random walks set to 0).
Over the runs

* the final-position NEES e^T P_pp^-1 e (full 3x3 block of ``ZuptResult.P``) must have
  its mean inside the 99 % chi^2(3 n) interval;
* the z-scores of position and velocity at mid-swing (``cov_diag``) must have an RMS
  inside the 99 % chi^2 interval for their number;
* with 15 states, the z-scores of the final accelerometer and gyro bias estimates too.

Each interval rejects a covariance wrong by 1.5^2 (sigma by 1.5) either way; set
IMUNAV_SIGMA_SCALE=1.5 or 0.6667 to see the tests fail.

What is left out, and why: the velocity *during a stance*.  The simulated foot is
exactly still there, while the ZUPT models its velocity as measured with noise
``zupt_noise_std``, so the stance velocity variance is an upper bound by design (the tests use
``zupt_noise_std`` = 0.1 mm/s so that this pessimism stays far below the swing uncertainty).

The attitude Jacobian of the velocity must be -[dv^n x] with the increment dv^n that the
nominal integration adds; it used C_{k-1} f_k dt, which at foot rotation rates differs by
~[omega dt x] f dt per sample, made the yaw look observable (its sigma fell from 0.5 to 0.29
deg over 20 strides on noise-free data) and gave a final-position NEES of 4 to 7 instead of 3.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _calibration import assert_nees_calibrated, assert_rms_calibrated, z_scores

from imunav.ins import ZuptConfig, ZuptFilter
from imunav.rotation import quat_from_rotvec, quat_multiply
from imunav.sim.gait import simulate_gait
from imunav.timeseries import ImuData

RUNS = 80
#: 800 Hz: the coning/sculling integration error of the noise-free gait is then below 0.15 sigma of every
#: checked quantity (at 200 Hz it reaches 2 sigma on the mid-swing vertical velocity and the biases)
FS = 800.0
#: the ZUPT noise: 0.1 mm/s (see the module docstring; with 1 mm/s the mid-swing z RMS of the 9-state
#: filter falls to 0.85, the pessimism of a noisy measurement model applied to a foot that is exactly still)
SIGMA_V = 1e-4


def _runs(states: int, seed: int):
    sim = simulate_gait(["walk", "run", "stairs"], 12, error_model=None, rng=seed, turn_deg=15.0, g=9.80665,
                        fs=FS)
    cfg = ZuptConfig(states=states, g=9.80665, accel_noise_std=0.1, gyro_noise_std=math.radians(0.6), zupt_noise_std=SIGMA_V,
                     init_att_std=math.radians(0.5), init_accel_bias_std=0.02, init_gyro_bias_std=math.radians(0.05),
                     accel_bias_random_walk=0.0, gyro_bias_random_walk=0.0, integration="coning")
    n = sim.imu.t.size
    # the middle sample of the middle swing (the foot at speed)
    edges = np.flatnonzero(np.diff(sim.stance.astype(np.int8)))
    starts, stops = edges[0::2] + 1, edges[1::2] + 1
    j = starts.size // 2
    k_mid = int((starts[j] + stops[j]) // 2)
    rng = np.random.default_rng(seed)
    nees, zp, zv, zba, zbg = [], [], [], [], []
    for _ in range(RUNS):
        ba = rng.normal(scale=cfg.init_accel_bias_std, size=3) if states == 15 else np.zeros(3)
        bg = rng.normal(scale=cfg.init_gyro_bias_std, size=3) if states == 15 else np.zeros(3)
        imu = ImuData(sim.imu.t, sim.ideal.gyro + bg + rng.normal(scale=cfg.gyro_noise_std, size=(n, 3)),
                      sim.ideal.accel + ba + rng.normal(scale=cfg.accel_noise_std, size=(n, 3)))
        dphi = rng.normal(scale=cfg.init_att_std, size=3)
        # C_true = exp([dphi x]) C_hat  =>  q_hat = q(-dphi) * q_true (nav-frame error)
        q0 = quat_multiply(quat_from_rotvec(-dphi), sim.q_nb[0])
        res = ZuptFilter(cfg).run(imu, sim.stance, initial_quaternion=q0)
        e = sim.position[-1] - res.position[-1]
        nees.append(float(e @ np.linalg.solve(res.P[:3, :3], e)))
        sd = np.sqrt(res.cov_diag[k_mid])
        zp.append(z_scores(res.position[k_mid], sim.position[k_mid], sd[0:3]))
        zv.append(z_scores(res.velocity[k_mid], sim.velocity[k_mid], sd[3:6]))
        if states == 15:
            sdf = np.sqrt(res.cov_diag[-1])
            zba.append(z_scores(res.accel_bias[-1], ba, sdf[9:12]))
            zbg.append(z_scores(res.gyro_bias[-1], bg, sdf[12:15]))
    return nees, zp, zv, zba, zbg


@pytest.mark.parametrize("states", [9, 15])
def test_zupt_covariance_calibrated_on_simulated_gait(states):
    nees, zp, zv, zba, zbg = _runs(states, seed=7 + states)
    where = f"ZUPT {states} states"
    # assert_nees_calibrated applies IMUNAV_SIGMA_SCALE itself
    assert_nees_calibrated(nees, 3, f"{where}: final position NEES")
    assert_rms_calibrated(np.concatenate(zp), f"{where}: mid-swing position z")
    assert_rms_calibrated(np.concatenate(zv), f"{where}: mid-swing velocity z")
    if states == 15:
        assert_rms_calibrated(np.concatenate(zba), f"{where}: accel bias z")
        assert_rms_calibrated(np.concatenate(zbg), f"{where}: gyro bias z")
