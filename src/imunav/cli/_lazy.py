"""Command modules imported when their command runs, not when ``imunav`` starts.

A command module imports the library it drives (numba kernels, scipy, pandas) at module level;
importing all of them would make ``imunav --help`` take seconds.  :class:`LazyGroup` knows each
command by name and first help sentence (:data:`imunav.cli.main.COMMANDS`) and imports
``imunav.cli.<name>`` (and calls its ``register(app)``) the first time the command is looked up:
to run it, to show its ``--help``, or when its object is asked for (``group.commands[name]``).
``imunav --help`` lists the commands from the table alone.

A command module, in turn, names the library modules it drives with :func:`lazy` instead of importing
them: ``imunav CMD --help`` builds the help from the command's signature, so it imports typer and the
command module but none of numba, scipy, pandas or the command's library, which load when the command
runs (tests/test_cli_help.py checks ``sys.modules`` after each ``--help``).
"""

from __future__ import annotations

import gc
import importlib
import inspect
import re
import sys
from collections.abc import Iterator, Mapping
from typing import Any

import typer
from typer.core import TyperCommand
from typer.main import get_group

from imunav.cli._errors import ImunavGroup, click

__all__ = ["LazyGroup", "LazyCommands", "LazyModule", "lazy", "plain_help"]


class LazyModule:
    """Stand-in for a module that imports it on the first attribute access.

    ``lazy("imunav.noise").fit_noise`` is ``imunav.noise.fit_noise``; building the stand-in imports
    nothing.
    """

    __slots__ = ("_name",)

    def __init__(self, name: str) -> None:
        object.__setattr__(self, "_name", name)

    def __getattr__(self, attr: str) -> Any:
        fresh = self._name not in sys.modules
        module = importlib.import_module(self._name)
        _after_library_import()
        if fresh:
            # The library's modules (numba, scipy, pandas, matplotlib: a few hundred thousand objects) live until
            # the process ends: out of the garbage collector's rounds, no full collection during the command nor
            # the interpreter's at exit walks them again (a fifth of a long `gins run`).  Objects made later are
            # collected as usual.
            gc.freeze()
        return getattr(module, attr)

    def __setattr__(self, attr: str, value: Any) -> None:
        raise AttributeError(f"{self._name} is imported lazily; it cannot be assigned to")

    def __repr__(self) -> str:
        return f"<lazy module {self._name!r}>"


def _after_library_import() -> None:
    """Once a command's library has loaded numba, have a first compilation said on screen (imunav.cli._compile)."""
    if "numba" in sys.modules and "imunav.cli._compile" not in sys.modules:
        importlib.import_module("imunav.cli._compile").watch_compilation()


def lazy(name: str) -> Any:
    """The module ``name``, imported when the command first uses one of its attributes.

    This is the command modules' way to name the library they drive (see the module docstring); the
    return is typed ``Any`` since a type checker cannot follow the stand-in.
    """
    return LazyModule(name)


def plain_help(t: typer.Typer) -> None:
    """Print every --help as written: Rich markup would swallow bracketed text such as ``[spec.<name>]``."""
    t.rich_markup_mode = None
    for group in t.registered_groups:
        if group.typer_instance is not None:
            plain_help(group.typer_instance)


#: Sphinx roles and literals of docstrings used as help: ":func:`x`" and "``x``" read "x" on a terminal
_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|obj|exc|ref|doc|py:\w+):`~?([^`<]*?)(?:\s*<[^>]*>)?`")
_LITERAL = re.compile(r"``(.+?)``")
#: where a sentence does not end although a full stop and a space follow
_NOT_AN_END = ("al", "e.g", "i.e", "cf", "vs", "approx", "Fig", "eq", "eqs", "No", "resp")


def clean_help(text: str | None) -> str | None:
    """A docstring as ``--help`` prints it: no Sphinx markup, no indentation or runs of spaces inside lines.

    Parameters
    ----------
    text : str or None
        The help text (a command's docstring or an option's help).

    Returns
    -------
    str or None
        The text with ``:func:`x``` / ````x```` as ``x``, the docstring's indentation removed
        (:func:`inspect.cleandoc`) and runs of spaces inside a line made one; leading indentation (example
        blocks) is kept.
    """
    if not text:
        return text
    text = _LITERAL.sub(r"\1", _ROLE.sub(r"\1", inspect.cleandoc(text)))
    paragraphs = []
    for para in re.split(r"\n[ \t]*\n", text):
        lines = [re.sub(r"(?<=\S) {2,}(?=\S)", " ", line.rstrip()) for line in para.splitlines()]
        if lines and not lines[0].lstrip().startswith("\b"):
            # click joins a paragraph's lines and keeps the first one's indentation: the others' is a run
            lines = lines[:1] + [line.lstrip() for line in lines[1:]]
            if lines[0].lstrip().startswith("Example") and "imunav " in para:
                # an example is printed as written: click's wrapping would cut a command at a hyphen
                lines = ["\b", *lines]
        paragraphs.append("\n".join(lines))
    return "\n\n".join(paragraphs)


def first_sentence(text: str | None) -> str:
    """The first sentence of a help text, not cut at "et al." or "e.g." (click's own cut is)."""
    flat = " ".join((text or "").split())
    for m in re.finditer(r"\.(?:\s|$)", flat):
        words = flat[:m.start()].split()
        if words and words[-1].rstrip(".") in _NOT_AN_END:
            continue
        return flat[:m.start() + 1]
    return flat


def _clean_command(cmd: Any) -> None:
    cmd.help = clean_help(cmd.help)
    if cmd.help and not getattr(cmd, "short_help", None):
        cmd.short_help = first_sentence(cmd.help.split("\n\n")[0])
    for p in getattr(cmd, "params", []):
        if getattr(p, "help", None):
            p.help = " ".join(clean_help(p.help).split())  # type: ignore[union-attr]
    for sub in getattr(cmd, "commands", {}).values():
        _clean_command(sub)


def load_command(name: str) -> Any:
    """The click command (or group) that ``imunav.cli.<name>.register`` adds, as ``imunav`` runs it: its help
    texts cleaned of docstring markup (:func:`clean_help`)."""
    sub = typer.Typer(add_completion=False)
    importlib.import_module(f"imunav.cli.{name}").register(sub)
    plain_help(sub)
    cmd = get_group(sub).commands[name]
    _clean_command(cmd)
    return cmd


class LazyCommands(dict):
    """``name -> click command`` that imports a command's module on first access.

    The keys (the command names, in listing order) are known from the start; iterating over them,
    ``len`` and ``in`` import nothing.  ``summaries`` holds each command's first help sentence.
    """

    def __init__(self, loaded: Mapping[str, Any], summaries: Mapping[str, str]) -> None:
        super().__init__({name: None for name in summaries})
        super().update(loaded)
        self.summaries = dict(summaries)

    def __getitem__(self, name: str) -> Any:
        cmd = super().__getitem__(name)
        if cmd is None:
            cmd = load_command(name)
            super().__setitem__(name, cmd)
        return cmd

    def get(self, name: str, default: Any = None) -> Any:
        return self[name] if name in self else default

    def values(self) -> Iterator[Any]:  # type: ignore[override]
        return (self[name] for name in self)

    def items(self) -> Iterator[tuple[str, Any]]:  # type: ignore[override]
        return ((name, self[name]) for name in self)

    def listing(self) -> dict[str, Any]:
        """The loaded commands, and a stand-in carrying the help sentence for each one not loaded yet."""
        return {name: super(LazyCommands, self).__getitem__(name) or TyperCommand(name, help=self.summaries[name])
                for name in self}


class LazyGroup(ImunavGroup):
    """The ``imunav`` group: :class:`~imunav.cli._errors.ImunavGroup` whose commands load on first use."""

    #: name -> first sentence of the command's help, in listing order (set by imunav.cli.main)
    summaries: Mapping[str, str] = {}

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.commands = LazyCommands(self.commands, self.summaries)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list of ``imunav --help``, from the help sentences: no command module is imported."""
        commands = self.commands
        self.commands = commands.listing()
        try:
            super().format_commands(ctx, formatter)
        finally:
            self.commands = commands
