"""Provenance: what was done to a recording travels with it in ``ImuData.meta``.

Every operation that changes the values of a recording appends one step to
``meta["provenance"]`` (a list of plain JSON dicts, so every writer and reader
of :mod:`imunav.io` keeps it)::

    {"op": "compensate", "time": "2025-01-31T12:00:00+00:00", "imunav": "0.1.0",
     "parameters": {...}, "calibration": {"sha256": "...", "source": "cal.json"}}

Operations recorded: ``convert_units`` (non-SI units declared at the edge,
:meth:`imunav.timeseries.ImuData.from_arrays` and every reader),
``resample`` (:meth:`~imunav.timeseries.ImuData.resample`), ``compensate``
and ``uncompensate`` (:meth:`imunav.calib.ImuCalibration.apply` /
``invert``).

A second compensation with the same calibration (same parameter hash) is
refused (:class:`~imunav.errors.ProvenanceError`) unless forced: it would
apply the bias and scale corrections twice.  A compensation with a
*different* calibration on already compensated data is allowed with an
:class:`~imunav.errors.ImunavWarning`: it is right only for a residual
calibration estimated on the compensated data, which imunav cannot tell
apart from a mistake.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
from collections.abc import Mapping
from typing import Any

from imunav import __version__
from imunav.files import jsonable

__all__ = ["PROVENANCE_KEY", "add_step", "steps", "fingerprint", "net_compensations"]

#: Key of the step list in ``ImuData.meta``.
PROVENANCE_KEY = "provenance"


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def add_step(meta: Mapping[str, Any] | None, op: str, parameters: Mapping[str, Any] | None = None,
             **extra: Any) -> dict[str, Any]:
    """A copy of ``meta`` with one provenance step appended (``meta`` itself is not changed).

    Parameters
    ----------
    meta : mapping, optional
        The recording's metadata.
    op : str
        Operation name (``"compensate"``, ``"resample"``, ``"convert_units"``, ...).
    parameters : mapping, optional
        The operation's parameters (JSON types).
    **extra
        Further fields of the step (e.g. ``calibration={...}``).

    Returns
    -------
    dict
        The new metadata.
    """

    out = dict(meta or {})
    step = {"op": op, "time": _now(), "imunav": __version__, "parameters": jsonable(dict(parameters or {}))}
    step.update(jsonable(extra))
    out[PROVENANCE_KEY] = [*steps(out), step]
    return out


def steps(meta_or_data: Any, op: str | None = None) -> list[dict[str, Any]]:
    """The provenance steps of a recording (or of its ``meta`` dict), optionally only those of ``op``.

    Parameters
    ----------
    meta_or_data : ImuData or mapping
        A recording (its ``meta`` is read) or its metadata dict.
    op : str, optional
        Keep only the steps of this operation (e.g. ``"compensate"``).

    Returns
    -------
    list of dict
        Copies of the steps, oldest first; empty when there is no provenance.
    """
    meta = getattr(meta_or_data, "meta", meta_or_data)
    if not isinstance(meta, Mapping):
        return []
    raw = meta.get(PROVENANCE_KEY) or []
    found = [s for s in raw if isinstance(s, Mapping)] if isinstance(raw, list) else []
    return [dict(s) for s in found if op is None or s.get("op") == op]


def fingerprint(obj: Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON of ``obj`` (sorted keys, no blanks): equal content, equal hash.

    Parameters
    ----------
    obj : mapping
        JSON-like content (numpy values are converted first).

    Returns
    -------
    str
        The SHA-256 hash (FIPS 180-4) as 64 hexadecimal characters.
    """

    text = json.dumps(jsonable(obj), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def net_compensations(meta_or_data: Any, sha256: str | None = None) -> list[dict[str, Any]]:
    """Compensation steps not undone by a later ``uncompensate`` with the same calibration.

    Parameters
    ----------
    meta_or_data : ImuData or mapping
        A recording (its ``meta`` is read) or its metadata dict.
    sha256 : str, optional
        Keep only the steps of the calibration with this fingerprint (:func:`fingerprint`).

    Returns
    -------
    list of dict
        The ``compensate`` steps still in effect, oldest first.
    """
    live: list[dict[str, Any]] = []
    for s in steps(meta_or_data):
        h = (s.get("calibration") or {}).get("sha256")
        if s.get("op") == "compensate":
            live.append(s)
        elif s.get("op") == "uncompensate":
            for k in range(len(live) - 1, -1, -1):
                if (live[k].get("calibration") or {}).get("sha256") == h:
                    del live[k]
                    break
    return [s for s in live if sha256 is None or (s.get("calibration") or {}).get("sha256") == sha256]
