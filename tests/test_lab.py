"""The lab framework and its first step (simulated calibration tests)."""

import json
import sys
import types

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import ConfigError
from imunav.io import read_imu
from imunav.lab import runner as lab_mod
from imunav.lab.runner import LabContext, StepResult, load_lab_config, run_lab
from imunav.sim import ImuErrorModel, presets

runner = CliRunner()

SMALL = """
[lab]
seed = 7
steps = ["simulate_tests"]

[simulate_tests]
fs = 10.0
dwell_s = 1.0
transition_s = 0.5
remount_s = 1.0
static_duration_s = 20.0
figures = {figures}
"""


def _cfg(tmp_path, figures="false"):
    p = tmp_path / "lab.toml"
    p.write_text(SMALL.format(figures=figures))
    return p


def test_cli_lab_writes_report_and_data(tmp_path):
    out = tmp_path / "report"
    res = runner.invoke(app, ["lab", "--out", str(out), "--config", str(_cfg(tmp_path, "true")), "--quiet",
                              "--json", str(tmp_path / "s.json")])
    assert res.exit_code == 0, res.output
    for f in ("summary.json", "summary.md", "index.html", "data/hundred_position.npz", "data/rate_table.npz",
              "data/static_long.npz", "data/true_model.toml", "data/rate_table_segments.csv",
              "figures/hundred_position.png"):
        assert (out / f).is_file(), f
    s = json.loads((out / "summary.json").read_text())
    assert s["seed"] == 7 and s["passed"] is True
    step = s["steps"][0]
    assert step["name"] == "simulate_tests" and step["passed"] is True
    tests = step["summary"]["tests"]
    assert tests["hundred_position"]["segments"] == {"static": 100, "transition": 99}
    assert tests["rate_table"]["segments"]["rate"] == 120
    assert tests["static_long"]["samples"] == 201
    assert step["summary"]["true_parameters"]["accel.S_x"] == pytest.approx(21283.0)
    assert step["summary"]["true_parameters"]["gyro.B_Gz"] == pytest.approx(0.0432)
    assert json.loads((tmp_path / "s.json").read_text()) == s
    html = (out / "index.html").read_text()
    assert "Simulated calibration tests" in html and "data:image/png;base64" in html
    # files round-trip and carry the true model
    d = read_imu(out / "data" / "hundred_position.npz")
    assert d.n == tests["hundred_position"]["samples"]
    m = ImuErrorModel.from_toml(out / "data" / "true_model.toml")
    np.testing.assert_allclose(m.gyro.scale_misalignment, presets.get("thesis_sim").gyro.scale_misalignment)


def test_run_lab_artifacts_and_reproducibility(tmp_path):
    r1 = run_lab(tmp_path / "a", _cfg(tmp_path), progress=False)
    r2 = run_lab(tmp_path / "b", _cfg(tmp_path), progress=False)
    assert r1.passed and not r1.failed_steps and r2.passed
    a = read_imu(tmp_path / "a" / "data" / "rate_table.npz")
    b = read_imu(tmp_path / "b" / "data" / "rate_table.npz")
    np.testing.assert_array_equal(a.gyro, b.gyro)
    # independent streams per test: the static records differ from the noise of other tests
    cfg = load_lab_config(_cfg(tmp_path))
    cfg["lab"]["seed"] = 8
    r3 = run_lab(tmp_path / "c", cfg, progress=False)
    c = read_imu(tmp_path / "c" / "data" / "rate_table.npz")
    assert not np.array_equal(a.gyro, c.gyro)
    assert r3.seed == 8


def test_step_context_shares_artifacts(tmp_path, monkeypatch):
    seen = {}

    def run(ctx: LabContext) -> StepResult:
        rec = ctx.artifacts["recordings"]["static_long"]
        seen["n"] = rec.n
        seen["g"] = ctx.artifacts["sim"]["g"]
        seen["model"] = ctx.artifacts["error_model"].name
        seen["rng"] = ctx.rng(1).integers(1 << 30)
        return StepResult({"mean_az": float(rec.accel[:, 2].mean())}, passed=None)

    def boom(ctx):
        raise RuntimeError("deliberate failure")

    for name, fn in (("zz_probe", run), ("zz_boom", boom)):
        mod = types.ModuleType(f"imunav.lab.steps.{name}")
        mod.TITLE, mod.run = name, fn
        monkeypatch.setitem(sys.modules, f"imunav.lab.steps.{name}", mod)
    monkeypatch.setattr(lab_mod, "available_steps", lambda: ["simulate_tests", "zz_boom", "zz_probe"])
    res = run_lab(tmp_path / "r", _cfg(tmp_path), steps=["simulate_tests", "zz_boom", "zz_probe"], progress=False)
    assert seen["n"] == 201 and seen["g"] == 9.80665 and seen["model"] == "thesis_sim"
    assert res.failed_steps == ["zz_boom"] and res.passed is False
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert "deliberate failure" in s["steps"][1]["error"]
    assert s["steps"][2]["summary"]["mean_az"] < -9
    assert "deliberate failure" in (tmp_path / "r" / "summary.md").read_text()


def test_config_errors(tmp_path):
    with pytest.raises(ConfigError, match="unknown table \\[noise_typo\\]"):
        load_lab_config({"noise_typo": {}})
    with pytest.raises(ConfigError, match="unknown step"):
        load_lab_config({"lab": {"steps": ["nope"]}})
    with pytest.raises(ConfigError, match="seed must be a non-negative integer"):
        load_lab_config({"lab": {"seed": "x"}})
    with pytest.raises(ConfigError, match="not found"):
        load_lab_config(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[lab\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_lab_config(bad)
    res = runner.invoke(app, ["lab", "--out", str(tmp_path / "o"), "--config", str(bad), "--quiet"])
    assert res.exit_code == 2 and "not valid TOML" in res.output
    # an invalid step option is a configuration error (issue 27): one line, exit 2, no report that looks complete
    opt = tmp_path / "opt.toml"
    opt.write_text("[lab]\nsteps = [\"simulate_tests\"]\n[simulate_tests]\nfs = -1.0\n")
    res = runner.invoke(app, ["lab", "--out", str(tmp_path / "p"), "--config", str(opt), "--quiet"])
    assert res.exit_code == 2 and "fs must be a positive number" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.output
    assert not (tmp_path / "p" / "index.html").exists()


def test_simulate_tests_options_earth_rate_and_format(tmp_path, monkeypatch):
    from imunav import earth
    from imunav.units import DEG

    cfg = load_lab_config(_cfg(tmp_path))
    cfg["simulate_tests"].update(earth_rate=True, gravity="normal", lat_deg=45.0, h_m=100.0, format="parquet",
                                 tests=["static_long"], preset="navigation")
    captured = {}

    def probe(ctx):
        captured.update(ctx.artifacts)
        return StepResult({})

    mod = types.ModuleType("imunav.lab.steps.zz_probe2")
    mod.TITLE, mod.run = "probe", probe
    monkeypatch.setitem(sys.modules, "imunav.lab.steps.zz_probe2", mod)
    monkeypatch.setattr(lab_mod, "available_steps", lambda: ["simulate_tests", "zz_probe2"])
    res = run_lab(tmp_path / "e", cfg, steps=["simulate_tests", "zz_probe2"], progress=False)
    assert not res.failed_steps
    assert (tmp_path / "e" / "data" / "static_long.parquet").is_file()
    assert set(captured["recordings"]) == {"static_long"}
    assert captured["sim"]["g"] == pytest.approx(earth.normal_gravity(45 * DEG, 100.0), abs=1e-12)
    rec = captured["recordings"]["static_long"]
    # navigation preset: ARW 5.8e-7 rad/sqrt(s) -> sigma of a 20 s mean 1.3e-7 rad/s, bias < 2e-8:
    # the mean is the Earth rate within ~4 sigma
    np.testing.assert_allclose(rec.gyro.mean(axis=0), earth.earth_rate_ned(45 * DEG), atol=5e-7)


def test_example_lab_configs_are_valid():
    from shared_data import ROOT

    files = sorted((ROOT / "examples").glob("lab*.toml"))
    assert files
    import tomllib

    for f in files:
        if "recordings" in tomllib.loads(f.read_text()):
            continue  # real-data labs need the shared data (tests/test_lab_steps.py)
        cfg = load_lab_config(f)
        assert "simulate_tests" in cfg


def test_lab_tasks_end_at_100_percent_and_the_monte_carlo_reports_progress(tmp_path):
    from imunav.lab.montecarlo import run_montecarlo
    from imunav.lab.runner import LabContext
    from imunav.scenarios import attitude_paper

    class Recorder:
        def __init__(self):
            self.tasks = {}

        def add_task(self, description, total=None, **kw):
            self.tasks[description] = {"total": total, "completed": 0}
            return description

        def advance(self, tid, n=1):
            self.tasks[tid]["completed"] += n

        def update(self, tid, **kw):
            self.tasks[tid].update({k: v for k, v in kw.items() if k in ("total", "completed")})

    rec = Recorder()
    ctx = LabContext(out_dir=tmp_path, seed=0, progress=rec)
    with ctx.task("unknown length", total=None):
        pass
    t = rec.tasks["unknown length"]
    assert t["total"] and t["completed"] == t["total"]
    seen = []
    run_montecarlo(attitude_paper, 3, seed=0, executor="serial", batched=True, chunk_size=1, duration=5.0,
                   progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 3), (2, 3), (3, 3)]
