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


def _assert_contract(r, argv) -> None:
    err = r.stderr
    assert r.exit_code == 2, f"{argv}: exit {r.exit_code}\nstdout: {r.stdout[-2000:]}\nstderr: {err[-3000:]}"
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
    from imunav.timeseries import ImuData

    d = tmp_path_factory.mktemp("faults")
    rng = np.random.default_rng(0)
    n = 3000
    data = ImuData.from_arrays(None, rng.normal(0, 0.01, (n, 3)), rng.normal([0, 0, -9.81], 0.01, (n, 3)), fs=100)
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
    import imunav.io

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
    assert len(written) == len(runs)
    for p in written:
        _strict(p.read_text())


def test_json_writer_nulls_non_finite(tmp_path):
    from imunav.io._atomic import write_json

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
