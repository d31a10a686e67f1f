"""The console every command prints through: Rich on a terminal, whole plain tables in a pipe or a file.

On a terminal a table is drawn to the window's width.  Sent to a pipe or a file (``imunav noise x.npz >
noise.txt``) Rich would cut it at 80 columns with ellipses ("278.6…"); :func:`make_console` then prints every
table whole (no width limit, no wrapping) in Markdown layout (``| a | b |``, a ``|---|`` rule under the
header), without colours, so that the figures survive intact and the table reads back as text.
"""

from __future__ import annotations

from typing import Any

from rich import box
from rich.console import Console
from rich.table import Table

__all__ = ["PlainConsole", "make_console"]

#: a width no table reaches: tables sent to a pipe or a file print whole
_UNLIMITED = 100_000


class PlainConsole(Console):
    """A Rich console for a pipe or a file: tables whole, in Markdown layout; the rest as Rich prints it."""

    def print(self, *objects: Any, **kwargs: Any) -> None:  # noqa: D102 - Console.print
        for obj in objects:
            if isinstance(obj, Table):
                obj.box = box.MARKDOWN
                obj.expand = False
                for col in obj.columns:
                    col.no_wrap = True
                    col.overflow = "fold"
        kwargs.setdefault("soft_wrap", not any(isinstance(o, Table) for o in objects))
        super().print(*objects, **kwargs)


def make_console(stderr: bool = False) -> Console:
    """The console a command prints through (see the module docstring).

    Parameters
    ----------
    stderr : bool
        Print to standard error (progress, notes) instead of standard output.

    Returns
    -------
    rich.console.Console
        A plain :class:`rich.console.Console` on a terminal, else a :class:`PlainConsole` without width limit
        or colours.
    """
    con = Console(stderr=stderr)
    if con.is_terminal:
        return con
    return PlainConsole(stderr=stderr, width=_UNLIMITED, no_color=True, highlight=False)
