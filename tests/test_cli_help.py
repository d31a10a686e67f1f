"""Every command of the `imunav` CLI documents an example in its --help."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from typer.main import get_command
from typer.testing import CliRunner

from imunav.cli.main import COMMANDS, app

ROOT = Path(__file__).resolve().parents[1]


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


def test_the_listed_summary_is_the_first_sentence_of_each_commands_help():
    group = get_command(app)
    assert list(group.commands) == list(COMMANDS)
    for name, summary in COMMANDS.items():
        own = " ".join((group.commands[name].help or "").split())
        assert own.startswith(" ".join(summary.split())), (name, own[:120])
