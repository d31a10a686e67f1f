"""pandas DataFrames <-> :class:`~imunav.timeseries.ImuData`.

One column per channel (``t, gyro_x ... temp``, the names of
:data:`imunav.io.csv.DEFAULT_NAMES`), SI; ``mag_unit`` and ``meta`` travel in
``DataFrame.attrs``.  Columns are found, and units, scales and offsets
declared, exactly as for a CSV file (:func:`imunav.io.csv.read_csv`).

Examples
--------
>>> import numpy as np
>>> from imunav.timeseries import ImuData
>>> d = ImuData(np.arange(3) / 100, np.zeros((3, 3)), np.tile([0, 0, -9.81], (3, 1)))
>>> df = to_dataframe(d)
>>> list(df.columns)[:4], from_dataframe(df).n
(['t', 'gyro_x', 'gyro_y', 'gyro_z'], 3)
"""

from __future__ import annotations

from typing import Any

import pandas as pd

from imunav.io._common import build_imu
from imunav.io.csv import imu_to_table, resolve_columns, table_to_arrays
from imunav.timeseries import ImuData, NanPolicy

__all__ = ["to_dataframe", "from_dataframe"]


def to_dataframe(data: ImuData) -> pd.DataFrame:
    """A recording as a pandas DataFrame, one column per channel (``t, gyro_x ... temp``), SI.

    Parameters
    ----------
    data : ImuData
        The recording.

    Returns
    -------
    pandas.DataFrame
        ``attrs["mag_unit"]`` and ``attrs["meta"]`` carry the magnetometer unit and the metadata.
    """
    names, block = imu_to_table(data)
    df = pd.DataFrame(block, columns=names)
    df.attrs["mag_unit"] = data.mag_unit
    df.attrs["meta"] = dict(data.meta)
    return df


def from_dataframe(
    df: pd.DataFrame,
    *,
    columns: dict[str, Any] | None = None,
    units: dict[str, str] | None = None,
    scales: dict[str, float] | None = None,
    offsets: dict[str, float] | None = None,
    fs: float | None = None,
    t0: float = 0.0,
    nan_policy: NanPolicy = "raise",
    mag_unit: str | None = None,
    meta: dict[str, Any] | None = None,
) -> ImuData:
    """A validated recording from a DataFrame; the inverse of :func:`to_dataframe`.

    Parameters
    ----------
    df : pandas.DataFrame
        One column per channel; ``attrs`` (as written by :func:`to_dataframe`) give back ``mag_unit`` and ``meta``.
    columns, units, scales, offsets, fs, t0, nan_policy, mag_unit, meta
        As for :func:`imunav.io.csv.read_csv` (e.g. ``columns={"t": "time_s", "gx": "GyrX", ...}``,
        ``units={"gyro": "deg/s"}``).

    Returns
    -------
    ImuData
        The recording in SI units.
    """
    source = "DataFrame"
    cols = resolve_columns(list(df.columns), columns, source)
    arrays = table_to_arrays(df, cols, source)
    stored = {"mag_unit": df.attrs.get("mag_unit"), "meta": df.attrs.get("meta") or {}}
    return build_imu(
        arrays, source, stored=stored, units=units, scales=scales, offsets=offsets, fs=fs, t0=t0,
        nan_policy=nan_policy, mag_unit=mag_unit, meta=meta,
    )  # fmt: skip
