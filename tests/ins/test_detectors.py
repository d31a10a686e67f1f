"""Zero-velocity detectors: closed-form statistics, published labels, bad input."""

from __future__ import annotations

import glob

import numpy as np
import pytest
from shared_data import data_path

from imunav.errors import InvalidInputError, ShapeError
from imunav.ins import amvd, ared, detect_zero_velocity, detector_statistic, mbgtd, motion_adaptive, shoe
from imunav.ins.zupt.detectors import optimize_threshold
from imunav.timeseries import ImuData


def _imu(acc, gyr, fs=200.0):
    n = len(acc)
    return ImuData(np.arange(n) / fs, np.asarray(gyr, float), np.asarray(acc, float))


def _mbgtd_reference(acc, W):
    """Direct transcription of the published MBGTD formula (oracle)."""
    n = len(acc)
    out = np.ones(n)
    for k in range(n - W + 1):
        A = acc[k:k + W]
        best = 0.0
        for a in range(W - 1):
            for b in range(a + 1, W):
                s = sum(np.linalg.norm(A[i] - A[j]) for i in range(a + 1) for j in range(b, W))
                best = max(best, s / ((b - a) * (W - b + 1)))
        out[k] = best
    return out


def test_closed_form_statistics(rng):
    g = 9.8029
    n = 23  # 4 full blocks of 5 + a tail of 3
    u = np.array([0.3, -0.2, -1.0]) / np.linalg.norm([0.3, -0.2, -1.0])
    acc = np.tile(g * u, (n, 1))
    w = np.array([0.01, -0.02, 0.03])
    gyr = np.tile(w, (n, 1))
    T = shoe(acc, gyr, 5, sigma_a=0.01, sigma_w=0.1, g=g)
    # accel term vanishes (specific force = g along its own mean direction)
    np.testing.assert_allclose(T[:20], np.dot(w, w) / 0.1**2, rtol=1e-12)
    assert np.all(T[20:] == 0.0)  # tail after the last full block
    np.testing.assert_allclose(ared(gyr, 5)[:20], np.dot(w, w), rtol=1e-12)
    # AMVD of samples alternating +-d around a mean: variance |d|^2 * (count weighting)
    d = np.array([0.1, 0.2, -0.2])
    acc2 = np.tile(g * u, (n, 1)) + np.where((np.arange(n) % 2)[:, None] == 0, d, -d)
    blk = acc2[:5]
    expected = np.mean(np.sum((blk - blk.mean(0)) ** 2, axis=1))
    np.testing.assert_allclose(amvd(acc2, 5)[:5], expected, rtol=1e-12)
    acc3 = acc2 + rng.normal(0, 0.3, acc2.shape)
    np.testing.assert_allclose(mbgtd(acc3, 5), _mbgtd_reference(acc3, 5), rtol=1e-12)
    np.testing.assert_allclose(mbgtd(acc3, 3), _mbgtd_reference(acc3, 3), rtol=1e-12)


def test_decision_is_strict_and_threshold_arrays():
    n = 20
    acc = np.tile([0.0, 0.0, -9.8029], (n, 1))
    gyr = np.tile([0.1, 0.0, 0.0], (n, 1))
    data = _imu(acc, gyr)
    r = detect_zero_velocity(data, "ared", 0.01)  # T == 0.01 exactly -> not stationary
    assert not r.zv.any()
    r = detect_zero_velocity(data, "ared", np.full(n, 0.0101))
    assert r.zv.all()
    with pytest.raises(ShapeError, match="threshold"):
        detect_zero_velocity(data, "ared", np.ones(3))


def test_bad_input():
    with pytest.raises(ShapeError, match=r"\(N, 3\)"):
        ared(np.zeros((10, 2)))
    with pytest.raises(InvalidInputError, match="window"):
        ared(np.zeros((10, 3)), window=1)
    with pytest.raises(InvalidInputError, match="fewer than the window"):
        amvd(np.zeros((3, 3)), window=5)
    with pytest.raises(InvalidInputError, match="non-finite"):
        ared(np.full((10, 3), np.nan))
    data = _imu(np.tile([0, 0, -9.8], (10, 1)), np.zeros((10, 3)))
    with pytest.raises(InvalidInputError, match="unknown detector"):
        detector_statistic(data, "magic")
    with pytest.raises(InvalidInputError, match="ImuData"):
        detector_statistic(np.zeros((10, 6)), "shoe")
    with pytest.raises(InvalidInputError, match="all-zero"):
        shoe(np.zeros((10, 3)), np.zeros((10, 3)))
    with pytest.raises(InvalidInputError, match="thresholds"):
        motion_adaptive(data, thresholds=(1.0,))


def _trials(k=None):
    files = sorted(glob.glob(str(data_path("foot", "pyshoe_vicon") / "*.mat")))
    return files if k is None else files[::k]


def test_stored_labels_reproduced_sample_for_sample():
    """All 42 trials: SHOE/ARED/AMVD/MBGTD at the stored thresholds == zv_*_opt."""
    from imunav.io.foot import read_pyshoe_mat

    files = _trials()
    assert len(files) == 42
    for f in files:
        tr = read_pyshoe_mat(f)
        for name in ("shoe", "ared", "amvd", "mbgtd"):
            r = detect_zero_velocity(tr.imu, name, tr.thresholds[name])
            mism = np.flatnonzero(r.zv != tr.labels[name])
            assert mism.size == 0, f"{tr.name} {name}: {mism.size} samples differ, first {mism[:5]}"


def test_motion_adaptive_switches_threshold():
    fs = 200.0
    n = 2000
    gyr = np.zeros((n, 3))
    gyr[n // 2:, 1] = 8.0 * np.sin(np.arange(n // 2) / fs * 2 * np.pi * 1.5)  # running-like swing
    acc = np.tile([0.0, 0.0, -9.8029], (n, 1))
    r = motion_adaptive(_imu(acc, gyr), thresholds=(1e7, 3.5e8), split_rate=4.0)
    assert r.threshold[100] == pytest.approx(1e7)
    assert r.threshold[-100] == pytest.approx(3.5e8)


def test_optimize_threshold_finds_stored_optimum_region():
    from imunav.io.foot import read_pyshoe_mat

    tr = read_pyshoe_mat(_trials()[0])
    grid = [tr.thresholds["ared"] * s for s in (0.1, 1.0, 30.0)]
    res = optimize_threshold(tr.imu, tr.position, "ared", grid)
    assert res.best_threshold == pytest.approx(tr.thresholds["ared"])
    assert res.best_error == pytest.approx(tr.published_error["ared"], abs=0.02)
    with pytest.raises(ShapeError, match="reference"):
        optimize_threshold(tr.imu, tr.position[:10], "ared", grid)


@pytest.mark.parametrize("bad", [float("nan"), 0.0, -1e8, float("inf")])
def test_bad_thresholds_refused(bad):
    n = 400
    data = ImuData(t=np.arange(n) / 200.0, gyro=np.zeros((n, 3)), accel=np.tile([0.0, 0.0, -9.81], (n, 1)))
    with pytest.raises(InvalidInputError, match="threshold"):
        detect_zero_velocity(data, "shoe", bad)
    with pytest.raises(InvalidInputError, match="margin_s"):
        detect_zero_velocity(data, "shoe", 1e8, margin_s=float("nan"))
