"""Noise identification refuses non-static data unless forced (issue 16, deliverable 5).

The gate (:func:`imunav.noise.check_static`) must pass static records of every preset, rate and pose
(false refusals are measured over 200 seeded records) and refuse multi-position, rate-table and
single-pose-change records, through the API, ``imunav noise`` and ``imunav batch noise``.
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import static_imu
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import NotStaticError
from imunav.io import write_imu
from imunav.noise import check_static, require_static
from imunav.rotation import quat_from_euler
from imunav.sim import (
    hundred_position_profile,
    presets,
    rate_table_step_profile,
    simulate_imu,
    static_profile,
)
from imunav.timeseries import ImuData

_SIM = dict(earth_rate=False, transport_rate=False, gravity="constant")


def _static(preset, fs, seed, duration=30.0, q=None):
    prof = static_profile(duration, fs, q)
    return simulate_imu(prof.trajectory, presets.get(preset), np.random.default_rng(seed), **_SIM)


def test_no_false_refusal_over_200_static_records():
    """Static records: every preset x 4 rates x 10 seeds, each in a random pose.

    Under white noise the statistical limit has a false-alarm probability <= 1e-6 per record and
    sensor (Bonferroni over the windows), and the presets' bias drift over 30 s is far below the
    physical allowances (2 deg of tilt, 2 deg of rotation per window): the expected number of false
    refusals is 0, and the largest drift seen must stay below a third of the limits.
    """
    rng = np.random.default_rng(2024)
    refused, worst_tilt, worst_rot, n = [], 0.0, 0.0, 0
    for preset in presets.names():
        for fs in (20.0, 50.0, 100.0, 400.0):
            for seed in range(10):
                q = quat_from_euler(rng.uniform(-np.pi, np.pi), rng.uniform(-1.4, 1.4), rng.uniform(-np.pi, np.pi))
                c = check_static(_static(preset, fs, seed, q=q))
                n += 1
                if not c.static:
                    refused.append((preset, fs, seed, c.reasons))
                worst_tilt = max(worst_tilt, c.max_tilt_deg / c.tilt_limit_deg)
                worst_rot = max(worst_rot, c.max_rotation_deg / c.rotation_limit_deg)
    assert n == 40 * len(presets.names())
    assert refused == []
    assert worst_tilt < 1 / 3 and worst_rot < 1 / 3, (worst_tilt, worst_rot)


def test_white_noise_far_above_the_physical_allowance_is_not_refused():
    """Very noisy, slow records (sigma = 0.5 m/s^2 and 0.5 rad/s per sample at 10 Hz): the window means
    scatter beyond 2 deg, so the statistical limit (chi-square, alpha = 1e-6) must take over: 200 seeds, 0 refused."""
    refused = 0
    for seed in range(200):
        d = static_imu(600, 10.0, seed=seed, accel=(0.0, 0.0, -9.81), gyro_sd=0.5, accel_sd=0.5)
        c = check_static(d)
        refused += not c.static
        assert c.tilt_limit_deg > 2.0 and c.rotation_limit_deg > 2.0
    assert refused == 0


@pytest.mark.parametrize("preset", presets.names())
def test_multiposition_and_rate_table_records_are_refused(preset):
    m = presets.get(preset)
    for prof in (hundred_position_profile(50.0, 5.0, 1.0), rate_table_step_profile(50.0, 5.0, 1.0)):
        d = simulate_imu(prof.trajectory, m, np.random.default_rng(0), **_SIM)
        c = check_static(d)
        assert not c.static and c.reasons
        with pytest.raises(NotStaticError, match="not static.*force=True"):
            require_static(d)
        assert require_static(d, force=True) is not None


def _pose_change(fs=100.0):
    """40 s level, then 20 s tilted by 5 deg about x (consumer MEMS)."""
    a = _static("consumer_mems", fs, 1, duration=40.0)
    b = _static("consumer_mems", fs, 2, duration=20.0, q=quat_from_euler(np.radians(5.0), 0.0, 0.0))
    return ImuData(np.arange(a.n + b.n) / fs, np.vstack([a.gyro, b.gyro]), np.vstack([a.accel, b.accel]))


def test_one_small_pose_change_is_refused():
    """The windows of the second pose lie 5 deg from the median (that of the first pose), beyond the 2 deg
    allowance."""
    d = _pose_change()
    c = check_static(d)
    assert not c.static and "changed pose" in " ".join(c.reasons)
    assert c.max_tilt_deg == pytest.approx(5.0, abs=0.5)


def test_accelerometer_in_g_is_refused_with_the_unit_hint():
    d = _static("tactical", 100.0, 0)
    in_g = d.with_(accel=d.accel / 9.80665)
    with pytest.raises(NotStaticError, match="in g"):
        require_static(in_g)


def test_real_static_records_pass_and_moving_ones_are_refused():
    from shared_data import data_path

    from imunav.io import read_imu

    adis = read_imu(data_path("adis16405", "adis16405_imu2.npz"), units={"gyro": "deg/s", "accel": "g"})
    assert check_static(adis).static  # 2.8 h at rest
    folder = data_path("mpu6050_tedaldi")

    def mpu(name):
        raw = np.loadtxt(folder / name, delimiter=",", skiprows=5)
        return ImuData.from_arrays(None, raw[:, 3:], raw[:, :3], fs=100.0, gyro_unit="counts",
                                   gyro_scale=np.radians(1 / 131), accel_unit="counts", accel_scale=9.80665 / 16384)

    assert check_static(mpu("imu_static_test.csv")).static
    assert not check_static(mpu("imu_90_x_rot.csv")).static
    assert not check_static(mpu("example_data_calibration.csv")).static


def test_cli_noise_refuses_a_multiposition_record_unless_forced(tmp_path):
    d = simulate_imu(hundred_position_profile(20.0, 3.0, 1.0).trajectory, presets.get("tactical"),
                     np.random.default_rng(0), **_SIM)
    p = write_imu(d, tmp_path / "mp.npz")
    r = CliRunner().invoke(app, ["noise", str(p), "--json", str(tmp_path / "n.json")])
    assert r.exit_code == 2 and "not static" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "n.json").exists()
    # forced: the 5-degree pose change is analysed (the multi-position record fits no noise model at all)
    p = write_imu(_pose_change(), tmp_path / "pc.npz")
    r = CliRunner().invoke(app, ["noise", str(p), "--terms", "N,K"])
    assert r.exit_code == 2 and "changed pose" in r.stderr
    r = CliRunner().invoke(app, ["noise", str(p), "--force", "--terms", "N,K", "--json", str(tmp_path / "n.json")])
    assert r.exit_code == 0, r.stderr


def test_batch_noise_of_a_multiposition_batch_is_refused(tmp_path):
    """The issue's case: `batch noise` on `batch simulate` output (100-position tests) reported ARW 320 deg/sqrt(h)."""
    from imunav.lab.batch import noise_batch, noise_unit, simulate_batch

    simulate_batch(2, tmp_path / "b", fs=10.0, dwell_s=2.0, transition_s=1.0, rate_table=False, executor="serial")
    with pytest.raises(NotStaticError, match="no unit"):
        noise_batch(tmp_path / "b", executor="serial")
    r = CliRunner().invoke(app, ["batch", "noise", str(tmp_path / "b"), "--executor", "serial", "--quiet"])
    assert r.exit_code == 2 and "not static" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    with pytest.raises(NotStaticError):
        noise_unit(tmp_path / "b" / "unit_001.npz")
    pc = write_imu(_pose_change(), tmp_path / "pc.npz")
    with pytest.raises(NotStaticError):
        noise_unit(pc)
    assert noise_unit(pc, force=True, terms=("N", "K"))["estimates"]


def test_cli_gyro_only_noise_skips_the_mean_force_test(tmp_path):
    """The README's gyro-only run on the ADIS record gives no accelerometer unit: only the analysed sensor's
    unit matters; with an accelerometer channel the file in g is refused with the unit hint."""
    d = _static("tactical", 50.0, 0, duration=120.0)
    p = write_imu(d.with_(accel=d.accel / 9.80665), tmp_path / "ing.npz")  # accelerometer values in g
    r = CliRunner().invoke(app, ["noise", str(p), "--channels", "gx,gy,gz", "--terms", "N,K"])
    assert r.exit_code == 0, r.stderr
    r = CliRunner().invoke(app, ["noise", str(p), "--channels", "gx,ax", "--terms", "N,K"])
    assert r.exit_code == 2 and "--accel-unit g" in r.stderr
