"""GNSS/INS on a real car (issue 33): the comma2k19 highway segment of the shared data, run as a user would, with
defaults, against comma's fused pose (a peer's estimate, not survey truth).  Skipped without the shared data.

What the defaults met here and what they were chosen on: the in-motion start (initial velocity, levelling and
mounting while driving, the gyro bias from the course) was written for this segment's symptoms, and the adaptive
GNSS noise was switched on by default after it was measured here: the figures below are in-sample for those
choices.  Held-out evidence for them: the simulated robot and car drives (``benchmarks/bench_gins_hard_sim.py``,
``tests/ins/gins/test_logrun_consistency.py``), the Jackal bag (no GNSS) and the real robot bag kept aside.

Acceptance (issue 33): the fixes are late (about 0.09 s against the pose at their receive stamps): the latency the
run reports lies within 3σ of 0.07 s with σ <= 0.03 s; full GNSS: horizontal RMS against the pose <= 0.5 m;
10 s outages every 15 s after 20 s (shifts 0 / 5 / 10 s): largest error RMS over the outages <= 1.5 m and every
outage inside its predicted 3σ throughout (the pose's own σ 0.5 m); the raw gyro: its heading-axis bias at the
end within 0.1 deg/s of Android's estimate, and the same outage figure within 20 %.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_contract import invoke
from shared_data import data_path

from imunav.ins.gins.logrun import LogRunOptions, log_outage_test, run_log
from imunav.io.comma2k19 import read_comma2k19_pose
from imunav.io.navlog import read_nav_sources
from imunav.rotation import dcm_from_quat

OUTAGES = dict(converge_s=20.0, every_s=15.0, length_s=10.0, shifts_s=(0.0, 5.0, 10.0))
POSE_STD = 0.5


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    """``imunav gins run SEGMENT --truth SEGMENT --out car`` with defaults, and its summary."""
    seg = data_path("comma2k19", "example1")
    out = tmp_path_factory.mktemp("car") / "car"
    r = invoke("gins", "run", seg, "--truth", seg, "--out", out, "--quiet")
    assert r.exit_code == 0, r.stderr
    return seg, out, json.loads((out / "summary.json").read_text()), r.stdout


def test_latency_is_the_fixes_lateness_with_an_honest_sigma(car):
    """The fixes, stamped when received, are about 0.07-0.09 s late against the pose; the run's latency lies
    within 3σ of 0.07 s with σ <= 0.03 s (the earlier run reported -0.075 ± 0.010 s: the car started at 8 m/s
    and the filter at rest)."""
    _, _, s, stdout = car
    lat = s["gnss_time_offset_s"]
    assert lat["std"] <= 0.03
    assert abs(lat["value"] - 0.07) <= 3 * lat["std"]
    assert "GNSS latency" in stdout and "honesty:" in stdout


def test_full_gnss_track_is_within_half_a_metre_of_the_pose(car):
    """The recommended (smoothed) track: horizontal RMS against the pose <= 0.5 m; the forward filter's is
    written beside it and is no better."""
    seg, out, s, _ = car
    h = float(np.hypot(*s["rmse"]["pos_ned_m"][:2]))
    hf = float(np.hypot(*s["rmse_forward"]["pos_ned_m"][:2]))
    assert h <= 0.5
    assert hf >= h
    assert (out / "KF_GINS_Navresult_forward.nav").is_file() and (out / "KF_GINS_STD_forward.txt").is_file()
    assert s["trajectory"].startswith("RTS-smoothed")


def test_summary_says_what_was_found_and_how(car):
    """The mounting found while driving (no rest), which self-calibration states the drive observed, the
    adaptive GNSS noise, the separation and the verdict in words."""
    _, _, s, _ = car
    assert s["mounting"]["source"] == "estimated" and "while driving" in s["mounting"]["method"]
    assert s["static_share"] == 0.0
    assert s["initial"]["gyro_bias"].startswith("mean rate over the drive")
    sc = s["self_calibration"]
    assert sc["gnss_latency"]["observable"] is True and sc["odometer_scale"]["observable"] is True
    assert sc["mount_pitch"]["observable"] is True
    # the roll of a car on a straight highway is not seen by the NHC: its prior stands, and the summary says so
    assert sc["mount_roll"]["observable"] is not True
    assert s["gnss_noise"]["adaptive"] is True
    assert s["honesty"]["trustworthy"] is True, s["honesty"]["verdict"]
    assert s["separation"]["mean_d2"] < 4.0


def _outages(src):
    return log_outage_test(src, LogRunOptions(), truth=read_comma2k19_pose(data_path("comma2k19", "example1")),
                           truth_std=POSE_STD, **OUTAGES)


@pytest.fixture(scope="module")
def outage_calibrated():
    return _outages(read_nav_sources(data_path("comma2k19", "example1")))


def test_outages_are_bounded_and_inside_their_sigma(outage_calibrated):
    """Six 10 s outages: the largest error of each, RMS over them, <= 1.5 m (the CAN speed with the gyro heading
    from the reference's start ends 1.6 m off); every outage inside its predicted 3σ throughout."""
    rep = outage_calibrated
    assert rep.end_m.size == 6
    assert float(np.sqrt(np.mean(rep.max_m**2))) <= 1.5
    assert rep.contained.all(), rep.normalised


def test_raw_gyro_bias_is_found_and_the_outages_hold(outage_calibrated):
    """With the raw gyro (bias up to 3.9 deg/s): the bias about the vehicle's down axis at the end within
    0.1 deg/s of Android's own estimate, and the outage figure within 20 % of the calibrated gyro's."""
    src = read_nav_sources(data_path("comma2k19", "example1"), gyro="raw")
    run = run_log(src, LogRunOptions(smoother=False))
    res = run.result
    down_b = dcm_from_quat(res.q_vb[-1]).T[:, 2]  # the vehicle's down axis in IMU axes
    diff = float(down_b @ (res.gyro_bias[-1] - np.asarray(src.meta["imu"]["android_gyro_bias_end"])))
    assert abs(math.degrees(diff)) < 0.1
    raw = _outages(src)
    a = float(np.sqrt(np.mean(raw.max_m**2)))
    b = float(np.sqrt(np.mean(outage_calibrated.max_m**2)))
    assert abs(a - b) <= 0.2 * b
    assert raw.contained.all()


def test_outage_cli_takes_the_source_flags_and_the_pose(tmp_path):
    """``gins outage-test`` on the segment with ``--gyro raw``, the pose as ``--truth`` and its σ: per outage the
    end, largest and normalised error."""
    seg = data_path("comma2k19", "example1")
    r = invoke("gins", "outage-test", seg, "--gyro", "raw", "--truth", seg, "--truth-std", "0.5", "--converge", "20",
               "--every", "15", "--length", "10", "--shifts", "0,5,10", "--out", tmp_path / "o", "--quiet")
    assert r.exit_code == 0, r.stderr
    doc = json.loads((tmp_path / "o" / "outage.json").read_text())
    assert len(doc["outages"]) == 6
    assert all(o["inside_3sigma"] and o["normalised_max"] <= 3.0 for o in doc["outages"])
    assert doc["rms"]["reference"] == "truth" and doc["rms"]["reference_noise_m"] == 0.5
