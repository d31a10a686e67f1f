"""Numba compilation as the command line shows it: a notice when a command has to compile, and the record
that ``imunav warmup`` prints.

imunav's kernels are compiled by numba on first use and cached on disk (``cache=True``): in the package's
``__pycache__`` folders where Python may write there, else in the user's cache folder (numba's own fallback,
or ``$NUMBA_CACHE_DIR`` when set).  A first run after an install or upgrade compiles them (tens of seconds on
two cores); :func:`watch_compilation` then says so on a terminal instead of a silent wait: the notice at the
first compilation, one line per kernel as it is compiled (on a terminal its name while it compiles, then its
seconds: ``gins_run`` alone takes 15 s), and the total when the command ends; ``imunav warmup`` does the compilation ahead.  ``IMUNAV_COMPILE_REPORT=1`` prints the same on standard
error where it is not a terminal (``benchmarks/bench_first_run.py`` reads it).

This module imports numba: the CLI's lazy loader (:mod:`imunav.cli._lazy`) imports it only once a command's
library has loaded numba.
"""

from __future__ import annotations

import atexit
import os
import py_compile
import sys
import time
from dataclasses import dataclass, field
from typing import Any, TextIO

from numba.core import event

__all__ = ["NOTICE", "REPORT_ENV", "CompileWatch", "watch_compilation", "write_bytecode"]

#: the line a command prints (on a terminal) when it has to compile kernels
NOTICE = ("note: compiling imunav's numba kernels (first run after an install or upgrade; they are cached for the "
          "next runs, and `imunav warmup` compiles them ahead) ...")


class CompileWatch(event.Listener):
    """Listener of numba's ``numba:compile`` events: what was compiled, how long it took, where it is cached.

    Parameters
    ----------
    stream : file-like, optional
        Where to print :data:`NOTICE` at the first compilation; ``None``: print nothing.
    """

    def __init__(self, stream: TextIO | None = None) -> None:
        self.stream = stream
        #: ``(kernel, seconds)`` of each top-level compilation (a kernel's callees compile inside it)
        self.top: list[tuple[str, float]] = []
        #: ``module.function`` of every kernel compiled (cache misses), in order
        self.kernels: list[str] = []
        #: folders numba caches the compiled kernels in
        self.cache_dirs: set[str] = set()
        #: seconds spent compiling (nested compilations counted once)
        self.seconds = 0.0
        self._depth = 0
        self._t0 = 0.0
        self._noticed = False
        self._top_name = ""
        #: a terminal: the kernel's name is shown while it compiles, its line completed when it is done
        self._live = stream is not None and bool(getattr(stream, "isatty", lambda: False)())

    def on_start(self, ev: Any) -> None:
        disp = (ev.data or {}).get("dispatcher")
        fn = getattr(disp, "py_func", None)
        name = f"{fn.__module__}.{fn.__qualname__}" if fn is not None else "?"
        if self._depth == 0:
            self._t0 = time.perf_counter()
            self._top_name = name
        self._depth += 1
        if fn is not None:
            self.kernels.append(name)
        path = getattr(getattr(disp, "_cache", None), "_cache_path", None)
        if path:
            self.cache_dirs.add(str(path))
        if self.stream is not None and not self._noticed:
            self._noticed = True
            print(NOTICE, file=self.stream, flush=True)
        if self._live and self._depth == 1:
            print(f"  compiling {name.removeprefix('imunav.')} ...", end="", file=self.stream, flush=True)

    def on_end(self, ev: Any) -> None:
        self._depth -= 1
        if self._depth == 0:
            dt = time.perf_counter() - self._t0
            self.seconds += dt
            self.top.append((self._top_name, dt))
            if self.stream is not None:
                print(("\r" if self._live else "") + f"  compiled {self._top_name.removeprefix('imunav.')} in "
                      f"{dt:.1f} s", file=self.stream, flush=True)

    def report(self) -> None:
        """Print the total (kernels, seconds) on the stream, when anything was compiled."""
        if self.stream is not None and self.top:
            print(f"note: compiled {len(self.kernels)} numba kernels in {self.seconds:.1f} s (cached for the next "
                  "runs)", file=self.stream, flush=True)


_WATCH: CompileWatch | None = None

#: set to 1: what is compiled is said on standard error even when it is not a terminal
REPORT_ENV = "IMUNAV_COMPILE_REPORT"


def watch_compilation(stream: TextIO | None = None) -> CompileWatch:
    """Install, once per process, the listener that prints :data:`NOTICE` at a command's first compilation.

    Parameters
    ----------
    stream : file-like, optional
        Where the notice goes; default ``sys.stderr`` when it is a terminal, else nowhere (a pipe, a log, a
        test runner gets no notice).

    Returns
    -------
    CompileWatch
        The installed listener (the same on every call).
    """
    global _WATCH
    if _WATCH is None:
        if stream is None and sys.stderr is not None and (sys.stderr.isatty() or os.environ.get(REPORT_ENV) == "1"):
            stream = sys.stderr
        _WATCH = CompileWatch(stream)
        event.register("numba:compile", _WATCH)
        atexit.register(_WATCH.report)
    return _WATCH


@dataclass
class Bytecode:
    """What :func:`write_bytecode` did."""

    written: int = 0
    current: int = 0
    #: source files whose bytecode could not be written (read-only folder)
    failed: list[str] = field(default_factory=list)


def write_bytecode() -> Bytecode:
    """Write the bytecode (``.pyc``) of every module imported so far whose cache is missing or stale.

    Python reads ``.pyc`` files even where it may not write them (``PYTHONDONTWRITEBYTECODE=1``, a
    read-only install): writing them once makes every later start skip compiling the sources
    (``pip install --no-compile`` writes none).  Only the modules a run imported are compiled, not every
    module of every dependency.

    Returns
    -------
    Bytecode
        Counts of files written and already current, and the sources that could not be written.
    """
    out = Bytecode()
    for mod in list(sys.modules.values()):
        spec = getattr(mod, "__spec__", None)
        origin, cached = getattr(spec, "origin", None), getattr(spec, "cached", None)
        if not origin or not cached or not origin.endswith(".py") or not os.path.isfile(origin):
            continue
        try:
            if os.path.getmtime(cached) >= os.path.getmtime(origin):
                out.current += 1
                continue
        except OSError:
            pass
        try:
            py_compile.compile(origin, cfile=cached, doraise=True)
            out.written += 1
        except (OSError, py_compile.PyCompileError):
            out.failed.append(origin)
    return out
