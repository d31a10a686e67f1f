"""The notebook entry points of ``import imunav`` (issue 35, deliverable 5): each recovers a known truth through the
object the user gets, its ``summary()`` is strict JSON and its ``plot()`` a figure."""

from __future__ import annotations

import json
import subprocess
import sys

import matplotlib
import numpy as np
import pytest
from builders import multipose_session, random_poses, static_imu

import imunav
from imunav.attitude.benchmark import make_filter
from imunav.errors import InvalidInputError, NotStaticError
from imunav.io import write_imu
from imunav.timeseries import ImuData

matplotlib.use("Agg")


def _strict_json(d: dict) -> dict:
    return json.loads(json.dumps(d, allow_nan=False))


def test_import_imunav_names_the_entry_points_and_loads_none_of_them():
    for name in imunav.NOTEBOOK:
        assert callable(getattr(imunav, name)) and name in dir(imunav)
    with pytest.raises(AttributeError, match="no attribute 'reed'"):
        imunav.reed  # noqa: B018
    code = "import sys, imunav; print('imunav.notebook' in sys.modules, 'imunav.ins.gins' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False"]


def test_read_and_its_summary(tmp_path):
    data = static_imu(3000, 100.0, seed=1)
    write_imu(data, tmp_path / "rec.csv")
    rec = imunav.read(tmp_path / "rec.csv")
    s = _strict_json(rec.summary())
    assert s["n"] == 3000 and s["fs_hz"] == pytest.approx(100.0) and s["gaps"] == 0
    assert s["duration_s"] == pytest.approx(29.99)
    assert s["static_s"] > 25.0  # at rest all along (the detector's windows trim the ends)
    np.testing.assert_allclose(rec.data.gyro, data.gyro, rtol=0, atol=1e-12)
    assert isinstance(rec.plot(), matplotlib.figure.Figure)


def test_analyse_noise_recovers_the_white_noise_density():
    """White gyro noise of density σ_d (rad/s/√Hz) sampled at fs has a per-sample σ = σ_d √fs and an Allan
    deviation N/√τ with N = σ_d (IEEE Std 952, Annex C); the fit recovers N within 4 of its standard errors."""
    fs, sd = 100.0, 2e-3  # rad/s/√Hz
    data = static_imu(200_000, fs, seed=7, gyro_sd=sd * np.sqrt(fs), accel_sd=3e-3 * np.sqrt(fs))
    res = imunav.analyse_noise(data, sensors=("gyro",))
    f = res.fits["gyro"]
    i = f.names.index("N")
    assert np.all(np.abs(f.value[i] - sd) < 4 * f.se[i] + 1e-12), (f.value[i], f.se[i])
    s = _strict_json(res.summary())
    want = sd * np.degrees(1.0) * 60.0  # deg/sqrt(h)
    assert s["gyro"]["units"]["N"] == "deg/sqrt(h)"
    for ch in ("gx", "gy", "gz"):
        assert s["gyro"]["N"][ch] == pytest.approx(want, rel=0.02)
    assert isinstance(res.plot("gyro"), matplotlib.figure.Figure)
    with pytest.raises(InvalidInputError, match="no 'accel'"):
        res.plot("accel")


def test_analyse_noise_refuses_a_moving_recording():
    data = static_imu(20_000, 100.0, seed=2)
    tilt = np.deg2rad(20.0) * (data.t > data.t[-1] / 2)  # tilted by 20° about x half way through
    f = data.accel - data.accel.mean(0) + 9.80665 * np.c_[np.zeros_like(tilt), np.sin(tilt), -np.cos(tilt)]
    moved = ImuData(data.t, data.gyro, f)
    with pytest.raises(NotStaticError):
        imunav.analyse_noise(moved)
    assert "gyro" in imunav.analyse_noise(moved, force=True).fits


def test_calibrate_recovers_the_scale_of_a_simulated_multipose_session():
    """A session whose accelerometer reads 2 % high with a 0.3 m/s² bias: the compensated poses have |f| = g."""
    rng = np.random.default_rng(5)
    f, w = multipose_session(random_poses(20, rng), 100.0, rest_s=20.0, static_s=3.0, move_s=1.5)
    raw_f = 1.02 * f + np.array([0.3, -0.2, 0.1]) + rng.normal(0, 0.01, f.shape)
    data = ImuData(np.arange(len(f)) / 100.0, w + rng.normal(0, 1e-3, w.shape), raw_f)
    cal = imunav.calibrate(data, init_s=20.0, wait_s=2.0)
    T = cal.result.calibration.accel_matrix
    assert np.diag(T) == pytest.approx([1.02, 1.02, 1.02], abs=2e-3)
    assert cal.result.calibration.accel_bias == pytest.approx([0.3, -0.2, 0.1], abs=0.02)
    s = _strict_json(cal.summary())
    assert s["method"] and set(s["condition"]) == {"accel", "gyro"}
    assert isinstance(cal.plot(), matplotlib.figure.Figure)
    with pytest.raises(InvalidInputError, match="multipose"):
        imunav.calibrate(data, "ratetable")


def test_estimate_attitude_is_the_named_filter_and_levels_a_resting_sensor():
    data = static_imu(2000, 100.0, seed=3, accel_sd=0.02, gyro_sd=0.002)
    est = imunav.estimate_attitude(data, "mekf")
    ref = make_filter("mekf").run(data)
    np.testing.assert_array_equal(est.result.q_nb, ref.q_nb)
    s = _strict_json(est.summary())
    assert s["filter"] == ref.name and s["samples"] == 2000
    roll, pitch, _ = s["final_roll_pitch_yaw_deg"]
    assert abs(roll) < 0.2 and abs(pitch) < 0.2  # level: (0, 0, -g) at rest
    assert isinstance(est.plot(), matplotlib.figure.Figure)
    with pytest.raises(Exception, match="unknown filter"):
        imunav.estimate_attitude(data, "kalman9000")


def test_gins_navigate_finds_the_odometer_scale_of_a_robot_log(tmp_path):
    """The simulated robot's odometry reads 9 % short (scale 0.91): the summary's odometer scale (reading / true
    speed − 1) is −0.09 within 4 of its σ."""
    from imunav.sim.robot_log import simulate_robot_log, write_robot_log

    write_robot_log(simulate_robot_log(1, distance_m=120), tmp_path, formats=("ros1",))
    (bag,) = tmp_path.glob("*.bag")
    nav = imunav.navigate(bag)
    s = _strict_json(nav.summary())
    scale = s["odometer_scale"]
    assert abs(scale["value"] - (0.91 - 1)) < 4 * scale["std"] + 1e-3, scale
    assert isinstance(nav.plot(), matplotlib.figure.Figure)
