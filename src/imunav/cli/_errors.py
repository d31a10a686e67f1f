"""The one error path of the ``imunav`` command.

Every command runs inside :class:`ImunavGroup`, whose ``invoke`` runs it in
one output transaction (:func:`imunav.files.output_transaction`: its output
files are moved in only when it completes; a command that fails leaves nothing
new), after checking every numeric option against its declared domain
(:mod:`imunav.cli._domains`) and refusing FIFOs, devices and link loops given
as paths (:func:`install_checks`), and turns

* an :class:`imunav.errors.ImunavError` or an :class:`OSError` (input or output
  file missing, unreadable, not writable, a folder where a file is expected)
  into ONE line on stderr, ``error: <message>``, and exit status 2;
* numba's cache of compiled kernels that cannot be written (no writable
  folder, a write the file system refuses) into one line naming the file or the
  folders and the fix (:func:`numba_cache_failure`), exit status 2;
* any other exception (a bug) into one line saying how to report it, and exit
  status 1.

With ``imunav --debug ...`` (or ``IMUNAV_DEBUG=1``) the traceback is printed
as well.  Click's own usage errors (unknown option, bad number, missing
argument, unknown command) are also ONE line on stderr,
``error: <message> (see 'imunav <command> --help')``, with exit status 2
(:meth:`ImunavGroup.main`).  A group called without a command prints its help.
An :class:`imunav.errors.ImunavWarning` (or any ``UserWarning``) is printed as
one line, ``warning: <message>``, and the command goes on.
"""

from __future__ import annotations

import errno
import functools
import os
import re
import stat
import sys
import traceback
import warnings
from pathlib import Path
from typing import Any, NoReturn

import typer
import typer.main
from typer.core import TyperGroup

from imunav.cli._domains import check_params, check_paths, flag_of, is_path
from imunav.cli._limits import ESTIMATORS, check_limits
from imunav.errors import ImunavError, ImunavWarning, InvalidInputError
from imunav.files import latch_interrupts, output_transaction

try:  # typer >= 0.20 carries its own copy of click (and no longer installs the click package)
    from typer import _click as click
    from typer._click.globals import get_current_context
except ImportError:  # older typer runs on the click package
    import click

    get_current_context = click.get_current_context

# exceptions that typer / click handle themselves (usage errors: reported by ImunavGroup.main; Exit; Abort)
_PASS_THROUGH = tuple({e for e in (typer.Exit, typer.Abort, getattr(typer, "TyperException", None),
                                   getattr(click, "ClickException", None), getattr(click, "Abort", None),
                                   getattr(getattr(click, "exceptions", None), "Exit", None)) if e is not None})
_ABORTS = tuple({e for e in (typer.Abort, getattr(click, "Abort", None)) if e is not None})

__all__ = ["ImunavGroup", "check_figure_path", "check_suffix", "fail", "install_checks", "numba_cache_failure",
           "one_line"]

REPORT_TO = "the imunav issue tracker"


def one_line(text: str) -> str:
    """``text`` with its line breaks and runs of blanks folded into single spaces."""
    return " ".join(str(text).split())


#: library wording -> command-line wording.  The library names its keywords and, in brackets, the flag
#: ("pass force=True (command line: --force)", "instance=... (CLI: --instance)"); a person at the command
#: line reads the flag alone.
_KEYWORD_FLAG = re.compile(r"[\w.]+=\S*? \((?:command line|CLI): ([^)]*)\)")
_API_FLAG = re.compile(r"\(([^;()]*); (?:command line|CLI): ([^)]*)\)")
_READER = re.compile(r"\b(read|write)_imu\((?:format|layout)='([\w-]+)'\)")
_OPTION_LIST = re.compile(r"(options?\(s\)|accepts) \[([^\]]*)\]")


def _flags(names: str) -> str:
    return ", ".join("--" + n.strip().strip("'\"").replace("_", "-") for n in names.split(",") if n.strip())


def command_line_words(msg: str) -> str:
    """A library message as the command line says it: flags instead of Python keywords and call syntax.

    Parameters
    ----------
    msg : str
        The message of an :class:`imunav.errors.ImunavError`.

    Returns
    -------
    str
        ``"pass force=True (command line: --force)"`` -> ``"pass --force"``, ``"(ImuData.window; command
        line: --start / --end)"`` -> ``"(--start / --end)"``, ``"read_imu(format='csv') does not take
        option(s) ['topic']"`` -> ``"the csv reader does not take option(s) --topic"``.
    """
    msg = _KEYWORD_FLAG.sub(r"\1", msg)
    msg = _API_FLAG.sub(r"(\2)", msg)
    if _READER.search(msg):
        msg = _READER.sub(lambda m: f"the {m.group(2)} {'reader' if m.group(1) == 'read' else 'writer'}", msg)
        msg = _OPTION_LIST.sub(lambda m: f"{m.group(1)} {_flags(m.group(2))}", msg)
    return msg


def _message(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        where = f"{exc.filename}: " if exc.filename is not None else ""
        two = f" -> {exc.filename2}" if getattr(exc, "filename2", None) else ""
        return one_line(f"{where}{exc.strerror}{two}")
    msg = str(exc) or type(exc).__name__
    if isinstance(exc, ImunavError):
        msg = command_line_words(msg)
    if isinstance(exc, OSError) and exc.filename is not None and str(exc.filename) not in msg:
        msg = f"{exc.filename}: {msg}"
    return one_line(msg)


#: numba's message when no cache folder can be written (numba.core.caching._CacheImpl, stable since numba 0.22)
_NO_CACHE_LOCATOR = re.compile(r"cannot cache function '([^']*)': no locator available for file '([^']*)'")
_NUMBA_CACHING = os.path.join("numba", "core", "caching.py")
#: what to do when numba cannot write a cache file, by errno
_CACHE_FIX = {
    errno.EFBIG: "raise the file-size limit (ulimit -f unlimited), or compile the kernels once without it "
                 "(imunav warmup) so that later runs only read the cache",
    errno.ENOSPC: "free space there, or set NUMBA_CACHE_DIR to a folder on a disk with room",
    errno.EDQUOT: "free space there, or set NUMBA_CACHE_DIR to a folder on a disk with room",
}


def _user_cache_dir() -> str:
    """numba's user-wide cache folder (its fallback where the package's ``__pycache__`` cannot be written)."""
    # only called once numba itself raised: its caching module has loaded appdirs (no import here, so that the
    # command line's start stays free of numba)
    appdirs = sys.modules.get("numba.misc.appdirs")
    if appdirs is None:
        return os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "numba")
    return str(appdirs.AppDirs(appname="numba", appauthor=False).user_cache_dir)


def numba_cache_failure(exc: BaseException) -> OSError | None:
    """A failure of numba's on-disk cache of compiled kernels as a user error: which file or folder, and the fix.

    numba caches imunav's kernels (``@njit(cache=True)``) next to the sources, else in the user's cache folder,
    else in ``$NUMBA_CACHE_DIR``.  Where no folder can be written it raises a ``RuntimeError`` at import (an
    internal error for the command line), and a write the file system refuses (a file-size limit, a full disk)
    is an ``OSError`` without a file name ("File too large").

    Parameters
    ----------
    exc : BaseException
        The exception a command ended with.

    Returns
    -------
    OSError or None
        One line naming the cache file or the folders tried and how to fix it, with ``exc`` as its cause (shown
        by ``--debug``); None when ``exc`` did not come from numba's cache.
    """
    msg: str | None = None
    if isinstance(exc, RuntimeError):
        m = _NO_CACHE_LOCATOR.search(str(exc))
        if m is not None:
            src = Path(m.group(2))
            tried = [str(src.parent / "__pycache__"), _user_cache_dir()]
            if os.environ.get("NUMBA_CACHE_DIR"):
                tried.insert(0, f"NUMBA_CACHE_DIR={os.environ['NUMBA_CACHE_DIR']}")
            msg = (f"numba cannot cache imunav's compiled kernels (of {src}): none of its cache folders can be "
                   f"written ({', '.join(tried)}); set NUMBA_CACHE_DIR to a folder you may write "
                   "(e.g. export NUMBA_CACHE_DIR=/tmp/numba-cache)")
    elif isinstance(exc, OSError):
        path = None
        tb = exc.__traceback__
        while tb is not None:  # the innermost frame of numba's cache that names the file it was writing
            f = tb.tb_frame
            if f.f_code.co_filename.endswith(_NUMBA_CACHING):
                loc = f.f_locals
                named = next((loc[k] for k in ("filepath", "path") if isinstance(loc.get(k), str)), None)
                path = named or getattr(loc.get("self"), "_cache_path", None) or path
            tb = tb.tb_next
        if path is not None:
            why = exc.strerror or str(exc) or type(exc).__name__
            fix = _CACHE_FIX.get(exc.errno or 0, "set NUMBA_CACHE_DIR to a folder you may write "
                                                 "(e.g. export NUMBA_CACHE_DIR=/tmp/numba-cache)")
            msg = f"numba could not write its cache of imunav's compiled kernels, {path} ({why}): {fix}"
    if msg is None:
        return None
    out = OSError(msg)
    out.__cause__ = exc
    return out


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


def check_suffix(path: Path | None, option: str, suffixes: tuple[str, ...], what: str) -> None:
    """Refuse an output path whose suffix is not among ``suffixes`` (the file would not be what its name says)."""

    if path is not None and Path(path).suffix.lower() not in suffixes:
        raise InvalidInputError(f"{option} {path}: {what} is written as {' / '.join(suffixes)}, not "
                                f"{Path(path).suffix or '(no suffix)'!r}; give a file name ending in {suffixes[0]}")


def check_figure_path(path: Path | None, option: str) -> None:
    """Refuse a figure path whose suffix matplotlib cannot write."""
    check_suffix(path, option, _FIG_SUFFIXES, "a figure")


_showwarning = warnings.showwarning


def _show_warning(message: Any, category: Any, filename: str, lineno: int, file: Any = None, line: Any = None) -> None:
    """A user warning (:class:`imunav.errors.ImunavWarning` or any other ``UserWarning``) as one line on
    stderr, ``warning: <message>``; other categories keep Python's format."""
    if isinstance(category, type) and issubclass(category, UserWarning):
        typer.echo(f"warning: {one_line(str(message))}", err=True)
    else:
        _showwarning(message, category, filename, lineno, file, line)


def _completed(exc: BaseException) -> bool:
    """An exit that ends a command whose outputs are complete: status 0, or 1 (failing units, spec fails)."""
    exits = tuple(e for e in (typer.Exit, getattr(getattr(click, "exceptions", None), "Exit", None)) if e is not None)
    return isinstance(exc, exits) and getattr(exc, "exit_code", 0) in (0, 1)


def _special_file(flag: str, value: Any) -> None:
    """Refuse a path option that names a FIFO, a device or a socket (reading it could block forever), or a
    symbolic-link loop."""
    for v in (value if isinstance(value, (list, tuple)) else [value]):
        if not isinstance(v, (str, os.PathLike)):
            continue
        try:
            st = os.stat(v)
        except FileNotFoundError:
            continue
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise InvalidInputError(f"{flag} {v}: a loop of symbolic links, not a file; give the file itself") from None
            continue
        if stat.S_ISFIFO(st.st_mode) or stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) or stat.S_ISSOCK(st.st_mode):
            kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(st.st_mode) else
                    "a socket" if stat.S_ISSOCK(st.st_mode) else "a device")
            raise InvalidInputError(f"{flag} {v}: is {kind}, not a regular file; imunav reads and writes regular files "
                                    "only (copy the data to a file first)")


@functools.cache
def _force_option() -> Any:
    """The ``--force`` option added to commands with a limits estimator (built by typer, like every option)."""
    t = typer.Typer()

    @t.command()
    def _cmd(force: bool = typer.Option(False, "--force", help="Run even when the request's estimated memory or "
                                        "time is far beyond the machine (refused otherwise, with the estimate).")
             ) -> None:
        pass  # pragma: no cover

    return typer.main.get_command(t).params[0]


def install_checks(cmd: Any, path: str) -> Any:
    """Wrap the callback of ``cmd`` (and of every command below it) so that, before it runs, every numeric
    option is checked against its declared domain (:func:`imunav.cli._domains.check_params`), no path
    option names a FIFO, a device or a link loop, the outputs are checked against the inputs by their
    declared roles (:func:`imunav.cli._domains.check_paths`), and the request's estimated memory and time are within
    the machine (:func:`imunav.cli._limits.check_limits`; a ``--force`` option is added where the command
    has none).  Idempotent; returns ``cmd``."""
    if cmd is None or getattr(cmd, "_imunav_checked", False):
        return cmd
    cmd._imunav_checked = True
    subs = getattr(cmd, "commands", None)
    if subs is not None:
        for name in list(subs):
            install_checks(subs[name], f"{path} {name}".strip())
        return cmd
    callback = cmd.callback
    if callback is None:
        return cmd
    added_force = path in ESTIMATORS and not any(p.name == "force" for p in cmd.params)
    if added_force:
        cmd.params.append(_force_option())

    @functools.wraps(callback)
    def checked(*args: Any, **kwargs: Any) -> Any:
        check_params(path, cmd.params, kwargs)
        for p in cmd.params:
            if is_path(p) and kwargs.get(p.name) is not None:
                _special_file(flag_of(p), kwargs[p.name])
        check_paths(path, cmd.params, kwargs)
        check_limits(path, kwargs)
        if added_force:
            kwargs.pop("force", None)
        return callback(*args, **kwargs)

    cmd.callback = checked
    return cmd


class ImunavGroup(TyperGroup):
    """Root command group: the single place where exceptions become messages and exit codes."""

    def get_command(self, ctx: click.Context, cmd_name: str) -> Any:
        """The command, with the option checks of :func:`install_checks` installed."""
        return install_checks(super().get_command(ctx, cmd_name), cmd_name)

    def invoke(self, ctx: click.Context) -> Any:
        latch_interrupts()  # an interrupt swallowed in a callback from C is raised again before any output
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("default", ImunavWarning)
                warnings.showwarning = _show_warning
                with output_transaction(keep=_completed):
                    return super().invoke(ctx)
        except (*_PASS_THROUGH, KeyboardInterrupt, SystemExit):  # usage errors are reported by main()
            raise
        except (ImunavError, OSError) as exc:
            fail(numba_cache_failure(exc) or exc, ctx)
        except MemoryError as exc:  # the machine's limit, as a refused write is the file system's (e.g. --force)
            said = command_line_words(_message(exc))
            short = MemoryError(said if "out of memory" in said else f"out of memory ({said}); reduce the request")
            short.__cause__ = exc  # --debug shows where
            fail(short, ctx)
        except UnicodeDecodeError as exc:  # a text input (TOML, JSON, CSV) that is not text
            fail(ValueError(f"an input file is not UTF-8 text ({exc.reason} at byte {exc.start}); "
                            "check the file given for each option"), ctx)
        except Exception as exc:  # noqa: BLE001  (a bug: say how to report it)
            cache = numba_cache_failure(exc)  # numba finds no cache folder it may write: the machine's, not a bug
            if cache is not None:
                fail(cache, ctx)
            debug = _debug_wanted(ctx)
            if debug:
                traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
            typer.echo(
                f"internal error: {type(exc).__name__}: {_message(exc)} -- this is a bug in imunav; please report it "
                f"to {REPORT_TO} with the command line{'' if debug else ' and the output of the same command with --debug'}",
                err=True,
            )
            raise typer.Exit(1) from None

    def main(self, args: Any = None, prog_name: str | None = None, complete_var: str | None = None,
             standalone_mode: bool = True, **extra: Any) -> Any:
        """Run the command line; a usage error becomes one line on stderr and exit status 2."""
        try:
            rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var, standalone_mode=False,
                              **extra)
        except click.ClickException as exc:
            if not standalone_mode:
                raise
            sys.exit(_usage_error(exc))
        except _ABORTS:  # EOF at a prompt (Ctrl-C arrives as Exit(130))
            if not standalone_mode:
                raise
            typer.echo("error: aborted", err=True)
            sys.exit(1)
        if not standalone_mode:
            return rv
        # in non-standalone mode Click returns an Exit's code; commands themselves return None
        code = rv if isinstance(rv, int) and not isinstance(rv, bool) else 0
        if code == 130:  # Ctrl-C (SIGINT): typer turns the KeyboardInterrupt into Exit(130)
            typer.echo("error: interrupted; files being written were not completed (no run folder got its manifest)",
                       err=True)
        sys.exit(code)


def _command_path(ctx: Any) -> str:
    names = []
    while ctx is not None:
        if ctx.parent is not None and ctx.info_name:
            names.append(ctx.info_name)
        ctx = ctx.parent
    return " ".join(["imunav", *reversed(names)])


def _usage_error(exc: BaseException) -> int:
    """Print a Click exception (one line on stderr, or the help of a group called without a command)."""
    ctx = getattr(exc, "ctx", None)
    if type(exc).__name__ == "NoArgsIsHelpError" and ctx is not None:
        typer.echo(ctx.get_help())
        return 0
    msg = exc.format_message() if hasattr(exc, "format_message") else str(exc)
    hint = f" (see '{_command_path(ctx)} --help')" if ctx is not None else ""
    typer.echo(f"error: {one_line(msg)}{hint}", err=True)
    code = getattr(exc, "exit_code", 2)
    return code if isinstance(code, int) and code else 2
