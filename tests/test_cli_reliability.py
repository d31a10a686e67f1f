"""Issue 27: never lose a user's file, never answer wrong in silence -- one test through the CLI per cause.

Each test names the cause of the issue it covers; together with ``test_cli_hostile.py`` (the cases the
CLI generates from its own options) they check the contract of the README's "Reliability" section.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.io import write_imu
from imunav.runfolder import FILES, MANIFEST, MARKER
from imunav.timeseries import ImuData

runner = CliRunner()


def _exit_2(r) -> str:
    assert r.exit_code == 2, (r.exit_code, r.stdout[-500:], r.stderr[-1000:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in r.stderr, r.stderr
    return lines[0]


def _rec(n: int = 400, fs: float = 100.0) -> ImuData:
    rng = np.random.default_rng(1)
    return ImuData(t=np.arange(n) / fs, gyro=rng.normal(0, 0.01, (n, 3)),
                   accel=np.tile([0.0, 0.0, -9.80665], (n, 1)) + rng.normal(0, 0.01, (n, 3)))


def _snapshot(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


# --------------------------------------------------------------------------- a user's files are deleted
def _killed_run(folder: Path, kind: str, written: list[str]) -> None:
    """What a run killed with SIGKILL leaves: its marker (a dead pid), its file log and its files."""
    folder.mkdir(parents=True)
    (folder / MARKER).write_text(json.dumps({"run_id": "x", "kind": kind, "pid": 2**22 + 7, "started": "then"}))
    (folder / FILES).write_text("".join(json.dumps(w) + "\n" for w in written))
    for w in written:
        (folder / w).parent.mkdir(parents=True, exist_ok=True)
        (folder / w).write_text("partial")


@pytest.mark.parametrize("argv", [
    ["batch", "simulate", "1", "--fs", "10", "--dwell", "2", "--no-rate-table", "--executor", "serial", "--quiet"],
    ["lab", "--steps", "noise", "--quiet"],
])
def test_overwrite_of_a_killed_run_keeps_the_users_notes(tmp_path, argv):
    out = tmp_path / "killed_run"
    _killed_run(out, argv[0], ["unit_001.npz", "figures/a.png"])
    (out / "notes.txt").write_text("my notes")
    before = _snapshot(out)
    msg = _exit_2(runner.invoke(app, [*argv, "--out", str(out), "--overwrite"]))
    assert "notes.txt" in msg
    assert _snapshot(out) == before  # nothing removed: not the run's files either (the refusal comes first)


def test_overwrite_of_a_killed_run_removes_only_its_files(tmp_path):
    out = tmp_path / "killed_run"
    _killed_run(out, "batch-simulate", ["unit_001.npz", "truth/unit_001.json"])
    r = runner.invoke(app, ["batch", "simulate", "1", "--fs", "10", "--dwell", "2", "--no-rate-table", "--executor",
                            "serial", "--quiet", "--out", str(out), "--overwrite"])
    assert r.exit_code == 0, r.stderr
    assert (out / MANIFEST).is_file() and not (out / MARKER).exists() and not (out / FILES).exists()


def test_report_folder_holding_an_input_is_refused(tmp_path):
    rec = write_imu(_rec(), tmp_path / "static.npz")
    rep = tmp_path / "rep"
    rep.mkdir()
    seg = rep / "report.json"
    seg.write_text(json.dumps({"segment_table": {}}))
    before = seg.read_bytes()
    msg = _exit_2(runner.invoke(app, ["calibrate", "multiposition", str(rec), "--segments", str(seg), "--report",
                                      str(rep), "--out", str(tmp_path / "cal.json")]))
    assert "input" in msg and str(rep) in msg
    assert seg.read_bytes() == before and not (tmp_path / "cal.json").exists()


def test_output_that_is_a_file_of_an_input_folder_is_refused(tmp_path):
    d = tmp_path / "trials"
    d.mkdir()
    trial = d / "walk_1.mat"
    trial.write_bytes(b"MATLAB 5.0 trial")
    msg = _exit_2(runner.invoke(app, ["zupt", "benchmark", str(d), "--json", str(trial)]))
    assert "input folder" in msg
    assert trial.read_bytes() == b"MATLAB 5.0 trial"


def test_batch_json_over_a_file_of_the_batch_is_refused(tmp_path):
    b = tmp_path / "b"
    r = runner.invoke(app, ["batch", "simulate", "1", "--fs", "10", "--dwell", "2", "--no-rate-table", "--executor",
                            "serial", "--quiet", "--out", str(b)])
    assert r.exit_code == 0, r.stderr
    before = _snapshot(b)
    msg = _exit_2(runner.invoke(app, ["batch", "calibrate", str(b), "--json", str(b / "segments.json"), "--executor",
                                      "serial", "--quiet"]))
    assert "segments.json" in msg and "input" in msg
    assert _snapshot(b) == before


def test_default_segments_name_never_replaces_the_model(tmp_path):
    model = tmp_path / "rec_segments.csv"
    model.write_text('name = "m"\n')
    msg = _exit_2(runner.invoke(app, ["simulate", "static", "--duration", "2", "--model", str(model), "--out",
                                      str(tmp_path / "rec.npz")]))
    assert "--segments" in msg and "--model" in msg
    assert model.read_text() == 'name = "m"\n' and not (tmp_path / "rec.npz").exists()
