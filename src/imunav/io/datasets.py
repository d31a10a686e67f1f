"""Locate the shared real-data folder (never vendored into the package).

The folder is found, in order, from the environment variable ``IMUNAV_DATA``
(the path of the ``shared/data`` folder), then ``../shared/data`` relative to
the project root (searched upward from the current directory and from this
file).  Callers that need a sub-folder get ``None`` when it is absent, so tests
can skip cleanly and commands can say what is missing.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["shared_data_dir", "shared_data_path"]


def shared_data_dir() -> Path | None:
    """Path of the shared data folder, or ``None`` if it cannot be found (module docstring).

    Returns
    -------
    pathlib.Path or None
        The folder.
    """
    env = os.environ.get("IMUNAV_DATA")
    if env:
        p = Path(env).expanduser()
        return p if p.is_dir() else None
    starts = [Path.cwd().resolve(), Path(__file__).resolve().parent]
    for start in starts:
        for d in (start, *start.parents):
            cand = d.parent / "shared" / "data"
            if (d / "pyproject.toml").is_file() and cand.is_dir():
                return cand
    return None


def shared_data_path(*parts: str) -> Path | None:
    """``shared_data_dir() / parts`` if it exists, else ``None``.

    Parameters
    ----------
    *parts : str
        Path components inside the data folder (e.g. ``"broad"``, ``"trial.mat"``).

    Returns
    -------
    pathlib.Path or None
        The existing path.
    """
    root = shared_data_dir()
    if root is None:
        return None
    p = root.joinpath(*parts)
    return p if p.exists() else None
