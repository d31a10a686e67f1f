"""imunav warmup's pieces: the compile notice and the bytecode writer (the full warmup takes a minute: not here)."""

from __future__ import annotations

import importlib.util
import io
import os
import re
import sys

import numba
import numpy as np
import pytest
from numba.core import event
from typer.testing import CliRunner

from imunav.cli._compile import NOTICE, CompileWatch, write_bytecode
from imunav.cli.main import app


def test_a_compilation_is_said_once_and_recorded():
    stream = io.StringIO()
    watch = CompileWatch(stream)

    @numba.njit(cache=False)
    def twice(x):
        return 2.0 * x

    @numba.njit(cache=False)
    def thrice(x):
        return 3.0 * x

    event.register("numba:compile", watch)
    try:
        assert twice(np.ones(3)).sum() == 6.0 and thrice(1.0) == 3.0
        twice(np.ones(3))  # compiled already: no event
    finally:
        event.unregister("numba:compile", watch)
    lines = stream.getvalue().splitlines()
    assert lines[0] == NOTICE and lines.count(NOTICE) == 1  # once, however many kernels
    # then one line per kernel compiled, with its seconds (issue 35: say what is compiled and for how long)
    assert [ln.split()[1].rsplit(".", 1)[-1] for ln in lines[1:]] == ["twice", "thrice"], lines
    assert all(re.fullmatch(r"  compiled \S+ in \d+\.\d s", ln) for ln in lines[1:]), lines
    names = [k.rsplit(".", 1)[-1] for k in watch.kernels]  # with numba's own helpers they call
    assert names[0] == "twice" and "thrice" in names
    assert watch.seconds > 0 and [n.rsplit(".", 1)[-1] for n, _ in watch.top] == ["twice", "thrice"]
    assert sum(dt for _, dt in watch.top) == pytest.approx(watch.seconds)
    watch.report()
    assert stream.getvalue().splitlines()[-1].startswith(f"note: compiled {len(watch.kernels)} numba kernels in ")


def test_on_a_terminal_the_kernel_is_named_while_it_compiles():
    """A terminal sees "compiling NAME ..." during a kernel's compilation (gins_run: 15 s), then the same line
    completed with its seconds; a pipe gets the completed lines only (the test above)."""

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    watch = CompileWatch(stream)

    @numba.njit(cache=False)
    def halve(x):
        return 0.5 * x

    event.register("numba:compile", watch)
    try:
        assert halve(4.0) == 2.0
    finally:
        event.unregister("numba:compile", watch)
    text = stream.getvalue()
    assert text.startswith(NOTICE + "\n")
    shown = text.removeprefix(NOTICE + "\n")
    assert re.fullmatch(r"  compiling \S+halve \.\.\.\r  compiled \S+halve in \d+\.\d s\n", shown), repr(shown)


def test_bytecode_is_written_for_imported_modules(tmp_path, monkeypatch):
    """What PYTHONDONTWRITEBYTECODE=1 prevents at import, write_bytecode writes, where Python then reads it."""
    src = tmp_path / "fh_warm_mod.py"
    src.write_text("VALUE = 3\n")
    monkeypatch.setattr(sys, "dont_write_bytecode", True)
    monkeypatch.syspath_prepend(str(tmp_path))
    import fh_warm_mod  # noqa: F401

    cached = importlib.util.cache_from_source(str(src))
    assert fh_warm_mod.__spec__.cached == cached
    assert not os.path.exists(cached)
    out = write_bytecode()
    assert os.path.exists(cached) and out.written >= 1 and str(src) not in out.failed
    again = write_bytecode()
    assert again.written == 0 and again.current >= out.current + out.written - len(out.failed)
    monkeypatch.delitem(sys.modules, "fh_warm_mod")


def test_warmup_is_listed_with_an_example():
    r = CliRunner().invoke(app, ["warmup", "--help"], env={"COLUMNS": "200"})
    assert r.exit_code == 0 and "Example: imunav warmup" in r.output


def test_each_step_finds_the_files_of_the_step_before(monkeypatch):
    """warmup runs its steps inside its own command: each step's outputs are in place when the step ends (not
    deferred to the end of warmup's output transaction), so that the next step reads them."""
    import imunav.cli.warmup as warmup

    monkeypatch.setattr(warmup, "TOUR", (
        ("simulate", ("simulate", "static", "--preset", "thesis_sim", "--duration", "20", "--fs", "50",
                      "--out", "still.npz")),
        ("info", ("info", "still.npz", "--json", "info.json")),
        ("read back", lambda: warmup.io_lib.read_imu("still.npz")),
    ))
    r = CliRunner().invoke(app, ["warmup"])
    assert r.exit_code == 0, r.output
    assert "failed" not in r.output, r.output
