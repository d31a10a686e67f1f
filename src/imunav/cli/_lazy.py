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

import importlib
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
        module = importlib.import_module(self._name)
        _after_library_import()
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


def load_command(name: str) -> Any:
    """The click command (or group) that ``imunav.cli.<name>.register`` adds, as ``imunav`` runs it."""
    sub = typer.Typer(add_completion=False)
    importlib.import_module(f"imunav.cli.{name}").register(sub)
    plain_help(sub)
    return get_group(sub).commands[name]


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
