"""KF-GINS text formats, the generic GNSS CSV reader and KF-GINS's YAML configuration.

Round trips are exact to the written precision (KF-GINS's ``%-15.9lf``: half a unit of the 9th decimal);
every refusal named by issue 15 has its test.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from imunav import earth
from imunav.errors import ConfigError, InvalidInputError, TimeOrderError
from imunav.io.gnss import GnssData, read_gnss_csv, read_gnss_text, read_table, write_gnss_text
from imunav.io.kfgins import (
    ImuIncrements,
    NavTrack,
    load_kfgins_config,
    read_kfgins_imu,
    read_kfgins_nav,
    write_kfgins_config,
    write_kfgins_imu,
    write_kfgins_imu_errors,
    write_kfgins_nav,
    write_kfgins_std,
)
from imunav.sim import ideal_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, vehicle_trajectory
from imunav.units import DEG

HALF_ULP = 0.5e-9  # half a unit of the 9th decimal written by %-15.9f
T0 = 456300.0  # seconds of week, as in KF-GINS's data set


@pytest.fixture(scope="module")
def drive():
    tr = vehicle_trajectory(demo_drive(180), fs=200, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.9), t0=T0)
    return tr, ideal_imu(tr)


def test_imu_increments_round_trip(tmp_path, drive):
    tr, imu = drive
    inc = ImuIncrements.from_imu_data(imu, 200.0)
    p = write_kfgins_imu(tmp_path / "imu.txt", inc)
    back = read_kfgins_imu(p, 200.0)
    assert back.n == tr.n and back.meta["n_gaps"] == 0
    np.testing.assert_allclose(back.t, inc.t, atol=HALF_ULP * 1.01, rtol=0)
    np.testing.assert_allclose(back.dtheta, inc.dtheta, atol=HALF_ULP * 1.01, rtol=0)
    np.testing.assert_allclose(back.dvel, inc.dvel, atol=HALF_ULP * 1.01, rtol=0)
    # mean rates over each interval: the cubic rule of the point rates inside, (-1, 13, 13, -1) / 24
    rates = back.to_imu_data()
    g = imu.gyro
    np.testing.assert_allclose(rates.gyro[2:-1], (-g[:-3] + 13 * g[1:-2] + 13 * g[2:-1] - g[3:]) / 24,
                               atol=2 * HALF_ULP * 200)
    assert not list(tmp_path.glob(".*tmp*"))  # written atomically: no temporary file left


def test_imu_file_refusals(tmp_path, drive):
    _, imu = drive
    inc = ImuIncrements.from_imu_data(imu, 200.0)
    p = write_kfgins_imu(tmp_path / "imu.txt", inc)
    with pytest.raises(InvalidInputError, match="declared rate is 100 Hz"):
        read_kfgins_imu(p, 100.0)  # the rate does not match the time stamps (5 ms steps)
    rates = ImuIncrements(inc.t, imu.gyro, imu.accel, inc.dt)  # rates written where increments belong
    with pytest.raises(InvalidInputError, match="not increments"):
        read_kfgins_imu(write_kfgins_imu(tmp_path / "rates.txt", rates), 200.0)
    lines = p.read_text().splitlines()
    lines[10], lines[11] = lines[11], lines[10]
    (tmp_path / "swapped.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(TimeOrderError, match="row 12"):
        read_kfgins_imu(tmp_path / "swapped.txt", 200.0)


def test_gnss_text_round_trip_7_and_13_columns(tmp_path, drive):
    tr, _ = drive
    g = simulate_gnss(tr, rng=1)
    p = write_gnss_text(tmp_path / "gnss.txt", g)
    assert read_table(p, (13,), "x").shape == (g.n, 13)
    back = read_gnss_text(p)
    np.testing.assert_allclose(np.degrees(back.lla[:, :2]), np.degrees(g.lla[:, :2]), atol=HALF_ULP * 1.01, rtol=0)
    np.testing.assert_allclose(back.vel_ned, g.vel_ned, atol=HALF_ULP * 1.01, rtol=0)
    np.testing.assert_allclose(back.pos_std, g.pos_std, atol=HALF_ULP * 1.01, rtol=0)
    p7 = write_gnss_text(tmp_path / "gnss7.txt", simulate_gnss(tr, vel_noise=None, rng=1))
    b7 = read_gnss_text(p7)
    assert b7.vel_ned is None and b7.n == g.n


def _gnss_file(tmp_path, rows, name="g.txt"):
    p = tmp_path / name
    p.write_text("\n".join(" ".join(f"{v:.10f}" for v in r) for r in rows) + "\n")
    return p


def test_gnss_refusals(tmp_path):
    ok = [T0, 30.44, 114.47, 20.0, 0.01, 0.01, 0.02]
    nxt = [T0 + 1, 30.44, 114.47, 20.0, 0.01, 0.01, 0.02]
    with pytest.raises(TimeOrderError, match="row 1"):
        read_gnss_text(_gnss_file(tmp_path, [nxt, ok]))  # non-monotonic time
    with pytest.raises(TimeOrderError):
        read_gnss_text(_gnss_file(tmp_path, [ok, ok]))  # duplicate epoch
    with pytest.raises(InvalidInputError, match="out of range"):
        read_gnss_text(_gnss_file(tmp_path, [ok, [T0 + 1, 95.0, 114.47, 20, 0.01, 0.01, 0.02]]))
    rad = [[T0, 0.5313, 1.9979, 20, 0.01, 0.01, 0.02], [T0 + 1, 0.5313, 1.9979, 20, 0.01, 0.01, 0.02]]
    with pytest.raises(InvalidInputError, match="look like radians"):
        read_gnss_text(_gnss_file(tmp_path, rad))
    assert read_gnss_text(_gnss_file(tmp_path, rad), angle_unit="rad").lla[0, 0] == pytest.approx(0.5313)
    assert read_gnss_text(_gnss_file(tmp_path, rad), angle_unit="deg_small").lla[0, 0] == pytest.approx(0.5313 * DEG)
    with pytest.raises(InvalidInputError, match="must be > 0"):
        read_gnss_text(_gnss_file(tmp_path, [ok, [T0 + 1, 30.44, 114.47, 20, 0.01, 0.0, 0.02]]))  # sigma = 0
    with pytest.raises(InvalidInputError, match="must be > 0"):
        read_gnss_text(_gnss_file(tmp_path, [ok, [T0 + 1, 30.44, 114.47, 20, 0.01, -0.1, 0.02]]))


def test_gnss_outside_the_imu_span_is_refused_and_partial_overlap_recorded():
    t = T0 + np.arange(10.0)
    g = GnssData(t, np.tile([30.44 * DEG, 114.47 * DEG, 20.0], (10, 1)), (0.01, 0.01, 0.02))
    with pytest.raises(InvalidInputError, match="outside the IMU span"):
        g.within(T0 + 100.0, T0 + 200.0)
    part = g.within(T0 + 4.5, T0 + 200.0)
    assert part.n == 5 and part.meta["removed"][0]["epochs"] == 5


def test_gnss_csv_reader(tmp_path):
    p = tmp_path / "fix.csv"
    p.write_text("time,la,lo,alt,sn,se,sd\n# a comment\n10,30.44,114.47,20,0.5,0.5,1\n11,30.4400001,114.47,20,0.5,0.5,1\n")
    g = read_gnss_csv(p, time="time", lat="la", lon="lo", height="alt", pos_std=("sn", "se", "sd"))
    assert g.n == 2 and g.lla[1, 0] == pytest.approx(30.4400001 * DEG, abs=1e-15)
    d = earth.lla_to_ned(g.lla[1], g.lla[0])
    assert d[0] == pytest.approx(1e-7 * DEG * (earth.radii(g.lla[0, 0])[0] + 20.0), rel=1e-6)  # 1.1 cm north
    with pytest.raises(InvalidInputError, match="not radians"):
        read_gnss_csv(p, time="time", lat="la", lon="lo", height="alt", pos_std=("sn", "se", "sd"), angle_unit="rad")
    with pytest.raises(InvalidInputError, match="no column"):
        read_gnss_csv(p)
    with pytest.raises(InvalidInputError, match="sigma"):
        read_gnss_csv(p, time="time", lat="la", lon="lo", height="alt", pos_std=None)


def test_nav_round_trip(tmp_path, drive):
    tr, _ = drive
    nav = NavTrack(tr.t[::100], tr.pos_lla[::100], tr.vel_ned[::100], tr.q_nb[::100], week=2198)
    back = read_kfgins_nav(write_kfgins_nav(tmp_path / "truth.nav", nav))
    assert back.week == 2198
    np.testing.assert_allclose(np.degrees(back.lla[:, :2]), np.degrees(nav.lla[:, :2]), atol=HALF_ULP * 1.01, rtol=0)
    np.testing.assert_allclose(np.degrees(back.euler()), np.degrees(nav.euler()), atol=HALF_ULP * 1.01, rtol=0)


def test_imu_error_and_std_files_are_in_kfgins_units(tmp_path):
    t = np.array([T0, T0 + 1])
    ones = np.ones((2, 3))
    p = write_kfgins_imu_errors(tmp_path / "err.txt", t, 0.027 * DEG / 3600 * ones, 15e-5 * ones, 300e-6 * ones,
                                -50e-6 * ones)
    a = read_table(p, (13,), "x")
    np.testing.assert_allclose(a[0], [T0, *[0.027] * 3, *[15.0] * 3, *[300.0] * 3, *[-50.0] * 3], atol=1e-9)
    p = write_kfgins_std(tmp_path / "std.txt", t, ones, 0.1 * ones, 0.01 * DEG * ones, 0.027 * DEG / 3600 * ones,
                         15e-5 * ones, 300e-6 * ones, 300e-6 * ones)
    a = read_table(p, (22,), "x")
    np.testing.assert_allclose(a[1], [T0 + 1, 1, 1, 1, .1, .1, .1, .01, .01, .01, *[0.027] * 3, *[15.0] * 3,
                                      *[300.0] * 6], atol=1e-9)


# KF-GINS's dataset/kf-gins.yaml (i2Nav-WHU/KF-GINS), keys and values as published
KFGINS_YAML = """\
imupath: "./dataset/Leador-A15.txt"
gnsspath: "./dataset/GNSS-RTK.txt"
outputpath: "./dataset"
imudatalen: 7
imudatarate: 200
starttime: 456300
endtime: -1
initpos: [ 30.4447873701, 114.4718632047, 20.899 ]
initvel: [ 0.0, 0.0, 0.0 ]
initatt: [ 0.85421502, -2.03480295, 185.70235133 ]
initgyrbias: [ 0, 0, 0 ]    # [deg/h]
initaccbias: [ 0, 0, 0 ]    # [mGal]
initgyrscale: [ 0, 0, 0 ]   # [ppm]
initaccscale: [ 0, 0, 0 ]   # [ppm]
initposstd: [ 0.005, 0.004, 0.008 ]
initvelstd: [ 0.003, 0.004, 0.004 ]
initattstd: [ 0.003, 0.003, 0.023 ]
#initbgstd: [ 1, 1, 1 ]          # [deg/h]
imunoise:
  arw: [0.003, 0.003, 0.003]          # [deg/sqrt(hr)]
  vrw: [0.03, 0.03, 0.03]          # [m/s/sqrt(hr)]
  gbstd: [0.027, 0.027, 0.027]        # [deg/hr]
  abstd: [15.0, 15.0, 15.0]     # [mGal]
  gsstd: [300.0, 300.0, 300.0]  # [ppm]
  asstd: [300.0, 300.0, 300.0]  # [ppm]
  corrtime: 4.0                    # [hr]
antlever:  [ 0.136, -0.301, -0.184 ]
"""


def test_kfgins_yaml_is_read_in_si(tmp_path):
    pytest.importorskip("yaml")
    d = tmp_path / "run"
    d.mkdir()
    p = d / "kf-gins.yaml"
    p.write_text(KFGINS_YAML + "odopath: odo.txt\n")
    c = load_kfgins_config(p)
    assert c.imu_path == d.resolve() / "dataset" / "Leador-A15.txt"  # relative to the YAML file
    assert c.output_path == d.resolve() / "dataset"
    assert c.imu_rate_hz == 200 and c.imu_columns == 7 and c.start_time == 456300 and c.end_time is None
    np.testing.assert_allclose(c.init_lla, [30.4447873701 * DEG, 114.4718632047 * DEG, 20.899], rtol=1e-15)
    np.testing.assert_allclose(c.init_euler[2], 185.70235133 * DEG, rtol=1e-15)
    np.testing.assert_allclose(c.imu_noise_model.gyro_noise_density, 0.003 * DEG / 60)  # deg/sqrt(h) -> rad/sqrt(s)
    np.testing.assert_allclose(c.imu_noise_model.accel_noise_density, 0.03 / 60)  # m/s/sqrt(h) -> m/s/sqrt(s)
    np.testing.assert_allclose(c.imu_noise_model.gyro_bias_std, 0.027 * DEG / 3600)
    np.testing.assert_allclose(c.imu_noise_model.accel_bias_std, 15e-5)  # mGal
    np.testing.assert_allclose(c.imu_noise_model.gyro_scale_std, 300e-6)
    assert c.imu_noise_model.corr_time == 4 * 3600.0
    # initbgstd ... absent: KF-GINS takes the imunoise sigmas
    np.testing.assert_allclose(c.init_gyro_bias_std, c.imu_noise_model.gyro_bias_std)
    np.testing.assert_allclose(c.init_accel_scale_std, c.imu_noise_model.accel_scale_std)
    np.testing.assert_allclose(c.init_att_std, np.array([0.003, 0.003, 0.023]) * DEG)
    np.testing.assert_allclose(c.antenna_lever_arm, [0.136, -0.301, -0.184])
    assert c.options == {"odopath": "odo.txt"}


def test_kfgins_yaml_writer_round_trips(tmp_path):
    """write_kfgins_config is the inverse of load_kfgins_config: every field back to 10 significant digits (the
    initial latitude / longitude to 1e-10 deg, the attitude to 1e-8 deg), paths relative to the YAML."""
    pytest.importorskip("yaml")
    d = tmp_path / "run"
    d.mkdir()
    (d / "kf-gins.yaml").write_text(KFGINS_YAML.replace("endtime: -1", "endtime: 457000.5"))
    a = load_kfgins_config(d / "kf-gins.yaml")
    out = tmp_path / "copy" / "written.yaml"
    out.parent.mkdir()
    write_kfgins_config(out, a, comment="a copy")
    b = load_kfgins_config(out)
    assert out.read_text().startswith("# a copy\n") and "../run/dataset/Leador-A15.txt" not in out.read_text()
    assert b.imu_path == a.imu_path and b.output_path == a.output_path and b.end_time == 457000.5
    for name in ("init_vel", "init_gyro_bias", "init_pos_std", "init_vel_std", "init_att_std", "init_gyro_bias_std",
                 "init_accel_bias_std", "init_gyro_scale_std", "init_accel_scale_std", "antenna_lever_arm"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-10, err_msg=name)
    for name in ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std", "gyro_scale_std", "accel_scale_std"):
        np.testing.assert_allclose(getattr(b.imu_noise_model, name), getattr(a.imu_noise_model, name), rtol=1e-10, err_msg=name)
    np.testing.assert_allclose(b.init_lla[:2], a.init_lla[:2], rtol=0, atol=1e-10 * DEG)
    np.testing.assert_allclose(b.init_euler, a.init_euler, rtol=0, atol=1e-8 * DEG)
    assert (b.imu_rate_hz, b.imu_columns, b.start_time, b.imu_noise_model.corr_time) == (a.imu_rate_hz, a.imu_columns,
                                                                                 a.start_time, a.imu_noise_model.corr_time)


@pytest.mark.parametrize(
    "old, new, match",
    [
        ("initposstd: [ 0.005, 0.004, 0.008 ]", "initposstd: [ 0.005, 0.0, 0.008 ]", "must be > 0"),
        ("  arw: [0.003, 0.003, 0.003]", "  arw: [0.003, -0.003, 0.003]", "must be > 0"),
        ("  corrtime: 4.0", "  corrtime: 0", "correlation time"),
        ("initpos: [ 30.4447873701, 114.4718632047, 20.899 ]", "initpos: [ 0.5314, 1.9979, 20.899 ]", "radians"),
        ("initpos: [ 30.4447873701, 114.4718632047, 20.899 ]", "initpos: [ 130.44, 114.47, 20.899 ]", "out of range"),
        ("antlever:  [ 0.136, -0.301, -0.184 ]", "antlever:  [ 0.136, -0.301 ]", "3 finite numbers"),
        ("imudatarate: 200", "imudatarate: 0", "imudatarate"),
        ("starttime: 456300", "starttime: 756300", "second of week"),
        ("endtime: -1", "endtime: 456000", "after starttime"),
        ("imupath: \"./dataset/Leador-A15.txt\"\n", "", "imupath"),
    ],
)
def test_kfgins_yaml_refusals(tmp_path, old, new, match):
    pytest.importorskip("yaml")
    assert old in KFGINS_YAML
    p = tmp_path / "kf-gins.yaml"
    p.write_text(KFGINS_YAML.replace(old, new))
    with pytest.raises(InvalidInputError, match=match) as e:
        load_kfgins_config(p)
    assert isinstance(e.value, (ConfigError, InvalidInputError))


def test_yaml_that_is_not_a_mapping(tmp_path):
    pytest.importorskip("yaml")
    p = tmp_path / "x.yaml"
    p.write_text(textwrap.dedent("- a\n- b\n"))
    with pytest.raises(ConfigError, match="mapping"):
        load_kfgins_config(p)
