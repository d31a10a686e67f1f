"""``imunav info``: summary table, JSON output, help example, errors."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from builders import static_imu
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.io import write_imu
from imunav.timeseries import ImuData
from imunav.units import DEG, G0

runner = CliRunner()


def _recording(path):
    """20 s at 100 Hz: rest 0-8 s, motion 8-12 s (gyro clipped at 250 °/s), rest 12-20 s; 3 samples lost at 5 s."""
    n = 2000
    rest = static_imu(n, seed=7, gyro_sd=1e-3, accel_sd=1e-2)
    t, gyro, accel = rest.t, rest.gyro.copy(), rest.accel.copy()
    k = np.arange(400) / 100.0
    gyro[800:1200] += np.column_stack([np.sin(2 * k), np.cos(3 * k), np.sin(k)]) * 2.0
    accel[800:1200] += np.column_stack([np.sin(5 * k), np.cos(4 * k), np.sin(3 * k)]) * 3.0
    gyro[1000:1005, 0] = 250 * DEG
    keep = np.ones(n, bool)
    keep[500:503] = False
    d = ImuData(t[keep], gyro[keep], accel[keep], temp=np.full(keep.sum(), 30.0), meta={"sensor": "demo"})
    write_imu(d, path)
    return d


def test_info_table_and_json(tmp_path):
    p = tmp_path / "rec.h5"
    _recording(p)
    out = tmp_path / "info.json"
    res = runner.invoke(app, ["info", str(p), "--json", str(out), "--gyro-full-scale-dps", "250"])
    assert res.exit_code == 0, res.output
    assert "1,997" in res.output and "static intervals" in res.output and "gyro_x 5" in res.output
    d = json.loads(out.read_text())
    assert d["n"] == 1997 and d["fs_hz"] == pytest.approx(100.0)
    assert d["duration_s"] == pytest.approx(19.99)
    assert [(g["index"], g["missing_samples"]) for g in d["gaps"]] == [(499, 3)]
    assert d["saturation"]["counts"]["gyro_x"] == 5 and d["saturation"]["method"] == "full_scale"
    si = d["static_intervals"]
    assert len(si["starts"]) == 2
    # rest ends at 8 s and resumes at 12 s, within one window (1 s)
    assert si["t_stop"][0] == pytest.approx(8.0, abs=1.0) and si["t_start"][1] == pytest.approx(12.0, abs=1.0)
    temp = next(c for c in d["channels"] if c["channel"] == "temp")
    assert temp["mean"] == 30.0 and temp["unit"] == "degC"
    gz = next(c for c in d["channels"] if c["channel"] == "accel_z")
    assert gz["unit"] == "m/s^2" and gz["mean"] == pytest.approx(-G0, abs=0.2)
    assert d["meta"] == {"sensor": "demo"}


def test_help_example_runs(tmp_path, monkeypatch):
    res = runner.invoke(app, ["info", "--help"], env={"COLUMNS": "400"})
    assert res.exit_code == 0 and "Example:" in res.output
    text = re.sub(r"\s+", " ", res.output)
    code = re.search(r'python -c "(.*?)"', text).group(1)
    monkeypatch.chdir(tmp_path)
    exec(code, {})  # the example's first step writes rec.csv
    res = runner.invoke(app, ["info", "rec.csv", "--json", "info.json"])
    assert res.exit_code == 0, res.output
    assert json.loads((tmp_path / "info.json").read_text())["n"] == 3000


def test_info_foreign_csv_options(tmp_path):
    p = tmp_path / "raw.txt"
    rows = "\n".join(f"{i},{131 * (i % 2)},0,0,0,0,16384" for i in range(300))
    p.write_text("idx,GX,GY,GZ,AX,AY,AZ\n" + rows + "\n")
    res = runner.invoke(
        app,
        ["info", str(p), "--fs", "50", "--gyro-unit", "counts", "--gyro-scale", str(DEG / 131), "--accel-unit", "counts",
         "--accel-scale", str(G0 / 16384), "--column", "gx=GX", "--column", "gy=GY", "--column", "gz=GZ",
         "--column", "ax=AX", "--column", "ay=AY", "--column", "az=AZ", "--json", str(tmp_path / "o.json")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    d = json.loads((tmp_path / "o.json").read_text())
    assert d["fs_hz"] == pytest.approx(50.0) and d["n"] == 300
    gx = d["channels"][0]
    assert gx["mean"] == pytest.approx(0.5) and gx["max"] == pytest.approx(1.0)  # deg/s


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["missing.csv"], "no such file"),
        (["bad.csv"], "cannot find the columns"),
        (["bad.csv", "--column", "gx"], "KEY=NAME"),
    ],
)
def test_info_errors_exit_2(tmp_path, monkeypatch, args, match):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.csv").write_text("a,b,c\n1,2,3\n")
    res = runner.invoke(app, ["info", *args])
    assert res.exit_code == 2
    assert match in re.sub(r"\s+", " ", res.output)
