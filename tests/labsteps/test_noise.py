"""The lab's noise step on a short static record of the virtual IMU."""

from __future__ import annotations

import json

from imunav.lab.runner import run_lab

CFG = """
[lab]
seed = 3
steps = ["simulate_tests", "noise"]

[simulate_tests]
fs = 50.0
static_duration_s = 1200.0
tests = ["static_long"]
figures = false
format = "npz"

[noise]
decimate_s = 1.0
"""


def test_lab_noise_step(tmp_path):
    cfg = tmp_path / "lab.toml"
    cfg.write_text(CFG)
    res = run_lab(tmp_path / "out", config=cfg)
    rec = {s.name: s for s in res.steps}["noise"]
    assert rec.error is None, rec.error
    assert rec.result.passed, rec.result.tables
    assert rec.result.summary["N_true_inside_familywise_95ci"] == "6/6"
    d = json.loads((tmp_path / "out" / "data" / "noise_fit.json").read_text())
    assert set(d) == {"gyro", "accel"}
    assert all(p.exists() for p in rec.result.figures)
