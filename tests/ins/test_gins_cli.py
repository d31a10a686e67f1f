"""``imunav gins simulate`` / ``imunav gins run``: KF-GINS files in, KF-GINS outputs and a JSON summary out."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.io.gnss import read_table
from imunav.io.kfgins import read_kfgins_nav


def test_simulate_then_run_a_kfgins_configuration(tmp_path):
    r = CliRunner()
    d = tmp_path / "drive"
    res = r.invoke(app, ["gins", "simulate", "--out", str(d), "--duration", "150", "--fs", "50", "--seed", "3"])
    assert res.exit_code == 0, res.output
    res = r.invoke(app, ["gins", "run", "--config", str(d / "kf-gins.yaml"), "--truth", str(d / "truth.nav"),
                         "--smoother"])
    assert res.exit_code == 0, res.output
    out = d / "result"  # the YAML's outputpath, relative to the YAML
    nav = read_kfgins_nav(out / "KF_GINS_Navresult.nav")
    assert nav.t.size == 7501
    assert read_table(out / "KF_GINS_IMU_ERR.txt", (13,), "x").shape == (7501, 13)
    assert read_table(out / "KF_GINS_STD.txt", (22,), "x").shape[1] == 22
    s = json.loads((out / "summary.json").read_text())
    # 1 Hz fixes with 0.5 / 0.5 / 1 m noise: the filter beats the fixes, the smoother beats the filter
    assert np.linalg.norm(s["rmse"]["pos_ned_m"][:2]) < 0.7
    assert np.linalg.norm(s["rmse_smoothed"]["pos_ned_m"]) < np.linalg.norm(s["rmse"]["pos_ned_m"])
    assert abs(s["gnss_position_nis_mean"] - 3) < 1.0


def test_user_errors_are_one_line_and_exit_2(tmp_path):
    r = CliRunner()
    res = r.invoke(app, ["gins", "run", "--config", str(tmp_path / "missing.yaml")])
    assert res.exit_code == 2 and "missing.yaml" in res.output and "Traceback" not in res.output
    (tmp_path / "bad.yaml").write_text("imupath: 3\n")
    res = r.invoke(app, ["gins", "run", "--config", str(tmp_path / "bad.yaml")])
    assert res.exit_code == 2 and "imunoise" in res.output
    res = r.invoke(app, ["gins", "simulate", "--out", str(tmp_path / "x"), "--duration", "10"])
    assert res.exit_code == 2 and "120" in res.output
