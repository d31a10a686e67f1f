"""Entry point of the ``imunav`` command.

Each command module in :mod:`imunav.cli` exposes ``register(app)``, which adds
its command or command group to the Typer app.  Keep the modules thin: they
parse options, call the library and print / write results.  They do not catch
errors: :class:`imunav.cli._errors.ImunavGroup` turns every imunav error and
every OS error into one line on stderr and exit status 2 (a traceback only
with ``--debug``), and any other exception into exit status 1.
"""

from __future__ import annotations

import importlib

import typer

from imunav.cli._errors import ImunavGroup

app = typer.Typer(
    cls=ImunavGroup,
    name="imunav",
    help=(
        "Inertial sensors end to end: simulate, characterize, calibrate IMUs and "
        "magnetometers; attitude and navigation filters.\n\n"
        "Example: imunav lab --out lab-report"
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
)

# One entry per command module (imunav.cli.<name> with a register(app) function).
_COMMAND_MODULES: list[str] = [
    "info",
    "convert",
    "noise",
    "simulate",
    "lab",
    "calibrate",
    "compensate",
    "attitude",
    "zupt",
    "gins",
    "airdata",
    "batch",
]

for _name in _COMMAND_MODULES:
    importlib.import_module(f"imunav.cli.{_name}").register(app)


def _plain_help(t: typer.Typer) -> None:
    """Print every --help as written: Rich markup would swallow bracketed text such as ``[spec.<name>]``."""
    t.rich_markup_mode = None
    for group in t.registered_groups:
        if group.typer_instance is not None:
            _plain_help(group.typer_instance)


_plain_help(app)


@app.callback(invoke_without_command=True)
def _main(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", help="Print the version and exit.", is_eager=True),
    debug: bool = typer.Option(False, "--debug", help="On an error, also print the Python traceback."),
) -> None:
    if version:
        from imunav import __version__

        typer.echo(__version__)
        raise typer.Exit()
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


if __name__ == "__main__":  # pragma: no cover
    app()
