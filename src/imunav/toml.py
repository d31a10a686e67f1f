"""TOML configurations: the one reader (:func:`read_toml`) and the writer beside :mod:`tomllib`, which only reads.

Tables of strings, numbers (``inf`` kept), booleans and arrays, nested tables as
``[a.b]`` sections; what :func:`tomllib.loads` reads back to the same dict.
Written by hand: no TOML-writing dependency.

Examples
--------
>>> import tomllib
>>> d = {"name": "imu", "rate": 100.0, "gyro": {"bias": [0.1, 0.0, -0.2]}}
>>> tomllib.loads(toml_text(d)) == d
True
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import ConfigError

__all__ = ["read_toml", "toml_text"]


def read_toml(path: str | os.PathLike[str], what: str = "configuration",
              missing: type[Exception] = ConfigError) -> dict[str, Any]:
    """Read a TOML file, with the one pair of messages every imunav TOML reader gives.

    Parameters
    ----------
    path : str or os.PathLike
        The file (UTF-8).
    what : str
        What the file is, for the message when it is missing (e.g. ``"lab configuration"``).
    missing : type of Exception
        The exception raised when the file does not exist (default :class:`~imunav.errors.ConfigError`;
        readers whose contract is :class:`FileNotFoundError` or
        :class:`~imunav.errors.FileFormatError` pass theirs).

    Returns
    -------
    dict
        The document.

    Raises
    ------
    ConfigError
        If the file is not valid TOML or not UTF-8 text (the message names the file and the reason).
    Exception
        ``missing``, if the file does not exist: ``"<what> file not found: <path>"``.
    """
    p = Path(path)
    if not p.is_file():
        raise missing(f"{what} file not found: {p}")
    try:
        return tomllib.loads(p.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{p}: not valid TOML ({exc})") from None


def toml_text(d: Mapping[str, Any]) -> str:
    """TOML text of ``d`` (see the module docstring).

    Parameters
    ----------
    d : mapping
        Keys to values (str, int, float, bool, numpy scalars and arrays, lists of them) or to nested mappings
        (tables).

    Returns
    -------
    str
        The TOML document, ending with a newline.

    Raises
    ------
    TypeError
        For a value TOML cannot hold (e.g. None, which TOML has no word for), naming its key.
    """
    return _to_toml(d)


def _toml_value(v: Any) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    elif isinstance(v, np.generic):
        v = v.item()  # numpy scalars (np.int64, np.float64, np.bool_) as the Python value they hold
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        f = float(v)
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(f) if isinstance(v, float) else str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def _key_value(k: str, v: Any, prefix: str) -> str:
    try:
        return f"{k} = {_toml_value(v)}"
    except TypeError as exc:  # name the key: TOML has no null, a None must be left out by the caller
        raise TypeError(f"{prefix + '.' if prefix else ''}{k}: {exc}") from None


def _to_toml(d: Mapping[str, Any], prefix: str = "") -> str:
    lines = [_key_value(k, v, prefix) for k, v in d.items() if not isinstance(v, Mapping)]
    out = "\n".join(lines)
    for k, v in d.items():
        if isinstance(v, Mapping):
            name = f"{prefix}.{k}" if prefix else k
            out += f"\n\n[{name}]\n" + _to_toml(v, name)
    return out.strip() + "\n"
