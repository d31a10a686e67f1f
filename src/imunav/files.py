"""Atomic file writing: write a temporary file next to the target, then rename.

A reader never sees a half-written file: the data go to a temporary file in
the *same directory* (so that :func:`os.replace` is an atomic rename on the
same file system) and replace the target only once they are complete.  On any
error the temporary file is removed and the target is left untouched.

Two more guarantees are kept here, in the one place every writer goes through:

* **All or nothing** (:func:`output_transaction`).  Inside a transaction (the
  ``imunav`` command runs each command in one) a completed temporary file is
  not renamed at once: every output is moved in when the whole command has
  succeeded, and on any failure the temporary files and the folders created
  for them are removed, so a failed command leaves nothing new behind.
* **Run folders own what they wrote** (:func:`claim_run_file`).  A file
  written inside a run folder that is being written (:mod:`imunav.lab.runfolder`:
  a hidden marker ``.imunav-run.json`` of this process or its parent) is
  recorded in the run's file log ``.imunav-run.files`` before it appears, so
  that a killed run's folder says which files are the run's and which are
  not.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import errno
import json
import math
import os
import signal
import sys
import tempfile
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, InvalidInputError

__all__ = ["RUN_FILES", "RUN_MARKER", "atomic_path", "check_interrupt", "check_outputs", "check_writable",
           "claim_run_file", "json_text", "jsonable", "latch_interrupts", "output_transaction", "read_json",
           "write_json"]

#: The hidden marker of a run folder being written (:mod:`imunav.lab.runfolder`).
RUN_MARKER = ".imunav-run.json"
#: The run's file log: one relative path per line, appended before each file appears.
RUN_FILES = ".imunav-run.files"
_RUN_DEPTH = 8  # how many folders up a run folder is looked for


def _run_root(target: Path) -> Path | None:
    """The run folder being written by this process (or its parent) that holds ``target``, if any."""
    for parent in list(target.parents)[:_RUN_DEPTH]:
        mk = parent / RUN_MARKER
        if mk.is_file():
            try:
                d = json.loads(mk.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                return None
            if isinstance(d, dict) and d.get("pid") in (os.getpid(), os.getppid()) and not d.get("failed"):
                return parent
            return None
    return None


def claim_run_file(path: str | os.PathLike[str]) -> Path | None:
    """Record ``path`` in the file log of the run folder being written that holds it.

    Called before the file appears (by :func:`atomic_path`, and by
    :meth:`imunav.lab.steps.LabContext.path`), so that a killed run's folder
    lists every file the run may have written.  Lines are appended with one
    ``write`` on a file opened for appending, safe across worker processes.

    Parameters
    ----------
    path : str or os.PathLike
        A file about to be written.

    Returns
    -------
    pathlib.Path or None
        The run folder, or None when ``path`` is not inside a run folder being written.
    """
    target = Path(os.path.abspath(path))
    root = _run_root(target)
    if root is not None:
        rel = target.relative_to(root).as_posix()
        fd = os.open(root / RUN_FILES, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, (json.dumps(rel) + "\n").encode("utf-8"))
        finally:
            os.close(fd)
    return root


_INTERRUPT = {"pending": False, "seen": False}


def _on_sigint(signum: int, frame: Any) -> None:
    _INTERRUPT["pending"] = True
    _INTERRUPT["seen"] = True
    signal.default_int_handler(signum, frame)


def _unraisable(hook: Callable[[Any], None]) -> Callable[[Any], None]:
    def unraisable(u: Any) -> None:
        if isinstance(u.exc_value, KeyboardInterrupt):
            _INTERRUPT["pending"] = True  # swallowed where it was raised: latched, raised again at the next check
            return
        if _INTERRUPT["seen"]:
            # the aftermath of an interrupt that landed inside a constructor from C (llvmlite's PassBuilder,
            # whose finaliser then meets a half-built object): the run is ending with its one-line message
            return
        hook(u)

    unraisable._imunav_latch = True  # type: ignore[attr-defined]
    return unraisable


def latch_interrupts() -> None:
    """Make an interrupt (SIGINT, Ctrl-C) impossible to lose for the rest of the process.

    Python raises :class:`KeyboardInterrupt` wherever the main thread is; raised inside a callback from C (a
    ctypes callback of the numba compiler, a finaliser) it is printed as "Exception ignored" and the program
    goes on as if nothing happened.  After this call the interrupt is also latched, and :func:`check_interrupt`
    (called before every output is published, before a transaction commits and before a run folder gets its
    manifest) raises it again; an interrupt swallowed that way prints nothing.  Called by the ``imunav`` command
    (main thread only; idempotent).
    """
    if threading.current_thread() is not threading.main_thread():
        return
    _INTERRUPT["pending"] = False
    _INTERRUPT["seen"] = False
    if signal.getsignal(signal.SIGINT) is not _on_sigint:
        signal.signal(signal.SIGINT, _on_sigint)
    if not getattr(sys.unraisablehook, "_imunav_latch", False):  # a hook set since (a test, an embedding program)
        sys.unraisablehook = _unraisable(sys.unraisablehook)


def check_interrupt() -> None:
    """Raise :class:`KeyboardInterrupt` if an interrupt arrived and was swallowed (see :func:`latch_interrupts`).

    Raises
    ------
    KeyboardInterrupt
        When an interrupt is pending (it is delivered once: the latch is cleared).
    """
    if _INTERRUPT["pending"]:
        _INTERRUPT["pending"] = False
        raise KeyboardInterrupt


class _Transaction:
    """The outputs of one command: completed temporary files waiting for the command to succeed."""

    def __init__(self) -> None:
        self.pending: list[tuple[Path, Path]] = []  # (temporary file, target)
        self.made: list[Path] = []  # folders created for the outputs, outermost first

    def mkdirs(self, directory: Path) -> None:
        missing = [d for d in (directory, *directory.parents) if not d.exists()]
        directory.mkdir(parents=True, exist_ok=True)
        self.made += list(reversed(missing))

    def commit(self) -> None:
        check_interrupt()
        for tmp, target in self.pending:
            os.replace(tmp, target)
        self.pending.clear()
        self.made.clear()

    def abort(self) -> None:
        for tmp, _target in self.pending:
            with contextlib.suppress(OSError):
                tmp.unlink()
        self.pending.clear()
        for d in reversed(self.made):
            with contextlib.suppress(OSError):
                d.rmdir()  # only when empty
        self.made.clear()


_TRANSACTION: contextvars.ContextVar[_Transaction | None] = contextvars.ContextVar("imunav_outputs", default=None)


@contextlib.contextmanager
def output_transaction(keep: Callable[[BaseException], bool] | None = None) -> Iterator[None]:
    """All or nothing for the outputs written inside the block (see the module docstring).

    Every :func:`atomic_path` write inside the block is kept as a completed temporary file beside its
    target and moved in when the block ends without an exception; on an exception (or an interrupt) the
    temporary files, and the folders created for them, are removed.  Files inside a run folder being
    written are not deferred (the run folder has its own all-or-nothing rule, :mod:`imunav.lab.runfolder`).
    Nested blocks join the outermost one.

    Parameters
    ----------
    keep : callable, optional
        ``keep(exc)`` True for an exception that ends a command that did complete (e.g. an exit status that
        reports failing units after every output was written): the outputs are moved in, then it propagates.

    Yields
    ------
    None
        The block runs inside the transaction.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with output_transaction():
    ...     _ = write_json(d / "a.json", {"a": 1})
    ...     (d / "a.json").exists()
    False
    >>> (d / "a.json").exists()
    True
    """
    if _TRANSACTION.get() is not None:
        yield
        return
    tr = _Transaction()
    token = _TRANSACTION.set(tr)
    try:
        yield
    except BaseException as exc:
        if keep is not None and keep(exc):
            tr.commit()
        else:
            tr.abort()
        raise
    else:
        try:
            tr.commit()
        except BaseException:
            tr.abort()
            raise
    finally:
        _TRANSACTION.reset(token)


def _output_target(path: str | os.PathLike[str]) -> tuple[Path, Path, Path | None]:
    """(target, its folder, the nearest existing ancestor folder or None); raises an OSError naming the target
    when the target is a folder or an existing ancestor is a file."""
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, "the output is a folder; give a file name", str(target))
    directory = target.parent if str(target.parent) else Path(".")
    for parent in (directory, *directory.parents):
        if parent.exists():
            if not parent.is_dir():
                raise NotADirectoryError(errno.ENOTDIR, f"cannot write the output: {parent} is a file, not a folder",
                                         str(target))
            return target, directory, parent
    return target, directory, None


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    The temporary name keeps the target's suffix, so libraries that look at
    the extension (numpy, scipy, pyarrow) behave as for the final name.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (its folder is created).

    Yields
    ------
    pathlib.Path
        The temporary file to write; on an error it is removed and ``path`` is left untouched.

    Raises
    ------
    OSError
        If the folder cannot be created or written, naming ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_path(d / "x.txt") as tmp:
    ...     _ = tmp.write_text("hello")
    >>> (d / "x.txt").read_text()
    'hello'
    """
    target, directory, _ = _output_target(path)
    tr = _TRANSACTION.get()
    try:
        if tr is not None:
            tr.mkdirs(directory)
        else:
            directory.mkdir(parents=True, exist_ok=True)
        run = claim_run_file(target)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{target.suffix}", dir=directory)
    except OSError as exc:
        # Name the target, not the temporary file, in the message.
        raise type(exc)(exc.errno, f"cannot write the output ({exc.strerror})", str(target)) from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        # mkstemp creates the file 0600; give it the usual umask-based mode.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        yield tmp
        # Make sure the bytes are on disk before the rename publishes them.
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        check_interrupt()
        if tr is not None and run is None:
            tr.pending.append((tmp, target))  # moved in when the whole command has succeeded
        else:
            os.replace(tmp, target)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if exc.filename is None or str(exc.filename) == str(tmp):
            # "File too large", "No space left on device" ...: name the output, not the temporary file
            raise type(exc)(exc.errno, f"cannot write the output ({exc.strerror or exc})", str(target)) from None
        raise
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def jsonable(obj: Any) -> Any:
    """``obj`` as plain JSON types, with ``None`` (JSON null) for NaN / ±inf.

    NumPy arrays and scalars become lists and numbers, objects with a
    ``to_dict()`` method their dictionary, other dataclasses a dictionary of
    their fields, paths and anything else their text.  This is the one JSON
    conversion of the package: :class:`imunav.results.Result` and
    :func:`write_json` use it.

    Parameters
    ----------
    obj : object
        Any value: None, bool, str, number, mapping, sequence, set, NumPy array or scalar, object
        with ``to_dict()``, dataclass instance, or anything with a text form.

    Returns
    -------
    object
        ``None``, bool, int, float (finite), str, list or dict (string keys), nested, that
        :func:`json.dumps` writes with ``allow_nan=False``; complex numbers become their text.
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return jsonable(float(obj))
    if isinstance(obj, np.complexfloating):
        return str(obj)
    if hasattr(obj, "to_dict") and callable(obj.to_dict):
        return jsonable(obj.to_dict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    return str(obj)


def json_text(obj: Any, indent: int | None = 2) -> str:
    """Standard JSON text of ``obj`` (no ``NaN`` / ``Infinity`` tokens: those are null).

    Parameters
    ----------
    obj : object
        Any value :func:`jsonable` converts.
    indent : int or None, optional
        Indentation (None: one line).

    Returns
    -------
    str
        The JSON text, ending with a newline.
    """
    return json.dumps(jsonable(obj), indent=indent, allow_nan=False) + "\n"


def write_json(path: str | os.PathLike[str], obj: Any, indent: int | None = 2) -> Path:
    """Write ``obj`` as standard JSON (see :func:`json_text`) to ``path`` atomically.

    Every JSON file the command line writes goes through here.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    obj : object
        Any value :func:`jsonable` converts.
    indent : int or None, optional
        Indentation (None: one line).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    text = json_text(obj, indent)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def read_json(path: str | os.PathLike[str], what: str = "JSON file") -> Any:
    """Load a JSON file; a syntax error becomes a :class:`~imunav.errors.FileFormatError` naming the file.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str, optional
        What the file is, for the error message.

    Returns
    -------
    object
        The parsed JSON.

    Raises
    ------
    FileFormatError
        If the file is not valid JSON.
    """

    text = Path(path).read_text(encoding="utf-8")
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{path}: not a valid {what} ({exc.msg} at line {exc.lineno}, column {exc.colno}); "
                              "fix or regenerate the file") from None


def check_writable(path: str | os.PathLike[str]) -> None:
    """Raise an :class:`OSError` naming ``path`` if a file cannot be written there.

    Checked before any work is done: the path is not a folder, no existing
    ancestor is a file, and a file can be created in the nearest existing
    ancestor folder (a probe file, removed at once).

    Parameters
    ----------
    path : str or os.PathLike
        The output file.

    Raises
    ------
    OSError
        If a file cannot be written there.
    """
    target, _, parent = _output_target(path)
    if parent is None:
        return
    try:
        with tempfile.TemporaryFile(dir=parent):
            pass
    except OSError as exc:
        raise type(exc)(exc.errno, f"cannot write the output in {parent} ({exc.strerror})", str(target)) from None


def _key(p: str | os.PathLike[str]) -> Path:
    return Path(p).expanduser().resolve()


def _within(inner: Path, outer: Path) -> bool:
    return inner == outer or outer in inner.parents


def check_outputs(inputs: Iterable[str | os.PathLike[str] | None],
                  outputs: Iterable[str | os.PathLike[str] | None], *,
                  folders: Iterable[str | os.PathLike[str] | None] = (),
                  run_folders: Iterable[str | os.PathLike[str] | None] = (), inputs_exist: bool = True) -> None:
    """The one check of a command's outputs against its inputs, done before any work.

    No output may equal, contain or sit inside an input of the same command, and no two outputs may be
    the same file or sit inside each other:

    * an output file may not be an input file, nor a file inside an input folder, nor be inside an input
      file (a path whose parent is a file);
    * an output folder (``folders``: report folders; ``run_folders``: run folders, :mod:`imunav.lab.runfolder`)
      may not be an input, nor hold an input file or folder;
    * no output (file, report folder or run folder) may sit inside another output of the same command:
      a report folder's ``report.json`` would overwrite an ``--out`` given inside it, a run would list
      the file as its own (or ``--overwrite`` would remove it);
    * each output file must be writable (:func:`check_writable`);
    * (``inputs_exist``) every input given exists: a missing input is refused before any work, even one
      the command would read last or not at all with the other options.

    Parameters
    ----------
    inputs : iterable of str or os.PathLike or None
        The files and folders the command reads (None entries skipped).
    outputs : iterable of str or os.PathLike or None
        The files it writes (None entries skipped).
    folders : iterable of str or os.PathLike or None
        The folders it writes files into.
    run_folders : iterable of str or os.PathLike or None
        The run folders it writes.
    inputs_exist : bool
        Refuse an input that does not exist (False for a command that looks a missing input up elsewhere).

    Raises
    ------
    InvalidInputError
        Naming both paths, when an output would replace or hold an input, or two outputs are the same.
    OSError
        When an output cannot be written there (a folder where a file is expected, a parent that is a file).
    """
    outs = [o for o in outputs if o is not None]
    dirs = [d for d in folders if d is not None]
    runs = [d for d in run_folders if d is not None]
    kinds = [*(("output", o) for o in outs), *(("output folder", d) for d in dirs), *(("run folder", d) for d in runs)]
    keys = [_key(o) for _, o in kinds]
    for i, (kind_i, o) in enumerate(kinds):
        for j in range(i):
            kind_j, p = kinds[j]
            if keys[i] == keys[j]:
                raise InvalidInputError(f"two outputs are the same path ({p} and {o}); give each its own path")
            inner, outer = ((kind_i, o), (kind_j, p)) if _within(keys[i], keys[j]) else \
                ((kind_j, p), (kind_i, o)) if _within(keys[j], keys[i]) else (None, None)
            if inner is not None and outer is not None:
                if outer[0] == "output":
                    raise NotADirectoryError(errno.ENOTDIR, f"cannot write the {inner[0]}: {outer[1]} is another output "
                                             "of the same command, a file, not a folder", str(inner[1]))
                raise InvalidInputError(f"{inner[0]} {inner[1]} is inside the {outer[0]} {outer[1]} that the same "
                                        "command writes (one would overwrite or list the other); choose a path "
                                        "outside it")
    ins: list[tuple[Path, str | os.PathLike[str]]] = []
    for p in inputs:
        if p is not None:
            ins.append((_key(p), p))
            if inputs_exist and not os.path.lexists(p):
                raise FileNotFoundError(errno.ENOENT, "does not exist (no such file or folder)", str(p))
    for o in outs:
        k = _key(o)
        for ik, p in ins:
            if k == ik:
                raise InvalidInputError(f"output {o} is the input file {p}: writing it would destroy the input; "
                                        "choose another output path")
            if ik.is_dir() and ik in k.parents and k.exists():
                raise InvalidInputError(f"output {o} is a file of the input folder {p}: writing it would replace "
                                        "an input; choose a path outside that folder")
    for d in [*dirs, *runs]:
        dk = _key(d)
        held = [p for ik, p in ins if _within(ik, dk)]
        if held:
            what = "is the input" if any(_key(p) == dk for p in held) else \
                f"holds the input{'s' if len(held) > 1 else ''}"
            raise InvalidInputError(f"the output folder {d} {what} {', '.join(map(str, held[:6]))}: writing it could "
                                    "replace an input; choose another output folder")
    for o in outs:
        check_writable(o)
    for d in [*dirs, *runs]:
        dk = _key(d)
        if dk.exists() and not dk.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "the output folder is a file; give a folder", str(d))
        for a in dk.parents:
            if a.exists():
                if not a.is_dir():
                    raise NotADirectoryError(errno.ENOTDIR, f"cannot write the output folder: {a} is a file, "
                                             "not a folder", str(d))
                break
