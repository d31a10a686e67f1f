"""The one error path of the ``imunav`` command.

Every command runs inside :class:`ImunavGroup`, whose ``invoke`` turns

* an :class:`imunav.errors.ImunavError` or an :class:`OSError` (input or output
  file missing, unreadable, not writable, a folder where a file is expected)
  into ONE line on stderr, ``error: <message>``, and exit status 2;
* any other exception (a bug) into one line saying how to report it, and exit
  status 1.

With ``imunav --debug ...`` (or ``IMUNAV_DEBUG=1``) the traceback is printed
as well.  Click's own usage errors (unknown option, bad number) keep Click's
format and exit status 2.
"""

from __future__ import annotations

import os
import sys
import traceback
from pathlib import Path
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

try:  # typer >= 0.20 carries its own copy of click (and no longer installs the click package)
    from typer import _click as click
    from typer._click.globals import get_current_context
except ImportError:  # older typer runs on the click package
    import click

    get_current_context = click.get_current_context

# exceptions that typer / click handle themselves (usage errors: exit 2 with the usage line; Exit; Abort)
_PASS_THROUGH = tuple({e for e in (typer.Exit, typer.Abort, getattr(typer, "TyperException", None),
                                   getattr(click, "ClickException", None), getattr(click, "Abort", None),
                                   getattr(getattr(click, "exceptions", None), "Exit", None)) if e is not None})

__all__ = ["ImunavGroup", "check_figure_path", "fail", "one_line"]

REPORT_TO = "the imunav issue tracker"


def one_line(text: str) -> str:
    """``text`` with its line breaks and runs of blanks folded into single spaces."""
    return " ".join(str(text).split())


def _message(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        where = f"{exc.filename}: " if exc.filename is not None else ""
        two = f" -> {exc.filename2}" if getattr(exc, "filename2", None) else ""
        return one_line(f"{where}{exc.strerror}{two}")
    msg = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.filename is not None and str(exc.filename) not in msg:
        msg = f"{exc.filename}: {msg}"
    return one_line(msg)


def _debug_wanted(ctx: click.Context | None = None) -> bool:
    if os.environ.get("IMUNAV_DEBUG", "").strip().lower() in ("1", "true", "yes", "on"):
        return True
    ctx = ctx or get_current_context(silent=True)
    while ctx is not None:
        if ctx.params.get("debug"):
            return True
        ctx = ctx.parent
    return False


def fail(exc: BaseException, ctx: click.Context | None = None) -> NoReturn:
    """Report a user error (one line on stderr) and exit with status 2."""
    if _debug_wanted(ctx):
        traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
    typer.echo(f"error: {_message(exc)}", err=True)
    raise typer.Exit(2)


_FIG_SUFFIXES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff", ".webp")


def check_figure_path(path: Path | None, option: str) -> None:
    """Refuse a figure path whose suffix matplotlib cannot write."""
    from imunav.errors import InvalidInputError

    if path is not None and Path(path).suffix.lower() not in _FIG_SUFFIXES:
        raise InvalidInputError(f"{option} {path}: unknown figure type {Path(path).suffix or '(no suffix)'!r}; "
                                f"use one of {', '.join(_FIG_SUFFIXES)}")


class ImunavGroup(TyperGroup):
    """Root command group: the single place where exceptions become messages and exit codes."""

    def invoke(self, ctx: click.Context) -> Any:
        from imunav.errors import ImunavError

        try:
            return super().invoke(ctx)
        except (*_PASS_THROUGH, KeyboardInterrupt, SystemExit):
            raise
        except (ImunavError, OSError) as exc:
            fail(exc, ctx)
        except UnicodeDecodeError as exc:  # a text input (TOML, JSON, CSV) that is not text
            fail(ValueError(f"an input file is not UTF-8 text ({exc.reason} at byte {exc.start}); "
                            "check the file given for each option"), ctx)
        except Exception as exc:  # noqa: BLE001  (a bug: say how to report it)
            debug = _debug_wanted(ctx)
            if debug:
                traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
            typer.echo(
                f"internal error: {type(exc).__name__}: {_message(exc)} -- this is a bug in imunav; please report it "
                f"to {REPORT_TO} with the command line{'' if debug else ' and the output of the same command with --debug'}",
                err=True,
            )
            raise typer.Exit(1) from None
