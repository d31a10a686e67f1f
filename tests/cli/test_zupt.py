"""`imunav zupt` commands on the shared data."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_contract import invoke, one_error_line
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.learn.lstm import DEFAULT_MODEL_PATH

runner = CliRunner()


def test_zupt_run_reproduces_published_error(tmp_path):
    f = data_path("foot", "pyshoe_vicon", "2017-11-22-11-22-03.mat")
    out = tmp_path / "run.json"
    r = runner.invoke(app, ["zupt", "run", str(f), "--detector", "labels:shoe", "--json", str(out),
                            "--out", str(tmp_path / "traj.npz")])
    assert r.exit_code == 0, r.output
    summary = json.loads(out.read_text())
    # trial_error[0] of the file (published, pyshoe's own EKF, rounded to 1 mm): imunav gives 0.0290 m, -9.4 %;
    # over all 42 trials the ratio has median 0.973 (tests/ins/test_zupt_reference.py)
    assert summary["error_2d_m"] == pytest.approx(0.032, rel=0.10)
    assert (tmp_path / "traj.npz").stat().st_size > 0
    r = runner.invoke(app, ["zupt", "run", str(f), "--detector", "labels:nothing"])
    assert r.exit_code != 0
    r = runner.invoke(app, ["zupt", "run", str(f), "--detector", "magic"])
    assert r.exit_code == 2 and "unknown detector" in r.output


def test_zupt_benchmark_json(tmp_path):
    if not DEFAULT_MODEL_PATH.is_file():
        pytest.skip("shipped model not built yet")
    d = data_path("foot", "pyshoe_vicon")
    out = tmp_path / "bench.json"
    r = runner.invoke(app, ["zupt", "benchmark", str(d), "--limit", "1", "--json", str(out)])
    assert r.exit_code == 0, r.output
    res = json.loads(out.read_text())
    # the JSON shape users' scripts rely on (issue 12): thresholds, trials as a list of rows, mean
    assert {"thresholds", "trials", "mean"} <= set(res) and isinstance(res["trials"], list)
    row = res["trials"][0]
    assert set(row) == {"trial", "shoe", "ared", "amvd", "mbgtd", "lstm"}
    assert row["lstm"] < 0.5


def test_zupt_run_xio_with_aids(tmp_path):
    """The README's x-io command: x-io's stance rule + level floor, loop closure below x-io's 82 mm."""
    f = data_path("foot", "xio_gait", "short_walk.csv")
    out = tmp_path / "xio.json"
    r = runner.invoke(app, ["zupt", "run", str(f), "--detector", "freeacc", "--margin-s", "0.1", "--level-floor",
                            "--json", str(out)])
    assert r.exit_code == 0, r.output
    s = json.loads(out.read_text())
    assert s["loop_closure_m"] < 0.082
    assert s["loop_closure_vertical_m"] < 0.005
    assert s["distance_m"] == pytest.approx(25.0, abs=1.5)  # x-io: a ~25 m walk
    r = runner.invoke(app, ["zupt", "run", str(f), "--states", "15", "--zaru", "--zaru-min-s", "1",
                            "--heading-hold"])
    assert r.exit_code == 0, r.output
    assert "loop_closure_m" in r.output


def test_zupt_run_lstm_reports_its_guard(tmp_path):
    if not DEFAULT_MODEL_PATH.is_file():
        pytest.skip("shipped model not built yet")
    f = data_path("foot", "pyshoe_vicon", "2017-11-22-11-22-03.mat")
    out = tmp_path / "lstm.json"
    r = runner.invoke(app, ["zupt", "run", str(f), "--detector", "lstm", "--json", str(out)])
    assert r.exit_code == 0, r.output
    s = json.loads(out.read_text())
    assert 0.0 <= s["guard_fallback_fraction"] <= 1.0 and s["error_2d_m"] < 0.1


@pytest.mark.parametrize("limit", ["-1", "0"])
def test_zupt_benchmark_limit_must_be_positive(tmp_path, limit):
    line = one_error_line(invoke("zupt", "benchmark", tmp_path, "--limit", limit))
    assert "--limit" in line


def test_failed_zupt_run_out_leaves_no_temp_file(tmp_path, monkeypatch):
    trial = sorted(data_path("foot", "pyshoe_vicon").glob("*.mat"))[0]

    def disk_full(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez_compressed", disk_full)
    r = invoke("zupt", "run", trial, "--out", tmp_path / "z.npz")
    assert "No space left" in one_error_line(r)
    assert list(tmp_path.iterdir()) == []
