"""GNSS/INS on a robot's log (issue 24): the simulated ground robot (consumer IMU at 30 Hz mounted x right, y up,
z backward; odometry at 10 Hz reading 9 % short; GNSS at 2.5 Hz, σ 0.8 m, 0.15 s late, 2 % of fixes jumping 10-30
m) written as a ROS 1 and a ROS 2 bag and run through ``imunav gins run`` with its defaults; the real Jackal bag
and the PX4 SITL log of the shared data; the command's refusals.

The defaults (rest detection, mounting σ floor, NHC σ, odometer σ floor, latency prior) were chosen on the robot
scenario's seed 0; the figures asserted here are on seeds 1 and 2.
"""

from __future__ import annotations

import dataclasses
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from cli_contract import invoke, one_error_line
from shared_data import data_path

from imunav.earth import lla_to_ned
from imunav.ins.gins.layout import LAY
from imunav.ins.gins.logrun import LogRunOptions, log_outage_test, run_log
from imunav.ins.gins.outputs import HONESTY_LIMITS, honesty, log_summary, run_summary, self_calibration
from imunav.ins.gins.smoother import forward_backward_separation
from imunav.ins.gins.truth import navigation_errors, nees_blocks
from imunav.io.aiding import OdometerData
from imunav.io.kfgins import read_kfgins_nav, write_kfgins_nav
from imunav.io.logs import TopicData
from imunav.io.navlog import read_nav_sources
from imunav.io.rosbag import StaticTransform, write_bag
from imunav.rotation import dcm_from_quat, euler_from_quat, quat_from_euler, quat_multiply
from imunav.sim.hard_log import simulate_hard_robot_log
from imunav.sim.log_faults import LogFaults
from imunav.sim.robot_log import simulate_robot_log, write_robot_log

SEEDS = (1, 2)


@pytest.fixture(scope="module", params=SEEDS)
def robot(request, tmp_path_factory):
    """A seeded robot log as ROS 1 and ROS 2 bags, and the command's outputs on the ROS 1 bag."""
    log = simulate_robot_log(request.param)
    d = tmp_path_factory.mktemp(f"robot{request.param}")
    write_robot_log(log, d, formats=("ros1", "ros2", "kfgins"))
    r = invoke("gins", "run", d / "robot.bag", "--gnss-lever-arm", "0,0,-0.3", "--out", d / "run", "--no-plots")
    assert r.exit_code == 0, r.stderr
    summary = json.loads((d / "run" / "summary.json").read_text())
    return log, d, summary


def _angle_errors_deg(q_est, q_true):
    """Small rotation between two mountings, about the vehicle axes, deg."""
    E = dcm_from_quat(q_est) @ dcm_from_quat(q_true).T
    return np.degrees([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]) / 2


def test_mounting_odometer_scale_and_latency_are_found(robot):
    """Mounting within 1 deg (roll, pitch) and 2 deg (yaw) of the truth and inside its reported 3 sigma; odometer
    scale within 0.5 % of the truth (9 % short); GNSS latency inside its 3 sigma of the truth (0.15 s), that sigma
    at most 50 ms."""
    log, _, s = robot
    tr = log.truth
    m = s["mounting"]
    assert m["source"] == "estimated"
    est = np.radians([m["roll_deg"], m["pitch_deg"], m["yaw_deg"]])
    err = np.degrees(np.remainder(est - np.radians(tr.mounting_euler_deg) + np.pi, 2 * np.pi) - np.pi)
    sd = np.array(m["std_deg"])
    print(f"mounting error roll / pitch / yaw {err.round(3)} deg, sigma {sd.round(3)}")
    assert abs(err[0]) < 1.0 and abs(err[1]) < 1.0 and abs(err[2]) < 2.0
    assert np.all(np.abs(err) < 3 * sd)
    k = s["odometer_scale"]
    print(f"odometer scale {1 + k['value']:.5f} +- {k['std']:.5f} (truth {tr.odometer_scale})")
    assert abs((1 + k["value"]) / tr.odometer_scale - 1) < 0.005 and abs(1 + k["value"] - tr.odometer_scale) < 3 * k["std"]
    lat = s["gnss_time_offset_s"]
    print(f"GNSS latency {lat['value']:.4f} +- {lat['std']:.4f} s (truth {tr.gnss_latency_s})")
    # issue 33: inside 3σ of a reported σ <= 50 ms (the Cramér-Rao bound of this scenario is 24 ms: 20 ms of error
    # is beyond any estimator, benchmarks/bench_gins_latency_bound.py)
    assert abs(lat["value"] - tr.gnss_latency_s) < 3 * lat["std"] and lat["std"] <= 0.05


def test_track_is_within_half_a_metre_and_the_jumps_are_rejected(robot):
    """Horizontal RMSE against the truth <= 0.5 m; every jumping fix rejected by the gate, at most 1 % of the good
    ones; the summary counts them; the .nav holds GPS week and seconds of week of the log's UTC date."""
    log, d, s = robot
    nav = read_kfgins_nav(d / "run" / "KF_GINS_Navresult.nav")
    assert nav.week == 2314 and s["t0_unix"] == pytest.approx(log.truth.t0_ns * 1e-9)
    tr = log.truth.trajectory
    t = nav.t - nav.t[0]
    truth = np.column_stack([np.interp(t, tr.t, tr.pos_lla[:, j]) for j in range(3)])
    e = lla_to_ned(nav.lla, tr.pos_lla[0]) - lla_to_ned(truth, tr.pos_lla[0])
    rmse = math.sqrt(float(np.mean(e[:, 0] ** 2 + e[:, 1] ** 2)))
    print(f"horizontal RMSE {rmse:.3f} m")
    assert rmse <= 0.5
    geo = json.loads((d / "run" / "track.geojson").read_text())
    pts = [f for f in geo["features"] if f["geometry"]["type"] == "Point"]
    accepted = np.array([f["properties"]["accepted"] for f in pts], dtype=bool)
    outlier = log.truth.gnss_outlier
    assert accepted.size == outlier.size and geo["features"][0]["geometry"]["type"] == "LineString"
    assert not np.any(accepted[outlier]) and np.mean(~accepted[~outlier]) <= 0.01
    assert s["gnss_rejected"]["by_gate"] == int(np.sum(~accepted))


def test_outage_test_against_the_removed_fixes_and_against_the_truth(robot):
    """60 s outages every 120 s after 60 s (shifts 0, 30, 60 s).  Against the drive's truth (``--truth``, the
    KF-GINS .nav of the vehicle on GPS time): RMS of the end-of-outage horizontal error <= 3 m and <= 0.3 x that of
    the wheel-odometry dead reckoning (odometer as read, gyro heading from the filter's state at the outage's start),
    every outage inside its 3 sigma.  Against the removed fixes (no truth), every outage inside its 3 sigma with the
    fixes' own sigma, and the mean squared end error is the truth's plus the fixes' noise (0.8 m per axis: 1.13 m
    horizontal RMS): within three standard errors of that noise's mean square over the K outages
    (sigma_ref^2 / sqrt(K), its square being exponential), which a 1.5 m bias (a lever arm left out) would leave."""
    _, d, _ = robot
    common = ("--gnss-lever-arm", "0,0,-0.3", "--converge", "60", "--every", "120", "--length", "60", "--shifts",
              "0,30,60", "--quiet")
    r = invoke("gins", "outage-test", d / "robot.bag", *common, "--truth", d / "kfgins" / "truth.nav", "--out",
               d / "outage_truth")
    assert r.exit_code == 0, r.stderr
    t = json.loads((d / "outage_truth" / "outage.json").read_text())["rms"]
    print(f"outages against the truth: end RMS {t['end_m']:.3f} m, dead reckoning "
          f"{t['dead_reckoning_end_m']:.3f} m, ratio {t['ratio_to_dead_reckoning']:.3f}")
    assert t["reference"] == "truth" and t["reference_noise_m"] == 0.0 and t["n_outages"] >= 9
    assert t["end_m"] <= 3.0 and t["ratio_to_dead_reckoning"] <= 0.3 and t["contained_3sigma"] >= 0.9
    assert t["end_above_noise_m"] == t["end_m"]
    r = invoke("gins", "outage-test", d / "robot.bag", *common, "--out", d / "outage")
    assert r.exit_code == 0, r.stderr
    doc = json.loads((d / "outage" / "outage.json").read_text())
    f = doc["rms"]
    noise, k = f["reference_noise_m"], f["n_outages"]
    print(f"outages against the fixes: end RMS {f['end_m']:.3f} m (noise {noise:.2f} m), dead reckoning "
          f"{f['dead_reckoning_end_m']:.3f} m, ratio {f['ratio_to_dead_reckoning']:.2f}; above the noise "
          f"{f['end_above_noise_m']} m")
    # the fixes' noise as the run identified it: their reported 0.8 m (the adaptive factor stays 1 for a right σ)
    # and the correlated part the identification reads in white fixes' residuals (0.13 and 0.37 m per axis here)
    assert f["reference"] == "removed fixes" and k == t["n_outages"]
    assert 0.8 * math.sqrt(2) <= noise <= 1.15 * 0.8 * math.sqrt(2)
    assert f["end_m"] <= 3.0 and f["contained_3sigma"] == 1.0 and f["ratio_to_dead_reckoning"] < 1.0
    assert abs(f["end_m"] ** 2 - noise**2 - t["end_m"] ** 2) < 3 * noise**2 / math.sqrt(k)
    assert all(o["fixes"] >= 100 for o in doc["outages"])


def test_ros1_and_ros2_bags_give_the_same_trajectory(robot):
    _, d, _ = robot
    o = LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3))
    a = run_log(read_nav_sources(d / "robot.bag"), o).result
    b = run_log(read_nav_sources(d / "robot_ros2"), o).result
    np.testing.assert_allclose(a.t, b.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lla_to_ned(b.lla, a.lla[0]), lla_to_ned(a.lla, a.lla[0]), rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.q_nb, a.q_nb, rtol=0, atol=1e-12)


def test_kfgins_text_files_give_the_bags_trajectory(robot):
    """The same drive as KF-GINS text files (write_robot_log's "kfgins" folder: sources.toml, repr-exact values) run
    as a log through `imunav gins run FOLDER`: the trajectory of the ROS 1 bag's run to 1e-9 m (the IMU rates come
    back from the increments within one ulp; a latitude's ulp is 0.7 nm, and the positions agree within one of them
    on seeds 1-3), the same mounting, odometer scale and latency, and the same .nav file."""
    log, d, s_bag = robot
    (d / "text").mkdir()
    text = write_robot_log(log, d / "text", formats=("kfgins",))["kfgins"]
    r = invoke("gins", "run", text, "--gnss-lever-arm", "0,0,-0.3", "--out", d / "run_text", "--no-plots", "--quiet")
    assert r.exit_code == 0, r.stderr
    s_text = json.loads((d / "run_text" / "summary.json").read_text())
    for key in ("mounting", "odometer_scale", "gnss_time_offset_s", "gnss_rejected"):
        assert _close(s_text[key], s_bag[key]), (key, s_text[key], s_bag[key])
    assert s_text["t0_unix"] == s_bag["t0_unix"] and s_text["sources"]["sources"]["imu"]["topic"] == "imu.txt"
    a, b = (read_kfgins_nav(p / "KF_GINS_Navresult.nav") for p in (d / "run", d / "run_text"))
    assert a.week == b.week and np.array_equal(a.t, b.t)
    np.testing.assert_allclose(b.lla[:, :2], a.lla[:, :2], rtol=0, atol=2e-9 * math.pi / 180)  # the file's digits
    o = LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3))
    ra = run_log(read_nav_sources(d / "robot.bag"), o).result
    rt = run_log(read_nav_sources(text), o).result
    np.testing.assert_array_equal(rt.t, ra.t)
    np.testing.assert_allclose(lla_to_ned(rt.lla, ra.lla[0]), lla_to_ned(ra.lla, ra.lla[0]), rtol=0, atol=1e-9)
    # the same one-ulp inputs: measured 1.2e-12 on seed 2 since the process model's cross-validation, 6e-14 before
    np.testing.assert_allclose(rt.q_nb, ra.q_nb, rtol=0, atol=5e-12)


def _close(x, y):
    """Nested summary values equal to 1e-9 (relative) / 1e-12 (absolute)."""
    if isinstance(x, dict):
        return x.keys() == y.keys() and all(_close(x[k], y[k]) for k in x)
    if isinstance(x, list):
        return len(x) == len(y) and all(_close(u, v) for u, v in zip(x, y))
    if isinstance(x, float) and isinstance(y, float):
        return abs(x - y) <= 1e-12 + 1e-9 * abs(y)
    return x == y


@pytest.mark.data
def test_jackal_bag_dead_reckoning():
    """The real Jackal (IMU + wheel odometry, no GNSS, a clock from boot).  Its IMU's frame_id is base_link: the
    mounting is the identity (REP-105), with the levelling at rest reported beside it as a check (roll and pitch
    with sigma).  It turns on the spot at the start (zero speed, the wheels' yaw rate and the gyro at -2 deg/s):
    not a rest, so that turn does not become a gyro bias.  The dead reckoning ends 5.8 m from robot_localization's
    regression value for its EKF on this bag ((1.0206, 3.4292) m in its odom frame, FLU; a peer's output, not a
    truth, that trusts the wheels' speed at their driver's σ of 0.03 m/s; in-sample: the rest test and the frame_id
    rule were written while running this bag), where the wheel odometry's own pose ends 24 m away; the sources
    named, the time columns flagged as not UTC.  With the odometer's σ at the driver's (floored at 0.05 m/s), its
    forced updates at that σ and no side slip, as before, the end was 2.0 m from it: the end moves by metres with
    how much the wheels are trusted, a dead reckoning this bag does not pin down.  Its wheels spin and lock (1.98
    m/s for 3 s while the IMU shows the body decelerating): with the adaptive factor (σ × 16 at the end) the gate
    rejects 8.5 % of the odometer's updates (31 % before) and the forward-backward separation is 76 for 2 degrees
    of freedom (572 before), and the verdict still says the trajectory cannot be trusted."""
    p = data_path("ros_bags/jackal_test2.bag")
    src = read_nav_sources(p)
    run = run_log(src)
    assert run.mounting_source == "frame_id"
    c = run.mounting_coarse
    assert c is not None and np.all(np.isfinite(c.euler[:2])) and np.all((c.std[:2] > 0) & (c.std[:2] < np.radians(5)))
    res = run.result
    assert not run.static[: int(1.0 * 50)].any()  # turning on the spot, not at rest
    ned = lla_to_ned(res.lla, res.lla[0])
    d = math.hypot(ned[-1, 0] - 1.0206, ned[-1, 1] + 3.4292)  # FLU (x, y) -> NED (x, -y) at heading 0
    print(f"Jackal: end {ned[-1, :2].round(2)} m, {d:.2f} m from robot_localization's")
    assert d < 8.0
    sep = forward_backward_separation(res) if res.smoothed is not None else None
    verdict = honesty(run, sep)
    assert not verdict["trustworthy"]
    assert verdict["checks"]["odometer_rejected_share"] <= 0.1 and verdict["checks"]["separation_mean_d2"] < 100.0
    # issue 33: nothing measures the odometer's scale or the claimed mounting without GNSS: both keep their prior σ
    # (Schmidt consider states) and the position's σ carries them; the summary says they were not observed
    lay = run.state_layout()
    io = int(lay[LAY.odo_scale])
    assert res.odo_scale[-1] == 0.0 and math.sqrt(res.cov_diag[-1, io]) == pytest.approx(0.02, rel=1e-9)
    sc = self_calibration(run)
    assert sc["odometer_scale"]["observable"] is False and sc["mount_yaw"]["observable"] is False
    it = int(lay[LAY.odo_turn])  # the over-reading in turns too, at its prior 0 ± 0.3 s/rad
    assert res.odo_turn[-1] == 0.0 and math.sqrt(res.cov_diag[-1, it]) == pytest.approx(0.3, rel=1e-9)
    summary = log_summary(run, src)
    assert summary["odometer_scale"]["estimated"] is False and summary["odometer_turn_overread"]["estimated"] is False
    assert float(np.sqrt(res.cov_diag[-1, 0] + res.cov_diag[-1, 1])) > 0.4
    assert np.max(np.abs(res.vel_ned)) < 3.0  # the Jackal drives at up to 2 m/s
    assert set(src.topics) == {"imu", "odometer"} and not src.time_is_utc
    assert res.gnss_t.size == 0 and run.initial["heading"].startswith("dead-reckoning frame")


def test_turning_on_the_spot_is_not_rest(tmp_path):
    """A wheeled robot whose odometer reads no speed but a yaw rate turns on the spot: the samples there are not
    declared at rest (no ZUPT / ZARU, no gyro bias from them), while the same log without the yaw rate rests."""
    write_robot_log(simulate_robot_log(0, distance_m=80.0), tmp_path, formats=("ros1",))
    src = read_nav_sources(tmp_path / "robot.bag")
    o = src.odometer
    first = o.t < 8.0  # the drive starts with 10 s at rest
    spin = OdometerData(o.t, o.speed, o.meta, o.speed_std, np.where(first, -0.03, 0.0))
    a = run_log(src)
    b = run_log(dataclasses.replace(src, odometer=spin))
    n8 = int(np.searchsorted(src.imu.t, 8.0))
    assert a.static[:n8].mean() > 0.9 and not b.static[:n8].any()


@pytest.mark.parametrize("noise", [0.02, 0.05])
def test_rest_is_the_odometers_mean_speed_not_each_noisy_sample(tmp_path, noise):
    """An odometer whose readings at rest scatter with σ 0.02 or 0.05 m/s (what its covariance says): rest is
    decided on its 1 s mean speed within twice that mean's noise, so the whole of each stop is at rest and no
    sample where the robot moves faster than that limit, ``0.02 + 2σ/√10`` m/s (slower, the odometer cannot tell
    it from rest; the IMU must be quiet too).  A test of each sample against 0.02 m/s took a third to
    two thirds of each stop for rest, the samples whose noise happened to be small, and handed the odometer only
    its large errors at rest (its NIS at rest 1.3; the NHC's, at a standing robot, near 0)."""
    log = simulate_robot_log(4, distance_m=160.0, odometer_noise_std=noise)
    write_robot_log(log, tmp_path, formats=("ros1",))
    run = run_log(read_nav_sources(tmp_path / "robot.bag"), LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3)))
    tr = log.truth.trajectory
    speed = np.linalg.norm(tr.vel_ned, axis=1)
    t = tr.t - tr.t[0]
    rest = speed < 1e-9
    edges = np.flatnonzero(np.diff(np.r_[0, rest.astype(np.int8), 0]))
    inner = np.zeros_like(rest)  # each stop less 0.5 s at both ends (the mean's window reaches past them)
    for a, b in zip(edges[0::2], edges[1::2]):
        inner[a:b] = (t[a:b] > t[a] + 0.5) & (t[a:b] < t[b - 1] - 0.5)
    print(f"noise {noise}: at rest {run.static[inner].mean():.3f} of the stops, max speed at rest "
          f"{speed[run.static].max():.3f} m/s")
    assert inner.sum() > 500 and run.static[inner].mean() > 0.99
    assert speed[run.static].max() < 0.02 + 2.0 * noise / math.sqrt(10.0)
    # a placeholder covariance (σ 1000 m/s) does not make a smoothly cruising robot rest: the test caps σ at 0.1
    src = read_nav_sources(tmp_path / "robot.bag")
    o = src.odometer
    huge = run_log(dataclasses.replace(src, odometer=dataclasses.replace(o, speed_std=np.full(o.t.size, 1e3))),
                   LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3)))
    assert speed[huge.static].max() < 0.02 + 2.0 * 0.1 / math.sqrt(10.0)


@pytest.mark.data
def test_px4_sitl_log_agrees_with_its_ground_truth():
    """PX4 SITL log with vehicle_global_position_groundtruth: the run's horizontal position agrees with it."""
    from imunav.io.ulog import read_px4_groundtruth

    p = data_path("px4_ulog/sample_logging_tagged_and_default_params.ulg")
    src = read_nav_sources(p)
    res = run_log(src).result
    gt = read_px4_groundtruth(p, t0_ns=src.t0_ns)
    inside = (res.t >= gt.t[0]) & (res.t <= gt.t[-1])
    ref = np.array([gt.lla[0, 0], gt.lla[0, 1], 0.0])
    est = np.column_stack([res.lla[inside, :2], np.zeros(inside.sum())])
    tru = np.column_stack([np.interp(res.t[inside], gt.t, gt.lla[:, j]) for j in range(2)] + [np.zeros(inside.sum())])
    h = np.hypot(*(lla_to_ned(est, ref) - lla_to_ned(tru, ref))[:, :2].T)
    print(f"PX4 SITL: horizontal RMS {np.sqrt(np.mean(h**2)):.4f} m over {inside.sum()} samples")
    from imunav.ins.gins.outputs import log_summary

    rej = log_summary(run_log(src), src)["gnss_rejected"]
    assert rej["fixes"] == 190 and rej["by_reader"][0]["epochs"] == 160 and rej["share"] == pytest.approx(160 / 190)
    assert np.sqrt(np.mean(h**2)) < 0.1 and inside.sum() > 1000


def test_log_refusals(tmp_path):
    """One line and exit 2: a log without an IMU topic, two candidate IMU topics without a choice, a GNSS topic
    without a valid fix, odometry that never overlaps the IMU, a mounting flag that is not a rotation."""
    log = simulate_robot_log(0, distance_m=60.0)
    imu, gnss, odo = log.imu, log.gnss, log.odometer
    n = 10
    nofix = TopicData("/fix", "gnss", np.arange(n) * 0.4, {
        "lat_deg": np.full(n, 48.1), "lon_deg": np.full(n, 11.5), "alt_m": np.full(n, 500.0),
        "fix_status": np.full(n, -1, dtype=np.int8), "pos_cov_enu_diag": np.full((n, 3), 0.64),
        "pos_cov_type": np.full(n, 2, dtype=np.uint8)}, {}, meta={"t0_ns": imu.meta["t0_ns"]})
    cases = {
        "noimu.bag": ({"/odom": odo}, (), "IMU"),
        "nofix.bag": ({"/imu": imu, "/fix": nofix}, (), "fix"),
        "twoimu.bag": ({"/imu_a": imu, "/imu_b": imu, "/fix": gnss}, (), "--imu-topic"),
        "late.bag": ({"/imu": imu, "/odom": OdometerData(odo.t + 1e4, odo.speed, {}, odo.speed_std)}, (), "overlap"),
        "good.bag": ({"/imu": imu, "/fix": gnss, "/odom": odo}, ("--imu-rotation", "1,2,3,4"), "rotation"),
    }
    for name, (topics, extra, word) in cases.items():
        write_bag(tmp_path / name, topics, storage="ros1")
        line = one_error_line(invoke("gins", "run", tmp_path / name, "--out", tmp_path / f"o_{name}", *extra))
        assert word.lower() in line.lower(), (name, line)
        assert not (tmp_path / f"o_{name}").exists()
    line = one_error_line(invoke("gins", "run", tmp_path / "good.bag", "--out", tmp_path / "o", "--imu-rotation",
                                 "10,20"))
    assert "--imu-rotation" in line
    line = one_error_line(invoke("gins", "outage-test", tmp_path / "good.bag", "--seed", "3",
                                 "--out", tmp_path / "o2"))
    assert "--seed" in line and not (tmp_path / "o2").exists()
    line = one_error_line(invoke("gins", "outage-test", tmp_path / "good.bag", "--truth-std", "0.5",
                                 "--out", tmp_path / "o2"))
    assert "--truth" in line and not (tmp_path / "o2").exists()
    line = one_error_line(invoke("gins", "run", tmp_path / "good.bag", "--forward-only", "--smoother",
                                 "--out", tmp_path / "o2"))
    assert "--forward-only" in line and not (tmp_path / "o2").exists()
    nav = log.truth.nav_track()  # on its own seconds, week 0: not the log's GPS time
    write_kfgins_nav(tmp_path / "truth.nav", nav)
    line = one_error_line(invoke("gins", "outage-test", tmp_path / "good.bag", "--truth", tmp_path / "truth.nav",
                                 "--out", tmp_path / "o3"))
    assert "overlap" in line and not (tmp_path / "o3").exists()
    before = (tmp_path / "good.bag").read_bytes()
    line = one_error_line(invoke("gins", "run", tmp_path / "good.bag", "--out", tmp_path))  # the log's own folder
    assert (tmp_path / "good.bag").read_bytes() == before


def test_rotation_flag_accepts_euler_degrees_and_unit_quaternions(tmp_path):
    from imunav.ins.gins.logrun import parse_rotation

    q = parse_rotation("90,0,90")
    np.testing.assert_allclose(np.degrees(euler_from_quat(q)), [90, 0, 90], atol=1e-9)
    np.testing.assert_allclose(parse_rotation("0.5,0.5,0.5,0.5"), [0.5, 0.5, 0.5, 0.5])


def test_a_bag_mounting_that_the_levelling_contradicts(tmp_path):
    """The IMU of the simulated robot sits rolled by about 90 deg.  A bag whose Imu frame_id claims the base frame is
    not taken at its word: the levelling at rest contradicts it, the mounting is estimated and the run says why.
    A /tf_static that claims the identity is refused in one line (exit 2), naming --imu-rotation."""
    log = simulate_robot_log(1, distance_m=200.0)
    topics = {"/imu/data": log.imu, "/odom": log.odometer, "/gps/fix": log.gnss}
    write_bag(tmp_path / "fid.bag", topics, storage="ros1", frame_ids={"/imu/data": "base_link", "/gps/fix": "gps"})
    run = run_log(read_nav_sources(tmp_path / "fid.bag"), LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3)))
    assert run.mounting_source == "estimated" and "levelling at rest reads" in run.initial["mounting"]
    e, sd = run.mounting_euler()
    err = np.degrees(np.remainder(e - np.radians(log.truth.mounting_euler_deg) + np.pi, 2 * np.pi) - np.pi)
    assert np.all(np.abs(err) < 3 * np.degrees(sd)), err
    tf = [StaticTransform("base_link", "imu_link", np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))]
    write_bag(tmp_path / "tf.bag", topics, storage="ros1", frame_ids={"/imu/data": "imu_link", "/gps/fix": "gps"},
              static_tf=tf)
    line = one_error_line(invoke("gins", "run", tmp_path / "tf.bag", "--out", tmp_path / "o"))
    assert "tf_static" in line and "--imu-rotation" in line and not (tmp_path / "o").exists()


def test_outage_test_against_fixes_accounts_for_the_lever_arm(tmp_path):
    """An antenna 1.5 m ahead of the IMU: the removed fixes hold the antenna, the run's position is the IMU's.  With
    the lever arm added the end error against the fixes is that of a 0.3 m filter error under 1.13 m of fix noise
    (RMS about 1.2 m over 10 outages); without it, 1.5 m more would put it near 1.9 m."""
    log = simulate_robot_log(1, gnss_lever_arm_base=(1.5, 0.0, -0.3))
    write_robot_log(log, tmp_path, formats=("ros1",))
    rep = log_outage_test(read_nav_sources(tmp_path / "robot.bag"), LogRunOptions(gnss_lever_arm=(1.5, 0.0, -0.3)))
    rms = rep.rms()
    print(f"lever 1.5 m: end RMS {rms['end_m']:.3f} m against the fixes")
    assert rms["n_outages"] >= 9 and rms["end_m"] < 1.6 and rms["contained_3sigma"] == 1.0


def test_outage_test_refuses_a_truth_that_covers_no_outage(robot, tmp_path):
    """A truth of three rows (or one) covers no outage: one line, exit 2, nothing written."""
    _, d, _ = robot
    lines = (d / "kfgins" / "truth.nav").read_text().splitlines()
    for n in (3, 1):
        (tmp_path / f"t{n}.nav").write_text("\n".join(lines[:n]) + "\n")
        line = one_error_line(invoke("gins", "outage-test", d / "robot.bag", "--truth", tmp_path / f"t{n}.nav",
                                     "--converge", "60", "--every", "120", "--length", "60", "--shifts", "0",
                                     "--out", tmp_path / f"o{n}"))
        assert ("covers none" in line) if n == 3 else ("2" in line and "row" in line)
        assert not (tmp_path / f"o{n}").exists()


def test_without_an_odometer_steady_driving_is_not_rest(tmp_path):
    """A log with IMU and GNSS only: a vehicle gliding at 1 m/s has a quiet IMU, but its fixes move; the samples
    declared at rest are (almost) only those where it stands: under 10 % of the moving ones (near the stops, where
    5 s of travel at the ramp's speed is within 3 sigma of two fixes), where the quiet IMU alone declares 75 %."""
    log = simulate_robot_log(1, distance_m=200.0)
    write_bag(tmp_path / "nodo.bag", {"/imu/data": log.imu, "/gps/fix": log.gnss}, storage="ros1")
    run = run_log(read_nav_sources(tmp_path / "nodo.bag"))
    tr = log.truth.trajectory
    moving = np.hypot(tr.vel_ned[:, 0], tr.vel_ned[:, 1]) > 0.5
    print(f"declared at rest while moving: {run.static[moving].mean():.3f}")
    assert run.static[moving].mean() < 0.1 and run.static[~moving].mean() > 0.3


def test_run_log_reports_progress_over_the_filter_and_smoother_passes(tmp_path, monkeypatch):
    """``run_log(progress=...)`` hears of the first pass (the fixes' correlated error), the filter's pass chunk by
    chunk and of the smoother's at its end (the command line's bar): increasing counts ending at three times the
    samples, one total throughout, and the same trajectory as without it."""
    from imunav.ins.gins import filter as gins_filter

    write_robot_log(simulate_robot_log(4, distance_m=160.0), tmp_path, formats=("ros1",))
    src = read_nav_sources(tmp_path / "robot.bag")
    o = LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3), smoother=True)
    plain = run_log(src, o).result
    monkeypatch.setattr(gins_filter, "PROGRESS_CHUNK", 1000)
    seen = []
    res = run_log(src, o, progress=lambda done, total: seen.append((done, total))).result
    n = src.imu.n
    assert len(seen) >= 2 * n // 1000 and seen[-1] == (3 * n, 3 * n)
    assert all(b[0] > a[0] and b[1] == 3 * n for a, b in zip(seen, seen[1:]))
    np.testing.assert_array_equal(res.lla, plain.lla)
    np.testing.assert_array_equal(res.smoothed.lla, plain.smoothed.lla)


def test_a_mounting_pulled_far_beyond_its_prior_is_held(monkeypatch):
    """A coarse mounting 12 deg off (about the IMU's y axis) with a σ of 0.5 deg, as a levelling fooled by a model
    error would give: the filter pulls it more than 4 prior σ and 5 deg, so the run keeps the coarse mounting as
    consider states and says so in ``initial``."""
    from imunav.ins.gins import logrun as lr

    real = lr.estimate_mounting

    def off(*args, **kw):
        m = real(*args, **kw)
        q = quat_multiply(m.q_vb, quat_from_euler(0.0, np.radians(12.0), 0.0))
        return dataclasses.replace(m, q_vb=q, euler=np.asarray(euler_from_quat(q)), std=np.full(3, np.radians(0.5)))

    monkeypatch.setattr(lr, "estimate_mounting", off)
    run = run_log(simulate_robot_log(1, distance_m=160.0).sources, LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3),
                                                                                 smoother=False))
    assert "mounting_held" in run.initial
    assert "mount" in run.config.consider_states
    np.testing.assert_allclose(run.result.q_vb[-1], run.result.q_vb[0], atol=1e-12)


def test_an_odometer_that_understates_its_sigma_is_found_out():
    """The real Jackal bag's symptom reproduced in simulation: wheel odometry whose reported σ (0.05 m/s) is five
    times smaller than its real noise (0.25 m/s).  The log run's adaptive factor on the odometer's σ ends within
    25 % of 5 (``summary.json`` ``wheel_noise``; a σ off by 1.5 fails; measured 4.51), and the verdict does not
    blame the odometer: its NIS over the accepted updates is 1.29 for its one degree of freedom (the first of them
    come before the factor has grown), under the verdict's limit of twice that; 1.04 with its σ reported right.
    Without the adaptation (``wheel_adaptive=False``, the filter of before) its NIS is far above 1, and the verdict
    names the odometer and says why."""
    log = simulate_robot_log(2, distance_m=160.0, odometer_noise_std=0.25)
    opts = LogRunOptions(gnss_lever_arm=(0.0, 0.0, -0.3))
    src = log.sources
    right = honesty(run_log(src, opts))
    o = src.odometer
    low = dataclasses.replace(src, odometer=dataclasses.replace(o, speed_std=np.full(o.t.size, 0.05)))
    low_run = run_log(low, opts)
    found = honesty(low_run)
    factor = log_summary(low_run, low)["wheel_noise"]["odometer"]["sigma_factor"]
    fixed = dataclasses.replace(opts, overrides={"wheel_adaptive": False})
    fixed_run = run_log(low, fixed)
    wrong = honesty(fixed_run)
    # summary.json's aids block gives the same accepted-update figure beside the mean over every update
    odo = run_summary(fixed_run.result, fixed_run)["aids"]["odometer"]
    assert odo["nis_mean_accepted"] == wrong["checks"]["odometer_nis_mean"] < odo["nis_mean"]
    print(f"odometer NIS: sigma right {right['checks']['odometer_nis_mean']:.2f}, five times too small "
          f"{found['checks']['odometer_nis_mean']:.2f} with the adaptive factor (sigma x {factor:.2f}), "
          f"{wrong['checks']['odometer_nis_mean']:.2f} without (rejected {wrong['checks']['odometer_rejected_share']:.2f})")
    assert factor == pytest.approx(5.0, rel=0.25)
    for h, bound in ((right, 1.5), (found, HONESTY_LIMITS["aid_nis_ratio"])):
        assert h["checks"]["odometer_nis_dof"] == 1
        assert h["checks"]["odometer_nis_mean"] < bound and not any("odometer" in r for r in h["reasons"])
    assert not wrong["trustworthy"]
    named = [r for r in wrong["reasons"] if r.startswith("the odometer disagrees with the IMU")]
    assert len(named) == 1 and ("mean NIS" in named[0] or "the gate rejected" in named[0]), wrong["reasons"]


def _velocity_nees(log, res, every_s: float = 10.0) -> float:
    """Mean velocity NEES of a forward run against the simulated IMU's truth, every ``every_s`` from 60 s on."""
    tr = log.truth.trajectory
    q_imu = quat_multiply(tr.q_nb, np.broadcast_to(log.truth.q_base_imu, (tr.t.size, 4)))
    k = np.searchsorted(res.cov_t, np.arange(60.0, min(tr.t[-1], res.cov_t[-1]), every_s), side="right") - 1
    it = np.clip(np.searchsorted(tr.t, res.cov_t[k] - 1e-9), 0, tr.t.size - 1)
    ir = np.searchsorted(res.t, res.cov_t[k] - 1e-9)
    truth = SimpleNamespace(pos_lla=tr.pos_lla[it], vel_ned=tr.vel_ned[it], q_nb=q_imu[it])
    est = SimpleNamespace(lla=res.lla[ir], vel_ned=res.vel_ned[ir], q_nb=res.q_nb[ir])
    return float(nees_blocks(navigation_errors(truth, np.arange(k.size), est), res.cov_nav[k])[1].mean())


def test_the_odometers_over_reading_in_turns_is_estimated_and_keeps_the_velocity_honest():
    """The hard robot's skid-steer wheels read 0.3 s/rad × |yaw rate| more than the body moves (the real Jackal bag's
    wheels read its turns 1.4 times the gyro's).  Without a state for it the filter trusts the odometer in every
    turn: velocity NEES 9.5 for 3 degrees of freedom on drives 100-103; with the over-reading state (the default)
    2.4, the same as the drives without the fault (2.35).  The estimate recovers the truth inside its σ, up to the
    0.01-0.03 s/rad that the same drives without any over-reading show (0.009-0.028 ± 0.010 on drives 0-3)."""
    with_state, without = [], []
    for seed in (0, 1):
        log = simulate_hard_robot_log(seed, distance_m=250.0, faults=LogFaults(odometer_turn_overread=0.3))
        opts = LogRunOptions(gnss_lever_arm=tuple(log.truth.gnss_lever_arm_base), smoother=False)
        run = run_log(log.sources, opts)
        i = int(run.state_layout()[LAY.odo_turn])
        c, sd = float(run.result.odo_turn[-1]), math.sqrt(run.result.cov_diag[-1, i])
        print(f"drive {seed}: over-reading {c:.4f} +- {sd:.4f} s/rad (truth 0.3)")
        assert abs(c - 0.3) < 3 * sd + 0.03 and sd < 0.03
        cal = self_calibration(run)["odometer_turn_overread"]
        assert cal["observable"] is True and cal["prior_std"] == pytest.approx(0.3)
        with_state.append(_velocity_nees(log, run.result))
        off = run_log(log.sources, dataclasses.replace(opts, overrides={"odo_turn_std": None}))
        assert off.state_layout()[LAY.odo_turn] < 0
        without.append(_velocity_nees(log, off.result))
    print(f"velocity NEES (3 dof): with the state {np.mean(with_state):.2f}, without {np.mean(without):.2f}")
    assert np.mean(with_state) < 4.0 < 6.0 < np.mean(without)
