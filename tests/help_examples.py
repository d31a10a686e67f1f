"""The examples of every ``imunav ... --help``, in order, and a way to run them (issue 26: each runs as written after
the ones before it, in an empty folder).

The order is the one a user reads them in: the commands as ``imunav --help`` lists them, each group's own help
before its subcommands' (as the group lists them).  An example is a command line, or several joined by ``&&``; a
``python -c "..."`` step (a file the next command reads, written with the library) runs as Python.  Paths such as
``../shared/data/...`` are relative to a work folder beside the shared data (:func:`work_folder`).

Used by ``tests/cli/test_help_examples.py`` (the quick examples) and ``benchmarks/bench_help_examples.py`` (all).
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from imunav.cli.main import COMMANDS, app

_HEAD = re.compile(r"Examples?(?: \([^)]*\))?:\s*(.*)")
_COMMAND = re.compile(r"(?<!&&) (?=(?:imunav|python) )")


def _examples(text: str) -> list[str]:
    """The example command lines of one help text: a paragraph ``Example: CMD`` or ``Example (why): CMD``, or a
    paragraph ``Examples:`` followed by paragraphs that are commands (``imunav ...``, ``python -c ...``)."""
    out: list[str] = []
    listing = False
    for par in (" ".join(p.split()) for p in re.split(r"\n\s*\n", text)):
        m = _HEAD.match(par)
        if m is not None:
            listing = not m.group(1)
            out += [e for e in _COMMAND.split(m.group(1)) if e]
        elif listing and par.startswith(("imunav ", "python ")):
            out += [e for e in _COMMAND.split(par) if e]
        else:
            listing = False
    return out


def _help(path: list[str]) -> str:
    r = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
    assert r.exit_code == 0, (path, r.output)
    return r.output


def _subcommands(text: str) -> list[str]:
    """The subcommands a group's help lists, in its order."""
    m = re.search(r"^Commands:\n(.*?)(?:\n\S|\Z)", text, re.S | re.M)
    if m is None:
        return []
    return [ln.split()[0] for ln in m.group(1).splitlines() if re.match(r"^  [a-z][\w-]*(\s|$)", ln)]


def help_examples() -> list[tuple[str, str]]:
    """Every example of every ``--help``: (``"imunav CMD SUB"``, the example's command line), in reading order."""
    out: list[tuple[str, str]] = []

    def walk(path: list[str]) -> None:
        text = _help(path)
        out.extend(("imunav " + " ".join(path), e) for e in _examples(text))
        for sub in _subcommands(text):
            walk([*path, sub])

    for name in COMMANDS:
        walk([name])
    return out


def steps(example: str) -> list[list[str]]:
    """The command lines of an example (``&&`` splits it), each as argv (shell comments dropped)."""
    return [shlex.split(part, comments=True) for part in example.split(" && ")]


def run_step(argv: list[str], *, subprocess_env: dict[str, str] | None = None) -> tuple[int, str]:
    """Run one step in the current folder: ``imunav ...`` through the CLI (in this process, or with
    ``subprocess_env`` a fresh ``python -m imunav.cli.main``), ``python -c CODE`` as Python.

    Returns
    -------
    tuple of (int, str)
        The exit status and the output (stdout and stderr).
    """
    if argv[:2] == ["python", "-c"]:
        if subprocess_env is not None:
            r = subprocess.run([sys.executable, "-c", argv[2]], env=subprocess_env, capture_output=True, text=True)
            return r.returncode, r.stdout + r.stderr
        exec(compile(argv[2], "<help example>", "exec"), {"__name__": "__example__"})  # noqa: S102
        return 0, ""
    assert argv[0] == "imunav", argv
    if subprocess_env is not None:
        r = subprocess.run([sys.executable, "-m", "imunav.cli.main", *argv[1:]], env=subprocess_env,
                           capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr
    r = CliRunner().invoke(app, argv[1:])
    return r.exit_code, r.output


def work_folder(root: Path, shared: Path) -> Path:
    """An empty folder ``root/work`` with ``root/shared/data`` standing for the shared data (a link), so that the
    examples' ``../shared/data/...`` paths resolve."""
    work = root / "work"
    work.mkdir()
    (root / "shared").mkdir()
    (root / "shared" / "data").symlink_to(shared)
    return work


#: Examples left out of the CI test (each too long for its budget), with the reason; the benchmark
#: ``benchmarks/bench_help_examples.py`` runs them with the others, in order.  Nothing after them reads their files.
LONG: dict[str, str] = {
    "imunav lab --out lab-report --seed 0": "the whole lab (every step on a simulated IMU): 70 s",
    "imunav zupt train ../shared/data/foot/pyshoe_vicon --out zupt_lstm.npz":
        "trains the LSTM on every shared trial: over 3 min, and needs torch (the learn extra)",
    "imunav batch simulate 3 --static 600 --out static_batch && imunav batch noise static_batch --terms N,B,K":
        "three 600 s static records and their Allan deviations: 22 s",
    "imunav warmup": "compiles every quick-tour kernel where none is cached (a minute) and writes bytecode into the "
                     "install",
    "imunav zupt benchmark ../shared/data/foot/pyshoe_vicon --limit 3 --json zupt-bench.json":
        "three detectors on three trials with their threshold searches: 25 s",
    "imunav noise ../shared/data/adis16405/adis16405_imu2.npz --gyro-unit deg/s --accel-unit g --json noise.json "
    "--plot allan.png --psd-plot psd.png --kalibr imu.yaml --openvins kalibr_imu_chain.yaml --vins vins_imu.yaml":
        "Allan deviation of a long real record: 8 s",
    "imunav airdata thesis --runs 50 --json thesis.json": "50 Monte Carlo flights of the thesis protocol: 6 s",
    "imunav gins run drive/imu.txt drive/gnss.txt --config drive/gins.toml --out res --truth drive/truth.nav":
        "the filter of the example before on the same 600 s drive, configured by the TOML: 4 s",
    "imunav attitude benchmark broad --filter madgwick_c --filter adaptive --json bench.json":
        "two filters on every shared BROAD trial: 5 s",
}
