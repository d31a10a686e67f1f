"""Every command of the `imunav` CLI documents an example in its --help."""

from __future__ import annotations

from typer.main import get_command
from typer.testing import CliRunner

from imunav.cli.main import app


def _leaves(cmd, path):
    if hasattr(cmd, "commands"):
        for name, sub in cmd.commands.items():
            yield from _leaves(sub, [*path, name])
    else:
        yield path, cmd


def test_every_command_has_an_example():
    leaves = list(_leaves(get_command(app), []))
    assert len(leaves) >= 20  # info, simulate, lab, noise, calibrate ×6, compensate, attitude ×3, zupt ×3, airdata ×4, batch ×3
    runner = CliRunner()
    for path, _ in leaves:
        res = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
        assert res.exit_code == 0, (path, res.output)
        assert "Example" in res.output or "example" in res.output, f"imunav {' '.join(path)} --help has no example"


def test_version():
    res = CliRunner().invoke(app, ["--version"])
    assert res.exit_code == 0 and res.output.strip()
