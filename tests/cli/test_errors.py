"""Fault injection over every command (issue 16): the CLI's error contract.

Each case runs one command with one fault -- a missing, empty, garbage or
folder input; an output that is a folder, that cannot be created, whose
parent is a file, or that is the input itself -- and asserts the contract of
:mod:`imunav.cli._errors`: exit status 2, exactly one line on stderr, no
traceback, and the input left as it was.  Every JSON the CLI writes in these
tests is loaded with a strict parser (no NaN / Infinity tokens).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from builders import static_imu
from shared_data import ROOT
from typer.testing import CliRunner

from imunav.cli.main import app

runner = CliRunner()

# (name, argv template, {placeholder: suffix of the input file}, [output placeholders with their suffix])
# {IN} is the input under test; other inputs get a valid-looking placeholder file.
COMMANDS: list[tuple[str, list[str], str, list[tuple[str, str]]]] = [
    ("info", ["info", "{IN}", "--json", "{OUT}"], ".csv", [("OUT", ".json")]),
    ("info-ulog", ["info", "{IN}", "--json", "{OUT}"], ".ulg", [("OUT", ".json")]),
    ("info-bag", ["info", "{IN}", "--json", "{OUT}"], ".bag", [("OUT", ".json")]),
    ("info-mcap-topic", ["info", "{IN}", "--topic", "/imu", "--json", "{OUT}"], ".mcap", [("OUT", ".json")]),
    ("convert-ulog", ["convert", "{IN}", "{OUT}"], ".ulg", [("OUT", ".parquet")]),
    ("convert-db3", ["convert", "{IN}", "{OUT}", "--topic", "/imu"], ".db3", [("OUT", ".h5")]),
    ("convert-layout", ["convert", "{IN}", "{OUT}", "--layout", "euroc"], ".csv", [("OUT", ".npz")]),
    ("attitude-run-ulog", ["attitude", "run", "{IN}", "--topic", "sensor_combined", "--json", "{OUT}"], ".ulg",
     [("OUT", ".json")]),
    ("noise-json", ["noise", "{IN}", "--json", "{OUT}"], ".csv", [("OUT", ".json")]),
    ("noise-plot", ["noise", "{IN}", "--plot", "{OUT}"], ".csv", [("OUT", ".png")]),
    ("noise-yaml", ["noise", "{IN}", "--yaml", "{OUT}"], ".csv", [("OUT", ".yaml")]),
    ("noise-openvins", ["noise", "{IN}", "--openvins", "{OUT}"], ".csv", [("OUT", ".yaml")]),
    ("noise-vins", ["noise", "{IN}", "--kalibr", "{OUT2}", "--vins", "{OUT}"], ".csv",
     [("OUT", ".yaml"), ("OUT2", ".yaml")]),
    ("simulate-model", ["simulate", "static", "--duration", "2", "--model", "{IN}", "--out", "{OUT}"], ".toml",
     [("OUT", ".csv")]),
    ("simulate-segments", ["simulate", "static", "--duration", "2", "--model", "{IN}", "--out", "{OUT2}",
                           "--segments", "{OUT}"], ".toml", [("OUT", ".csv"), ("OUT2", ".npz")]),
    ("cal-multiposition", ["calibrate", "multiposition", "{IN}", "--segments", "{SEG}", "--out", "{OUT}"], ".npz",
     [("OUT", ".json")]),
    ("cal-multiposition-seg", ["calibrate", "multiposition", "{REC}", "--segments", "{IN}", "--out", "{OUT}"], ".json",
     [("OUT", ".json")]),
    ("cal-ratetable", ["calibrate", "ratetable", "{IN}", "--segments", "{SEG}", "--out", "{OUT}"], ".npz",
     [("OUT", ".json")]),
    ("cal-ratetable-base", ["calibrate", "ratetable", "{REC}", "--segments", "{SEG}", "--base", "{IN}", "--out",
                            "{OUT}"], ".json", [("OUT", ".json")]),
    ("cal-ferraris", ["calibrate", "ferraris", "{IN}", "--sections", "{SEG}", "--out", "{OUT}"], ".csv",
     [("OUT", ".json")]),
    ("cal-ferraris-sections", ["calibrate", "ferraris", "{REC}", "--sections", "{IN}", "--out", "{OUT}",
                               "--imucal-out", "{OUT2}"], ".json", [("OUT", ".json"), ("OUT2", ".json")]),
    ("cal-multipose", ["calibrate", "multipose", "{IN}", "--out", "{OUT}"], ".csv", [("OUT", ".json")]),
    ("cal-temperature", ["calibrate", "temperature", "{IN}@20", "{CAL}@40", "--out", "{OUT}"], ".json",
     [("OUT", ".json")]),
    ("cal-mag", ["calibrate", "mag", "{IN}", "--out", "{OUT}"], ".csv", [("OUT", ".json")]),
    ("cal-multiposition-px4", ["calibrate", "multiposition", "{IN}", "--segments", "{SEG}", "--out", "{OUT2}",
                               "--px4-params", "{OUT}"], ".npz", [("OUT", ".params"), ("OUT2", ".json")]),
    ("cal-mag-px4", ["calibrate", "mag", "{IN}", "--out", "{OUT2}", "--px4-params", "{OUT}"], ".csv",
     [("OUT", ".params"), ("OUT2", ".json")]),
    ("cal-mag-npz", ["calibrate", "mag", "{IN}", "--method", "minmax", "--out", "{OUT}"], ".npz",
     [("OUT", ".json")]),
    ("compensate", ["compensate", "{IN}", "--cal", "{CAL}", "--out", "{OUT}"], ".npz", [("OUT", ".npz")]),
    ("compensate-cal", ["compensate", "{REC}", "--cal", "{IN}", "--out", "{OUT}"], ".json", [("OUT", ".npz")]),
    ("attitude-run", ["attitude", "run", "{IN}", "--filter", "mahony", "--json", "{OUT}"], ".npz",
     [("OUT", ".json")]),
    ("zupt-run", ["zupt", "run", "{IN}", "--out", "{OUT}", "--json", "{OUT2}"], ".csv",
     [("OUT", ".npz"), ("OUT2", ".json")]),
    ("zupt-run-model", ["zupt", "run", "{REC}", "--detector", "lstm", "--model", "{IN}", "--json", "{OUT}"], ".npz",
     [("OUT", ".json")]),
    ("airdata-run", ["airdata", "run", "{IN}", "--json", "{OUT}", "--out", "{OUT2}", "--plot", "{OUT3}"], ".npz",
     [("OUT", ".json"), ("OUT2", ".npz"), ("OUT3", ".png")]),
    ("airdata-simulate", ["airdata", "simulate", "--config", "{IN}", "--out", "{OUT}", "--json", "{OUT2}"], ".toml",
     [("OUT", ".npz"), ("OUT2", ".json")]),
    ("lab", ["lab", "--config", "{IN}", "--out", "{DIR}", "--json", "{OUT}", "--quiet"], ".toml", [("OUT", ".json")]),
    ("batch-calibrate", ["batch", "calibrate", "{REC}", "--spec", "{IN}", "--json", "{OUT}"], ".toml",
     [("OUT", ".json")]),
]

INPUT_FAULTS = ("missing", "folder", "empty", "garbage")
OUTPUT_FAULTS = ("folder", "unwritable", "parent-is-file", "same-as-input")


def _log(argv, err: str) -> None:
    """Append a case's stderr to the log the session checks for 'Traceback' (see tests/conftest.py)."""
    d = os.environ.get("IMUNAV_FAULT_LOG_DIR")
    if d:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        with open(Path(d) / f"{worker}.log", "a", encoding="utf-8") as fh:
            fh.write(f"=== case {' '.join(map(str, argv))}\n{err}\n")


def _assert_contract(r, argv, code: int = 2) -> None:
    err = r.stderr
    _log(argv, err)
    assert r.exit_code == code, f"{argv}: exit {r.exit_code}\nstdout: {r.stdout[-2000:]}\nstderr: {err[-3000:]}"
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, f"{argv}: {len(lines)} stderr lines:\n{err}"
    assert lines[0].startswith("error: "), lines[0]


def _placeholders(tmp: Path) -> dict[str, str]:
    (tmp / "placeholder.npz").write_bytes(b"not really an npz")
    (tmp / "placeholder.json").write_text("{}")
    (tmp / "rec.csv").write_text("t,gx,gy,gz,ax,ay,az\n")
    return {"SEG": str(tmp / "placeholder.json"), "CAL": str(tmp / "placeholder.json"),
            "REC": str(tmp / "rec.csv"), "DIR": str(tmp / "labdir")}


def _fill(argv: list[str], values: dict[str, str]) -> list[str]:
    return [a.format(**values) for a in argv]


def _input(tmp: Path, fault: str, suffix: str) -> Path:
    p = tmp / f"input{suffix}"
    if fault == "missing":
        return tmp / f"nope{suffix}"
    if fault == "folder":
        p = tmp / f"afolder{suffix}"
        p.mkdir()
    elif fault == "empty":
        p.write_bytes(b"")
    elif fault == "garbage":
        p.write_bytes(bytes(range(256)) * 3)
    return p


@pytest.mark.parametrize("fault", INPUT_FAULTS)
@pytest.mark.parametrize("name,argv,in_suffix,outs", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_bad_input(tmp_path, name, argv, in_suffix, outs, fault):
    if fault == "empty" and in_suffix == ".toml":
        pytest.skip("an empty TOML file is a valid (default) configuration")
    values = _placeholders(tmp_path)
    values["IN"] = str(_input(tmp_path, fault, in_suffix))
    for ph, suf in outs:
        values[ph] = str(tmp_path / f"out_{ph}{suf}")
    args = _fill(argv, values)
    r = runner.invoke(app, args)
    _assert_contract(r, args)
    for ph, _ in outs:  # nothing written on failure, no temp file left
        assert not Path(values[ph]).exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".") and ".tmp" in p.name]


def _output(tmp: Path, fault: str, suffix: str, inp: Path) -> Path:
    if fault == "folder":
        p = tmp / f"outfolder{suffix}"
        p.mkdir()
        return p
    if fault == "unwritable":  # no file can be created there, even by root
        return Path("/proc/imunav-no-such-dir") / f"out{suffix}"
    if fault == "parent-is-file":
        f = tmp / "plainfile"
        f.write_text("x")
        return f / f"out{suffix}"
    return inp


@pytest.mark.parametrize("fault", OUTPUT_FAULTS)
@pytest.mark.parametrize("name,argv,in_suffix,outs", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_bad_output(tmp_path, name, argv, in_suffix, outs, fault):
    values = _placeholders(tmp_path)
    inp = tmp_path / f"input{in_suffix}"
    content = b"precious input \x00\x01"
    inp.write_bytes(content)
    values["IN"] = str(inp)
    for ph, suf in outs:
        values[ph] = str(tmp_path / f"out_{ph}{suf}")
    values[outs[0][0]] = str(_output(tmp_path, fault, outs[0][1], inp))
    args = _fill(argv, values)
    r = runner.invoke(app, args)
    _assert_contract(r, args)
    assert inp.read_bytes() == content, "the input was modified"
    if fault == "same-as-input":
        assert "input" in r.stderr


# ---------------------------------------------------------------- the single cases listed in issue 16
@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from imunav.io import write_imu

    d = tmp_path_factory.mktemp("faults")
    data = static_imu(3000, accel=(0.0, 0.0, -9.81))
    write_imu(data, d / "st.csv")
    write_imu(data, d / "st.npz")
    (d / "bad.json").write_text("{bad")
    (d / "trunc.npz").write_bytes((d / "st.npz").read_bytes()[:300])
    return d


SINGLE = [
    ("missing-recording", ["calibrate", "multiposition", "{d}/nope.npz", "--segments", "{d}/bad.json", "--out", "{t}/c.json"]),
    ("bad-segments-json", ["calibrate", "multiposition", "{d}/st.npz", "--segments", "{d}/bad.json", "--out", "{t}/c.json"]),
    ("bad-sections-json", ["calibrate", "ferraris", "{d}/st.csv", "--sections", "{d}/bad.json", "--out", "{t}/c.json"]),
    ("bad-columns-json", ["calibrate", "multiposition", "{d}/st.csv", "--segments", "{d}/bad.json", "--columns", "{{x",
                          "--out", "{t}/c.json"]),
    ("too-few-poses", ["calibrate", "multipose", "{d}/st.csv", "--out", "{t}/c.json"]),
    ("bad-cal-json", ["compensate", "{d}/st.csv", "--cal", "{d}/bad.json", "--out", "{t}/o.npz"]),
    ("bad-filter", ["attitude", "run", "{d}/st.npz", "--filter", "bogus"]),
    ("runs-0", ["attitude", "montecarlo", "--runs", "0"]),
    ("bad-mc-plot", ["attitude", "montecarlo", "--runs", "1", "--plot", "{t}/x.xyz"]),
    ("taus-log-abc", ["noise", "{d}/st.csv", "--taus", "log:abc"]),
    ("taus-unknown", ["noise", "{d}/st.csv", "--taus", "weekly"]),
    ("plot-xyz", ["noise", "{d}/st.csv", "--plot", "{t}/out.xyz"]),
    ("window-nan", ["info", "{d}/st.csv", "--window", "nan"]),
    ("window-neg", ["info", "{d}/st.csv", "--window", "-1"]),
    ("rate-ads-0", ["airdata", "simulate", "--rate-ads", "0", "--out", "{t}/a.npz"]),
    ("rate-doppler-nan", ["airdata", "simulate", "--rate-doppler", "nan", "--out", "{t}/a.npz"]),
    ("airdata-truncated", ["airdata", "run", "{d}/trunc.npz"]),
    ("zupt-truncated-model", ["zupt", "run", "{d}/st.csv", "--detector", "lstm", "--model", "{d}/trunc.npz"]),
    ("mag-truncated", ["calibrate", "mag", "{d}/trunc.npz", "--out", "{t}/m.json"]),
    ("two-outputs-one-file", ["simulate", "static", "--duration", "2", "--out", "{t}/s.csv", "--segments", "{t}/s.csv"]),
]


@pytest.mark.parametrize("name,argv", SINGLE, ids=[s[0] for s in SINGLE])
def test_issue_cases(files, tmp_path, name, argv):
    args = [a.format(d=files, t=tmp_path) for a in argv]
    r = runner.invoke(app, args)
    _assert_contract(r, args)


def test_debug_shows_the_traceback(files):
    r = runner.invoke(app, ["--debug", "info", str(files / "nope.csv")])
    assert r.exit_code == 2 and "Traceback" in r.stderr and r.stderr.strip().splitlines()[-1].startswith("error: ")


def test_unexpected_exception_exits_1_with_how_to_report(monkeypatch, files):
    import imunav.io  # the command module looks read_imu up in imunav.io when it runs (imunav.cli._lazy.lazy)

    def boom(*a, **k):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(imunav.io, "read_imu", boom)
    r = runner.invoke(app, ["info", str(files / "st.csv")])
    assert r.exit_code == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "report" in lines[0] and "--debug" in lines[0] and "Traceback" not in r.stderr


# ---------------------------------------------------------------- standard JSON from every writer
def _strict(text: str):
    def refuse(tok):
        raise ValueError(f"non-standard JSON token {tok}")

    return json.loads(text, parse_constant=refuse)


def test_every_cli_json_is_standard(files, tmp_path):
    """info / noise / simulate / calibrate mag (minmax, with NaN-prone input) / airdata JSON: strict parse."""
    t = tmp_path
    mag = np.random.default_rng(1).normal(size=(400, 3))
    mag /= np.linalg.norm(mag, axis=1, keepdims=True)
    np.savez(t / "mag.npz", mag=mag * [30, 40, 50] + [5, -3, 2])
    runs = [
        ["info", str(files / "st.csv"), "--json", str(t / "info.json")],
        ["noise", str(files / "st.csv"), "--json", str(t / "noise.json")],
        ["simulate", "static", "--duration", "2", "--preset", "ideal", "--out", str(t / "s.npz"), "--json", str(t / "sim.json")],
        ["calibrate", "mag", str(t / "mag.npz"), "--method", "minmax", "--out", str(t / "mag.json")],
        ["airdata", "simulate", "cruise", "--duration", "20", "--out", str(t / "a.npz"), "--json", str(t / "as.json")],
        ["airdata", "run", str(t / "a.npz"), "--json", str(t / "ar.json")],
    ]
    for args in runs:
        r = runner.invoke(app, args)
        assert r.exit_code == 0, (args, r.stdout[-2000:], r.stderr[-2000:])
    written = sorted(t.glob("*.json"))
    assert len(written) == len(runs) + 1  # and simulate's segment table, s_segments.json
    for p in written:
        _strict(p.read_text())


def test_json_writer_nulls_non_finite(tmp_path):
    from imunav.files import write_json

    p = write_json(tmp_path / "x.json", {"a": float("nan"), "b": [np.inf, -np.inf, 1.5], "c": np.float32("nan"),
                                         "d": np.array([1.0, np.nan]), "e": np.int64(3), "f": Path("p")})
    assert _strict(p.read_text()) == {"a": None, "b": [None, None, 1.5], "c": None, "d": [1.0, None], "e": 3, "f": "p"}
    assert oct(os.stat(p).st_mode & 0o777) != oct(0o600)


def test_calibrate_report_that_is_a_file_leaves_no_calibration(tmp_path):
    """--report naming an existing file: exit 2 before any work, one line, and no calibration output written."""
    rng = np.random.default_rng(0)
    u = rng.normal(size=(500, 3))
    h = 50.0 * u / np.linalg.norm(u, axis=1)[:, None] + [10.0, -5.0, 3.0]
    rec = tmp_path / "mag.csv"
    np.savetxt(rec, h, delimiter=",", header="mag_x,mag_y,mag_z", comments="")
    blocker = tmp_path / "rep"
    blocker.write_text("not a folder")
    out = tmp_path / "cal.json"
    r = CliRunner().invoke(app, ["calibrate", "mag", str(rec), "--out", str(out), "--report", str(blocker)])
    assert r.exit_code == 2
    assert not out.exists()
    ok = CliRunner().invoke(app, ["calibrate", "mag", str(rec), "--out", str(out), "--report", str(tmp_path / "r2")])
    assert ok.exit_code == 0 and out.exists() and (tmp_path / "r2" / "report.json").exists()


# ---------------------------------------------------------------- commands whose input is a folder
# (name, argv template with {IN} the folder, output placeholders)
DIR_COMMANDS: list[tuple[str, list[str], list[tuple[str, str]]]] = [
    ("attitude-benchmark", ["attitude", "benchmark", "{IN}", "--json", "{OUT}"], [("OUT", ".json")]),
    ("zupt-benchmark", ["zupt", "benchmark", "{IN}", "--json", "{OUT}"], [("OUT", ".json")]),
    ("zupt-train", ["zupt", "train", "{IN}", "--out", "{OUT}"], [("OUT", ".npz")]),
    ("batch-calibrate-folder", ["batch", "calibrate", "{IN}", "--executor", "serial", "--quiet", "--json", "{OUT}"],
     [("OUT", ".json")]),
    ("batch-noise-folder", ["batch", "noise", "{IN}", "--executor", "serial", "--quiet", "--json", "{OUT}"],
     [("OUT", ".json")]),
]
DIR_FAULTS = ("missing", "file-not-folder", "empty", "garbage")


def _dir_input(tmp: Path, fault: str) -> Path:
    d = tmp / "indir"
    if fault == "missing":
        return tmp / "nowhere"
    if fault == "file-not-folder":
        d.write_text("a file, not a folder")
        return d
    d.mkdir()
    if fault == "garbage":
        (d / "trial.mat").write_bytes(bytes(range(256)) * 4)
    return d


@pytest.mark.parametrize("fault", DIR_FAULTS)
@pytest.mark.parametrize("name,argv,outs", DIR_COMMANDS, ids=[c[0] for c in DIR_COMMANDS])
def test_bad_folder_input(tmp_path, name, argv, outs, fault):
    if fault == "garbage" and name.startswith("batch"):
        pytest.skip("a batch reports a unit that cannot be read in its table (exit 1), see test_batch.py")
    values = {"IN": str(_dir_input(tmp_path, fault))}
    for ph, suf in outs:
        values[ph] = str(tmp_path / f"out_{ph}{suf}")
    args = _fill(argv, values)
    r = runner.invoke(app, args)
    _assert_contract(r, args)
    for ph, _ in outs:
        assert not Path(values[ph]).exists()


@pytest.mark.parametrize("fault", OUTPUT_FAULTS[:3])
@pytest.mark.parametrize("name,argv,outs", DIR_COMMANDS, ids=[c[0] for c in DIR_COMMANDS])
def test_bad_output_of_folder_commands(tmp_path, name, argv, outs, fault):
    d = tmp_path / "indir"
    d.mkdir()
    (d / "u1.npz").write_bytes(b"unread: the output is checked first")
    values = {"IN": str(d), outs[0][0]: str(_output(tmp_path, fault, outs[0][1], d))}
    args = _fill(argv, values)
    r = runner.invoke(app, args)
    _assert_contract(r, args)
    assert sorted(p.name for p in d.iterdir()) == ["u1.npz"]


# ---------------------------------------------------------------- commands that only write
OUTPUT_ONLY: list[tuple[str, list[str], str]] = [
    ("attitude-montecarlo-json", ["attitude", "montecarlo", "--runs", "1", "--executor", "serial", "--json", "{OUT}"],
     ".json"),
    ("attitude-montecarlo-plot", ["attitude", "montecarlo", "--runs", "1", "--executor", "serial", "--plot", "{OUT}"],
     ".png"),
    ("airdata-faults", ["airdata", "faults", "--runs", "1", "--json", "{OUT}"], ".json"),
    ("airdata-thesis", ["airdata", "thesis", "--runs", "2", "--json", "{OUT}"], ".json"),
    ("simulate-static", ["simulate", "static", "--duration", "2", "--out", "{OUT}"], ".csv"),
]


@pytest.mark.parametrize("fault", OUTPUT_FAULTS[:3])
@pytest.mark.parametrize("name,argv,suffix", OUTPUT_ONLY, ids=[c[0] for c in OUTPUT_ONLY])
def test_bad_output_of_writers(tmp_path, name, argv, suffix, fault):
    out = _output(tmp_path, fault, suffix, tmp_path / "unused")
    args = _fill(argv, {"OUT": str(out)})
    r = runner.invoke(app, args)
    _assert_contract(r, args)


# ---------------------------------------------------------------- run folders (lab, batch --out)
# (name, argv template with {DIR} the run folder, {REC} a folder of recordings)
RUN_FOLDER_COMMANDS: list[tuple[str, list[str]]] = [
    ("lab", ["lab", "--out", "{DIR}", "--steps", "simulate_tests", "--quiet"]),
    ("batch-simulate", ["batch", "simulate", "1", "--out", "{DIR}", "--fs", "10", "--dwell", "2", "--no-rate-table",
                        "--executor", "serial", "--quiet"]),
    ("batch-calibrate-out", ["batch", "calibrate", "{REC}", "--out", "{DIR}", "--executor", "serial", "--quiet"]),
    ("batch-noise-out", ["batch", "noise", "{REC}", "--out", "{DIR}", "--executor", "serial", "--quiet"]),
]
RUN_FOLDER_FAULTS = ("is-a-file", "unwritable", "parent-is-file", "holds-another-run", "killed-run", "foreign-files",
                     "overwrite-foreign-files")


def _run_folder(tmp: Path, fault: str) -> tuple[Path, list[str]]:
    from imunav.lab.runfolder import RunFolder

    d = tmp / "run"
    if fault == "is-a-file":
        d.write_text("x")
    elif fault == "unwritable":
        d = Path("/proc/imunav-no-such-dir/run")
    elif fault == "parent-is-file":
        (tmp / "plainfile").write_text("x")
        d = tmp / "plainfile" / "run"
    elif fault == "holds-another-run":
        with RunFolder(d, "earlier"):
            (d / "result.json").write_text("{}")
    elif fault == "killed-run":
        RunFolder(d, "killed").start()
        (d / "partial.npz").write_bytes(b"half")
    elif fault in ("foreign-files", "overwrite-foreign-files"):
        d.mkdir()
        (d / "notes.txt").write_text("not from imunav")
    return d, (["--overwrite"] if fault == "overwrite-foreign-files" else [])


@pytest.mark.parametrize("fault", RUN_FOLDER_FAULTS)
@pytest.mark.parametrize("name,argv", RUN_FOLDER_COMMANDS, ids=[c[0] for c in RUN_FOLDER_COMMANDS])
def test_bad_run_folder(tmp_path, name, argv, fault):
    rec = tmp_path / "recs"
    rec.mkdir()
    (rec / "u1.npz").write_bytes(b"unread: the run folder is refused first")
    d, extra = _run_folder(tmp_path, fault)
    before = sorted(p.name for p in d.iterdir()) if d.is_dir() else None
    args = _fill(argv, {"DIR": str(d), "REC": str(rec)}) + extra
    r = runner.invoke(app, args)
    _assert_contract(r, args)
    if before is not None:
        assert sorted(p.name for p in d.iterdir()) == before, "the refused folder was changed"


# ---------------------------------------------------------------- Click usage errors, every command
def _leaf_commands():
    from typer.main import get_command

    def walk(cmd, path):
        if hasattr(cmd, "commands"):
            for name, sub in cmd.commands.items():
                yield from walk(sub, [*path, name])
        else:
            yield path, cmd

    return list(walk(get_command(app), []))


def _numeric(param) -> bool:
    """Whether a Click parameter takes a number (Click's type, or the annotation under typer's own click)."""
    import typing

    t = getattr(param, "type", None)
    if t is not None:
        return getattr(t, "name", "") in ("integer", "float")
    ann = getattr(getattr(param, "type_descriptor", None), "annotation", None)
    return any(a in (int, float) for a in (typing.get_args(ann) or (ann,)))


def _dummy(param) -> str:
    return "1" if _numeric(param) else "x"


def _usage_cases():
    cases = [("root-unknown-option", ["--no-such-option"]), ("root-unknown-command", ["no-such-command"]),
             ("group-unknown-command", ["calibrate", "no-such-method"]), ("group-unknown-option", ["batch", "--nope"])]
    for path, cmd in _leaf_commands():
        name = "-".join(path)
        required = [p for p in cmd.params if p.required]
        fill = []
        for p in required:
            fill += [_dummy(p)] if p.param_type_name == "argument" else [p.opts[0], _dummy(p)]
        cases.append((f"{name}-unknown-option", [*path, *fill, "--no-such-option"]))
        if required:
            cases.append((f"{name}-missing-{required[0].name}", [*path]))
        numeric = [p for p in cmd.params if p.param_type_name == "option" and not p.required and _numeric(p)
                   and not p.is_flag]
        if numeric:
            cases.append((f"{name}-bad-number", [*path, *fill, numeric[0].opts[0], "abc"]))
    return cases


USAGE = _usage_cases()


@pytest.mark.parametrize("name,argv", USAGE, ids=[u[0] for u in USAGE])
def test_usage_errors_are_one_line(name, argv):
    r = runner.invoke(app, argv)
    _assert_contract(r, argv)
    assert "--help" in r.stderr  # says where to look


def test_usage_table_covers_every_command():
    leaves = _leaf_commands()
    assert len(leaves) >= 24
    names = {u[0] for u in USAGE}
    for path, _ in leaves:
        assert f"{'-'.join(path)}-unknown-option" in names


def test_help_still_works_everywhere():
    for path, _ in _leaf_commands():
        r = runner.invoke(app, [*path, "--help"])
        assert r.exit_code == 0 and "Usage" in r.stdout and not r.stderr, path


def test_debug_shows_the_traceback_in_commands_that_report_errors_themselves(tmp_path):
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[lab]\nsteps = ['nope']\n")
    r = runner.invoke(app, ["--debug", "lab", "--config", str(cfg), "--out", str(tmp_path / "r"), "--quiet"])
    assert r.exit_code == 2 and "Traceback" in r.stderr and r.stderr.strip().splitlines()[-1].startswith("error: ")


# ---------------------------------------------------------------- interrupt and concurrent runs (subprocesses)
SLOW_RUNS = {
    # a lab whose first step writes data files for a while (a 2 h static record at 50 Hz, in one piece), and whose
    # later steps run for tens of seconds more: the interrupt, sent when the run reports its first file, lands
    # in the middle of the work however loaded the machine is
    "lab": (["lab", "--out", "{DIR}", "--config", "{CFG}", "--quiet"],
            "[lab]\nsteps = ['simulate_tests', 'noise', 'temperature', 'attitude']\n[simulate_tests]\nfs = 50.0\n"
            "dwell_s = 1.0\ntransition_s = 0.5\nremount_s = 1.0\nstatic_duration_s = 7200.0\nfigures = false\n"),
    "batch-simulate": (["batch", "simulate", "3000", "--out", "{DIR}", "--fs", "20", "--dwell", "2", "--no-rate-table",
                        "--executor", "serial", "--quiet"], None),
}


def _reported_files(d: Path) -> list[str]:
    """The files a run being written says it is writing (its file log, appended before each file appears)."""
    from imunav.lab.runfolder import FILES

    try:
        return [ln for ln in (d / FILES).read_text().splitlines() if ln.strip()]
    except OSError:
        return []


@pytest.mark.parametrize("name", list(SLOW_RUNS))
def test_concurrent_run_refused_and_sigint_leaves_no_manifest(tmp_path, name):
    """A second run into the folder of a running one is refused; SIGINT stops the first with one stderr
    line, exit 130, no manifest, and every file it left complete (loadable), no temp file.

    Deterministic: the test waits for states the run reports (its marker, then its file log naming a file), not
    for time; the runs have minutes of work left when they report their first file, so the interrupt lands in
    the middle of the work."""
    import signal
    import subprocess
    import sys
    import time

    from imunav.lab.runfolder import MANIFEST, MARKER

    argv, cfg_text = SLOW_RUNS[name]
    d = tmp_path / "run"
    cfg = tmp_path / "lab.toml"
    if cfg_text:
        cfg.write_text(cfg_text)
    args = _fill(argv, {"DIR": str(d), "CFG": str(cfg)})
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.Popen([sys.executable, "-m", "imunav.cli.main", *args], env=env, cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.monotonic()
        while not (d / MARKER).exists() and proc.poll() is None and time.monotonic() - t0 < 300:
            time.sleep(0.05)
        assert (d / MARKER).exists(), proc.communicate()[1] if proc.poll() is not None else "no marker"
        second = runner.invoke(app, args)  # the concurrent run
        _assert_contract(second, args)
        assert "still going or was killed" in second.stderr
        while not _reported_files(d) and proc.poll() is None and time.monotonic() - t0 < 300:
            time.sleep(0.05)
        assert _reported_files(d), "the run reported no file"
        assert proc.poll() is None, "the first run ended before the interrupt"
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    _log(["SIGINT", *args], err)
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "interrupted" in lines[0] and "Traceback" not in err, err
    assert not (d / MANIFEST).exists() and (d / MARKER).exists()
    hidden_tmp = [p for p in d.rglob(".*") if ".tmp" in p.name]
    assert hidden_tmp == []
    for p in d.rglob("*"):  # no corrupt target: every file there is complete
        if p.is_file() and not p.name.startswith("."):
            if p.suffix == ".npz":
                with np.load(p) as z:
                    [z[k] for k in z.files]
            elif p.suffix == ".json":
                json.loads(p.read_text())
