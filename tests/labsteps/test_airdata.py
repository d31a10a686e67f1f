"""The airdata lab step runs through run_lab and passes its checks."""

import json

from imunav.lab.runner import run_lab


def test_airdata_lab_step(tmp_path):
    res = run_lab(tmp_path, {"airdata": {"runs": 6, "robust_methods": ["gate2", "nis"]}}, rng=1, steps=["airdata"], progress=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    text = json.dumps(summary)
    assert "airdata" in text
    rep = json.loads((tmp_path / "data" / "airdata_thesis.json").read_text())
    assert len(rep["wind_scenario_tables"]["table_6_3"]) == 14
    for name in ("wind", "innovations", "detectors"):  # imunav.airdata.plot renders from results
        assert (tmp_path / "figures" / f"airdata_{name}.png").stat().st_size > 5000
    assert res is not None
