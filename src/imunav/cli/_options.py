"""The reader options that several commands build from their flags (one place, not one per command)."""

from __future__ import annotations

from typing import Any


def reader_options(*, units: dict[str, str] | None = None, scales: dict[str, float] | None = None,
                   fs: float | None = None, skiprows: int | None = None, columns: Any = None,
                   **extra: Any) -> dict[str, Any]:
    """Keyword options for :func:`imunav.io.read_imu`, leaving out what the user did not give.

    ``units`` / ``scales`` are per-group dicts already filtered by the caller; empty ones and ``None``
    values are dropped so that the reader's own defaults apply.
    """
    opts: dict[str, Any] = dict(extra)
    if units:
        opts["units"] = units
    if scales:
        opts["scales"] = scales
    if fs is not None:
        opts["fs"] = fs
    if skiprows is not None:
        opts["skiprows"] = skiprows
    if columns:
        opts["columns"] = columns
    return opts
