"""`imunav airdata` commands end to end (small runs)."""

import json

import numpy as np
import pytest
from cli_contract import invoke, one_error_line
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import InvalidInputError

runner = CliRunner()


def test_thesis_command_writes_covariance_sequence(tmp_path):
    out = tmp_path / "thesis.json"
    res = runner.invoke(app, ["airdata", "thesis", "--runs", "8", "--robust-methods", "gate2,nis", "--json", str(out)])
    assert res.exit_code == 0, res.output
    rep = json.loads(out.read_text())
    np.testing.assert_allclose(rep["covariance_sequence"]["P44"], rep["covariance_sequence"]["P44_thesis"], atol=1e-4)
    fa = rep["monte_carlo"]["false_alarms"]
    assert fa["alg1"]["per_step_thesis"] > 0.3 and fa["alg1"]["per_step"] < 0.05
    assert rep["single_run_detection"]["variance"]["fault_step"] == 151


def test_simulate_run_and_faults(tmp_path):
    f = tmp_path / "th.npz"
    assert runner.invoke(app, ["airdata", "simulate", "thesis", "--kind", "outliers", "--out", str(f)]).exit_code == 0
    js = tmp_path / "run.json"
    res = runner.invoke(app, ["airdata", "run", str(f), "--robust", "nis", "--json", str(js)])
    assert res.exit_code == 0, res.output
    s = json.loads(js.read_text())
    assert max(s["wind_rms_per_axis"]) < 0.5 and s["rejected_samples"] >= 9
    fl = tmp_path / "flight.npz"
    res = runner.invoke(app, ["airdata", "simulate", "cruise", "--duration", "30", "--out", str(fl)])
    assert res.exit_code == 0, res.output
    png = tmp_path / "lh.png"
    res = runner.invoke(app, ["airdata", "run", str(fl), "--json", str(tmp_path / "r2.json"), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 5000
    fj = tmp_path / "f.json"
    res = runner.invoke(app, ["airdata", "faults", "--kind", "bias", "--channels", "0", "--runs", "5", "--json", str(fj)])
    assert res.exit_code == 0, res.output
    rows = json.loads(fj.read_text())["rows"]
    assert any(r["detector"] == "alg3" and r["missed"] == 0.0 for r in rows)


def test_cli_bad_inputs(tmp_path):
    res = runner.invoke(app, ["airdata", "run", str(tmp_path / "missing.npz")])
    assert res.exit_code == 2 and "no such file" in res.output
    res = runner.invoke(app, ["airdata", "faults", "--channels", "7", "--runs", "2"])
    assert res.exit_code == 2 and "--channels" in res.output and "in [0, 2]" in res.output
    res = runner.invoke(app, ["airdata", "simulate", "cruise", "--wind", "1,2", "--out", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "3 comma-separated" in res.output


def test_toml_config(tmp_path):
    from imunav.airdata.scenario import WindScenario, load_config
    from imunav.errors import ConfigError
    from imunav.sim.flight import FlightConfig

    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    fc = load_config(root / "examples" / "airdata_flight.toml")
    assert isinstance(fc, FlightConfig) and fc.over_water == ((100.0, 200.0),) and fc.doppler.scale == 0.002
    tc = load_config(root / "examples" / "airdata_thesis_bias.toml")
    assert isinstance(tc, WindScenario) and tc.channels == (0,) and tc.kind == "bias"
    bad = tmp_path / "bad.toml"
    bad.write_text("[thesis]\nkind = 'bias'\nbias_mps = 3\n")
    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['bias_mps'\]"):
        load_config(bad)
    bad.write_text("[thesis]\nkind = 'icing'\n")
    with pytest.raises(ConfigError, match="kind must be one of"):
        load_config(bad)
    bad.write_text("[other]\n")
    with pytest.raises(ConfigError, match="exactly one"):
        load_config(bad)


@pytest.mark.parametrize("gate", ["0", "-1", "nan"])
def test_gate_m_must_be_positive(tmp_path, gate):
    from imunav.airdata.filter import BodyWindFilter

    with pytest.raises(InvalidInputError, match="gate_m"):
        BodyWindFilter(robust="gate", gate_m=float(gate)).run(np.zeros((20, 3)))
    assert invoke("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "a.npz").exit_code == 0
    assert "gate" in one_error_line(invoke("airdata", "run", tmp_path / "a.npz", "--robust", "gate", "--gate-m", gate))


def test_airdata_simulate_out_csv_is_refused(tmp_path):
    assert ".npz" in one_error_line(invoke("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "x.csv"))
    assert not (tmp_path / "x.csv").exists()
