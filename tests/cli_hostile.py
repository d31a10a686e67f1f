"""Hostile cases generated from the CLI itself (issue 27, deliverable 6).

:func:`generate` walks the typer application and, for every command and every
option, derives cases from the option's type and declared domain
(:mod:`imunav.cli._domains`): for numbers NaN, ±inf, 0, negative, beyond the
range, not an integer, empty and not a number (only values outside the
domain); for paths, by the path's role (:func:`role`): an input that is
missing, a folder, a FIFO, behind a file or a link loop; an output that is a
folder, a FIFO, behind a file, the same as an input or inside the command's
run folder; a report / run folder that is a file, behind a file, or holds an
input.  Each case starts from a baseline command line (:data:`BASELINE`, valid
files made by :func:`make_fixtures`) with ONE option changed.

Issue 36 added four families: output pairs (every output on another output's
path, every output file inside another output's folder: the files a report or
run folder will hold), configuration-named inputs (an output on a file a
configuration of the baseline names, :data:`CONFIGURED`), file-system limits
(the commands that write recordings, in every format, under a file-size limit
that refuses the write, :func:`_fsize_cases`) and option-multiplied work (every
numeric option of a command with a limits estimator at the top of its domain,
where the estimate is beyond the machine, :func:`_work_cases`).

:func:`run_case` checks the contract: exit status 2, one line on stderr
starting ``error:`` that names the option or the file, no traceback, every
file of the case folder byte-identical afterwards and nothing new left in it.

Used by ``tests/cli/test_hostile.py`` (a seeded sample, in CI) and
``benchmarks/bench_cli_hostile.py`` (every case).
"""

from __future__ import annotations

import contextlib
import os
import random
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from typer.main import get_command
from typer.testing import CliRunner

from imunav.cli._domains import Domain, domain_of, flag_of, is_path, numeric, path_role
from imunav.cli.main import app

runner = CliRunner()

#: A valid command line for each command: placeholders {NAME} are files of :func:`make_fixtures`
#: (relative to the case folder); {OUT...} are outputs in the case folder.
BASELINE: dict[str, list[str]] = {
    "info": ["info", "{REC}", "--json", "{OUT}.json"],
    "convert": ["convert", "{REC}", "{OUT}.npz"],
    "noise": ["noise", "{REC}", "--json", "{OUT}.json"],
    "simulate": ["simulate", "static", "--duration", "2", "--fs", "10", "--out", "{OUT}.npz", "--model", "{MODEL}"],
    "lab": ["lab", "--out", "{OUT}_lab", "--config", "{LAB}", "--steps", "simulate_tests,noise", "--quiet", "--json", "{OUT}.json"],
    "compensate": ["compensate", "{REC}", "--cal", "{CAL}", "--out", "{OUT}.npz"],
    "calibrate multiposition": ["calibrate", "multiposition", "{BREC}", "--segments", "{BSEG}", "--out",
                                "{OUT}.json", "--report", "{OUT}_rep"],
    "calibrate ratetable": ["calibrate", "ratetable", "{BRATE}", "--segments", "{BRSEG}", "--out", "{OUT}.json",
                            "--report", "{OUT}_rep", "--static", "{BREC}", "--static-segments", "{BSEG}"],
    "calibrate ferraris": ["calibrate", "ferraris", "{REC}", "--sections", "{SEG}", "--out", "{OUT}.json",
                           "--report", "{OUT}_rep"],
    "calibrate multipose": ["calibrate", "multipose", "{REC}", "--out", "{OUT}.json", "--report", "{OUT}_rep"],
    "calibrate temperature": ["calibrate", "temperature", "{CAL}@20", "{CAL2}@40", "{CAL3}@60", "--orders", "1", "--out",
                              "{OUT}.json", "--report", "{OUT}_rep"],
    "calibrate mag": ["calibrate", "mag", "{MAG}", "--out", "{OUT}.json", "--report", "{OUT}_rep"],
    "attitude run": ["attitude", "run", "{REC}", "--filter", "mahony", "--json", "{OUT}.json"],
    "attitude benchmark": ["attitude", "benchmark", "{DIR}", "--json", "{OUT}.json"],
    "attitude montecarlo": ["attitude", "montecarlo", "--runs", "1", "--duration", "5", "--executor", "serial",
                            "--json", "{OUT}.json"],
    "zupt run": ["zupt", "run", "{FOOT}", "--json", "{OUT}.json"],
    "zupt train": ["zupt", "train", "{DIR}", "--out", "{OUT}.npz"],
    "zupt benchmark": ["zupt", "benchmark", "{DIR}", "--json", "{OUT}.json"],
    "gins simulate": ["gins", "simulate", "--duration", "5", "--out", "{OUT}_gins"],
    "gins run": ["gins", "run", "{IMU}", "{GNSS}", "--config", "{GCFG}", "--out", "{OUT}_gins"],
    "gins outage-test": ["gins", "outage-test", "{IMU}", "{GNSS}", "--config", "{GCFG}", "--truth", "{TRUTH}",
                         "--converge", "20", "--every", "40", "--length", "10", "--shifts", "0", "--out", "{OUT}_gins"],
    "airdata simulate": ["airdata", "simulate", "cruise", "--duration", "5", "--out", "{OUT}.npz"],
    "airdata run": ["airdata", "run", "{FLIGHT}", "--json", "{OUT}.json"],
    "airdata faults": ["airdata", "faults", "--runs", "1", "--json", "{OUT}.json"],
    "airdata thesis": ["airdata", "thesis", "--runs", "2", "--json", "{OUT}.json"],
    "batch simulate": ["batch", "simulate", "1", "--out", "{OUT}_batch", "--fs", "10", "--dwell", "2",
                       "--no-rate-table", "--executor", "serial", "--quiet"],
    "batch calibrate": ["batch", "calibrate", "{BATCH}", "--out", "{OUT}_cal", "--executor", "serial", "--quiet",
                        "--json", "{OUT}.json"],
    "warmup": ["warmup", "--quiet"],  # no numeric or path option: no case runs it
    "batch noise": ["batch", "noise", "{BATCH}", "--out", "{OUT}_noise", "--executor", "serial", "--quiet",
                    "--json", "{OUT}.json"],
    "batch gins": ["batch", "gins", "{LOGS}", "--out", "{OUT}_logs", "--executor", "serial", "--quiet", "--no-plots",
                   "--json", "{OUT}.json"],
}

#: Violations found in code this work may not change, reported to the lead (none left: the GNSS/INS commands'
#: result folders are checked against their inputs by the declared path roles, imunav.cli._domains.check_paths).
KNOWN: dict[str, str] = {}

def role(command: str, flag: str) -> str:
    """The declared role of a path option (:func:`imunav.cli._domains.path_role`)."""
    return path_role(command, flag)


def leaf_commands() -> list[tuple[str, Any]]:
    """Every command of ``imunav`` as (path, click command).

    Returns
    -------
    list of tuple
        ``("calibrate mag", command)``, ...
    """

    def walk(cmd: Any, path: list[str]) -> Any:
        if hasattr(cmd, "commands"):
            for name in list(cmd.commands):
                yield from walk(cmd.commands[name], [*path, name])
        else:
            yield " ".join(path), cmd

    return list(walk(get_command(app), []))


@dataclass
class Case:
    """One hostile case: the command, the option changed, how, and the command line (placeholders)."""

    command: str
    flag: str
    kind: str
    argv: list[str]
    names: list[str] = field(default_factory=list)  # what the error line may name (flag, value, file)
    setup: str = ""  # what to make in the case folder first (see _setup)

    @property
    def id(self) -> str:
        return f"{self.command.replace(' ', '-')}{self.flag}:{self.kind}"


def _fmt(x: float, integer: bool) -> str:
    return str(int(x)) if integer and float(x).is_integer() and abs(x) < 1e18 else repr(float(x))


def numeric_values(d: Domain) -> list[tuple[str, str]]:
    """Values outside ``d`` (kind, text): NaN, ±inf, 0, negative, below / at an open bound, beyond the range,
    not an integer, empty, not a number.

    Parameters
    ----------
    d : Domain
        The option's domain.

    Returns
    -------
    list of tuple
        ``(kind, text)``, only values that ``d`` refuses.
    """
    cands: list[tuple[str, Any]] = [("nan", "nan"), ("+inf", "inf"), ("-inf", "-inf"), ("zero", 0.0), ("negative", -1.0),
                                    ("huge", 1e300), ("empty", ""), ("wrong-type", "abc")]
    if d.lo is not None:
        cands += [("below-range", d.lo - (1 if d.integer else max(1.0, abs(d.lo) * 0.5)))]
        if d.lo_open:
            cands += [("at-open-bound", d.lo)]
    if d.hi is not None:
        cands += [("beyond-range", d.hi * 10 + 1 if d.hi > 0 else d.hi + 1)]
        if d.hi_open:
            cands += [("at-open-bound-hi", d.hi)]
    if d.integer:
        cands += [("not-integer", 1.5)]
    out: list[tuple[str, str]] = []
    seen: set[str] = set()
    for kind, v in cands:
        if isinstance(v, str):
            ok = v in ("", "abc") or not d.contains(float(v))
            text = v
        else:
            ok = not d.contains(v)
            text = _fmt(v, d.integer and kind != "not-integer")
        if ok and text not in seen:
            seen.add(text)
            out.append((kind, text))
    return out


def _positionals(cmd: Any, argv: list[str], n_words: int) -> list[int]:
    """Indices in ``argv`` of the command's positional values (after its ``n_words`` command words)."""
    takes_value = {o for p in cmd.params if p.param_type_name == "option" and not getattr(p, "is_flag", False)
                   and not getattr(p, "count", False) for o in p.opts}
    out, i = [], n_words
    while i < len(argv):
        a = argv[i]
        if a.startswith("-") and len(a) > 1:
            i += 2 if a in takes_value else 1
            continue
        out.append(i)
        i += 1
    return out


def _set(cmd: Any, n_words: int, argv: list[str], param: Any, value: str) -> list[str]:
    """``argv`` with the parameter's value replaced (or the option appended)."""
    out = list(argv)
    if param.param_type_name == "argument":
        args = [p for p in cmd.params if p.param_type_name == "argument"]
        k = args.index(param)
        pos = _positionals(cmd, out, n_words)
        if k < len(pos):
            out[pos[k]] = value
        else:
            out.append(value)
        return out
    for i, a in enumerate(out):
        if a in param.opts and i + 1 < len(out):
            out[i + 1] = value
            return out
    return [*out, flag_of(param), value]


def generate() -> tuple[list[Case], dict[str, int]]:
    """Every hostile case of every command and option.

    Returns
    -------
    cases : list of Case
        The cases.
    coverage : dict
        ``commands``, ``options`` (all), ``numeric``, ``paths`` (options with cases), ``cases``.
    """
    cases: list[Case] = []
    n_opts = n_num = n_path = 0
    commands = leaf_commands()
    for path, cmd in commands:
        base = BASELINE[path]
        words = len(path.split())
        for p in cmd.params:
            n_opts += 1
            flag = flag_of(p)
            if numeric(p):
                n_num += 1
                d = domain_of(path, p)
                assert d is not None, f"{path} {flag}: no declared domain"
                for kind, v in numeric_values(d):
                    cases.append(Case(path, flag, kind, _set(cmd, words, base, p, v), [flag, p.name, v]))
            elif is_path(p):
                n_path += 1
                for kind, value, setup in _path_values(path, flag, base):
                    cases.append(Case(path, flag, kind, _set(cmd, words, base, p, value), [flag, value], setup))
    cases += _work_cases(commands) + _fsize_cases()
    return cases, {"commands": len(commands), "options": n_opts, "numeric": n_num, "paths": n_path,
                   "cases": len(cases)}


def _work_cases(commands: list[tuple[str, Any]]) -> list[Case]:
    """Work multiplied by an option: every numeric option of a command with a limits estimator
    (:data:`imunav.cli._limits.ESTIMATORS`) set to the top of its domain, where the estimator then puts the
    request beyond the machine; the command must refuse it before any work, naming the option."""
    from imunav.cli._limits import ESTIMATORS, MEMORY, TIME

    out = []
    for path, cmd in commands:
        est = ESTIMATORS.get(path)
        if est is None:
            continue
        words = len(path.split())
        argv = BASELINE[path]
        base = dict(cmd.make_context(path, list(argv[words:]), resilient_parsing=True).params)
        for p in cmd.params:
            d = domain_of(path, p) if numeric(p) else None
            if d is None or d.hi is None or p.name in ("seed", "workers"):
                continue
            top = d.hi if not d.hi_open else d.hi * (1 - 1e-9)
            e = est({**base, p.name: int(top) if d.integer else top})
            if e is not None and not (e.bytes <= MEMORY and e.seconds <= TIME):
                v = _fmt(top, d.integer)
                out.append(Case(path, flag_of(p), "work-beyond-limit", _set(cmd, words, argv, p, v), [flag_of(p), v]))
    return out


#: Commands whose baseline writes a recording larger than :data:`FSIZE_LIMIT`, and the formats they write.
FSIZE_COMMANDS = ("convert", "compensate")
FSIZE_FORMATS = ("csv", "npz", "h5", "parquet", "mat")
FSIZE_LIMIT = 20000  # bytes: RLIMIT_FSIZE of the case's process (the file system refuses larger files)


def _fsize_cases() -> list[Case]:
    """A file system that refuses the write (a file-size limit) under every recording format."""
    out = []
    for path in FSIZE_COMMANDS:
        for fmt in FSIZE_FORMATS:
            argv = [a.replace("{OUT}.npz", "{OUT}." + fmt) for a in BASELINE[path]]
            out.append(Case(path, "(file-size-limit)", fmt, argv, ["{OUT}." + fmt], "fsize"))
    return out


def _inputs_of(argv: list[str]) -> list[str]:
    return [a.split("@")[0] for a in argv if a.startswith("{") and not a.startswith("{OUT")]


def _path_values(command: str, flag: str, base: list[str]) -> list[tuple[str, str, str]]:
    r = role(command, flag)
    out: list[tuple[str, str, str]] = []
    inputs = _inputs_of(base)
    if r == "input":
        out += [("missing", "missing_input.csv", ""), ("folder", "a_folder", "mkdir a_folder"),
                ("fifo", "a_fifo", "mkfifo a_fifo"), ("parent-is-file", "{REC}/x.csv", ""),
                ("link-loop", "loop_a", "linkloop loop_a loop_b")]
    elif r == "input-folder":
        out += [("missing", "missing_folder", ""), ("is-a-file", "{REC}", ""), ("fifo", "a_fifo", "mkfifo a_fifo")]
    elif r == "output":
        out += [("folder", "a_folder", "mkdir a_folder"), ("fifo", "a_fifo.json", "mkfifo a_fifo.json"),
                ("parent-is-file", "{REC}/x.json", "")]
        if inputs:
            out += [("same-as-input", inputs[0], "")]
        out += [(f"same-as-{configured[1:-1].lower()}-named-by-{cfg[1:-1].lower()}", configured, "")
                for cfg, configured in CONFIGURED.items() if cfg in base]
    elif r in ("report-folder", "run-folder"):
        out += [("is-a-file", "a_file.txt", "touch a_file.txt"), ("parent-is-file", "{REC}/sub", "")]
        if inputs:
            out += [("holds-an-input", "inputs", "")]
        if r == "run-folder":
            out += [("foreign-files-overwrite", "foreign", "foreign foreign")]
    if r in ("output", "report-folder", "run-folder"):
        out += _output_pairs(command, flag, r, base)
    return out


#: A configuration file of the fixtures -> a file it names (an input the command reads through it).
CONFIGURED = {"{LAB}": "{MODEL}"}


def _output_pairs(command: str, flag: str, r: str, base: list[str]) -> list[tuple[str, str, str]]:
    """Two outputs of one command on one path: this output on another output's path, or (an output file)
    inside another output's folder (the files a report or run folder will hold)."""
    out: list[tuple[str, str, str]] = []
    for i, other in enumerate(base[:-1]):
        value = base[i + 1]
        if not other.startswith("--") or other == flag or not value.startswith("{OUT"):
            continue
        r2 = role(command, other)
        if r2 not in ("output", "report-folder", "run-folder"):
            continue
        out.append((f"same-as-{other[2:]}", value, ""))
        if r == "output" and r2 in ("report-folder", "run-folder"):
            out.append((f"inside-{other[2:]}-folder", f"{value}/report.json", ""))
    return out


# ------------------------------------------------------------------------------------------ fixtures
def make_fixtures(root: Path) -> dict[str, str]:
    """Valid inputs in ``root/inputs`` (made once, copied into each case folder).

    Parameters
    ----------
    root : pathlib.Path
        Folder to create them in.

    Returns
    -------
    dict
        Placeholder -> path relative to the case folder.
    """
    import json

    import numpy as np

    from imunav.calib import ImuCalibration
    from imunav.io import write_imu
    from imunav.lab.batch import simulate_batch
    from imunav.sim import hundred_position_profile
    from imunav.sim.robot_log import simulate_robot_log, write_robot_log
    from imunav.timeseries import ImuData

    d = root / "inputs"
    d.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    n, fs = 2000, 100.0
    rec = ImuData(np.arange(n) / fs, rng.normal(0, 0.01, (n, 3)),
                  np.tile([0.0, 0.0, -9.80665], (n, 1)) + rng.normal(0, 0.01, (n, 3)),
                  np.tile([20.0, 0.0, 40.0], (n, 1)) + rng.normal(0, 0.1, (n, 3)))
    write_imu(rec, d / "rec.csv")
    write_imu(rec, d / "rec.npz")
    mag = d / "mag.csv"
    u = rng.normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    np.savetxt(mag, 50 * u, delimiter=",", header="mag_x,mag_y,mag_z", comments="")
    (d / "segments.json").write_text(json.dumps(hundred_position_profile(10.0, 2.0, 1.0).to_dict()))
    cal = ImuCalibration()
    cal.save(d / "cal.json")
    cal.save(d / "cal2.json")
    cal.save(d / "cal3.json")
    (d / "model.toml").write_text('name = "m"\n[gyro]\nbias = [0.001, 0, 0]\n')
    (d / "lab.toml").write_text('[lab]\ntitle = "hostile"\n[simulate_tests]\nmodel = "model.toml"\n')
    r = runner.invoke(app, ["gins", "simulate", "--duration", "120", "--out", str(d / "gins")])
    assert r.exit_code == 0, r.stderr
    foot = d / "walk.csv"
    head = ["Time (s)"] + [f"Gyroscope {a} (deg/s)" for a in "XYZ"] + [f"Accelerometer {a} (g)" for a in "XYZ"]
    tf = np.arange(1000) / 100.0
    block = np.column_stack([tf, rng.normal(0, 1, (1000, 3)), np.tile([0, 0, 1.0], (1000, 1))])
    foot.write_text(",".join(head) + "\n" + "".join(",".join(f"{x:.6f}" for x in r_) + "\n" for r_ in block))
    (d / "trials").mkdir(exist_ok=True)
    (d / "trials" / "t1.mat").write_bytes(b"not a trial")
    simulate_batch(1, d / "batch", fs=20.0, dwell_s=4.0, transition_s=1.0, rate_table=True, executor="serial",
                   progress=False)
    r = runner.invoke(app, ["airdata", "simulate", "cruise", "--duration", "10", "--out", str(d / "flight.npz")])
    assert r.exit_code == 0, r.stderr
    (d / "logs").mkdir(exist_ok=True)
    if not (d / "logs" / "kfgins").exists():  # a folder of logs: a short robot drive as KF-GINS text files
        write_robot_log(simulate_robot_log(1, distance_m=80.0), d / "logs", formats=("kfgins",))
    return {"REC": "inputs/rec.csv", "NPZ": "inputs/rec.npz", "MAG": "inputs/mag.csv",
            "SEG": "inputs/segments.json", "CAL": "inputs/cal.json", "CAL2": "inputs/cal2.json", "CAL3": "inputs/cal3.json",
            "MODEL": "inputs/model.toml", "LAB": "inputs/lab.toml", "IMU": "inputs/gins/imu.txt",
            "GNSS": "inputs/gins/gnss.txt", "GCFG": "inputs/gins/gins.toml", "TRUTH": "inputs/gins/truth.nav",
            "FOOT": "inputs/walk.csv", "FLIGHT": "inputs/flight.npz", "BREC": "inputs/batch/unit_001.npz", "BSEG": "inputs/batch/segments.json",
            "BRATE": "inputs/batch/unit_001_rate.npz", "BRSEG": "inputs/batch/rate_segments.json",
            "DIR": "inputs/trials", "BATCH": "inputs/batch", "LOGS": "inputs/logs", "OUT": "out"}


def _snapshot(root: Path) -> dict[str, bytes | None]:
    snap: dict[str, bytes | None] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            rel = p.relative_to(root).as_posix()
            if p.is_symlink() or not p.is_file():
                snap[rel] = None
            else:
                snap[rel] = p.read_bytes()
    return snap


def _setup(case_dir: Path, setup: str) -> None:
    words = setup.split()
    if not words:
        return
    if words[0] == "mkdir":
        (case_dir / words[1]).mkdir()
    elif words[0] == "mkfifo":
        os.mkfifo(case_dir / words[1])
    elif words[0] == "touch":
        (case_dir / words[1]).write_text("a file")
    elif words[0] == "linkloop":
        os.symlink(words[2], case_dir / words[1])
        os.symlink(words[1], case_dir / words[2])
    elif words[0] == "foreign":
        (case_dir / words[1]).mkdir()
        (case_dir / words[1] / "notes.txt").write_text("a user's notes")


def _run_limited(argv: list[str], work: Path) -> tuple[int, str]:
    """(exit status, stderr) of ``imunav argv`` in a process whose files may not exceed :data:`FSIZE_LIMIT`."""
    import resource
    import subprocess
    import sys

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (FSIZE_LIMIT, FSIZE_LIMIT))

    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", *argv], cwd=work, env=env, capture_output=True,
                       text=True, timeout=600, preexec_fn=limit)
    return r.returncode, r.stderr


def run_case(case: Case, fixtures: Path, values: dict[str, str], work: Path) -> list[str]:
    """Run one case in a fresh folder (a copy of ``fixtures``) and list its contract violations.

    Parameters
    ----------
    case : Case
        The case.
    fixtures : pathlib.Path
        Folder holding ``inputs/`` (:func:`make_fixtures`).
    values : dict
        Placeholders of :func:`make_fixtures`.
    work : pathlib.Path
        A new folder for the case.

    Returns
    -------
    list of str
        The violations (empty: the contract holds).
    """
    shutil.copytree(fixtures / "inputs", work / "inputs", symlinks=True)
    _setup(work, case.setup)
    argv = [a.format(**values) for a in case.argv]
    if case.kind == "foreign-files-overwrite":
        argv.append("--overwrite")
    before = _snapshot(work)
    if case.setup == "fsize":
        code, err = _run_limited(argv, work)
    else:
        cwd = os.getcwd()
        os.chdir(work)
        try:
            r = runner.invoke(app, argv)
        finally:
            os.chdir(cwd)
        code, err = r.exit_code, r.stderr
    bad = []
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if code != 2:
        bad.append(f"exit {code}")
    if "Traceback" in err or "internal error" in err:
        bad.append("traceback / internal error")
    if len(lines) != 1 or not lines[0].startswith("error: "):
        bad.append(f"{len(lines)} stderr lines")
    names = [n.format(**values) for n in case.names if n]
    # a negative value in a positional slot is read by click as an option: "No such option: -i"
    names += [n[:2] for n in names if n.startswith("-") and not n.startswith("--")]
    if lines and not any(n in lines[0] or Path(n).name in lines[0] for n in names):
        bad.append(f"the message names neither {names}")
    after = _snapshot(work)
    changed = [k for k in before if before[k] != after.get(k, b"<gone>")]
    new = [k for k in after if k not in before]
    if changed:
        bad.append(f"changed or removed: {changed[:5]}")
    if new:
        bad.append(f"left behind: {new[:5]}")
    if bad:
        bad.append(f"stderr: {err.strip()[:300]!r}")
    with contextlib.suppress(OSError):
        shutil.rmtree(work)
    return bad


def family(case: Case) -> str:
    """The family of a case: ``numeric``, ``path``, ``output-pair`` (two outputs of one command on one path or
    one inside the other's folder), ``configured-input`` (an output on a file a configuration names),
    ``file-size-limit`` or ``work`` (an option that multiplies the work beyond the machine).

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    str
        Its family.
    """
    if case.setup == "fsize":
        return "file-size-limit"
    if case.kind == "work-beyond-limit":
        return "work"
    if "-named-by-" in case.kind:
        return "configured-input"
    if case.kind.startswith("inside-") or (case.kind.startswith("same-as-") and case.kind != "same-as-input"):
        return "output-pair"
    return "path" if any(a.startswith("{") for a in case.names) or case.kind in PATH_KINDS else "numeric"


#: kinds of the path cases (values that are paths, not numbers)
PATH_KINDS = frozenset({"missing", "folder", "fifo", "parent-is-file", "link-loop", "is-a-file", "same-as-input",
                        "holds-an-input", "foreign-files-overwrite"})


def sample(cases: list[Case], n: int, seed: int) -> list[Case]:
    """A seeded sample of ``n`` cases that covers every command and every option at least once when ``n``
    allows (one case per option first, and one of each :func:`family` not among those, then random others).

    Parameters
    ----------
    cases : list of Case
        All cases.
    n : int
        How many.
    seed : int
        Seed of the draw.

    Returns
    -------
    list of Case
        The sample.
    """
    rnd = random.Random(seed)
    by_option: dict[tuple[str, str], list[Case]] = {}
    by_family: dict[str, list[Case]] = {}
    for c in cases:
        by_option.setdefault((c.command, c.flag), []).append(c)
        by_family.setdefault(family(c), []).append(c)
    first = [rnd.choice(v) for _, v in sorted(by_option.items())]
    have = {family(c) for c in first}
    first += [rnd.choice(v) for f, v in sorted(by_family.items()) if f not in have]
    rnd.shuffle(first)
    rest = [c for c in cases if c not in first]
    rnd.shuffle(rest)
    return (first + rest)[:n] if n >= len(first) else first[:n]
