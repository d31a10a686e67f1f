"""Robotics logs: ROS 1 / ROS 2 bags and PX4 ULog files, read through the field's own libraries.

Where things live
-----------------
* :mod:`imunav.io.rosbag` reads ROS 1 ``.bag``, ROS 2 folders (``metadata.yaml``) and bare ROS 2
  ``.db3`` / ``.mcap`` files with ``rosbags`` (extra ``imunav[ros]``);
* :mod:`imunav.io.ulog` reads PX4 ``.ulg`` files with ``pyulog`` (extra ``imunav[px4]``);
* :mod:`imunav.io.topics` holds what both share: the result types (:class:`TopicInfo`,
  :class:`TopicData`, re-exported here), the time-axis checks and the merge of a second topic
  (magnetometer, temperature) onto the IMU's time stamps;
* this module is the dispatch (:func:`list_topics`, :func:`read_topic`, :func:`read_log_imu`, reached
  from :func:`imunav.io.read_imu`).

Neither extra is needed to ``import imunav``; a reader called without its extra raises
:class:`~imunav.errors.MissingDependencyError` naming ``pip install 'imunav[ros]'`` / ``'imunav[px4]'``.

Frames and units, converted at the edge
---------------------------------------
ROS (REP-103, REP-145): body frames are FLU (x forward, y left, z up), world frames ENU.  imunav is FRD
/ NED, so body vectors (angular velocity, linear acceleration, magnetic field) become
``(x, -y, -z)`` (:data:`imunav.rotation.C_FLU_FRD`, its own inverse) and world vectors (a GNSS
velocity in ENU) ``(y, x, -z)`` (:data:`imunav.rotation.C_ENU_NED`).  ``sensor_msgs/Imu`` carries specific
force (``+g`` up at rest, i.e. ``(0, 0, +9.81)`` FLU), which is imunav's convention once in FRD
``(0, 0, -9.81)``.  Covariances are rotated the same way (``C Σ Cᵀ``).  Magnetic field: tesla → µT
(``× 1e6``).  PX4 (FRD body, NED world, Hamilton scalar-first ``q`` body → NED) passes through; its
magnetometer is in gauss → µT (``× 100``).  :func:`ros_to_frd` / :func:`frd_to_ros` are the two
directions, tested on simulated motion.

Time
----
The time axis is the sensor's own stamp (ROS ``header.stamp``, PX4 ``timestamp_sample`` or
``timestamp``), in seconds since the first stamp; the first stamp in integer nanoseconds is kept in
``meta["t0_ns"]`` (seconds since 1970 for ROS wall-clock stamps, since boot for PX4), so that float64
keeps sub-nanosecond resolution over a long log.  The bag's receive (record) time is kept too,
in :attr:`TopicData.t_receive` on the same origin, and summarised (latency = receive − stamp) in the
IMU's ``meta``.  Stamps out of order are **sorted** (stable, by stamp) with a :class:`UserWarning`, and
the count is recorded in ``meta["time"]["out_of_order"]``: messages delivered late by a transport or a
multi-threaded driver still carry a valid sensor stamp, and every downstream step needs increasing time.
Duplicated stamps are refused (:class:`~imunav.errors.TimeOrderError`, naming the messages): two
samples cannot share one instant.  Jitter (std and worst deviation from the median of the intervals
that are not gaps) and gaps (intervals over 1.5 × the median, with the estimated count of missing messages) are in
``meta["time"]`` and printed by ``imunav info FILE --topic T``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from imunav.errors import FileFormatError, InvalidInputError
from imunav.io import rosbag, ulog
from imunav.io.topics import (
    EXTRAS,
    TopicData,
    TopicInfo,
    enu_to_ned,
    frd_to_ros,
    log_kind,
    merge_onto,
    ned_to_enu,
    require,
    ros_to_frd,
)
from imunav.timeseries import ImuData

__all__ = [
    "TopicInfo",
    "TopicData",
    "log_kind",
    "list_topics",
    "read_topic",
    "read_topics",
    "read_log_imu",
    "imu_from_topic",
    "ros_to_frd",
    "frd_to_ros",
    "enu_to_ned",
    "ned_to_enu",
    "EXTRAS",
]

# -- dispatch -----------------------------------------------------------------------------------
def _module(path: str | os.PathLike[str], feature: str) -> tuple[Any, str]:
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"{os.fspath(path)}: no such file or folder")
    kind = log_kind(p)
    if kind is None:
        raise FileFormatError(
            f"{os.fspath(path)}: not a ROS bag (.bag, ROS 2 folder with metadata.yaml, .db3, .mcap) nor a PX4 "
            "ULog (.ulg)"
        )
    if p.is_file() and p.stat().st_size == 0:
        raise FileFormatError(f"{os.fspath(path)}: the file is empty (0 bytes)")
    require(kind, feature)
    return (rosbag if kind == "rosbag" else ulog), kind


def list_topics(path: str | os.PathLike[str]) -> list[TopicInfo]:
    """Topics (ROS) or topic instances (PX4) of a log with type, count, rate and duration.

    Reads only the bag's index / metadata (ROS) or the ULog's message headers and time stamps, not
    the message contents.

    Parameters
    ----------
    path : str or os.PathLike
        ROS 1 ``.bag``, ROS 2 folder / ``.db3`` / ``.mcap``, or PX4 ``.ulg``.

    Returns
    -------
    list of TopicInfo
        Sorted by topic and instance.
    """
    mod, _ = _module(path, f"listing the topics of {os.fspath(path)}")
    return mod.list_topics(path)


def read_topic(path: str | os.PathLike[str], topic: str, *, instance: int | None = None) -> TopicData:
    """Read one topic (any supported message type) into SI / FRD / NED.

    Parameters
    ----------
    path : str or os.PathLike
        The bag or log.
    topic : str
        Topic name (ROS ``/imu/data``; PX4 ``sensor_gps``, optionally ``name:instance``).
    instance : int, optional
        PX4 ``multi_id`` when the topic has several instances.

    Returns
    -------
    TopicData
        The topic in SI units, body FRD / world NED, ``t`` in s since ``meta["t0_ns"]``.
    """
    mod, _ = _module(path, f"reading {os.fspath(path)}")
    return mod.read_topic(path, topic, instance=instance)


def read_log_imu(path: str | os.PathLike[str], *, topic: str | None = None, instance: int | None = None,
                 mag_topic: str | None = None, temp_topic: str | None = None, nan_policy: str = "raise",
                 meta: Mapping[str, Any] | None = None) -> ImuData:
    """An :class:`ImuData` from a bag or a ULog (what :func:`imunav.io.read_imu` calls for those files).

    Parameters
    ----------
    path : str or os.PathLike
        The bag or log.
    topic : str, optional
        The IMU topic (ROS ``sensor_msgs/Imu``; PX4 ``sensor_combined`` (default), ``vehicle_imu``,
        ``sensor_gyro`` / ``sensor_accel`` (the two of one instance are paired)).  With several
        candidates and none chosen, the error lists them.
    instance : int, optional
        PX4 ``multi_id`` of ``topic``.
    mag_topic, temp_topic : str, optional
        A magnetometer (``sensor_msgs/MagneticField``, ``sensor_mag``,
        ``vehicle_magnetometer``) or temperature topic, linearly interpolated onto the IMU stamps;
        IMU samples outside its span are cut (counts in ``meta``).  PX4 ``sensor_combined`` logs that
        carry ``magnetometer_ga`` give the magnetometer without this.
    nan_policy : str
        ``"raise"``, ``"drop"`` or ``"interpolate"`` (:meth:`ImuData.from_arrays`).
    meta : mapping, optional
        Entries added to the result's ``meta``.

    Returns
    -------
    ImuData
        SI, body FRD, magnetometer in µT, ``t`` in s since ``meta["t0_ns"]``.

    Raises
    ------
    InvalidInputError
        If the topic is ambiguous or not an IMU topic, or ``mag_topic`` / ``temp_topic`` lack that data or
        duplicate what the IMU topic carries.
    FileFormatError
        If the file is not a bag or a ULog, or a topic is empty or does not overlap the IMU in time.
    MissingDependencyError
        If ``rosbags`` / ``pyulog`` is not installed.
    """
    mod, _ = _module(path, f"reading {os.fspath(path)}")
    source = os.fspath(path)
    imu = mod.read_imu_topic(path, topic, instance=instance)
    notes: dict[str, Any] = {}
    for opt, name, _kinds in (("mag_topic", "mag", ("mag",)), ("temp_topic", "temp", ("temperature", "imu"))):
        tp = mag_topic if name == "mag" else temp_topic
        if tp is None:
            continue
        aux = mod.read_topic(path, tp)
        if name not in aux.values:
            raise InvalidInputError(f"{source}: {opt}={tp!r} is a {aux.kind} topic without {name} data")
        if name in imu.values:
            raise InvalidInputError(f"{source}: topic {imu.topic!r} already carries {name}; drop {opt}")
        imu, notes[name] = merge_onto(imu, aux, name, source)
    return imu_from_topic(imu, source, nan_policy=nan_policy,
                          meta={**{f"{k}_from": v for k, v in notes.items()}, **dict(meta or {})})


def imu_from_topic(imu: TopicData, source: str, *, nan_policy: str = "raise",
                   meta: Mapping[str, Any] | None = None) -> ImuData:
    """The :class:`ImuData` of an IMU topic already read (what :func:`read_log_imu` returns for it).

    Parameters
    ----------
    imu : TopicData
        A topic with ``gyro`` and ``accel`` values (and ``mag``, ``temp`` when it carries them).
    source : str
        The log, for messages.
    nan_policy : str
        ``"raise"``, ``"drop"`` or ``"interpolate"`` (:meth:`ImuData.from_arrays`).
    meta : mapping, optional
        Entries added to the topic's ``meta``.

    Returns
    -------
    ImuData
        SI, body FRD, magnetometer in µT, ``t`` in s since ``meta["t0_ns"]``.

    Raises
    ------
    InvalidInputError
        If the values are not a valid recording (non-finite with ``nan_policy="raise"`` ...).
    """
    m = dict(imu.meta)
    m.update(meta or {})
    try:
        return ImuData.from_arrays(imu.t, imu.values["gyro"], imu.values["accel"], imu.values.get("mag"),
                                   imu.values.get("temp"), mag_unit="uT", nan_policy=nan_policy,  # type: ignore[arg-type]
                                   meta=m)
    except InvalidInputError as e:
        raise type(e)(f"{source}: topic {imu.topic!r}: {e}") from None


def read_topics(path: str | os.PathLike[str], topics: list[str]) -> dict[str, TopicData]:
    """Several topics of a log (:func:`read_topic` each); a ROS bag is read in one pass over its messages.

    Parameters
    ----------
    path : str or os.PathLike
        The bag or log.
    topics : list of str
        Topic names (PX4: ``name`` or ``name:instance``).

    Returns
    -------
    dict of str to TopicData
        Topic -> its data.
    """
    mod, kind = _module(path, f"reading {os.fspath(path)}")
    if kind == "rosbag":
        return rosbag.read_topics(path, topics)
    return {t: mod.read_topic(path, t) for t in dict.fromkeys(topics)}
