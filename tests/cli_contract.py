"""Running the CLI in the tests: one way to invoke a command, and the check of its user-error contract."""

from __future__ import annotations

from click.testing import Result
from typer.testing import CliRunner

from imunav.cli.main import app


def invoke(*args, **kw) -> Result:
    """Run ``imunav ARGS...`` in-process (each argument passed through ``str``)."""
    return CliRunner().invoke(app, [str(a) for a in args], **kw)


def one_error_line(r: Result, code: int = 2) -> str:
    """The one line a user error writes on stderr, after checking the exit status and that no traceback shows."""
    assert r.exit_code == code, (r.exit_code, r.stdout[-800:], r.stderr[-1500:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    return lines[0]
