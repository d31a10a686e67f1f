"""A foot recording of any format imunav reads, by its content: what ``imunav zupt`` reads.

Above :mod:`imunav.io.foot` (the format readers, which :mod:`imunav.io.layouts` uses) and :mod:`imunav.io.core`
(:func:`imunav.io.read_imu`, for logs and named layouts), so that neither imports the other.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from imunav.errors import FileFormatError
from imunav.io._common import check_nonempty
from imunav.io.core import read_imu
from imunav.io.foot import FootTrial, read_fgo_csv, read_pyshoe_mat, read_xio_gait_csv
from imunav.io.logs import log_kind

__all__ = ["read_foot_trial"]


def read_foot_trial(path: str | Path, **read: Any) -> FootTrial:
    """Read a foot recording by its format (what ``imunav zupt`` reads).

    A pyshoe ``.mat`` (:func:`read_pyshoe_mat`), an x-io Gait-Tracking ``.csv`` (:func:`read_xio_gait_csv`,
    recognised by its ``Gyroscope X (deg/s)`` column) or a Constrained-ZUPT-FGO ``imuMeas*.csv``
    (:func:`read_fgo_csv`, with the ``positionGt.csv`` beside it when there is one); a ROS bag / PX4 ULog, or
    any file given with ``read`` options, through :func:`imunav.io.read_imu` (a trial without reference).

    Parameters
    ----------
    path : str or pathlib.Path
        The recording.
    **read
        Options of :func:`imunav.io.read_imu` (``topic``, ``instance``, ``layout``, ...).

    Returns
    -------
    FootTrial
        The IMU and, where the format has them, the reference positions and stance labels.

    Raises
    ------
    FileFormatError
        If the file is empty, a directory, or of none of these formats.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path)
    if read or (path.exists() and log_kind(path) is not None):
        return FootTrial(read_imu(path, **read), name=path.stem)
    check_nonempty(path)
    if path.suffix.lower() == ".mat":
        return read_pyshoe_mat(path)
    if path.suffix.lower() == ".csv":
        with open(path) as fh:
            header = fh.readline()
        if "Gyroscope X (deg/s)" in header:
            return read_xio_gait_csv(path)
        if "time_index" in header and "acc_x" in header:
            gt = path.with_name("positionGt.csv")
            return read_fgo_csv(path, gt if gt.is_file() else None)
    raise FileFormatError(f"{path}: unknown foot-recording format (pyshoe .mat, x-io Gait-Tracking .csv or "
                          "Constrained-ZUPT-FGO imuMeas*.csv)")
