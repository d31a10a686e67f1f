"""TOML text of a configuration: the writer beside :mod:`tomllib`, which only reads.

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
from collections.abc import Mapping
from typing import Any

__all__ = ["toml_text"]


def toml_text(d: Mapping[str, Any]) -> str:
    """TOML text of ``d`` (see the module docstring).

    Parameters
    ----------
    d : mapping
        Keys to values (str, int, float, bool, lists of them) or to nested mappings (tables).

    Returns
    -------
    str
        The TOML document, ending with a newline.

    Raises
    ------
    TypeError
        For a value TOML cannot hold (e.g. None).
    """
    return _to_toml(d)


def _toml_value(v: Any) -> str:
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


def _to_toml(d: Mapping[str, Any], prefix: str = "") -> str:
    lines = [f"{k} = {_toml_value(v)}" for k, v in d.items() if not isinstance(v, Mapping)]
    out = "\n".join(lines)
    for k, v in d.items():
        if isinstance(v, Mapping):
            name = f"{prefix}.{k}" if prefix else k
            out += f"\n\n[{name}]\n" + _to_toml(v, name)
    return out.strip() + "\n"
