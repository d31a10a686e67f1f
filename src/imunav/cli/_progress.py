"""The one progress display of the commands: a Rich bar on a terminal, nothing in a pipe, a log or with --quiet.

A command that can run for more than a few seconds wraps its work in :func:`progress` and hands the
callable it yields to the library (every long-running library function takes ``progress=callable(done,
total)``, e.g. :func:`imunav.lab.montecarlo.run_montecarlo`, :func:`imunav.lab.batch.calibrate_batch`) or calls it
itself between stages::

    with progress("noise analysis", quiet=quiet) as report:
        for k, item in enumerate(items):
            ...
            report(k + 1, len(items))

The bar goes to standard error, so that standard output (tables, JSON) stays clean.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

__all__ = ["progress", "shows_progress"]


def shows_progress(quiet: bool = False) -> bool:
    """Whether a progress bar is drawn: not with ``--quiet``, and only when standard error is a terminal.

    Parameters
    ----------
    quiet : bool
        The command's ``--quiet``.

    Returns
    -------
    bool
        True on an interactive terminal without ``--quiet``.
    """
    return not quiet and sys.stderr is not None and sys.stderr.isatty()


@contextmanager
def progress(description: str, *, quiet: bool = False, total: int | None = None) -> Iterator[Callable[[int, int], None]]:
    """A ``report(done, total)`` callable that moves a Rich bar on a terminal (a no-op otherwise).

    Parameters
    ----------
    description : str
        The bar's label.
    quiet : bool
        The command's ``--quiet``: no bar.
    total : int, optional
        Steps expected, when known before the first report.

    Yields
    ------
    callable
        ``report(done, total)``: ``done`` of ``total`` steps are finished.
    """
    if not shows_progress(quiet):
        yield lambda done, total_: None
        return
    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                   console=Console(stderr=True), transient=True)
    with bar:
        task = bar.add_task(description, total=total)

        def report(done: int, total_: int) -> None:
            bar.update(task, completed=done, total=total_)

        yield report
