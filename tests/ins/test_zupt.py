"""ZUPT-aided INS: published reproduction, static convergence, configuration errors."""

from __future__ import annotations

import dataclasses
import glob
import math

import numpy as np
import pytest
from builders import static_imu
from shared_data import data_path

from imunav.errors import (
    ConfigError,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
    TimeOrderError,
)
from imunav.ins import ZuptConfig, ZuptFilter, align_from_accel, error_2d, first_stance
from imunav.rotation import euler_from_quat, quat_from_euler
from imunav.timeseries import ImuData


def _static(n=2000, rng=None, noise=(0.0, 0.0)):
    """At rest at 200 Hz under the filter's gravity, 9.8029 m/s², with white noise of σ ``noise`` (accel, gyro)."""
    return static_imu(n, 200.0, seed=rng, accel=(0.0, 0.0, -9.8029), accel_sd=noise[0], gyro_sd=noise[1])


def test_published_trial_error_reproduced_all_trials():
    """Stored zv_shoe_opt labels -> 2-D error within 0.02 m of trial_error[0] on all 42 trials."""
    from imunav.io.foot import read_pyshoe_mat

    files = sorted(glob.glob(str(data_path("foot", "pyshoe_vicon") / "*.mat")))
    assert len(files) == 42
    diffs = []
    for f in files:
        tr = read_pyshoe_mat(f)
        res = ZuptFilter().run(tr.imu, tr.labels["shoe"])
        diffs.append(error_2d(res.position, tr.position) - tr.published_error["shoe"])
    diffs = np.abs(diffs)
    assert diffs.max() < 0.02, f"worst trial differs by {diffs.max():.4f} m"
    # the published values are rounded to 1 mm; the bulk agrees to a few mm
    assert np.median(diffs) < 0.004


def test_tilt_error_shrinks_under_zupt():
    """Attitude-error sign check (spec §5.3): a 2° roll error decays while static."""
    data = _static(n=4000)
    q0 = quat_from_euler(math.radians(2.0), 0.0, 0.0)
    res = ZuptFilter(ZuptConfig(init_att_std=math.radians(3.0))).run(data, np.ones(data.n, bool), initial_quaternion=q0)
    roll = euler_from_quat(res.q_nb)[:, 0]
    assert abs(roll[-1]) < 0.1 * math.radians(2.0)
    # the filter is consistent: the final error is inside 3 sigma of its attitude variance
    assert abs(roll[-1]) < 3 * math.sqrt(res.cov_diag[-1, 6]) + 1e-6
    # and the velocity stays bounded by the ZUPTs
    assert np.max(np.abs(res.velocity)) < 0.05


def test_static_with_noise_bounded_and_innovations_white(rng):
    data = _static(n=3000, rng=rng, noise=(0.02, 0.002))
    res = ZuptFilter().run(data, np.ones(data.n, bool))
    assert np.max(np.linalg.norm(res.position, axis=1)) < 0.01
    nis = res.innovation[1:] ** 2 / res.innovation_var[1:]
    assert np.all(np.isfinite(nis))
    # at least the innovations are not larger than their predicted spread on average
    assert np.mean(nis) < 3.0


def test_free_fall_without_updates_matches_kinematics():
    """No ZUPT: constant body specific force in a level frame gives p = a t^2 / 2."""
    n, fs = 401, 100.0
    acc = np.tile([0.5, 0.0, -9.8029], (n, 1))
    data = ImuData(np.arange(n) / fs, np.zeros((n, 3)), acc)
    res = ZuptFilter().run(data, np.zeros(n, bool), initial_quaternion=[1, 0, 0, 0])
    T = data.t[-1]
    np.testing.assert_allclose(res.position[-1], [0.25 * T**2, 0, 0], atol=1e-9)
    np.testing.assert_allclose(res.velocity[-1], [0.5 * T, 0, 0], atol=1e-9)
    # without updates the position variance grows
    assert res.cov_diag[-1, 0] > res.cov_diag[0, 0]


def test_alignment():
    q = align_from_accel([0.0, 0.0, -9.8])
    np.testing.assert_allclose(q, [1, 0, 0, 0], atol=1e-12)
    roll, pitch = 0.2, -0.1
    q = quat_from_euler(roll, pitch, 0.0)
    from imunav.rotation import dcm_from_quat

    f_b = dcm_from_quat(q).T @ np.array([0, 0, -9.8])
    np.testing.assert_allclose(euler_from_quat(align_from_accel(f_b)), [roll, pitch, 0.0], atol=1e-12)
    assert first_stance([0, 0, 1, 1, 1, 0, 1]) == (2, 5)
    with pytest.raises(InsufficientDataError, match="no stationary"):
        first_stance([0, 0, 0])
    with pytest.raises(InvalidInputError, match="non-zero"):
        align_from_accel([0, 0, 0])


def test_config_and_input_errors():
    with pytest.raises(ConfigError, match="states"):
        ZuptConfig(states=12)
    with pytest.raises(ConfigError, match="states=15"):
        ZuptConfig(zaru=True)
    with pytest.raises(ConfigError, match="zupt_noise_std"):
        ZuptConfig(zupt_noise_std=0.0)
    with pytest.raises(ConfigError, match="integration"):
        ZuptConfig(integration="rk4")
    data = _static(n=50)
    with pytest.raises(ShapeError, match="zv"):
        ZuptFilter().run(data, np.ones(10, bool))
    with pytest.raises(InvalidInputError, match="ImuData"):
        ZuptFilter().run(np.zeros((50, 6)), np.ones(50, bool))
    with pytest.raises(InvalidInputError, match="unit quaternion"):
        ZuptFilter().run(data, np.ones(50, bool), initial_quaternion=[2, 0, 0, 0])


def test_fifteen_state_and_options_run_static(rng):
    """ZARU + heading hold on a static IMU with a gyro bias: the bias is recovered."""
    data = _static(n=4000, rng=rng, noise=(0.01, 0.001))
    bias = np.array([0.01, -0.02, 0.015])
    data = data.with_(gyro=data.gyro + bias)
    cfg = ZuptConfig(states=15, zaru=True, heading_hold=True, zaru_noise_std=0.005)
    res = ZuptFilter(cfg).run(data, np.ones(data.n, bool))
    sd = np.sqrt(res.cov_diag[-1, 12:15])
    np.testing.assert_array_less(np.abs(res.gyro_bias[-1] - bias), 3 * sd + 1e-5)
    assert np.all(sd < 1e-3)


def _step_through(f, imu, zv, **kw):
    """Step a filter through a recording; one ZuptState per sample, stacked field by field."""
    states = [f.step(imu.t[k], imu.gyro[k], imu.accel[k], bool(zv[k]), **kw) for k in range(imu.n)]
    return {f.name: np.array([getattr(s, f.name) for s in states]) for f in dataclasses.fields(states[0])}


@pytest.mark.parametrize("cfg", [
    ZuptConfig(g=9.80665, align_samples=1),
    ZuptConfig(g=9.80665, states=15, zaru=True, heading_hold=True, level_floor=True, integration="coning"),
])
def test_step_gives_the_trajectory_of_run(cfg):
    """Stepping sample by sample (state carried between calls) gives run's trajectory to 1e-12.

    Both paths run the same kernel loop in the same order of floating-point operations, so the only
    admissible difference is none; 1e-12 leaves room for a compiler that fuses operations differently.
    """
    from imunav.sim.gait import simulate_gait

    sim = simulate_gait("walk", 6, error_model="foot_mems", rng=4, turn_deg=20)
    imu = sim.imu
    res = ZuptFilter(cfg).run(imu, sim.stance, initial_position=[1.0, 2.0, 0.5])
    f = ZuptFilter(cfg)
    f.reset(res.q_nb[0], position=[1.0, 2.0, 0.5])
    st = _step_through(f, imu, sim.stance)
    np.testing.assert_array_equal(st["t"], res.t)
    for name in ("position", "velocity", "q_nb", "accel_bias", "gyro_bias", "cov_diag", "innovation",
                 "innovation_var"):
        np.testing.assert_allclose(st[name], getattr(res, name), rtol=0, atol=1e-12, err_msg=name)
    np.testing.assert_allclose(f.P, res.P, rtol=0, atol=1e-12)
    assert np.isfinite(res.innovation[sim.stance][1:]).all()  # the updates did apply
    if cfg.align_samples == 1:  # without reset(q_nb): levelled from the first sample, as run with 1 sample
        f.reset(position=[1.0, 2.0, 0.5])
        np.testing.assert_allclose(_step_through(f, imu, sim.stance)["q_nb"], res.q_nb, rtol=0, atol=1e-12)


def test_step_continues_run_and_reset_forgets():
    """After run() a step goes on from the last sample (as a run over the longer recording); reset() restarts."""
    from imunav.sim.gait import simulate_gait

    sim = simulate_gait("walk", 4, error_model="foot_mems", rng=2)
    imu, zv = sim.imu, sim.stance
    cfg = ZuptConfig(g=9.80665, integration="coning", heading_hold=True)
    full = ZuptFilter(cfg).run(imu, zv)
    f = ZuptFilter(cfg)
    n = imu.n - 50
    f.run(imu.slice(0, n), zv[:n])
    last = [f.step(imu.t[k], imu.gyro[k], imu.accel[k], bool(zv[k])) for k in range(n, imu.n)][-1]
    np.testing.assert_allclose(last.position, full.position[-1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(last.q_nb, full.q_nb[-1], rtol=0, atol=1e-12)
    with pytest.raises(TimeOrderError, match="not after the previous sample"):
        f.step(imu.t[-1], imu.gyro[-1], imu.accel[-1])
    with pytest.raises(NonFiniteError):
        f.step(imu.t[-1] + 0.01, [np.nan, 0, 0], imu.accel[-1])
    f.reset()
    first = f.step(0.0, imu.gyro[0], imu.accel[0])
    np.testing.assert_array_equal(first.position, np.zeros(3))
    with pytest.raises(ConfigError, match="zaru_min_s"):
        ZuptFilter(ZuptConfig(states=15, zaru=True, zaru_min_s=1.0)).step(0.0, imu.gyro[0], imu.accel[0], True)
