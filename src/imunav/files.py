"""Atomic file writing: write a temporary file next to the target, then rename.

A reader never sees a half-written file: the data go to a temporary file in
the *same directory* (so that :func:`os.replace` is an atomic rename on the
same file system) and replace the target only once they are complete.  On any
error the temporary file is removed and the target is left untouched.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import json
import math
import os
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, InvalidInputError

__all__ = ["atomic_path", "check_outputs", "check_writable", "json_text", "jsonable", "read_json", "write_json"]


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
    try:
        directory.mkdir(parents=True, exist_ok=True)
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
        os.replace(tmp, target)
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


def check_outputs(inputs: Iterable[str | os.PathLike[str] | None],
                  outputs: Iterable[str | os.PathLike[str] | None]) -> None:
    """Refuse an output path that resolves to an input file (it would replace the input),
    and two outputs that resolve to the same file.

    ``None`` entries are skipped.  Each output is also checked with :func:`check_writable`.

    Parameters
    ----------
    inputs : iterable of str, os.PathLike or None
        The files a command reads.
    outputs : iterable of str, os.PathLike or None
        The files it writes.

    Raises
    ------
    InvalidInputError
        If an output is an input file, or two outputs are the same file.
    OSError
        If an output cannot be written.
    """

    def key(p: str | os.PathLike[str]) -> Path:
        return Path(p).expanduser().resolve()

    seen: dict[Path, str | os.PathLike[str]] = {}
    outputs = list(outputs)
    for o in outputs:
        if o is None:
            continue
        k = key(o)
        if k in seen:
            raise InvalidInputError(f"two outputs are the same file ({seen[k]} and {o}); give each its own path")
        seen[k] = o
    for o in outputs:
        if o is not None:
            check_writable(o)
    ins = {}
    for p in inputs:
        if p is not None:
            ins.setdefault(key(p), p)
    for o in outputs:
        if o is None:
            continue
        k = key(o)
        if k in ins:
            raise InvalidInputError(f"output {o} is the input file {ins[k]}: writing it would destroy the input; "
                                    "choose another output path")
