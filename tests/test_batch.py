"""Production-batch processing: simulate, calibrate and noise-analyse a folder of units."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import InvalidInputError
from imunav.lab.batch import calibrate_batch, find_units, noise_batch, simulate_batch
from imunav.sim import ImuErrorModel, presets
from imunav.sim.robot_log import simulate_robot_log, write_robot_log

runner = CliRunner()


@pytest.fixture(scope="module")
def tiny_batch(tmp_path_factory):
    """3 units, 100-position + rate-table tests at 20 Hz, 4 s per position (about 1 s each to simulate)."""
    d = tmp_path_factory.mktemp("batch")
    res = runner.invoke(app, ["batch", "simulate", "3", "--out", str(d), "--fs", "20", "--dwell", "4",
                              "--seed", "5", "--executor", "serial", "--quiet"])
    assert res.exit_code == 0, res.output
    return d


def test_simulate_batch_layout_and_unit_spread(tiny_batch):
    units = find_units(tiny_batch)
    assert [u.name for u in units] == ["unit_001.npz", "unit_002.npz", "unit_003.npz"]
    assert (tiny_batch / "unit_002_rate.npz").is_file() and (tiny_batch / "rate_segments.json").is_file()
    meta = json.loads((tiny_batch / "batch.json").read_text())
    assert meta["n_units"] == 3 and meta["seed"] == 5
    base = presets.get("thesis_sim")
    m = [ImuErrorModel.from_dict(json.loads((tiny_batch / "truth" / f"unit_00{k}.json").read_text())) for k in (1, 2, 3)]
    # every unit differs from the preset and from the others, with a relative spread of about 0.2
    rel = np.array([(x.accel.bias - base.accel.bias) / base.accel.bias for x in m])
    assert np.all(rel != 0) and 0.02 < rel.std() < 0.6
    assert not np.allclose(m[0].gyro.scale_misalignment, m[1].gyro.scale_misalignment)
    # the noise parameters stay the preset's
    np.testing.assert_array_equal(m[2].gyro.noise_density, base.gyro.noise_density)


def test_simulate_batch_is_seeded(tmp_path):
    a = simulate_batch(1, tmp_path / "a", fs=10.0, dwell_s=4.0, rate_table=False, rng=9, executor="serial")
    b = simulate_batch(1, tmp_path / "b", fs=10.0, dwell_s=4.0, rate_table=False, rng=9, executor="serial")
    assert (tmp_path / "a" / "truth" / "unit_001.json").read_text() == (tmp_path / "b" / "truth" / "unit_001.json").read_text()
    assert a[0].read_bytes() == b[0].read_bytes()


def test_batch_calibrate_three_units_summary_and_truth(tiny_batch, tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text("[spec.accel_bias]\nmax = 600\nunit = 'mg'\n[spec.gyro_bias]\nmax = 1.0\nunit = 'deg/s'\n"
                    "[spec.gyro_arw]\nmax = 0.001\nunit = 'deg/sqrt(h)'\n")  # a noise line: not a calibration item
    out = tmp_path / "cal"
    res = runner.invoke(app, ["batch", "calibrate", str(tiny_batch), "--method", "thesis", "--out", str(out),
                              "--spec", str(spec), "--json", str(tmp_path / "s.json"), "--executor", "serial", "-q"])
    # thesis_sim gyro biases are ~1.5 deg/s: every unit fails the 1 deg/s line -> exit 1, table still printed
    assert res.exit_code == 1, res.output
    assert "unit_003" in res.output and "FAIL" in res.output
    s = json.loads((tmp_path / "s.json").read_text())
    assert s["n_units"] == 3 and s["n_failed"] == 0 and s["passed"] is False
    for f in ("summary.csv", "summary.json", "index.html", "unit_001.json", "unit_002_report.json"):
        assert (out / f).is_file(), f
    rows = s["table"]
    for r in rows:
        assert r["status"] == "ok"
        # estimates against each unit's truth: inside 5 sigma for every parameter (27 per unit)
        errs = [k for k in r if k.endswith("_err")]
        assert len(errs) == 27
        z = np.array([r[k] / r[k[:-4] + "_se"] for k in errs])
        assert np.all(np.abs(z) < 5.0), dict(zip(errs, z))
    checks = s["spec_checks"]["unit_001"]
    by = {c["name"]: c["passed"] for c in checks}
    assert by["accel_bias_x"] is True and by["gyro_bias_z"] is False
    assert not any(n.startswith("gyro_arw") for n in by)  # families the batch does not measure are not checked
    # the saved calibration compensates the unit's own data
    from imunav.calib import ImuCalibration

    cal = ImuCalibration.load(out / "unit_001.json")
    assert cal.gyro_matrix.shape == (3, 3) and np.all(np.diag(cal.gyro_matrix) > 1.0)


def test_batch_calibrate_reports_a_bad_unit_and_continues(tiny_batch, tmp_path):
    import shutil

    d = tmp_path / "mixed"
    d.mkdir()
    for f in ("unit_001.npz", "segments.json"):
        shutil.copy(tiny_batch / f, d / f)
    (d / "unit_002.npz").write_bytes(b"truncated")
    s = calibrate_batch(d, method="multiposition", executor="serial")
    st = dict(zip(s.table["unit"], s.table["status"]))
    assert st == {"unit_001": "ok", "unit_002": "error"}
    assert "unit_002" in s.units and "error" in s.units["unit_002"]
    assert s.passed is False and s.n_failed == 1
    with pytest.raises(InvalidInputError, match="no recordings"):
        find_units(tmp_path / "mixed" / "..")
    res = runner.invoke(app, ["batch", "calibrate", str(tmp_path / "nowhere")])
    assert res.exit_code == 2 and "does not exist" in res.output
    with pytest.raises(Exception, match="unknown calibration method"):
        calibrate_batch(d, method="voodoo", executor="serial")


def test_batch_noise_recovers_white_noise(tmp_path):
    """Static units: the Allan fit's ARW / VRW match the simulated noise densities."""
    from imunav.io import write_imu
    from imunav.sim import TriadErrors, simulate_imu, static_profile

    m = ImuErrorModel(gyro=TriadErrors(noise_density=np.array([1e-3, 2e-3, 1.5e-3])),
                      accel=TriadErrors(noise_density=2e-3))
    prof = static_profile(300.0, 50.0)
    for k in range(1):
        write_imu(simulate_imu(prof.trajectory, m, k, earth_rate=False, transport_rate=False, gravity="constant"),
                  tmp_path / f"u{k}.npz")
    s = noise_batch(tmp_path, executor="serial", terms=("Q", "N", "K"))
    assert list(s.table["status"]) == ["ok"]
    for u in s.units.values():
        est = u["estimates"]
        for i, a in enumerate("xyz"):
            v, se = est[f"gyro_arw_{a}"]
            # 300 s at 50 Hz: the fitted N is within a few standard errors (and 10 %) of the truth
            assert v == pytest.approx(m.gyro.noise_density[i], rel=0.1)
            assert abs(v - m.gyro.noise_density[i]) < 4 * se
            assert est[f"accel_vrw_{a}"][0] == pytest.approx(2e-3, rel=0.1)
    assert (tmp_path / "noise" / "u0_noise.json").is_file() and (tmp_path / "noise" / "index.html").is_file()


def test_batch_gins_runs_every_log_as_gins_run_does(tmp_path):
    """A folder with two short robot drives (a ROS 1 bag and a ROS 2 bag folder) and a broken bag: one result folder
    per log, each the outputs of `imunav gins run LOG`; the table's values are those of `gins run` on the same log
    (its summary.json and the last row of its state sigma file); the broken log is a row with its error, exit 1."""
    pytest.importorskip("rosbags")
    from cli_contract import invoke

    from imunav.io.kfgins import read_kfgins_nav

    logs = tmp_path / "logs"
    logs.mkdir()
    for seed, fmt in ((1, "ros1"), (2, "ros2")):
        d = tmp_path / f"w{seed}"
        d.mkdir()
        written = write_robot_log(simulate_robot_log(seed, distance_m=80.0), d, formats=(fmt,))
        written[fmt].rename(logs / ("a.bag" if fmt == "ros1" else "b"))
    (logs / "broken.bag").write_bytes(b"#ROSBAG V2.0\ntruncated")
    (logs / "notes.txt").write_text("not a log")
    r = invoke("batch", "gins", logs, "--executor", "serial", "--quiet", "--no-plots", "--smoother")
    assert r.exit_code == 1, r.stderr  # a log failed: the batch commands' rule
    out = logs / "gins"
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["a", "b"]
    table = pd.read_csv(out / "summary.csv")
    assert list(table["unit"]) == ["a", "b", "broken"] and list(table["status"]) == ["ok", "ok", "error"]
    assert "broken.bag" in table.loc[2, "error"] and "ROS bag" in table.loc[2, "error"]
    doc = json.loads((out / "summary.json").read_text())
    assert doc["kind"] == "gins" and doc["n_failed"] == 1 and "| broken | error |" in (out / "summary.md").read_text()
    for i, name in enumerate(("a.bag", "b")):
        one = tmp_path / f"run_{i}"
        assert invoke("gins", "run", logs / name, "--out", one, "--no-plots", "--smoother", "--quiet").exit_code == 0
        s = json.loads((one / "summary.json").read_text())
        row = table.loc[i]
        assert json.loads((out / row["unit"] / "summary.json").read_text())["mounting"] == s["mounting"]
        m = s["mounting"]
        expect = {"duration_s": s["duration_s"], "imu_samples": s["imu_samples"], "gnss_used": s["gnss_used"],
                  "mounting_roll_deg": m["roll_deg"], "mounting_pitch_deg": m["pitch_deg"],
                  "mounting_yaw_deg": m["yaw_deg"], "mounting_roll_std_deg": m["std_deg"][0],
                  "mounting_pitch_std_deg": m["std_deg"][1], "mounting_yaw_std_deg": m["std_deg"][2],
                  "odometer_scale": 1 + s["odometer_scale"]["value"], "odometer_scale_std": s["odometer_scale"]["std"],
                  "gnss_time_offset_s": s["gnss_time_offset_s"]["value"],
                  "gnss_time_offset_std_s": s["gnss_time_offset_s"]["std"],
                  "gnss_rejected_share": s["gnss_rejected"]["share"]}
        for k, v in expect.items():
            assert row[k] == pytest.approx(v, rel=1e-12, abs=0), k  # CSV keeps repr-exact floats
        std = np.loadtxt(one / "KF_GINS_STD.txt")[-1, 1:4]
        np.testing.assert_allclose(row[["final_pos_std_n_m", "final_pos_std_e_m", "final_pos_std_d_m"]].to_numpy(float),
                                   std, rtol=1e-6)  # the file's digits
        assert row["mounting_source"] == "estimated" and "/gps/fix" in row["sources"]
        # the recommended (smoothed) track and the forward filter's beside it
        assert read_kfgins_nav(out / row["unit"] / "KF_GINS_Navresult_forward.nav").t.size == s["imu_samples"]
        assert abs(row["odometer_scale"] - 0.91) < 4 * row["odometer_scale_std"]
