"""imunav lab end to end (virtual IMU and real-recording mode), TOML validation, spec checks."""

from __future__ import annotations

import json

import browser
import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import ConfigError
from imunav.lab.runner import parse_lab_config, run_lab
from imunav.units import DEG, G0

runner = CliRunner()

# A reduced lab: short profiles at low rates, the thermal test at 4 temperatures.
REDUCED = """
[lab]
seed = 3
title = "reduced lab"
steps = ["simulate_tests", "calibration", "temperature", "compensation"]

[simulate_tests]
fs = 20.0
dwell_s = 4.0
transition_s = 1.0
remount_s = 1.0
static_duration_s = 30.0
figures = true

[temperature]
temps_c = [-10.0, 10.0, 30.0, 50.0]
fs = 10.0
dwell_s = 5.0
rate_dps = [100.0]
orders = [1, 2]

[compensation]
positions = 5
rate_steps = 3
dwell_s = 4.0

[spec.accel_bias]
max = 500
unit = "mg"

[spec.gyro_scale]
max = 30000          # thesis_sim S_y = 32650 ppm: fails
unit = "ppm"

[spec.gyro_arw]      # not measured by these steps: a spec item without a measurement fails
max = 1.0
unit = "deg/sqrt(h)"
"""


def test_lab_end_to_end_reduced_renders_in_chromium(tmp_path):
    cfg = tmp_path / "lab.toml"
    cfg.write_text(REDUCED)
    out = tmp_path / "report"
    res = runner.invoke(app, ["lab", "--out", str(out), "--config", str(cfg), "--quiet"])
    # no step errors; the failed spec lines give exit status 1, as imunav batch (issue 26), and say so
    assert res.exit_code == 1 and "a [spec] check failed" in res.stderr, res.output
    s = json.loads((out / "summary.json").read_text())
    steps = {st["name"]: st for st in s["steps"]}
    assert list(steps) == ["simulate_tests", "calibration", "temperature", "compensation"]
    assert all("error" not in st for st in steps.values())
    # temperature: the fitted curves follow the true B(T), S(T) (the step's 4-sigma acceptance)
    assert steps["temperature"]["passed"] is True
    assert steps["temperature"]["summary"]["max_dev_over_sigma"] <= 4.0
    # compensation: the calibration step's estimate applied to a fresh recording; residuals consistent
    # with the reported uncertainty, far below the raw errors
    comp = steps["compensation"]["summary"]
    assert comp["calibration"] == "the calibration step's estimate"
    assert steps["compensation"]["passed"] is True
    for sensor in ("accel", "gyro"):
        assert 0.5 <= comp[sensor]["rms_z"] <= 2.0
    assert comp["accel"]["rms_error_ug"] < 0.01 * comp["accel"]["rms_raw_error_mg"] * 1e3
    # parameters (harvested from the calibration step's result) carry their uncertainty;
    # the spec checks every axis of an axis-less limit
    p = steps["calibration"]["parameters"]
    assert p["gyro_scale_y"]["sigma_si"] > 0
    checks = {c["name"]: c for c in s["spec_checks"] if c["limit"]}
    assert checks["accel_bias_x"]["passed"] is True
    assert checks["gyro_scale_y"]["passed"] is False and checks["gyro_scale_x"]["passed"] is True
    assert checks["gyro_arw"]["passed"] is False  # specified, not measured
    assert s["spec_passed"] is False and s["passed"] is False
    html = (out / "index.html").read_text()
    for title in ("Overview", "Specification", "Simulated calibration tests", "Deterministic calibration",
                  "Temperature model", "Compensation"):
        assert title in html
    assert html.count("data:image/png;base64") >= 5  # 3 test recordings, thermal curves, compensation z-scores
    console = browser.render(out / "index.html", tmp_path / "lab.png", height=4000)
    assert console == [], console
    browser.assert_not_blank(tmp_path / "lab.png")


def test_lab_real_recordings_mode(tmp_path):
    """[recordings]: files with declared units, segment table, default steps without simulation-only ones."""
    from imunav.io import write_imu
    from imunav.sim import hundred_position_profile, presets, simulate_imu, static_profile

    model = presets.get("thesis_sim")
    prof = hundred_position_profile(20.0, 4.0, 1.0)
    d = simulate_imu(prof.trajectory, model, 1, earth_rate=False, transport_rate=False, gravity="constant")
    write_imu(d, tmp_path / "mp.npz")
    (tmp_path / "mp_segments.json").write_text(json.dumps(prof.to_dict(), default=lambda o: np.asarray(o).tolist()))
    st = simulate_imu(static_profile(30.0, 20.0).trajectory, model, 2, earth_rate=False, transport_rate=False,
                      gravity="constant")
    # the static record in deg/s and g, CSV: converted at the edge
    rows = np.column_stack([st.t, np.rad2deg(st.gyro), st.accel / G0])
    np.savetxt(tmp_path / "static.csv", rows, delimiter=",", header="time,gx,gy,gz,ax,ay,az", comments="")
    cfg = tmp_path / "real.toml"
    cfg.write_text("""
[lab]
seed = 1
[recordings.bench]
path = "mp.npz"
test = "multiposition"
segments = "mp_segments.json"
[recordings.night]
path = "static.csv"
test = "static"
columns = { t = "time", gyro = ["gx", "gy", "gz"], accel = ["ax", "ay", "az"] }
units = { gyro = "deg/s", accel = "g" }
max_duration_s = 20.0
""")
    typed = parse_lab_config(cfg)
    assert typed.mode == "recordings"
    steps = typed.default_steps()
    assert steps[0] == "recordings" and "simulate_tests" not in steps and "temperature" not in steps
    res = run_lab(tmp_path / "out", cfg, steps=["recordings", "compensation"], progress=False)
    assert not res.failed_steps, res.steps[-1].error
    rec = res.steps[0].result.summary["recordings"]
    assert rec["night"]["samples"] == 400 and rec["bench"]["samples"] == d.n
    # deg/s -> rad/s at the edge: the static gyro mean is the thesis bias (1.44 deg/s on x) within noise
    assert float(rec["night"]["gyro mean (deg/s)"].split(",")[0]) == pytest.approx(1.4402, abs=0.01)
    comp = res.steps[1].result
    assert comp.summary["calibration"].startswith("multi-position")
    # compensated static intervals: |f| = g within 1 mg where the raw error is ~ 100s of mg
    assert comp.summary["median_abs_norm_error_mg"]["compensated"] < 1.0
    assert comp.summary["median_abs_norm_error_mg"]["raw"] > 50.0
    assert comp.parameters["accel_bias_x"][0] == pytest.approx(model.accel.bias[0], abs=5 * comp.parameters["accel_bias_x"][1] + 2e-3)


@pytest.mark.parametrize(
    ("toml", "match"),
    [
        ("[recordings]\n", r"\[recordings\] is empty"),
        ("[recordings.a]\ntest = 'static'\n", "path is required"),
        ("[recordings.a]\npath = 'x.npz'\ntest = 'static'\n", "does not exist"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'sideways'\n", "test must be one of"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\ncolour = 1\n", r"unknown key\(s\) \['colour'\]"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'multiposition'\n", "needs segments"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\nsegments = 'f.npz'\n", "segments applies to"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\nfs = -5\n", "fs must be a positive number"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\nunits = 'deg/s'\n", "units must be a table"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\n[recordings.b]\npath = 'f.npz'\ntest = 'static'\n",
         "already given"),
        ("[recordings.a]\npath = 'f.npz'\ntest = 'static'\nformat = 'xls'\n", "format must be"),
        ("[spec.gyro_bias]\nmin = 2\nmax = 1\nunit = 'deg/h'\n", "min > max"),
        ("[spec.gyro_bias]\nmax = 1\nunit = 'furlongs'\n", "unknown display unit"),
        ("[spec.gyro_bias]\nunit = 'deg/h'\n", "needs min and/or max"),
        ("[lab]\nseed = -1\n", "non-negative integer"),
        ("[lab]\ntitle = 3\n", "title must be a string"),
        ("[bogus]\n", r"unknown table \[bogus\]"),
    ],
)
def test_lab_toml_validation_errors(tmp_path, toml, match):
    (tmp_path / "f.npz").write_bytes(b"not read during validation")
    p = tmp_path / "lab.toml"
    p.write_text(toml)
    with pytest.raises(ConfigError, match=match):
        parse_lab_config(p)


def test_lab_shared_path_needs_the_data_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("IMUNAV_DATA", str(tmp_path / "nowhere"))
    p = tmp_path / "lab.toml"
    p.write_text("[recordings.a]\npath = 'shared:adis16405/adis16405_imu2.npz'\ntest = 'static'\n")
    with pytest.raises(ConfigError, match="set IMUNAV_DATA"):
        parse_lab_config(p)
    res = runner.invoke(app, ["lab", "--config", str(p), "--out", str(tmp_path / "o"), "--quiet"])
    assert res.exit_code == 2 and "IMUNAV_DATA" in res.output


def test_example_real_lab_resolves_shared_data(monkeypatch):
    from shared_data import ROOT, data_path

    data = data_path("adis16405", "adis16405_imu2.npz").parents[1]
    data_path("mpu6050_tedaldi", "example_data_calibration.csv")
    monkeypatch.setenv("IMUNAV_DATA", str(data))
    typed = parse_lab_config(ROOT / "examples" / "lab_real.toml")
    assert {r.test for r in typed.recordings.values()} == {"static", "multipose"}
    assert typed.recordings["mpu_session"].read["skiprows"] == 4
    assert typed.spec["accel_bias"].max_si == pytest.approx(0.150 * G0)
    typed = parse_lab_config(ROOT / "examples" / "lab_spec.toml")
    assert typed.mode == "virtual" and typed.spec["gyro_bias"].max_si == pytest.approx(2.0 * DEG)
