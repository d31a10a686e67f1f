"""``imunav attitude`` commands (the examples in their help run)."""

from __future__ import annotations

import json

import pytest
from cli_contract import invoke, one_error_line
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli.main import app

runner = CliRunner()


def test_montecarlo_json(tmp_path):
    out = tmp_path / "mc.json"
    r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "2", "--duration", "60", "--json", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    assert d["table"]["proposed"]["pitch_mean"] < 0.05
    assert len(d["rmse"]["lee"]) == 2


def test_montecarlo_executors_identical(tmp_path):
    """Same seed, same numbers whatever the executor (serial vs a 2-process pool)."""
    out = {}
    for ex in ("serial", "processes"):
        out[ex] = tmp_path / f"{ex}.json"
        r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "3", "--duration", "40", "-f", "proposed",
                                "--executor", ex, "-j", "2", "--json", str(out[ex])])
        assert r.exit_code == 0, r.output
    a, b = (json.loads(out[k].read_text()) for k in ("serial", "processes"))
    assert a["rmse"] == b["rmse"] and len(a["rmse"]["proposed"]) == 3
    r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "2", "--executor", "gpu"])
    assert r.exit_code == 2 and "executor" in r.stderr
    r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "2", "-f", "kalman"])
    assert r.exit_code == 2 and "unknown filter" in r.stderr


def test_run_and_benchmark(tmp_path):
    src = data_path("broad", "02_undisturbed_slow_rotation_B.mat")
    out = tmp_path / "run.json"
    r = runner.invoke(app, ["attitude", "run", str(src), "--filter", "madgwick_c", "--json", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    pub = json.loads(data_path("broad", "published_rmse.json").read_text())
    want = pub["madgwick"]["trials"]["02_undisturbed_slow_rotation_B"]["total_rmse_deg"]
    assert d["rmse"]["total_rmse_deg"] == pytest.approx(want, abs=0.1)
    # benchmark over a folder holding one trial (a symlink, outside the repository)
    folder = tmp_path / "broad"
    folder.mkdir()
    (folder / src.name).symlink_to(src)
    bj = tmp_path / "bench.json"
    r = runner.invoke(app, ["attitude", "benchmark", str(folder), "-f", "mahony", "-f", "madgwick_c",
                            "--json", str(bj)])
    assert r.exit_code == 0, r.output
    b = json.loads(bj.read_text())
    assert set(b["filters"]) == {"mahony", "madgwick_c"}
    assert b["filters"]["mahony"]["trials"]["02_undisturbed_slow_rotation_B"]["total_rmse_deg"] == pytest.approx(
        pub["mahony"]["trials"]["02_undisturbed_slow_rotation_B"]["total_rmse_deg"], abs=0.1)


def test_bad_filter_name(tmp_path):
    r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "1", "-f", "lee,nosuch"])
    assert r.exit_code == 2  # a user error: one line on stderr, no traceback
    assert "nosuch" in r.stderr and len(r.stderr.splitlines()) == 1


def test_zero_runs_refused():
    r = runner.invoke(app, ["attitude", "montecarlo", "--runs", "0"])
    assert r.exit_code == 2
    assert "--runs" in r.stderr and "Traceback" not in r.stderr  # the flag, not the Python keyword (issue 27)


def test_grid_search_cli(tmp_path):
    src = data_path("broad", "05_undisturbed_slow_rotation_with_breaks_B.mat")
    folder = tmp_path / "broad"
    folder.mkdir()
    (folder / src.name).symlink_to(src)
    out = tmp_path / "grid.json"
    r = runner.invoke(app, ["attitude", "benchmark", str(folder), "-f", "madgwick", "--grid", "beta=0.02,0.5",
                            "-j", "1", "--json", str(out)])
    assert r.exit_code == 0, r.output
    g = json.loads(out.read_text())["grid"]
    assert len(g) == 2
    assert g[0]["mean"]["total_rmse_deg"] <= g[1]["mean"]["total_rmse_deg"]  # sorted best first
    assert {x["params"]["beta"] for x in g} == {0.02, 0.5}


def test_bad_param_syntax():
    r = runner.invoke(app, ["attitude", "benchmark", "broad", "--param", "oops"])
    assert r.exit_code != 0


def test_grid_search_cli_reports_leave_one_trial_out(tmp_path):
    """With two trials, each is scored with the beta that is best on the other one."""
    folder = tmp_path / "broad"
    folder.mkdir()
    for name in ("05_undisturbed_slow_rotation_with_breaks_B.mat", "18_undisturbed_fast_translation_with_breaks_B.mat"):
        (folder / name).symlink_to(data_path("broad", name))
    out = tmp_path / "grid.json"
    r = runner.invoke(app, ["attitude", "benchmark", str(folder), "-f", "madgwick", "--grid", "beta=0.005,0.05,0.5",
                            "-j", "1", "--json", str(out)])
    assert r.exit_code == 0, r.output
    assert "leave-one-trial-out" in r.output
    d = json.loads(out.read_text())
    score = {(x["params"]["beta"], t): v["total_rmse_deg"] for x in d["grid"] for t, v in x["trials"].items()}
    trials = list(d["grid"][0]["trials"])
    for item in d["cv"]["items"]:
        other = next(t for t in trials if t != item["item"])
        beta = min({b for b, _ in score}, key=lambda b: score[(b, other)])
        assert item["oof"] == pytest.approx(score[(beta, item["item"])], abs=1e-12)
    assert d["cv"]["oof_mean"] >= d["cv"]["in_sample_mean"] - 1e-12


def test_attitude_montecarlo_address_without_dask_is_refused():
    r = invoke("attitude", "montecarlo", "--runs", "1", "--executor", "serial", "--address", "tcp://127.0.0.1:1")
    assert "--executor dask" in one_error_line(r)
