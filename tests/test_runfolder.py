"""Run folders of ``lab`` and ``batch`` (issue 16, item 3 / deliverable 4).

A folder holding another run is refused unless ``--overwrite`` (which clears only imunav runs);
``manifest.json`` is written last; readers trust only the files of a complete manifest and refuse a
killed run; temp files are hidden, ignored and removed; ``batch.json`` comes after the units.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import RunFolderError
from imunav.files import atomic_path
from imunav.lab import batch as batch_mod
from imunav.lab import runner as lab_mod
from imunav.lab.batch import calibrate_batch, find_units, simulate_batch
from imunav.lab.runfolder import FAILED, FILES, MANIFEST, MARKER, RunFolder, read_manifest, sha256_file
from imunav.lab.runner import StepResult, run_lab

ROOT = Path(__file__).resolve().parents[1]
SIM = dict(fs=10.0, dwell_s=2.0, transition_s=1.0, rate_table=False, executor="serial")


def _one_line_exit_2(r):
    assert r.exit_code == 2, (r.exit_code, r.stdout[-500:], r.stderr[-1000:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in r.stderr, r.stderr
    return lines[0]


def test_manifest_lists_every_file_with_size_and_hash(tmp_path):
    out = tmp_path / "b"
    simulate_batch(2, out, rng=5, **SIM)
    m = read_manifest(out)
    assert m.kind == "batch-simulate" and m.seed == 5 and len(m.run_id) == 36
    listed = {f["path"]: f for f in m.files}
    on_disk = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file() and p.name != MANIFEST}
    assert set(listed) == on_disk
    assert {"unit_001.npz", "unit_002.npz", "batch.json", "segments.json", "truth/unit_001.json"} <= set(listed)
    for rel, f in listed.items():
        assert f["size"] == (out / rel).stat().st_size and f["sha256"] == sha256_file(out / rel)
    assert not (out / MARKER).exists()
    # the manifest is the last file written
    assert (out / MANIFEST).stat().st_mtime_ns >= max((out / rel).stat().st_mtime_ns for rel in listed)


def test_a_folder_holding_another_run_is_refused(tmp_path):
    out = tmp_path / "b"
    simulate_batch(3, out, rng=0, **SIM)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with pytest.raises(RunFolderError, match="holds the finished run .*--overwrite"):
        simulate_batch(2, out, rng=1, **SIM)
    r = CliRunner().invoke(app, ["batch", "simulate", "2", "--out", str(out), "--fs", "10", "--dwell", "2",
                                 "--no-rate-table", "--executor", "serial", "--quiet"])
    assert "--overwrite" in _one_line_exit_2(r)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before  # untouched
    # a folder of someone else's files is refused too, even with --overwrite, and left as it was
    other = tmp_path / "mine"
    other.mkdir()
    (other / "notes.txt").write_text("keep me")
    with pytest.raises(RunFolderError):
        simulate_batch(1, other, **SIM)
    with pytest.raises(RunFolderError, match="no imunav run manifest or file log lists.*notes.txt"):
        simulate_batch(1, other, overwrite=True, **SIM)
    assert (other / "notes.txt").read_text() == "keep me"


def test_resimulating_fewer_units_with_overwrite_leaves_no_old_unit(tmp_path):
    out = tmp_path / "b"
    simulate_batch(3, out, rng=0, **SIM)
    calibrate_batch(out, executor="serial")  # a nested run folder: b/calibration
    r = CliRunner().invoke(app, ["batch", "simulate", "2", "--out", str(out), "--fs", "10", "--dwell", "2",
                                 "--no-rate-table", "--executor", "serial", "--quiet", "--seed", "4", "--overwrite"])
    assert r.exit_code == 0, r.stderr
    assert [p.name for p in find_units(out)] == ["unit_001.npz", "unit_002.npz"]
    assert not any(out.rglob("unit_003*")) and not (out / "calibration").exists()
    assert read_manifest(out).seed == 4 and json.loads((out / "batch.json").read_text())["n_units"] == 2


def test_batch_json_comes_after_the_units_and_a_failed_run_has_no_manifest(tmp_path, monkeypatch):
    real = batch_mod._simulate_unit

    def second_unit_dies(item, **kw):
        if item[0] == 1:
            raise MemoryError("killed")
        return real(item, **kw)

    monkeypatch.setattr(batch_mod, "_simulate_unit", second_unit_dies)
    out = tmp_path / "b"
    with pytest.raises(MemoryError):
        simulate_batch(3, out, **SIM)
    # all or nothing: the unit written before the failure is gone; FAILED says why
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [FAILED]
    assert "MemoryError: killed" in (out / FAILED).read_text()
    assert (out / MARKER).exists() and not (out / MANIFEST).exists()
    # readers refuse the failed run with a clear message
    with pytest.raises(RunFolderError, match="failed"):
        find_units(out)
    r = CliRunner().invoke(app, ["batch", "calibrate", str(out), "--executor", "serial", "--quiet"])
    assert "failed" in _one_line_exit_2(r)
    assert not (out / "calibration").exists()
    # a new run needs --overwrite, which removes FAILED (the run's own) and nothing else
    (out / "notes.txt").write_text("mine")
    with pytest.raises(RunFolderError, match="notes.txt"):
        simulate_batch(1, out, overwrite=True, **SIM)
    (out / "notes.txt").unlink()
    simulate_batch(1, out, overwrite=True, **SIM)
    assert read_manifest(out).kind == "batch-simulate" and not (out / FAILED).exists()


def test_readers_trust_only_the_manifest(tmp_path):
    out = tmp_path / "b"
    simulate_batch(2, out, **SIM)
    # a stale unit left by someone (or an older run) beside the manifest's units, and an orphan temp file
    (out / "unit_003.npz").write_bytes((out / "unit_001.npz").read_bytes())
    (out / ".unit_004.npz.k2j3.tmp.npz").write_bytes(b"half written")
    assert [p.name for p in find_units(out)] == ["unit_001.npz", "unit_002.npz"]
    # a listed file changed after the run: refused
    (out / "truth" / "unit_002.json").write_text("{}")
    with pytest.raises(RunFolderError, match="differs from"):
        find_units(out)


def test_plain_folders_ignore_hidden_temp_files(tmp_path):
    """A user's folder of recordings (no manifest): a hidden temp file of a killed writer is not a unit."""
    simulate_batch(1, tmp_path / "b", **SIM)
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "unit_001.npz").write_bytes((tmp_path / "b" / "unit_001.npz").read_bytes())
    (plain / ".unit_002.npz.x1y2.tmp.npz").write_bytes(b"\x00" * 100)
    assert [p.name for p in find_units(plain)] == ["unit_001.npz"]


def test_concurrent_runs_second_refused_or_takeover_detected(tmp_path):
    out = tmp_path / "run"
    with RunFolder(out, "demo-a"):
        (out / "a.txt").write_text("a")
        with pytest.raises(RunFolderError, match="still going or was killed"):
            RunFolder(out, "demo-b").start()
        r = CliRunner().invoke(app, ["batch", "simulate", "1", "--out", str(out), "--fs", "10", "--dwell", "2",
                                     "--no-rate-table", "--executor", "serial", "--quiet"])
        _one_line_exit_2(r)
    assert read_manifest(out).kind == "demo-a"
    # a second run that forces its way in (overwrite) while the first is still writing:
    # the first finds the marker is not its own and writes no manifest
    out2 = tmp_path / "run2"
    a = RunFolder(out2, "demo-a").start()
    with atomic_path(out2 / "a.txt") as tmp:  # written the way imunav writes: recorded in the run's file log
        tmp.write_text("a")
    with RunFolder(out2, "demo-b", overwrite=True):
        (out2 / "b.txt").write_text("b")
    with pytest.raises(RunFolderError, match="took over"):
        a.finish()
    m = read_manifest(out2)
    assert m.kind == "demo-b" and [f["path"] for f in m.files] == ["b.txt"]


def test_overwrite_never_clears_a_folder_holding_an_input(tmp_path, monkeypatch):
    out = tmp_path / "b"
    simulate_batch(1, out, **SIM)
    spec = out / "truth" / "unit_001.json"
    with pytest.raises(RunFolderError, match="holds an input"):
        RunFolder(out, "x", overwrite=True, inputs=[spec]).start()
    monkeypatch.chdir(out)
    with pytest.raises(RunFolderError, match="working folder"):
        RunFolder(out, "x", overwrite=True).start()
    assert spec.exists()


# ---------------------------------------------------------------- the lab
@pytest.fixture
def fast_step(monkeypatch):
    def run(ctx):
        p = ctx.path("data", "x.json")
        p.write_text(json.dumps({"seed": ctx.seed}))
        return StepResult({"ok": 1}, passed=True)

    mod = types.ModuleType("imunav.lab.steps.zz_fast")
    mod.TITLE, mod.run = "fast", run
    monkeypatch.setitem(sys.modules, "imunav.lab.steps.zz_fast", mod)
    monkeypatch.setattr(lab_mod, "available_steps", lambda: ["zz_fast", "zz_interrupt"])
    return mod


def test_lab_report_folder_is_a_run_folder(tmp_path, fast_step):
    out = tmp_path / "rep"
    run_lab(out, {"lab": {"seed": 3}}, steps=["zz_fast"], progress=False)
    m = read_manifest(out)
    assert m.kind == "lab" and m.seed == 3
    assert {"summary.json", "summary.md", "index.html", "data/x.json"} <= {f["path"] for f in m.files}
    with pytest.raises(RunFolderError, match="finished run"):
        run_lab(out, {"lab": {"seed": 4}}, steps=["zz_fast"], progress=False)
    r = CliRunner().invoke(app, ["lab", "--out", str(out), "--steps", "zz_fast", "--quiet"])
    _one_line_exit_2(r)
    r = CliRunner().invoke(app, ["lab", "--out", str(out), "--steps", "zz_fast", "--quiet", "--seed", "9",
                                 "--overwrite"])
    assert r.exit_code == 0, r.stderr
    assert read_manifest(out).seed == 9 and json.loads((out / "data" / "x.json").read_text())["seed"] == 9


def test_an_interrupted_lab_leaves_no_manifest(tmp_path, fast_step, monkeypatch):
    def interrupt(ctx):
        raise KeyboardInterrupt

    mod = types.ModuleType("imunav.lab.steps.zz_interrupt")
    mod.TITLE, mod.run = "interrupt", interrupt
    monkeypatch.setitem(sys.modules, "imunav.lab.steps.zz_interrupt", mod)
    out = tmp_path / "rep"
    with pytest.raises(KeyboardInterrupt):
        run_lab(out, {}, steps=["zz_fast", "zz_interrupt"], progress=False)
    # the step's file is removed (all or nothing); FAILED says the lab was interrupted
    assert not (out / "data").exists() and not (out / MANIFEST).exists() and (out / MARKER).exists()
    assert "interrupted" in (out / FAILED).read_text()
    with pytest.raises(RunFolderError, match="failed"):
        read_manifest(out)


def _cli_process(args, cwd):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    return subprocess.Popen([sys.executable, "-m", "imunav.cli.main", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for(pred, timeout=60.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if pred():
            return True
        time.sleep(0.05)
    return False


def test_a_killed_batch_run_is_refused_then_cleared_by_overwrite(tmp_path):
    """SIGKILL (no clean-up at all) in the middle of `batch simulate`: the folder keeps its marker and
    no manifest; readers refuse it; a new run needs --overwrite, which clears it, orphan temp file included."""
    out = tmp_path / "b"
    args = ["batch", "simulate", "400", "--out", str(out), "--fs", "20", "--dwell", "2", "--no-rate-table",
            "--executor", "serial", "--quiet"]
    proc = _cli_process(args, tmp_path)
    try:
        assert _wait_for(lambda: (out / "unit_002.npz").exists()), proc.stderr.read() if proc.poll() else ""
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    (out / ".unit_009.npz.abcd.tmp.npz").write_bytes(b"half")  # what a kill during a write leaves
    assert (out / MARKER).exists() and not (out / MANIFEST).exists() and not (out / "batch.json").exists()
    assert "unit_001.npz" in (out / FILES).read_text()  # the file log names the run's files
    r = CliRunner().invoke(app, ["batch", "calibrate", str(out), "--executor", "serial", "--quiet"])
    assert "incomplete run" in _one_line_exit_2(r)
    r = CliRunner().invoke(app, ["batch", "simulate", "2", "--out", str(out), "--fs", "10", "--dwell", "2",
                                 "--no-rate-table", "--executor", "serial", "--quiet"])
    assert "still going or was killed" in _one_line_exit_2(r)
    # the user keeps notes in the killed run's folder: --overwrite refuses, naming them, and deletes nothing
    (out / "notes.txt").write_text("my notes")
    n_before = len(list(out.rglob("*")))
    r = CliRunner().invoke(app, ["batch", "simulate", "2", "--out", str(out), "--fs", "10", "--dwell", "2",
                                 "--no-rate-table", "--executor", "serial", "--quiet", "--overwrite"])
    assert "notes.txt" in _one_line_exit_2(r)
    assert (out / "notes.txt").read_text() == "my notes" and len(list(out.rglob("*"))) == n_before
    (out / "notes.txt").unlink()
    r = CliRunner().invoke(app, ["batch", "simulate", "2", "--out", str(out), "--fs", "10", "--dwell", "2",
                                 "--no-rate-table", "--executor", "serial", "--quiet", "--overwrite"])
    assert r.exit_code == 0, r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["batch.json", "manifest.json", "segments.json", "truth",
                                                     "unit_001.npz", "unit_002.npz"]
    assert np.load(out / "unit_002.npz")  # a readable recording


def test_overwrite_keeps_what_no_manifest_lists(tmp_path):
    """A user's symlink to a listed file is not listed (paths compared as written, not resolved): --overwrite refuses
    rather than delete it; an empty folder of the user's survives, a folder that held listed files goes (review)."""
    from imunav.errors import RunFolderError
    from imunav.lab.runfolder import RunFolder

    d = tmp_path / "run"
    with RunFolder(d, "demo"):
        (d / "a.txt").write_text("a")
        (d / "sub").mkdir()
        (d / "sub" / "b.txt").write_text("b")
    os.symlink("a.txt", d / "mylink")
    (d / "emptyuser").mkdir()
    with pytest.raises(RunFolderError, match="mylink"):
        with RunFolder(d, "demo", overwrite=True):
            pass
    assert (d / "mylink").is_symlink() and (d / "a.txt").exists()
    os.remove(d / "mylink")
    with RunFolder(d, "demo", overwrite=True):
        (d / "c.txt").write_text("c")
    assert sorted(p.name for p in d.iterdir()) == ["c.txt", "emptyuser", "manifest.json"]
