"""The reader options that several commands build from their flags (one place, not one per command).

The ``typer`` options shared by every command that reads a recording from a bag, a PX4 log or a named
CSV layout are defined here once (:data:`TOPIC`, :data:`INSTANCE`, :data:`MAG_TOPIC`, :data:`LAYOUT`).
"""

from __future__ import annotations

from typing import Any

import typer

from imunav.cli._lazy import lazy

io = lazy("imunav.io")
logs = lazy("imunav.io.logs")

#: ``--topic``: the topic of a ROS bag or PX4 ULog.
TOPIC = typer.Option(None, "--topic", help="ROS bag / PX4 ULog: the IMU topic (`imunav info FILE` lists them).")
#: ``--instance``: the PX4 multi_id of the topic.
INSTANCE = typer.Option(None, "--instance", help="PX4 ULog: the instance (multi_id) of --topic.")
#: ``--mag-topic``: a magnetometer topic merged onto the IMU stamps.
MAG_TOPIC = typer.Option(None, "--mag-topic", help="ROS bag / PX4 ULog: magnetometer topic, interpolated onto the "
                         "IMU stamps (PX4: name or name:instance).")
#: ``--layout``: a named CSV layout.
LAYOUT = typer.Option(None, "--layout", help="Named CSV layout: euroc, tum-vi, kalibr, px4-csv or xio.")


def reader_options(*, units: dict[str, str] | None = None, scales: dict[str, float] | None = None,
                   fs: float | None = None, skiprows: int | None = None, columns: Any = None,
                   topic: str | None = None, instance: int | None = None, mag_topic: str | None = None,
                   layout: str | None = None, **extra: Any) -> dict[str, Any]:
    """Keyword options for :func:`imunav.io.read_imu`, leaving out what the user did not give.

    ``units`` / ``scales`` are per-group dicts already filtered by the caller; empty ones and ``None``
    values are dropped so that the reader's own defaults apply.  ``topic`` / ``instance`` /
    ``mag_topic`` are for bags and ULogs, ``layout`` for CSV files; the reader refuses an option that
    does not fit the file, naming it.
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
    for k, v in (("topic", topic), ("instance", instance), ("mag_topic", mag_topic), ("layout", layout)):
        if v is not None:
            opts[k] = v
    return opts


# ---------------------------------------------------------------- time window (issue 26: first hour)
#: ``--start``: start of the window, s from the recording's first sample.
START = typer.Option(None, "--start", help="Analyse from this many seconds after the recording's first sample.")
#: ``--end``: end of the window, s from the recording's first sample.
END = typer.Option(None, "--end", help="Analyse up to this many seconds after the recording's first sample.")


def window(data: Any, start: float | None, end: float | None) -> Any:
    """``data`` cut to ``--start`` / ``--end`` (:meth:`imunav.timeseries.ImuData.window`), or ``data`` itself."""
    if start is None and end is None:
        return data
    return data.window(start, end)


def read_recording(path: Any, **opts: Any) -> Any:
    """:func:`imunav.io.read_imu` of ``path`` with the options of :func:`reader_options`; a ROS bag or PX4 ULog
    (without ``layout``) read by :func:`imunav.io.logs.read_log_imu`, which is what ``read_imu`` calls for them,
    so that the readers of the other formats, and with them pandas and scipy.io, are not loaded (0.5-0.9 s of a
    first ``imunav attitude run`` on a PX4 log; issue 35).

    Parameters
    ----------
    path : path-like
        The recording.
    **opts
        Reader options (:func:`reader_options`).

    Returns
    -------
    imunav.timeseries.ImuData
        The recording, as :func:`imunav.io.read_imu` gives it.
    """
    if "layout" not in opts and logs.log_kind(path) is not None:
        return logs.read_log_imu(path, **opts)
    return io.read_imu(path, **opts)
