"""The commands' one progress display (imunav.cli._progress) and plain tables off a terminal (cli._console)."""

from __future__ import annotations

import io
import sys

from rich.markup import escape
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._progress import progress, shows_progress


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_bar_only_on_a_terminal_and_without_quiet(monkeypatch):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert not shows_progress()
    with progress("x", total=3) as report:
        report(1, 3)  # a no-op: nothing is written to a pipe
    assert sys.stderr.getvalue() == ""
    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    assert shows_progress() and not shows_progress(quiet=True)
    with progress("x", quiet=True) as report:
        report(1, 2)
    assert tty.getvalue() == ""
    with progress("noise analysis", total=2) as report:
        report(1, 2)
        report(2, 2)
    assert "noise analysis" in tty.getvalue()


def test_tables_to_a_pipe_print_whole_in_markdown(monkeypatch):
    out = io.StringIO()
    monkeypatch.setattr(sys, "stdout", out)
    t = Table(title="t")
    t.add_column(escape("parameter [unit]"))  # a bracket is Rich markup: a command escapes its units
    t.add_column("value")
    t.add_row(escape("gyro_bias_x [deg/h]"), "278.61234567890123 ± 0.0001234" * 4)
    make_console().print(t)
    text = out.getvalue()
    assert "| parameter [unit]" in text and "|---" in text  # Markdown layout, the bracketed unit kept
    assert "278.61234567890123 ± 0.0001234" * 4 in text and "…" not in text  # whole, past 80 columns
