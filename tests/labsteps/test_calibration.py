"""The lab's calibration step on the simulated tests (small and fast settings)."""

import json

from imunav.lab.runner import run_lab


def test_calibration_step(tmp_path):
    cfg = {"simulate_tests": {"fs": 5.0, "dwell_s": 30.0, "tests": ["hundred_position", "rate_table"], "figures": False},
           "calibration": {"figures": False}}
    run_lab(tmp_path, config=cfg, rng=1, steps=["simulate_tests", "calibration"], progress=False)
    s = json.loads((tmp_path / "summary.json").read_text())
    step = next(x for x in s["steps"] if x["name"] == "calibration")
    assert step["passed"] is True, step
    assert step["summary"]["share_within_3_sigma"] >= 0.9
    assert (tmp_path / "data" / "calibration.json").exists()
