"""Every command of the `imunav` CLI documents an example in its --help."""

from __future__ import annotations

import functools
import os
import re
import subprocess
import sys

import pytest
from shared_data import ROOT
from typer.main import get_command
from typer.testing import CliRunner

from imunav.cli.main import COMMANDS, app


def _leaves(cmd, path, groups=False):
    if hasattr(cmd, "commands"):
        if groups:
            yield path, cmd
        for name, sub in cmd.commands.items():
            yield from _leaves(sub, [*path, name], groups)
    else:
        yield path, cmd


def test_every_command_has_an_example():
    leaves = list(_leaves(get_command(app), [], groups=True))
    assert len(leaves) >= 20  # info, simulate, lab, noise, calibrate ×6, compensate, attitude ×3, zupt ×3, airdata ×4, batch ×3
    runner = CliRunner()
    for path, _ in leaves:
        res = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
        assert res.exit_code == 0, (path, res.output)
        assert "Example" in res.output or "example" in res.output, f"imunav {' '.join(path)} --help has no example"


def test_version():
    res = CliRunner().invoke(app, ["--version"])
    assert res.exit_code == 0 and res.output.strip()


def test_bracketed_help_text_is_shown_as_written():
    """Rich markup swallowed '[spec.<parameter>]' and '[lab]' from the lab's help (issue 16)."""
    res = CliRunner().invoke(app, ["lab", "--help"], env={"COLUMNS": "200"})
    assert res.exit_code == 0
    text = " ".join(res.output.split())
    for tag in ("[recordings.<name>]", "[spec.<parameter>]", "[lab]"):
        assert tag in text, tag


def test_a_group_without_a_command_prints_its_help():
    res = CliRunner().invoke(app, ["calibrate"])
    assert res.exit_code == 0 and "multiposition" in res.stdout and not res.stderr


def test_help_lists_the_commands_without_importing_them():
    """`imunav --help` reads the command table, not the command modules (and so no numba, scipy, matplotlib)."""
    code = (
        "import sys\n"
        "from typer.testing import CliRunner\n"
        "from imunav.cli.main import app\n"
        "r = CliRunner().invoke(app, ['--help'])\n"
        "assert r.exit_code == 0 and 'calibrate' in r.output, r.output\n"
        "heavy = ('numba', 'scipy', 'pandas', 'matplotlib', 'torch', 'dask')\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy or (m.startswith('imunav.cli.') and m not in "
        "('imunav.cli.main', 'imunav.cli._lazy', 'imunav.cli._errors', 'imunav.cli._domains', 'imunav.cli._limits'))))\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"


def test_the_command_line_compiles_at_its_numba_opt_level_unless_the_user_set_one():
    """The command line has numba compile at LLVM level 2 (issue 35: a shorter first run, the same results and
    speed): set before numba is imported, a level the user set is kept."""
    from imunav.cli.main import NUMBA_OPT_LEVEL

    code = ("import os, sys\n"
            "import imunav.cli.main\n"
            "assert 'numba' not in sys.modules\n"
            "from numba.core import config\n"
            "print(os.environ['NUMBA_OPT'], int(config.OPT))\n")
    base = {k: v for k, v in os.environ.items() if k != "NUMBA_OPT"}
    base["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)
    assert NUMBA_OPT_LEVEL == "2"
    for given, want in ((None, "2 2"), ("3", "3 3"), ("0", "0 0")):
        env = base if given is None else {**base, "NUMBA_OPT": given}
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
        assert r.returncode == 0, r.stderr
        assert r.stdout.strip() == want, (given, r.stdout)


def test_the_listed_summary_is_the_first_sentence_of_each_commands_help():
    group = get_command(app)
    assert list(group.commands) == list(COMMANDS)
    for name, summary in COMMANDS.items():
        own = " ".join((group.commands[name].help or "").split())
        assert own.startswith(" ".join(summary.split())), (name, own[:120])


#: what `imunav CMD --help` may import of the package: the CLI, and the core that `import imunav` loads
_HELP_MODULES = ("imunav", "imunav.errors", "imunav.units", "imunav.files")
_HEAVY = ("numba", "scipy", "pandas", "matplotlib", "torch", "dask", "pyulog", "rosbags", "yaml", "sklearn")
_HELP_CODE = (
    "import sys, time\n"
    "t = time.perf_counter()\n"
    "from imunav.cli.main import app\n"
    "try:\n"
    "    app(sys.argv[1:], standalone_mode=False)\n"
    "except SystemExit:\n"
    "    pass\n"
    "dt = time.perf_counter() - t\n"
    f"heavy = {_HEAVY!r}\n"
    f"own = {_HELP_MODULES!r}\n"
    "bad = sorted(m for m in sys.modules if m.split('.')[0] in heavy\n"
    "             or (m.startswith('imunav.') and m not in own and not m.startswith('imunav.cli')))\n"
    "print(repr((dt, bad)), file=sys.stderr)\n"
)


def _help_run(*argv: str) -> tuple[float, list[str]]:
    """(seconds from the first import of imunav to the printed help, heavy / library modules then loaded)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-c", _HELP_CODE, *argv], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    return eval(r.stderr.strip().splitlines()[-1])  # noqa: S307 - our own repr


@functools.cache
def _floor() -> float:
    return _help_run("--help")[0]


@pytest.mark.parametrize("name", list(COMMANDS))
def test_command_help_imports_no_library(name):
    """`imunav CMD --help` builds the help from the signature: no numba, scipy, pandas, nor the command's library
    (issue 26: it took 2-7 s).  The time is a generous bound over the floor of `imunav --help` (typer, numpy)."""
    floor = _floor()
    dt, loaded = _help_run(name, "--help")
    assert loaded == [], f"imunav {name} --help imported {loaded[:10]}"
    # generous, for a loaded machine (numpy + typer take the floor; a library import adds seconds): a second
    # try before failing on a spike of load
    bound = max(floor + 0.5, 3 * floor)
    if dt > bound:
        dt = min(dt, _help_run(name, "--help")[0])
    assert dt <= bound, (name, dt, floor)


def test_help_texts_are_plain_prose():
    """No Sphinx markup and no runs of spaces in any help text; listings keep whole first sentences (issue 26)."""
    markup = ("``", ":func:", ":class:", ":meth:", ":mod:", ":data:")
    problems = []
    for path, cmd in _leaves(get_command(app), [], groups=True):
        texts = [("help", cmd.help)] + [(p.name, getattr(p, "help", None)) for p in cmd.params]
        for what, text in texts:
            for line in (text or "").splitlines():
                if any(m in line for m in markup) or re.search(r"\S {2,}\S", line):
                    problems.append((" ".join(path), what, line.strip()[:80]))
        res = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
        if any(m in res.output for m in markup):
            problems.append((" ".join(path), "--help output", "markup"))
    assert problems == []
    listing = CliRunner().invoke(app, ["calibrate", "--help"], env={"COLUMNS": "200"}).output
    assert "Tedaldi et al. (2014) multi-pose calibration without a rate table." in " ".join(listing.split())
