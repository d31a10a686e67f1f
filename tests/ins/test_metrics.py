"""Metrics (closed form) and the foot-dataset frame adapters (tested on the data)."""

from __future__ import annotations

import numpy as np
import pytest
from shared_data import data_path

from imunav.errors import FileFormatError, InsufficientDataError, InvalidInputError, ShapeError
from imunav.ins import ZuptConfig, ZuptFilter, detect_zero_velocity, error_2d, loop_closure_error, position_rmse
from imunav.ins.zupt.metrics import align_heading, vertical_error


def _track(n=500):
    s = np.linspace(0, 3, n)
    return np.column_stack([s, 0.3 * np.sin(s), 0.05 * s])


def test_error_2d_invariant_to_start_offset_and_heading():
    ref = _track()
    a = 0.7
    R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    est = ref @ R.T + [5.0, -2.0, 1.0]
    assert error_2d(est, ref) == pytest.approx(0.0, abs=1e-12)
    # a constant lateral offset d after alignment at the start: sqrt(d^2 / 2)
    est2 = ref.copy()
    est2[1:, 1] += 0.1
    # alignment sample rotates slightly; compare with the definition computed by hand
    e = align_heading(est2, ref) - (ref - ref[0])
    assert error_2d(est2, ref) == pytest.approx(np.mean(np.sqrt((e[:, 0] ** 2 + e[:, 1] ** 2) / 2)))


def test_position_rmse_and_loop_closure():
    ref = _track()
    a = -1.1
    R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    assert position_rmse(ref @ R.T, ref, align="yaw") == pytest.approx(0.0, abs=1e-12)
    shifted = ref + [0.0, 0.0, 0.2]
    assert position_rmse(shifted, ref, align="none", dims=3) == pytest.approx(0.2)
    loop = np.array([[0, 0, 0], [3, 0, 0], [3, 4, 0], [0.03, 0.04, -0.12]], float)
    lc = loop_closure_error(loop)
    assert lc.horizontal == pytest.approx(0.05)
    assert lc.vertical == pytest.approx(0.12)
    assert lc.error_3d == pytest.approx(0.13)
    np.testing.assert_allclose(vertical_error(loop, [0.12], [3]), [0.0], atol=1e-12)
    with pytest.raises(ShapeError, match="one row per sample"):
        position_rmse(ref[:10], ref)
    with pytest.raises(InvalidInputError, match="align"):
        position_rmse(ref, ref, align="best")
    with pytest.raises(InsufficientDataError):
        loop_closure_error(loop[:1])


def test_pyshoe_adapter_flip_needed():
    """gt x-y matches the z-down INS frame directly; a mirrored y would be ~30x worse."""
    from imunav.io.foot import read_pyshoe_mat

    tr = read_pyshoe_mat(data_path("foot", "pyshoe_vicon", "2017-11-22-11-22-03.mat"))
    assert tr.imu.accel[:20, 2].mean() < -9.0  # body z down
    res = ZuptFilter().run(tr.imu, tr.labels["shoe"])
    good = error_2d(res.position, tr.position)
    mirrored = error_2d(res.position, tr.position * [1, -1, 1])
    assert good < 0.05 and mirrored > 5 * good
    assert tr.published_error["shoe"] == pytest.approx(0.032)  # README / file value
    assert tr.meta["best_detector"] == "shoe"


def test_xio_reader_units_frames_and_loop_closure():
    """x-io loop walks: loop-closure error against x-io's published 82 mm (short) / 421 mm (long).

    With x-io's own stance rule at x-io's settings (free acceleration < 3 m/s²,
    moving periods widened by 0.1 s) and the level-floor constraint (both walks
    are on one floor) both walks beat the published figures (57 / 229 mm).
    Without the floor constraint the short walk does not (≈0.13-0.14 m, mostly
    vertical drift): pinned here so that a regression shows.
    """
    from imunav.io.foot import read_xio_gait_csv

    for name, bound in (("short_walk.csv", 0.15), ("long_walk.csv", 0.421)):
        tr = read_xio_gait_csv(data_path("foot", "xio_gait", name))
        d = tr.imu
        assert np.all(np.diff(d.t) > 0)
        assert 350 < d.fs < 450
        # FRD after the adapter: gravity reaction points up -> f_z < 0 while standing
        assert d.accel[:50, 2].mean() < -7.0
        assert abs(np.linalg.norm(d.accel[:50].mean(0)) - 9.8) < 0.3  # g -> m/s^2
        zv = detect_zero_velocity(d, "shoe", 1e8, margin_s=0.125)
        res = ZuptFilter(ZuptConfig(alignment="first_stance", g=None, accel_noise_std=2.0)).run(d, zv.zv)
        lc = loop_closure_error(res.position)
        assert lc.error_3d < bound, f"{name}: {lc.error_3d:.3f} m"
        assert lc.horizontal < 0.2
        zx = detect_zero_velocity(d, "freeacc", 3.0, margin_s=0.1)
        cfg = ZuptConfig(alignment="first_stance", g=None, level_floor=True)
        lc = loop_closure_error(ZuptFilter(cfg).run(d, zx.zv).position)
        published = 0.082 if name.startswith("short") else 0.421
        assert lc.error_3d < published, f"{name}: {lc.error_3d:.3f} m with freeacc + level floor"
        assert lc.vertical < 0.005  # the constraint holds the height


def test_fgo_adapter():
    from imunav.io.foot import read_fgo_csv

    base = data_path("foot", "constrained_zupt_fgo")
    tr = read_fgo_csv(base / "imuMeasRight.csv", base / "positionGt.csv")
    assert tr.imu.fs == pytest.approx(60.0)
    assert tr.imu.accel[:20, 2].mean() < -9.0
    res = ZuptFilter(ZuptConfig(alignment="first_stance", g=None)).run(tr.imu, tr.labels["authors"])
    good = error_2d(res.position, tr.position)
    assert good < 0.3
    assert error_2d(res.position, tr.position * [1, -1, 1]) > 3 * good


def test_reader_errors(tmp_path):
    from imunav.io.foot import read_fgo_csv, read_pyshoe_mat, read_xio_gait_csv, spread_duplicate_times

    p = tmp_path / "x.csv"
    p.write_text("Time (s),Gyroscope X (deg/s)\n0,1\n")
    with pytest.raises(FileFormatError, match="Gyroscope Y"):
        read_xio_gait_csv(p)
    p.write_text("")
    with pytest.raises(FileFormatError, match="empty"):
        read_xio_gait_csv(p)
    q = tmp_path / "imu.csv"
    q.write_text("time_index,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z\n0,0,0,9.8,0,0,0\n1,0,0,9.8,0,0,0\n")
    with pytest.raises(FileFormatError, match="foot"):
        read_fgo_csv(q, q)
    m = tmp_path / "bad.mat"
    m.write_bytes(b"not a mat file")
    with pytest.raises(FileFormatError, match="MATLAB"):
        read_pyshoe_mat(m)
    t, moved = spread_duplicate_times(np.array([0.0, 1.0, 3.0, 3.0, 4.0]))
    np.testing.assert_allclose(t, [0, 1, 2, 3, 4])
    assert moved == 2
    with pytest.raises(FileFormatError, match="backwards"):
        spread_duplicate_times(np.array([0.0, 2.0, 1.0]))
