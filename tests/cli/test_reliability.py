"""Issue 27: never lose a user's file, never answer wrong in silence -- one test through the CLI per cause.

Each test names the cause of the issue it covers; together with ``tests/cli/test_hostile.py`` (the cases the
CLI generates from its own options) they check the contract of the README's "Reliability" section.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.files import json_text
from imunav.io import write_imu
from imunav.lab.runfolder import FAILED, FILES, MANIFEST, MARKER
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
    ["lab", "--steps", "simulate_tests,noise", "--quiet"],
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
    model = tmp_path / "rec_segments.json"
    model.write_text('name = "m"\n')
    msg = _exit_2(runner.invoke(app, ["simulate", "static", "--duration", "2", "--model", str(model), "--out",
                                      str(tmp_path / "rec.npz")]))
    assert "--segments" in msg and "--model" in msg
    assert model.read_text() == 'name = "m"\n' and not (tmp_path / "rec.npz").exists()


# --------------------------------------------------------------------------- partial results that look complete
def test_a_lab_configuration_error_leaves_no_report(tmp_path):
    cfg = tmp_path / "lab.toml"
    cfg.write_text('[lab]\nsteps = ["simulate_tests"]\n[simulate_tests]\nfs = -1.0\n')
    out = tmp_path / "rep"
    msg = _exit_2(runner.invoke(app, ["lab", "--config", str(cfg), "--out", str(out), "--quiet"]))
    assert "fs must be a positive number" in msg
    assert not (out / "index.html").exists() and not (out / MANIFEST).exists() and not (out / "summary.json").exists()


def test_a_lab_that_fails_after_writing_leaves_only_failed(tmp_path, monkeypatch):
    """The first step writes its recordings, the second finds itself misconfigured as it runs: the run's files
    go, FAILED stays (was: a complete-looking report folder with a manifest, exit 1).  (A step whose input no
    earlier step makes, e.g. [noise] record = "nope", is now refused before the first step: nothing written.)"""
    import types

    from imunav.errors import ConfigError
    from imunav.lab import runner as lab_runner

    cfg = tmp_path / "lab.toml"
    cfg.write_text('[lab]\nsteps = ["simulate_tests", "noise"]\n[simulate_tests]\nfs = 10.0\ndwell_s = 2.0\n'
                   'transition_s = 1.0\nstatic_duration_s = 20.0\ntests = ["static_long"]\nfigures = false\n'
                   '[noise]\nrecord = "nope"\n')
    out = tmp_path / "rep"
    msg = _exit_2(runner.invoke(app, ["lab", "--config", str(cfg), "--out", str(out), "--quiet"]))
    assert "nope" in msg and not out.exists()

    def misconfigured(ctx):
        raise ConfigError("[zz_late] nope: found out while running")

    mod = types.ModuleType("imunav.lab.steps.zz_late")
    mod.TITLE, mod.run = "zz_late", misconfigured
    monkeypatch.setitem(sys.modules, "imunav.lab.steps.zz_late", mod)
    monkeypatch.setattr(lab_runner, "available_steps", lambda: ["simulate_tests", "zz_late"])
    msg = _exit_2(runner.invoke(app, ["lab", "--config", str(cfg), "--out", str(out), "--quiet", "--steps",
                                      "simulate_tests,zz_late"]))
    assert "nope" in msg
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [FAILED]
    assert "ConfigError" in (out / FAILED).read_text()


def test_gins_run_with_a_bad_truth_leaves_no_result(tmp_path):
    """`gins run --truth` that fails after the filter ran: no .nav, IMU-error or sigma file is left (all or nothing)."""
    d = tmp_path / "sim"
    r = runner.invoke(app, ["gins", "simulate", "--duration", "120", "--out", str(d)])
    assert r.exit_code == 0, r.stderr
    truth = tmp_path / "other_day.nav"  # a valid truth of another time: found out after the filter ran
    rows = [ln.split() for ln in (d / "truth.nav").read_text().splitlines() if ln.strip()]
    truth.write_text("".join(" ".join([r[0], f"{float(r[1]) + 1e5:.9f}", *r[2:]]) + "\n" for r in rows))
    out = tmp_path / "res"
    _exit_2(runner.invoke(app, ["gins", "run", str(d / "imu.txt"), str(d / "gnss.txt"), "--config", str(d / "gins.toml"),
                                "--truth", str(truth), "--out", str(out)]))
    assert not out.exists() or not any(out.iterdir()), sorted(p.name for p in out.iterdir())


# --------------------------------------------------------------------------- work started that cannot end
@pytest.mark.parametrize("argv, words", [
    (["simulate", "static", "--duration", "1e9", "--out", "{tmp}/x.npz"], "--force"),
    (["attitude", "montecarlo", "--runs", "100000000", "--json", "{tmp}/mc.json"], "--force"),
    (["airdata", "simulate", "cruise", "--duration", "1e9", "--out", "{tmp}/f.npz"], "--force"),
    (["noise", "{rec}", "--taus", "log:1000000000"], "--force"),
])
def test_requests_far_beyond_the_machine_are_refused_with_the_estimate(tmp_path, argv, words):
    rec = write_imu(_rec(), tmp_path / "rec.npz")
    args = [a.format(tmp=tmp_path, rec=rec) for a in argv]
    msg = _exit_2(runner.invoke(app, args))
    assert words in msg and "memory" in msg and "24 GiB" in msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.npz"]


def test_a_fifo_input_is_refused_not_waited_on(tmp_path):
    fifo = tmp_path / "rec.csv"
    os.mkfifo(fifo)
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", "info", str(fifo)], capture_output=True, text=True,
                       env=env, timeout=120)
    assert r.returncode == 2 and "FIFO" in r.stderr and len(r.stderr.strip().splitlines()) == 1


# --------------------------------------------------------------------------- bare internal errors
@pytest.mark.parametrize("argv, flag", [
    (["calibrate", "multiposition", "{rec}", "--segments", "{seg}", "--out", "{tmp}/c.json", "--gravity", "nan"],
     "--gravity"),
    (["calibrate", "multipose", "{rec}", "--out", "{tmp}/c.json", "--init-s", "nan"], "--init-s"),
    (["batch", "calibrate", "{tmp}", "--workers", "-1"], "--workers"),
    (["compensate", "{rec}", "--cal", "{cal}", "--out", "{tmp}/o.npz", "--temp-c", "nan"], "--temp-c"),
    (["simulate", "static", "--duration", "2", "--gravity", "nan", "--out", "{tmp}/s.npz"], "--gravity"),
])
def test_nan_negative_or_zero_options_are_user_errors(tmp_path, argv, flag):
    from imunav.calib import ImuCalibration

    rec = write_imu(_rec(), tmp_path / "rec.npz")
    seg = tmp_path / "seg.json"
    seg.write_text("{}")
    cal = ImuCalibration().save(tmp_path / "cal.json")
    args = [a.format(tmp=tmp_path, rec=rec, seg=seg, cal=cal) for a in argv]
    assert flag in _exit_2(runner.invoke(app, args))


@pytest.mark.parametrize("content, words", [
    ("[1, 2]", "not list"),
    ('{"format": "imunav-calibration", "format_version": 1, "accel": {"bias": ["a", "b", "c"]}}', "accel.bias"),
])
def test_json_inputs_of_the_wrong_shape_name_file_and_key(tmp_path, content, words):
    rec = write_imu(_rec(), tmp_path / "rec.npz")
    cal = tmp_path / "cal.json"
    cal.write_text(content)
    from imunav.calib import ImuCalibration

    good = json.loads(json_text(ImuCalibration().to_dict()))
    if "accel" in content:
        cal.write_text(json.dumps({**good, "accel": {"bias": ["a", "b", "c"], "matrix": good["accel"]["matrix"]}}))
    msg = _exit_2(runner.invoke(app, ["compensate", str(rec), "--cal", str(cal), "--out", str(tmp_path / "o.npz")]))
    assert "cal.json" in msg and words in msg


def test_segment_table_with_text_for_numbers_names_the_column(tmp_path):
    from imunav.sim import hundred_position_profile

    rec = write_imu(_rec(), tmp_path / "rec.npz")
    d = hundred_position_profile(10.0, 2.0, 1.0).to_dict()
    table = d.get("segment_table", d)
    table["t_start"] = ["soon"] * len(table["t_start"])
    seg = tmp_path / "seg.json"
    seg.write_text(json.dumps(d))
    msg = _exit_2(runner.invoke(app, ["calibrate", "multiposition", str(rec), "--segments", str(seg), "--out",
                                      str(tmp_path / "c.json")]))
    assert "seg.json" in msg and "t_start" in msg


def test_a_symlink_loop_is_a_user_error(tmp_path):
    os.symlink(tmp_path / "b.csv", tmp_path / "a.csv")
    os.symlink(tmp_path / "a.csv", tmp_path / "b.csv")
    assert "a.csv" in _exit_2(runner.invoke(app, ["info", str(tmp_path / "a.csv")]))


# --------------------------------------------------------------------------- accepted nonsense
@pytest.mark.parametrize("argv, flag", [
    (["calibrate", "mag", "{rec}", "--out", "{tmp}/m.json", "--min-coverage", "-0.5"], "--min-coverage"),
    (["simulate", "static", "--duration", "2", "--seed", "-3", "--out", "{tmp}/s.npz"], "--seed"),
    (["info", "{rec}", "--skiprows", "-2"], "--skiprows"),
    (["airdata", "simulate", "cruise", "--duration", "5", "--wind", "1e9,0,0", "--out", "{tmp}/f.npz"], "--wind"),
    (["info", "{rec}", "--gyro-unit", ""], "--gyro-unit"),
])
def test_nonsense_options_are_refused(tmp_path, argv, flag):
    rec = write_imu(_rec(), tmp_path / "rec.npz")
    args = [a.format(tmp=tmp_path, rec=rec) for a in argv]
    assert flag in _exit_2(runner.invoke(app, args))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.npz"]


@pytest.mark.parametrize("spec, words", [("[spec.bogus_param]\nmax = 1\n", "bogus_param"),
                                         ("[spec.gyro_bias]\nmax = nan\n", "not a finite number")])
def test_a_spec_with_an_unknown_parameter_or_a_nan_limit_is_refused(tmp_path, spec, words):
    b = tmp_path / "b"
    assert runner.invoke(app, ["batch", "simulate", "1", "--out", str(b), "--fs", "10", "--dwell", "2",
                               "--no-rate-table", "--executor", "serial", "--quiet"]).exit_code == 0
    s = tmp_path / "spec.toml"
    s.write_text(spec)
    msg = _exit_2(runner.invoke(app, ["batch", "calibrate", str(b), "--spec", str(s), "--executor", "serial",
                                      "--quiet"]))
    assert "spec.toml" in msg and words in msg and not (b / "calibration").exists()


# --------------------------------------------------------------------------- messages that leak Python
def test_unknown_filter_parameter_lists_the_known_ones(tmp_path):
    rec = write_imu(_rec(), tmp_path / "rec.npz")
    msg = _exit_2(runner.invoke(app, ["attitude", "run", str(rec), "--filter", "mekf", "--param", "bogus=1"]))
    assert "bogus" in msg and "gyro_noise_density" in msg and "__init__" not in msg and "keyword argument" not in msg


def test_file_too_large_names_the_file(tmp_path):
    import resource

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))

    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    out = tmp_path / "big.csv"
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", "simulate", "static", "--duration", "60", "--out",
                        str(out)], capture_output=True, text=True, env=env, timeout=300, preexec_fn=small_files)
    assert r.returncode == 2, r.stderr
    assert "big.csv" in r.stderr and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()
