"""Navigation sources from logs (imunav.io.navlog): the robot scenario written as bags and read back,
GNSS receiver faults, topic choice and its one-line errors, and the shared real logs.

The scenario bags are written by imunav's own writer from :mod:`imunav.sim.robot_log`; the frame and
unit conversions of that writer/reader pair are checked against REP-103 physics in ``test_io_rosbag``.
Here the round trip must give back exactly what was written, and the mounting in ``/tf_static`` must be
the truth's.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from shared_data import data_path

from imunav import earth
from imunav.atmosphere import isa, pressure_altitude
from imunav.errors import ConfigError, FileFormatError, InvalidInputError
from imunav.io.aiding import MagnetometerData
from imunav.io.gnss import GnssData, read_gnss_text
from imunav.io.kfgins import read_kfgins_imu
from imunav.io.navlog import choose_nav_topics, gnss_fixes, nav_topics, read_nav_sources
from imunav.io.rosbag import write_bag
from imunav.io.topics import TopicData, topic_data
from imunav.io.ulog import read_px4_groundtruth
from imunav.rotation import dcm_from_quat
from imunav.sim.robot_log import C_BASE_IMU, ROBOT_T0_NS, simulate_robot_log, write_robot_log

pytest.importorskip("rosbags")


@pytest.fixture(scope="module")
def robot(tmp_path_factory):
    log = simulate_robot_log(1, distance_m=80.0)  # one loop: the round trip does not need 400 m
    out = write_robot_log(log, tmp_path_factory.mktemp("robot"), static_tf=True)
    return log, out


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_robot_bag_round_trip(robot, fmt):
    log, out = robot
    s = read_nav_sources(out[fmt])
    assert s.t0_ns == ROBOT_T0_NS and s.time_is_utc and s.t0_unix == ROBOT_T0_NS * 1e-9
    # stamps are integer ns: t comes back within the rounding of t * 1e9 (0.5 ns) plus float64 of t
    np.testing.assert_allclose(s.imu.t, log.imu.t, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(s.imu.gyro, log.imu.gyro)  # FRD -> FLU -> FRD: sign flips, exact
    np.testing.assert_array_equal(s.imu.accel, log.imu.accel)
    np.testing.assert_allclose(s.gnss.t, log.gnss.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(s.gnss.lla[:, :2], log.gnss.lla[:, :2], rtol=0, atol=1e-15)  # rad -> deg -> rad
    np.testing.assert_array_equal(s.gnss.lla[:, 2], log.gnss.lla[:, 2])
    np.testing.assert_allclose(s.gnss.pos_std, log.gnss.pos_std, rtol=1e-15)  # sqrt(sigma^2)
    np.testing.assert_allclose(s.odometer.t, log.odometer.t, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(s.odometer.speed, log.odometer.speed)
    np.testing.assert_allclose(s.odometer.speed_std, log.odometer.speed_std, rtol=1e-15)
    assert s.mag is None and s.baro is None and s.meta["mag"] == "no magnetometer topic in the log"
    assert {k: (v.topic, v.count, v.used) for k, v in s.topics.items()} == {
        "imu": ("/imu/data", log.imu.n, log.imu.n), "gnss": ("/gps/fix", log.gnss.n, log.gnss.n),
        "odometer": ("/odom", log.odometer.t.size, log.odometer.t.size)}
    assert s.gnss.meta["faults"] == {"no_fix": 0, "no_solution": 0, "covariance_unknown": 0,
                                     "covariance_not_positive": 0, "duplicate_stamp": 0, "out_of_order": 0,
                                     "sigma_assumed": 0}
    # the mounting from /tf_static is the truth's
    np.testing.assert_allclose(dcm_from_quat(s.imu_to_base), C_BASE_IMU, atol=1e-15)
    np.testing.assert_array_equal(s.imu_lever_base, np.zeros(3))
    # GPS time of the first row: 2024-05-14T09:30:00Z + 18 s, week 2314 (started 2024-05-12 GPS)
    g = s.gps_time([0.0])
    assert g.week[0] == 2314 and g.sow[0] == pytest.approx(2 * 86400 + 9.5 * 3600 + 18, abs=1e-6)
    assert s.to_dict()["sources"]["gnss"]["rate_hz"] == pytest.approx(2.5, rel=1e-9)


def test_robot_kfgins_text_is_the_same_drive(robot):
    """The drive's KF-GINS text folder (sources.toml) read as a log gives the bags' sources: the same stamps to the
    nanosecond, the same fixes, speeds and sigmas bit for bit, the IMU rates within one ulp (increment = rate x
    interval, read back as increment / interval), the same UTC origin."""
    log, out = robot
    s = read_nav_sources(out["ros1"])
    k = read_nav_sources(out["kfgins"])
    assert k.t0_ns == s.t0_ns and k.t0_unix == s.t0_unix and k.time_is_utc
    for a, b in ((k.imu.t, s.imu.t), (k.gnss.t, s.gnss.t), (k.gnss.lla, s.gnss.lla), (k.gnss.pos_std, s.gnss.pos_std),
                 (k.odometer.t, s.odometer.t), (k.odometer.speed, s.odometer.speed),
                 (k.odometer.speed_std, s.odometer.speed_std)):
        np.testing.assert_array_equal(a, b)
    ulp = np.spacing(np.abs(s.imu.accel))
    assert np.all(np.abs(k.imu.accel - s.imu.accel) <= ulp) and np.all(np.abs(k.imu.gyro - s.imu.gyro)
                                                                        <= np.spacing(np.abs(s.imu.gyro)))
    assert {r: (v.topic, v.used) for r, v in k.topics.items()} == {
        "imu": ("imu.txt", log.imu.n), "gnss": ("gnss.txt", log.gnss.n), "odometer": ("odo.txt", log.odometer.t.size)}
    assert k.gnss.meta["faults"] == s.gnss.meta["faults"] and k.imu_to_base is None  # no /tf_static in text
    inc = read_kfgins_imu(out["kfgins"] / "imu.txt")  # still a KF-GINS file for any KF-GINS reader
    assert inc.n == log.imu.n and read_gnss_text(out["kfgins"] / "gnss.txt").n == log.gnss.n


def test_kfgins_text_log_refusals(robot, tmp_path):
    """A text folder names its files in sources.toml: topic flags, unknown keys, no IMU, a bad week are refused;
    without gps_week the time is the files' own (not UTC)."""
    import shutil

    _, out = robot
    d = tmp_path / "text"
    shutil.copytree(out["kfgins"], d)
    with pytest.raises(InvalidInputError, match="--imu-topic"):
        read_nav_sources(d, imu_topic="/imu")
    cfg = (d / "sources.toml").read_text()
    for text, word in ((cfg + "\nspeed = 1\n", "unknown key"), (cfg.replace('imu = "imu.txt"', ""), "imu ="),
                       (cfg.replace("gps_week = 2314", "gps_week = -1"), "gps_week")):
        (d / "sources.toml").write_text(text)
        with pytest.raises(ConfigError, match=word):
            read_nav_sources(d)
    (d / "sources.toml").write_text(cfg.replace("gps_week = 2314", ""))
    k = read_nav_sources(d)
    assert not k.time_is_utc and k.gps_time([0.0]).sow[0] == pytest.approx(2 * 86400 + 9.5 * 3600 + 18, abs=1e-9)


def test_no_static_tf_leaves_the_mounting_to_estimate(robot, tmp_path):
    log, _ = robot
    p = write_robot_log(log, tmp_path, formats=("ros2",), ros2_storage="sqlite3")["ros2"]
    s = read_nav_sources(p)
    assert s.imu_to_base is None and s.meta["mounting"] == "no /tf_static in the bag"
    np.testing.assert_array_equal(s.imu.accel, log.imu.accel)


# -- GNSS receiver faults ---------------------------------------------------------------------------
def _gnss_topic(n: int = 10, t0_ns: int = ROBOT_T0_NS) -> dict:
    return {"lat_deg": np.full(n, 48.1), "lon_deg": np.linspace(11.5, 11.5001, n), "alt_m": np.full(n, 500.0),
            "fix_status": np.zeros(n, dtype=np.int8), "pos_cov_enu_diag": np.full((n, 3), 0.64),
            "pos_cov_type": np.full(n, 2, dtype=np.uint8)}


def test_gnss_faults_refused_and_counted_through_a_bag(robot, tmp_path):
    log, _ = robot
    v = _gnss_topic()
    v["fix_status"][[1, 2]] = -1                      # no fix
    v["pos_cov_type"][3] = 0                          # covariance of unknown type
    v["pos_cov_enu_diag"][4] = 0.0                    # zero covariance
    v["lat_deg"][5] = np.nan                          # a fix without a solution
    t = np.arange(10) * 0.4
    gn = TopicData("/gps/fix", "gnss", t, v, {}, meta={"t0_ns": ROBOT_T0_NS})
    p = write_bag(tmp_path / "f.bag", {"/imu/data": log.imu, "/gps/fix": gn}, storage="ros1")
    s = read_nav_sources(p)
    f = s.gnss.meta["faults"]
    assert (f["no_fix"], f["no_solution"], f["covariance_unknown"], f["covariance_not_positive"]) == (2, 1, 1, 1)
    np.testing.assert_allclose(s.gnss.t, t[[0, 6, 7, 8, 9]], atol=1e-9)
    assert sum(r["epochs"] for r in s.meta["gnss"]["removed"]) == 5
    # with a sigma for fixes without a covariance, those two are kept and marked
    s2 = read_nav_sources(p, gnss_pos_std=1.5)
    assert s2.gnss.meta["faults"]["sigma_assumed"] == 2 and s2.gnss.n == 7
    np.testing.assert_array_equal(s2.gnss.pos_std[[1, 2]], 1.5)


def test_gnss_duplicated_and_out_of_order_stamps():
    v = _gnss_topic(6)
    v["lon_deg"][3] = 11.6  # the re-published fix (same stamp) differs: the first is kept
    stamps = ROBOT_T0_NS + np.array([0, 400, 800, 800, 1600, 1200]) * 1_000_000
    with pytest.warns(UserWarning, match="go backwards"):
        td = topic_data("/gps/fix", "gnss", stamps, v, {}, "mem", duplicates="drop")
    g = gnss_fixes(td, ROBOT_T0_NS)
    assert g.meta["faults"]["duplicate_stamp"] == 1 and g.meta["faults"]["out_of_order"] == 1
    np.testing.assert_allclose(g.t, [0.0, 0.4, 0.8, 1.2, 1.6], atol=1e-12)
    assert np.degrees(g.lla[2, 1]) == pytest.approx(v["lon_deg"][2], abs=1e-12)


# -- topic choice and bad input: one line, imunav.errors ---------------------------------------------
def _one_line(e: pytest.ExceptionInfo) -> str:
    msg = str(e.value)
    assert "\n" not in msg
    return msg


def test_log_without_imu(tmp_path):
    gn = GnssData(np.arange(5.0), np.tile([0.84, 0.2, 500.0], (5, 1)), (1.0, 1.0, 1.0), meta={"t0_ns": ROBOT_T0_NS})
    p = write_bag(tmp_path / "g.bag", {"/gps/fix": gn}, storage="ros1")
    with pytest.raises(FileFormatError) as e:
        read_nav_sources(p)
    assert "no IMU topic" in _one_line(e) and "/gps/fix (sensor_msgs/msg/NavSatFix)" in str(e.value)


def test_two_gnss_topics_need_a_choice(robot, tmp_path):
    log, _ = robot
    p = write_bag(tmp_path / "two", {"/imu/data": log.imu, "/gps/fix": log.gnss, "/rtk/fix": log.gnss})
    assert [i.topic for i in nav_topics(p)["gnss"]] == ["/gps/fix", "/rtk/fix"]
    with pytest.raises(InvalidInputError) as e:
        read_nav_sources(p)
    msg = _one_line(e)
    assert "2 GNSS topics" in msg and "/gps/fix" in msg and "/rtk/fix" in msg and "--gnss-topic" in msg
    assert choose_nav_topics(p, gnss_topic="/rtk/fix")["gnss"].topic == "/rtk/fix"
    assert read_nav_sources(p, gnss_topic="/rtk/fix").topics["gnss"].topic == "/rtk/fix"
    with pytest.raises(InvalidInputError) as e:
        read_nav_sources(p, gnss_topic="/imu/data")
    assert "--gnss-topic '/imu/data': not a GNSS topic" in _one_line(e)


def test_gnss_without_a_valid_fix(robot, tmp_path):
    log, _ = robot
    v = _gnss_topic()
    v["fix_status"][:] = -1
    gn = TopicData("/gps/fix", "gnss", np.arange(10) * 0.4, v, {}, meta={"t0_ns": ROBOT_T0_NS})
    p = write_bag(tmp_path / "nofix", {"/imu/data": log.imu, "/gps/fix": gn}, storage="sqlite3")
    with pytest.raises(InvalidInputError) as e:
        read_nav_sources(p)
    assert "none of its 10 fixes is usable (no fix: 10)" in _one_line(e)


def test_stamps_that_never_overlap_the_imu(robot, tmp_path):
    log, _ = robot
    late = GnssData(log.gnss.t, log.gnss.lla, log.gnss.pos_std, meta={"t0_ns": ROBOT_T0_NS + 10**13})
    p = write_bag(tmp_path / "late", {"/imu/data": log.imu, "/gps/fix": late})
    with pytest.raises(InvalidInputError) as e:
        read_nav_sources(p)
    assert "never overlap" in _one_line(e) and "--gnss-topic" in str(e.value)


# -- real logs ----------------------------------------------------------------------------------------
def test_jackal_bag_imu_and_odometry_without_gnss():
    p = data_path("ros_bags", "jackal_test2.bag")
    s = read_nav_sources(p)
    assert s.topics["imu"].topic == "/imu/data" and s.topics["odometer"].topic == "/jackal_velocity_controller/odom"
    assert s.gnss is None and s.meta["gnss"] == "no GNSS topic in the log"
    assert s.odometer.t.size == 3060 and s.odometer.speed_std is not None
    np.testing.assert_allclose(s.odometer.speed_std, np.sqrt(0.001))  # the driver's fixed twist covariance
    assert np.max(np.abs(s.odometer.speed)) < 2.0  # a Jackal drives under 2 m/s
    assert not s.time_is_utc and s.t0_unix is None  # the robot's clock starts at boot
    g = s.gps_time([0.0])
    assert not g.is_utc and g.week[0] == 0 and g.sow[0] == pytest.approx(s.t0_ns * 1e-9)
    # at rest at the start the IMU (frame base_link) reads gravity up, FRD z negative
    assert s.imu.accel[:50].mean(axis=0)[2] == pytest.approx(-9.8, abs=0.3)


def test_px4_logs_gps_mag_baro():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s0 = read_nav_sources(data_path("px4_ulog", "sample.ulg"))
    assert s0.gnss is None and s0.meta["logger_dropouts"]["count"] == 4
    s = read_nav_sources(data_path("px4_ulog", "sample_log_small.ulg"))
    assert s.topics["gnss"].topic == "vehicle_gps_position" and s.gnss.n == 32
    assert s.gnss.vel_ned is not None and s.meta["logger_dropouts"] == {"count": 1, "total_ms": 30.0,
                                                                        "longest_ms": 30.0}
    # 2021-04-21 UTC from the receiver, leap 18 s
    assert s.time_is_utc and s.t0_unix == pytest.approx(1618986658.47, abs=0.05)
    np.testing.assert_allclose(s.gnss.pos_std[0], [3.26, 3.26, 6.984], rtol=1e-6)  # eph, eph, epv
    assert np.degrees(s.gnss.lla[0, 0]) == pytest.approx(63.4170622, abs=1e-9)
    assert s.mag.field_b.shape[1] == 3 and 20 < np.median(np.linalg.norm(s.mag.field_b, axis=1)) < 70  # uT
    # ISA height of the static pressure against PX4's own baro_alt_meter (its QNH 1013.25 hPa = ISA)
    assert s.baro.height[0] == pytest.approx(86.15, abs=0.3)


def test_px4_sitl_gnss_against_groundtruth():
    p = data_path("px4_ulog", "sample_logging_tagged_and_default_params.ulg")
    s = read_nav_sources(p)
    assert s.gnss.meta["faults"]["no_fix"] == 160 and s.gnss.n == 30  # fix_type < 3 until the receiver settles
    ref = read_px4_groundtruth(p, t0_ns=s.t0_ns)
    assert ref.meta["missing"] == [] and not ref.meta["altitude_filled"]
    lat = np.interp(s.gnss.t, ref.t, ref.lla[:, 0])
    lon = np.interp(s.gnss.t, ref.t, ref.lla[:, 1])
    d = earth.dlla_to_ned(s.gnss.lla - np.column_stack([lat, lon, s.gnss.lla[:, 2]]), s.gnss.lla)
    horiz = np.linalg.norm(d[:, :2], axis=1)
    assert np.all(horiz < 3 * s.gnss.pos_std[:, 0] * np.sqrt(2))  # inside 3 sigma of the receiver's eph
    with pytest.raises(InvalidInputError, match="no vehicle_global_position_groundtruth"):
        read_px4_groundtruth(data_path("px4_ulog", "sample_log_small.ulg"))


def test_ros_magnetometer_and_barometer(robot, tmp_path):
    log, _ = robot
    t = np.arange(50) * 0.1
    mag = MagnetometerData(t, np.column_stack([20 + t, -3 + 0 * t, 40 - t]), {"t0_ns": ROBOT_T0_NS})
    p = 95000.0 + 10 * t
    baro = TopicData("/pressure", "pressure", t, {"pressure": p, "variance": np.full(t.size, 4.0)}, {},
                     meta={"t0_ns": ROBOT_T0_NS})
    path = write_bag(tmp_path / "mb.bag", {"/imu/data": log.imu, "/mag": mag, "/pressure": baro}, storage="ros1")
    s = read_nav_sources(path)
    np.testing.assert_allclose(s.mag.field_b, mag.field_b, rtol=1e-15)  # uT -> T -> uT
    np.testing.assert_allclose(s.baro.t, t, atol=1e-9)
    np.testing.assert_array_equal(s.baro.height, pressure_altitude(p))
    # sigma of the height from the pressure's: |dh/dp| * 2 Pa, dh/dp by central difference of the ISA
    h = pressure_altitude(p)
    dhdp = (pressure_altitude(p + 0.5) - pressure_altitude(p - 0.5)) / 1.0
    np.testing.assert_allclose(s.baro.height_std, 2.0 * np.abs(dhdp), rtol=1e-4)
    assert isa(h).pressure == pytest.approx(p, rel=1e-9)


def test_twist_stamped_odometry_when_the_bag_has_no_odometry(robot, tmp_path):
    log, _ = robot
    speeds = np.array([0.0, 0.5, 1.0, 0.75])
    t = 0.5 * np.arange(1, 5)
    tw = TopicData("/wheel/twist", "gnss_velocity", t, {"linear_raw": np.column_stack([speeds, 0 * t, 0 * t])}, {},
                   meta={"t0_ns": ROBOT_T0_NS})
    p = write_bag(tmp_path / "twist", {"/imu/data": log.imu, "/wheel/twist": tw}, frame_ids={"/wheel/twist": "base_link"})
    s = read_nav_sources(p)
    assert s.topics["odometer"].topic == "/wheel/twist" and s.odometer.speed_std is None
    np.testing.assert_array_equal(s.odometer.speed, speeds)
    np.testing.assert_allclose(s.odometer.t, t, atol=1e-9)
    assert "no covariance" in s.meta["odometer"]["speed"]
    # beside a nav_msgs/Odometry topic, the TwistStamped is no candidate (it may be a GNSS velocity) unless named
    p2 = write_bag(tmp_path / "both", {"/imu/data": log.imu, "/wheel/twist": tw, "/odom": log.odometer})
    assert read_nav_sources(p2).topics["odometer"].topic == "/odom"
    assert read_nav_sources(p2, odo_topic="/wheel/twist").odometer.t.size == 4
