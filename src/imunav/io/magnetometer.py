"""Magnetometer samples for a hard- / soft-iron calibration, from a table or a robotics log.

What ``imunav calibrate mag`` reads (:func:`read_mag_samples`):

* a ROS bag or PX4 ULog (recognised by content, :func:`imunav.io.logs.log_kind`): the magnetometer topic named by
  ``topic`` (µT, FRD, converted by the log readers);
* an ``.npz``: the first of the arrays ``mag``, ``h``, ``m`` (N, 3);
* otherwise a CSV with a header (``#`` comments): the columns ``mag_x, mag_y, mag_z`` (or ``mx, my, mz``,
  ``hx, hy, hz``; case and underscores ignored), in the file's unit.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from imunav.errors import FileFormatError, InvalidInputError
from imunav.io._common import check_nonempty, wrap_read_errors
from imunav.io.logs import log_kind, read_topic

__all__ = ["read_mag_samples"]

#: Column triples of a magnetometer CSV (lower case, underscores removed), in the order they are looked for.
MAG_COLUMNS = (("magx", "magy", "magz"), ("mx", "my", "mz"), ("hx", "hy", "hz"))


def read_mag_samples(path: str | os.PathLike[str], *, topic: str | None = None,
                     instance: int | None = None) -> NDArray[np.float64]:
    """Read magnetometer samples: a log's magnetometer topic, an ``.npz`` array or CSV columns.

    Parameters
    ----------
    path : str or os.PathLike
        A ROS bag / PX4 ULog, an ``.npz`` or a CSV (see the module docstring).
    topic : str, optional
        The magnetometer topic of a log (required for one; ``imunav info LOG`` lists them).
    instance : int, optional
        Instance of a multi-instance ULog topic.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        The samples, in the file's unit (µT from a log).

    Raises
    ------
    InvalidInputError
        If a log is given without ``topic``, the topic is not a magnetometer, or ``topic`` / ``instance`` are given
        for a table.
    FileFormatError
        If the file is empty, unreadable, or has no magnetometer array / columns.
    FileNotFoundError
        If the file does not exist.
    """
    p = Path(path)
    if p.exists() and log_kind(p) is not None:
        if topic is None:
            raise InvalidInputError(f"{p}: name the magnetometer topic with --topic (`imunav info {p}` lists them)")
        d = read_topic(p, topic, instance=instance)
        if "mag" not in d.values:
            raise InvalidInputError(f"{p}: topic {topic!r} is a {d.kind} topic, not a magnetometer")
        return np.asarray(d.values["mag"], float)
    if topic is not None or instance is not None:
        raise InvalidInputError(f"{p}: --topic / --instance apply to ROS bags and PX4 ULogs only")

    check_nonempty(p)
    if p.suffix == ".npz":
        with wrap_read_errors(str(p), "NPZ"), open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            for k in ("mag", "h", "m"):
                if k in z:
                    return np.asarray(z[k], float)
            names = list(z.files)
        raise FileFormatError(f"{p}: no 'mag' array (found {names})")

    df = pd.read_csv(p, comment="#")
    low = {c.lower().replace("_", ""): c for c in df.columns}
    for names in MAG_COLUMNS:
        if all(n in low for n in names):
            return df[[low[n] for n in names]].to_numpy(float)
    raise FileFormatError(f"{p}: needs columns mag_x, mag_y, mag_z (or mx, my, mz); found {list(df.columns)}")
