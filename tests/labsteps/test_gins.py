"""The ``gins`` lab step through the lab runner: a simulated drive, and files named in the lab TOML."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import chi2
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import ConfigError
from imunav.lab.runner import parse_lab_config, run_lab


def test_gins_step_on_a_simulated_drive(tmp_path):
    res = run_lab(tmp_path, {"lab": {"steps": ["gins"]}, "gins": {"duration": 150, "fs": 50, "seed": 4}}, rng=1,
                  progress=False)
    assert not res.failed_steps, res.steps[0].error
    s = json.loads((tmp_path / "summary.json").read_text())["steps"][0]
    assert s["name"] == "gins" and s["passed"] is True
    summ = s["summary"]
    n = summ["gnss_used"]
    assert n == 150  # 151 fixes at 1 Hz, the one at the first IMU sample stands for the initial state
    # the band is that of the mean of n chi2(3) variables, independently recomputed here
    assert summ["nis_band_99"] == pytest.approx([chi2.ppf(0.005, 3 * n) / n, chi2.ppf(0.995, 3 * n) / n])
    assert np.linalg.norm(summ["rmse"]["pos_ned_m"][:2]) < 0.7  # below the fixes' own 0.71 m horizontal σ
    for name in ("track", "errors", "imu_errors"):
        assert (tmp_path / "figures" / f"gins_{name}.png").stat().st_size > 20_000
    assert json.loads((tmp_path / "data" / "gins_summary.json").read_text())["gnss_used"] == n
    assert summ["gnss_fixes"] == n and summ["gnss_accepted_share"] == 1.0  # every fix evaluated, none gated


def test_gins_step_on_files_of_the_lab_toml(tmp_path):
    assert CliRunner().invoke(app, ["gins", "simulate", "--out", str(tmp_path / "drive"), "--duration", "150",
                                    "--fs", "50", "--seed", "5"]).exit_code == 0
    lab = tmp_path / "lab.toml"
    lab.write_text('[lab]\nsteps = ["gins"]\n[gins]\nconfig = "drive/kf-gins.yaml"\ntruth = "drive/truth.nav"\n'
                   "states = 15\n")
    res = run_lab(tmp_path / "out", lab, progress=False)
    assert not res.failed_steps, res.steps[0].error
    summ = res.steps[0].result.summary
    assert summ["states"] == 15 and summ["source"]["config"].endswith("kf-gins.yaml")
    assert np.linalg.norm(summ["rmse"]["pos_ned_m"][:2]) < 0.7


def test_gins_step_options_are_checked(tmp_path):
    with pytest.raises(ConfigError, match="durations"):
        parse_lab_config({"lab": {"steps": ["gins"]}, "gins": {"durations": 100}})
    # a misconfigured step ends the lab as a user error (issue 27): no report that looks complete
    with pytest.raises(ConfigError, match="does not exist"):
        run_lab(tmp_path / "rep", {"lab": {"steps": ["gins"]}, "gins": {"config": str(tmp_path / "none.toml")}},
                progress=False)
    assert not (tmp_path / "rep").exists()
