"""`imunav simulate` end to end (typer CliRunner)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.io import read_imu
from imunav.units import G0

runner = CliRunner()


def test_simulate_ideal_static_with_earth_rate(tmp_path):
    out = tmp_path / "static.csv"
    res = runner.invoke(app, ["simulate", "static", "--preset", "ideal", "--duration", "5", "--fs", "20",
                              "--lat-deg", "45", "--out", str(out), "--json", str(tmp_path / "s.json")])
    assert res.exit_code == 0, res.output
    data = read_imu(out)
    assert data.n == 101
    from imunav import earth

    g = earth.normal_gravity(np.pi / 4)
    np.testing.assert_allclose(data.accel, np.tile([0, 0, -g], (101, 1)), atol=1e-12)
    np.testing.assert_allclose(data.gyro[:, 0], earth.OMEGA_E * np.cos(np.pi / 4), rtol=1e-12)
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["earth_rate"] is True and summary["segments"] == {"static": 1}
    assert json.loads((tmp_path / "static_segments.json").read_text())["segment_table"]["kind"] == ["static"]


def test_simulate_rate_table_with_preset_is_seeded(tmp_path):
    args = ["simulate", "ratetable", "--preset", "thesis_sim", "--fs", "10", "--dwell", "1", "--transition", "0.5"]
    r1 = runner.invoke(app, args + ["--seed", "3", "--out", str(tmp_path / "a.npz")])
    r2 = runner.invoke(app, args + ["--seed", "3", "--out", str(tmp_path / "b.npz")])
    r3 = runner.invoke(app, args + ["--seed", "4", "--out", str(tmp_path / "c.npz")])
    assert r1.exit_code == r2.exit_code == r3.exit_code == 0, r1.output
    a, b, c = (read_imu(tmp_path / f"{k}.npz") for k in "abc")
    np.testing.assert_array_equal(a.gyro, b.gyro)
    assert not np.array_equal(a.gyro, c.gyro)
    assert runner.invoke(app, args + ["--seed", "3", "--out", str(tmp_path / "d.npz"), "--segments",
                                      str(tmp_path / "a_segments.csv")]).exit_code == 0
    seg = np.genfromtxt(tmp_path / "a_segments.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert np.sum(seg["kind"] == "rate") == 120
    # during the +250 deg/s step about x the x gyro reads about (1 + S_x) * 250 deg/s + bias
    k = np.flatnonzero((seg["kind"] == "rate") & np.isclose(seg["rate_dps"], 250.0) & (seg["axis_x"] == 1.0))[0]
    m = np.rad2deg(a.gyro[seg["i_start"][k] : seg["i_stop"][k], 0].mean())
    assert m == pytest.approx(250 * (1 + 0.019872) + 1.4402 + 0.0485, abs=0.1)
    assert np.mean(a.accel[seg["i_start"][k] : seg["i_stop"][k], 0]) / G0 == pytest.approx(1 + 0.021283 + 0.3945, abs=0.01)


@pytest.mark.parametrize("profile", ["multiposition", "sixposition", "ferraris"])
def test_simulate_other_profiles(tmp_path, profile):
    out = tmp_path / f"{profile}.npz"
    res = runner.invoke(app, ["simulate", profile, "--preset", "ideal", "--fs", "10", "--dwell", "1",
                              "--transition", "1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    data = read_imu(out)
    np.testing.assert_allclose(np.linalg.norm(data.accel, axis=1)[data.gyro.any(axis=1) == 0], G0, rtol=1e-12)


def test_simulate_bad_inputs(tmp_path):
    res = runner.invoke(app, ["simulate", "loop", "--out", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "unknown profile 'loop'" in res.output
    res = runner.invoke(app, ["simulate", "static", "--earth-rate", "--out", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "--lat-deg" in res.output
    res = runner.invoke(app, ["simulate", "static", "--preset", "nope", "--duration", "1", "--out", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "nope" in res.output
    res = runner.invoke(app, ["simulate", "static", "--gravity", "heavy", "--out", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "--gravity" in res.output


def test_cli_simulate_refuses_bad_latitude_and_height(tmp_path):
    from typer.testing import CliRunner

    from imunav.cli.main import app

    for extra in (["--lat-deg", "100"], ["--lat-deg", "45", "--h-m", "1e12"]):
        r = CliRunner().invoke(app, ["simulate", "static", "--duration", "2", "--out", str(tmp_path / "s.csv"), *extra])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert not (tmp_path / "s.csv").exists()


def test_simulate_segments_chain_into_calibrate(tmp_path):
    """What `simulate --segments` writes (JSON by default, or CSV) is what `calibrate --segments` reads (issue 26)."""
    from imunav.sim import Segments

    args = ["simulate", "ratetable", "--preset", "ideal", "--fs", "10", "--dwell", "1", "--transition", "0.5"]
    assert runner.invoke(app, args + ["--out", str(tmp_path / "r.npz")]).exit_code == 0
    assert runner.invoke(app, args + ["--out", str(tmp_path / "r2.npz"), "--segments", str(tmp_path / "r.csv")]
                         ).exit_code == 0
    a, b = Segments.read(tmp_path / "r_segments.json"), Segments.read(tmp_path / "r.csv")
    assert len(a) == len(b) > 120
    for f in ("kind", "step", "i_start", "i_stop"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    for f in ("t_start", "t_stop", "q_nb", "up_b", "axis_b", "rate", "angle"):
        np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=1e-15, atol=1e-15)
