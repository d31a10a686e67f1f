"""comma2k19 segments as a navigation log (issue 33): the shared real segment (skipped when absent) and small
synthetic segments written here for the refusals (no shared data copied)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shared_data import data_path

from imunav.earth import lla_to_ned
from imunav.errors import FileFormatError, InvalidInputError
from imunav.io.comma2k19 import UBLOX_POS_STD, is_comma2k19_segment, read_comma2k19, read_comma2k19_pose
from imunav.io.gpstime import GPS_EPOCH_UNIX
from imunav.io.navlog import is_nav_log, read_nav_sources
from imunav.rotation import dcm_from_quat


def _segment():
    return data_path("comma2k19", "example1")


def _arr(seg, rel):
    return np.load(seg / rel, allow_pickle=False)


def test_the_shared_segment_reads_as_a_log_on_gps_time():
    """Every sensor on the IMU's origin; t0 the UTC of the first IMU sample through the pose's frame_gps_times:
    the GPS seconds of week of t = 0 equal the first IMU boot stamp plus the frames' boot -> GPS offset."""
    seg = _segment()
    assert is_comma2k19_segment(seg) and is_nav_log(seg)
    src = read_nav_sources(seg)
    t_imu = _arr(seg, "processed_log/IMU/accelerometer/t")
    ft, fg = _arr(seg, "global_pose/frame_times"), _arr(seg, "global_pose/frame_gps_times")
    assert src.imu.n == t_imu.size == 6256
    assert src.gnss.n == 579 and src.odometer.t.size == 4972 and src.mag is not None
    assert src.time_is_utc
    g = src.gps_time([0.0])
    assert int(g.week[0]) == int(fg[0, 0]) == 2012
    # the frames' own mapping of the boot clock, applied to the first IMU stamp (float64: 1e-6 s at 4e5 s)
    assert float(g.sow[0]) == pytest.approx(t_imu[0] + np.median(fg[:, 1] - ft), abs=2e-6)
    np.testing.assert_allclose(src.imu.t, t_imu - t_imu[0], atol=1e-9)
    # the fixes reach the logger about 0.2 s after their own UTC epoch (README: they are late)
    late = src.meta["gnss"]["receive_after_epoch_s"]
    assert 0.15 < late["mean"] < 0.25 and late["std"] < 0.03
    # unknown accuracy: the datasheet sigma, counted
    np.testing.assert_allclose(src.gnss.pos_std, np.tile(UBLOX_POS_STD, (src.gnss.n, 1)))
    assert src.gnss.meta["faults"]["sigma_assumed"] == src.gnss.n
    # u-blox fix 0: latitude and longitude as written, in radians
    v = _arr(seg, "processed_log/GNSS/live_gnss_ublox/value")
    assert src.gnss.lla[0, 0] == pytest.approx(math.radians(v[0, 0]), abs=1e-15)


def test_raw_and_calibrated_gyro_differ_by_androids_bias():
    """gyro='raw' reads gyro_uncalibrated: raw - calibrated is Android's gyro_bias sample by sample (float32
    rounding of the files)."""
    seg = _segment()
    cal, raw = read_comma2k19(seg), read_comma2k19(seg, gyro="raw")
    np.testing.assert_allclose(raw.imu.gyro - cal.imu.gyro, _arr(seg, "processed_log/IMU/gyro_bias/value"),
                               atol=2e-6)
    assert raw.meta["imu"]["android_gyro_bias_end"] == pytest.approx(_arr(seg, "processed_log/IMU/gyro_bias/value")
                                                                     [-1].tolist())
    # the bias is up to about 4 deg/s (README)
    assert np.degrees(np.abs(raw.meta["imu"]["android_gyro_bias_end"])).max() == pytest.approx(3.9, abs=0.1)


def test_pose_is_a_nav_track_whose_velocity_and_attitude_agree():
    """The fused pose as a .nav track: its NED velocity is the derivative of its position (finite differences of
    20 Hz frames, within 0.05 m/s RMS), and the camera's forward axis points along the velocity within 5 deg (the
    device sits on the windshield pitched about 4 deg)."""
    seg = _segment()
    tr = read_comma2k19_pose(seg)
    assert tr.week == 2012 and tr.t.size == 1200
    ned = lla_to_ned(tr.lla, tr.lla[0])
    vd = np.gradient(ned, tr.t, axis=0)
    assert float(np.sqrt(np.mean((vd[5:-5] - tr.vel_ned[5:-5]) ** 2))) < 0.05
    x_n = dcm_from_quat(tr.q_nb)[:, :, 0]
    u = tr.vel_ned / np.linalg.norm(tr.vel_ned, axis=1, keepdims=True)
    ang = np.degrees(np.arccos(np.clip(np.sum(x_n * u, axis=1), -1, 1)))
    assert ang.max() < 5.0


def _write(folder, rel, t, v):
    d = folder / rel
    d.mkdir(parents=True, exist_ok=True)
    for name, a in (("t", t), ("value", v)):
        with open(d / name, "wb") as f:  # comma2k19 stores the arrays without the .npy suffix
            np.save(f, np.asarray(a))


def _synthetic(folder, n=300):
    """A 3 s segment at 100 Hz with a pose at 20 Hz: enough for the reader (not for a run)."""
    t = 1000.0 + np.arange(n) * 0.01
    _write(folder, "processed_log/IMU/accelerometer", t, np.tile([0.0, 0.0, -9.81], (n, 1)))
    _write(folder, "processed_log/IMU/gyro", t, np.zeros((n, 3)))
    _write(folder, "processed_log/IMU/gyro_uncalibrated", t, np.full((n, 3), 0.01))
    _write(folder, "processed_log/IMU/gyro_bias", t, np.full((n, 3), 0.01))
    tg = t[::10] + 0.005
    utc_ms = (GPS_EPOCH_UNIX + 2012 * 604800 + 400000.0 + tg - 0.2 - 18) * 1e3
    _write(folder, "processed_log/GNSS/live_gnss_ublox", tg,
           np.column_stack([np.full(tg.size, 37.7), np.full(tg.size, -122.4), np.zeros(tg.size), utc_ms,
                            np.full(tg.size, 30.0), np.zeros(tg.size)]))
    _write(folder, "processed_log/CAN/speed", t[::2], np.zeros((t[::2].size, 1)))
    ft = t[::5]
    pose = folder / "global_pose"
    pose.mkdir(parents=True, exist_ok=True)
    for name, a in (("frame_times", ft), ("frame_gps_times", np.column_stack([np.full(ft.size, 2012.0),
                                                                              400000.0 + ft])),
                    ("frame_positions", np.tile([-2712087.5, -4261670.0, 3881014.4], (ft.size, 1))),
                    ("frame_velocities", np.zeros((ft.size, 3))),
                    ("frame_orientations", np.tile([1.0, 0.0, 0.0, 0.0], (ft.size, 1)))):
        with open(pose / name, "wb") as f:
            np.save(f, a)
    return folder


def test_synthetic_segment_reads_and_maps_its_clock(tmp_path):
    """A segment written here: sow = boot + 400000 s, fixes received 0.2 s after their epochs."""
    seg = _synthetic(tmp_path / "seg")
    src = read_comma2k19(seg, gnss_pos_std=1.5)
    assert float(src.gps_time([0.0]).sow[0]) == pytest.approx(401000.0, abs=1e-6)
    assert src.meta["gnss"]["receive_after_epoch_s"]["mean"] == pytest.approx(0.2, abs=1e-3)
    np.testing.assert_allclose(src.gnss.pos_std, 1.5)
    raw = read_comma2k19(seg, gyro="raw")
    np.testing.assert_allclose(raw.imu.gyro, 0.01)


def test_refusals(tmp_path):
    """Bad choices and broken segments end in one imunav error that names the file or the option."""
    seg = _synthetic(tmp_path / "seg")
    with pytest.raises(InvalidInputError, match="gyro"):
        read_comma2k19(seg, gyro="filtered")
    with pytest.raises(InvalidInputError, match="gnss_pos_std"):
        read_comma2k19(seg, gnss_pos_std=-1.0)
    with pytest.raises(InvalidInputError, match="--imu-topic"):
        read_nav_sources(seg, imu_topic="/imu")
    with pytest.raises(InvalidInputError, match="--gyro"):
        read_nav_sources(tmp_path / "drive.bag", gyro="raw")
    (seg / "global_pose" / "frame_gps_times").unlink()
    with pytest.raises(FileFormatError, match="frame_gps_times"):
        read_comma2k19(seg)
    seg2 = _synthetic(tmp_path / "seg2")
    with open(seg2 / "processed_log/IMU/gyro/t", "wb") as f:
        np.save(f, np.arange(5.0))
    with pytest.raises(FileFormatError, match="stamps"):
        read_comma2k19(seg2)
    seg3 = _synthetic(tmp_path / "seg3")
    (seg3 / "processed_log/CAN/speed/value").write_bytes(b"not numpy")
    with pytest.raises(FileFormatError, match="NumPy"):
        read_comma2k19(seg3)
    for bad in (np.float64(3.0), np.array(["a", "b"]), np.ones(5, dtype=complex)):
        with open(seg3 / "processed_log/CAN/speed/value", "wb") as f:
            np.save(f, bad)
        with pytest.raises(FileFormatError, match="real numeric"):
            read_comma2k19(seg3)


@pytest.mark.parametrize("damage", ["missing", "empty", "truncated", "pickled"])
@pytest.mark.parametrize("rel", ["processed_log/IMU/accelerometer/t", "processed_log/IMU/gyro/value",
                                 "processed_log/GNSS/live_gnss_ublox/t", "global_pose/frame_times",
                                 "global_pose/frame_gps_times", "global_pose/frame_positions"])
def test_a_damaged_file_of_a_segment_is_named(tmp_path, rel, damage):
    """Every file of a segment, missing or damaged, is named: an empty file (EOFError), a truncated or pickled one
    in global_pose ended in an internal error, a missing accelerometer/t in "not a ROS bag nor a PX4 ULog"."""
    from typer.testing import CliRunner

    from imunav.cli.main import app

    seg = _synthetic(tmp_path / "seg")
    p = seg / rel
    if damage == "missing":
        p.unlink()
    elif damage == "empty":
        p.write_bytes(b"")
    elif damage == "truncated":
        p.write_bytes(p.read_bytes()[:-40])
    else:
        with open(p, "wb") as f:
            np.save(f, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    assert is_comma2k19_segment(seg)
    read = read_comma2k19_pose if rel in ("global_pose/frame_positions",) else read_comma2k19
    with pytest.raises(FileFormatError) as e:
        read(seg)
    msg = str(e.value)
    assert (f"{seg}: the comma2k19 segment has no {rel}" if damage == "missing" else f"{p}: not a NumPy array "
            "file") in msg, msg
    r = CliRunner().invoke(app, ["gins", "run", str(seg), "--out", str(tmp_path / "o"), "--truth", str(seg)])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and rel in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()
