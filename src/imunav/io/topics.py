"""What the robotics-log readers share: the result types (:class:`TopicInfo`, :class:`TopicData`), the
log kind of a path, the frame conversions at the edge, the time-axis checks and the merge of a second
topic (magnetometer, temperature) onto the IMU's time stamps.

The readers (:mod:`imunav.io.rosbag`, :mod:`imunav.io.ulog`) import this module and the dispatch
(:mod:`imunav.io.logs`) imports them: this module sits below both, so neither imports the other.
Frames, units and time conventions are stated in :mod:`imunav.io.logs`.
"""

from __future__ import annotations

import importlib
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import FileFormatError, MissingDependencyError, TimeOrderError
from imunav.rotation import C_ENU_NED, C_FLU_FRD

__all__ = ["TopicInfo", "TopicData", "EXTRAS", "log_kind", "require", "ros_to_frd", "frd_to_ros", "enu_to_ned",
           "ned_to_enu", "time_axis", "topic_data", "merge_onto"]

Array = NDArray[np.float64]

#: Log kind -> (package, extra) needed to read it.
EXTRAS: dict[str, tuple[str, str]] = {"rosbag": ("rosbags", "ros"), "ulog": ("pyulog", "px4")}
_SUFFIX_KIND = {".bag": "rosbag", ".db3": "rosbag", ".mcap": "rosbag", ".ulg": "ulog"}
_MAGIC = ((b"ULog\x01\x12\x35", "ulog"), (b"#ROSBAG V2.0", "rosbag"), (b"\x89MCAP0\r\n", "rosbag"),
          (b"SQLite format 3\x00", "rosbag"))  # fmt: skip


def log_kind(path: str | os.PathLike[str]) -> str | None:
    """``"rosbag"``, ``"ulog"`` or None for anything else (by suffix, folder layout, then magic bytes).

    Parameters
    ----------
    path : str or os.PathLike
        A file or a ROS 2 bag folder.

    Returns
    -------
    str or None
        The kind of log.
    """
    p = Path(path)
    if p.is_dir():
        return "rosbag" if (p / "metadata.yaml").is_file() else None
    kind = _SUFFIX_KIND.get(p.suffix.lower())
    if kind is not None:
        return kind
    try:
        with open(p, "rb") as fh:
            head = fh.read(16)
    except OSError:
        return None
    for magic, k in _MAGIC:
        if head.startswith(magic):
            if k == "rosbag" and magic.startswith(b"SQLite") and p.suffix.lower() not in (".db3", ""):
                return None  # any SQLite file is not a bag; only .db3 (or no suffix) is tried as one
            return k
    return None


def require(kind: str, feature: str) -> None:
    """Raise :class:`MissingDependencyError` naming the extra when the package of ``kind`` is absent.

    Parameters
    ----------
    kind : {"rosbag", "ulog"}
        The log kind (``rosbags`` / ``pyulog``).
    feature : str
        What the user asked for, for the message.

    Raises
    ------
    MissingDependencyError
        If the package is not installed; the message names ``pip install 'imunav[ros]'`` / ``'imunav[px4]'``.
    """
    pkg, extra = EXTRAS[kind]
    try:
        importlib.import_module(pkg)
    except ImportError:
        raise MissingDependencyError(pkg, extra, feature) from None


# -- frames -------------------------------------------------------------------------------------
# imunav.rotation is imported in the functions: it loads numba kernels, which listing topics does not need
def ros_to_frd(v: Any) -> Array:
    """Body vectors from ROS FLU to imunav FRD: ``(x, -y, -z)`` (REP-103).

    Parameters
    ----------
    v : array_like, shape (3,) or (N, 3)
        Vectors.

    Returns
    -------
    numpy.ndarray
        The vectors in FRD, same shape and unit.
    """

    return np.asarray(v, dtype=np.float64) @ C_FLU_FRD.T


def frd_to_ros(v: Any) -> Array:
    """Body vectors from FRD to ROS FLU (the same flip; its own inverse).

    Parameters
    ----------
    v : array_like, shape (3,) or (N, 3)
        Vectors.

    Returns
    -------
    numpy.ndarray
        The vectors in FLU, same shape and unit.
    """

    return np.asarray(v, dtype=np.float64) @ C_FLU_FRD


def enu_to_ned(v: Any) -> Array:
    """World vectors from ENU to NED: ``(y, x, -z)``.

    Parameters
    ----------
    v : array_like, shape (3,) or (N, 3)
        Vectors.

    Returns
    -------
    numpy.ndarray
        The vectors in NED.
    """

    return np.asarray(v, dtype=np.float64) @ C_ENU_NED


def ned_to_enu(v: Any) -> Array:
    """World vectors from NED to ENU (the same swap; its own inverse).

    Parameters
    ----------
    v : array_like, shape (3,) or (N, 3)
        Vectors.

    Returns
    -------
    numpy.ndarray
        The vectors in ENU.
    """

    return np.asarray(v, dtype=np.float64) @ C_ENU_NED.T


# -- result types -------------------------------------------------------------------------------
@dataclass(frozen=True)
class TopicInfo:
    """One topic (ROS) or one topic instance (PX4 ``multi_id``) of a log, from its index.

    Attributes
    ----------
    topic : str
        Topic name (``/imu/data``, ``sensor_accel``).
    msgtype : str
        Message type (``sensor_msgs/msg/Imu``) or, for ULog, the topic name again.
    count : int
        Number of messages.
    instance : int, optional
        PX4 ``multi_id`` (None for ROS).
    duration_s : float, optional
        Span of the stamps, s (ROS: of the bag's record times when only the index is read).
    rate_hz : float, optional
        ``(count - 1) / duration_s`` (None for fewer than 2 messages).
    kind : str, optional
        What imunav reads from it (``imu``, ``mag``, ``gnss``, ``gnss_velocity``, ``pressure``,
        ``temperature``, ``attitude``) or None when imunav does not read that type.
    """

    topic: str
    msgtype: str
    count: int
    instance: int | None = None
    duration_s: float | None = None
    rate_hz: float | None = None
    kind: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict.

        Returns
        -------
        dict
            The attributes by name.
        """
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True, eq=False)
class TopicData:
    """One topic of a bag or log, in SI units and imunav frames (FRD body, NED world).

    Attributes
    ----------
    topic : str
        Topic name.
    kind : str
        ``imu``, ``mag``, ``gnss``, ``gnss_velocity``, ``pressure``, ``temperature`` or ``attitude``.
    t : numpy.ndarray, shape (N,)
        s since ``meta["t0_ns"]``, increasing (the sensor stamp, see the module docstring).
    values : dict of str to numpy.ndarray
        Arrays by name: ``gyro`` (N, 3) rad/s and ``accel`` (N, 3) m/s² body FRD, ``mag`` (N, 3) µT
        body FRD, ``temp`` (N,) °C, ``pressure`` (N,) Pa, ``lat_deg`` / ``lon_deg`` / ``alt_m`` (N,),
        ``vel_ned`` (N, 3) m/s, ``q_nb`` (N, 4) body → NED Hamilton scalar-first, and what else a
        message carries (``fix_status``, ``eph_m`` ...).
    units : dict of str to str
        Unit of each entry of ``values``.
    t_receive : numpy.ndarray, shape (N,), or None
        Receive (record) time on the same origin, s (None for ULog).
    instance : int or None
        PX4 ``multi_id`` (None for ROS).
    meta : dict
        Source, message type, frame id, conversions applied, time report.
    """

    topic: str
    kind: str
    t: Array
    values: dict[str, np.ndarray]
    units: dict[str, str]
    t_receive: Array | None = None
    instance: int | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of messages."""
        return int(self.t.shape[0])

    def __repr__(self) -> str:
        inst = "" if self.instance is None else f", instance={self.instance}"
        return f"TopicData({self.topic!r}{inst}, kind={self.kind!r}, n={self.n}, values={sorted(self.values)})"


# -- time ---------------------------------------------------------------------------------------
def time_axis(stamps_ns: NDArray[np.int64], source: str, what: str) -> tuple[NDArray[np.intp] | None, dict[str, Any]]:
    """Order and quality report of integer-nanosecond stamps.

    Parameters
    ----------
    stamps_ns : numpy.ndarray of int64, shape (N,)
        Sensor stamps, ns.
    source : str
        The log, for messages.
    what : str
        The topic, for messages.

    Returns
    -------
    order : numpy.ndarray of intp or None
        None when the stamps are already increasing, else the stable sort order (and a
        :class:`UserWarning` is issued).
    report : dict
        The count, the median interval, the jitter, the gaps and the out-of-order count (s).

    Raises
    ------
    TimeOrderError
        On duplicated stamps (the messages are named).
    """
    s = np.asarray(stamps_ns, dtype=np.int64)
    d0 = np.diff(s)
    back = np.flatnonzero(d0 < 0)
    order = None
    if back.size:
        order = np.argsort(s, kind="stable")
        s = s[order]
        warnings.warn(
            f"{source}: {what}: {back.size} stamp(s) go backwards (first after message {int(back[0])}); "
            "the messages were sorted by stamp (count in meta['time']['out_of_order'])",
            UserWarning, stacklevel=3,
        )
    d = np.diff(s)
    dup = np.flatnonzero(d == 0)
    if dup.size:
        idx = (dup if order is None else order[dup]).tolist()
        raise TimeOrderError(
            f"{source}: {what}: {dup.size} message(s) repeat the stamp of the one before (first at message "
            f"{idx[:5]}); two samples cannot share one instant - drop the duplicates when recording, or read "
            "another topic"
        )
    rep: dict[str, Any] = {"messages": int(s.size), "out_of_order": int(back.size)}
    if s.size >= 2:
        dts = d * 1e-9
        med = float(np.median(dts))
        big = dts > 1.5 * med
        ok = dts[~big] if (~big).any() else dts  # jitter: the intervals that are not gaps
        rep.update({
            "dt_median_s": med,
            "jitter_std_s": float(np.std(ok)),
            "jitter_max_s": float(np.max(np.abs(ok - med))),
            "gaps": int(big.sum()),
            "missing_estimate": int(np.sum(np.round(dts[big] / med) - 1)) if big.any() else 0,
            "longest_gap_s": float(dts.max()) if big.any() else None,
        })
    return order, rep


def topic_data(topic: str, kind: str, stamps_ns: Any, values: Mapping[str, np.ndarray], units: Mapping[str, str],
               source: str, *, receive_ns: Any = None, instance: int | None = None,
               meta: Mapping[str, Any] | None = None, duplicates: str = "raise") -> TopicData:
    """Build a :class:`TopicData` from integer-ns stamps: sort/check them, set the origin, report.

    Parameters
    ----------
    topic : str
        Topic name.
    kind : str
        What the topic holds (see :class:`TopicData`).
    stamps_ns : array_like of int, shape (N,)
        Sensor stamps, ns.
    values : mapping of str to numpy.ndarray
        Arrays by name, SI, in imunav frames, one row per message.
    units : mapping of str to str
        Unit of each array.
    source : str
        The log, for messages.
    receive_ns : array_like of int, shape (N,), optional
        Receive (record) times, ns.
    instance : int, optional
        PX4 ``multi_id``.
    meta : mapping, optional
        Entries of the result's ``meta``.
    duplicates : {"raise", "drop"}
        Messages that repeat an earlier stamp: refused (a sensor cannot sample twice at one instant), or
        dropped, keeping the first published, with their count in ``meta["time"]["duplicates_dropped"]``
        (GNSS drivers re-publish a fix).

    Returns
    -------
    TopicData
        The topic in SI units, body FRD / world NED, ``t`` in s since ``meta["t0_ns"]``.
        Sorted by stamp, ``t`` in s since ``meta["t0_ns"]``.

    Raises
    ------
    FileFormatError
        If the topic has no message.
    TimeOrderError
        On duplicated stamps with ``duplicates="raise"``.
    """
    stamps = np.asarray(stamps_ns, dtype=np.int64)
    if stamps.size == 0:
        raise FileFormatError(f"{source}: topic {topic!r} has no messages")
    what = f"topic {topic!r}" + ("" if instance is None else f" instance {instance}")
    vals = {k: np.asarray(v) for k, v in values.items()}
    recv = None if receive_ns is None else np.asarray(receive_ns, dtype=np.int64)
    n_dup = 0
    if duplicates == "drop":
        o = np.argsort(stamps, kind="stable")
        dup = o[1:][np.diff(stamps[o]) == 0]
        n_dup = int(dup.size)
        if n_dup:
            keep = np.ones(stamps.size, dtype=bool)
            keep[dup] = False
            stamps = stamps[keep]
            vals = {k: v[keep] for k, v in vals.items()}
            recv = None if recv is None else recv[keep]
    elif duplicates != "raise":
        raise ValueError(f"duplicates must be 'raise' or 'drop'; got {duplicates!r}")
    order, rep = time_axis(stamps, source, what)
    if duplicates == "drop":
        rep["duplicates_dropped"] = n_dup
    if order is not None:
        stamps = stamps[order]
        vals = {k: v[order] for k, v in vals.items()}
        recv = None if recv is None else recv[order]
    t0 = int(stamps[0])
    m = dict(meta or {})
    m.update({"source": source, "topic": topic, "t0_ns": t0, "time": rep})
    if instance is not None:
        m["instance"] = instance
    t_rec = None
    if recv is not None:
        lat = (recv - stamps) * 1e-9
        m["receive_latency_s"] = {"min": float(lat.min()), "median": float(np.median(lat)), "max": float(lat.max())}
        t_rec = (recv - t0) * 1e-9
    return TopicData(topic, kind, (stamps - t0) * 1e-9, vals, dict(units), t_rec, instance, m)


def merge_onto(imu: TopicData, aux: TopicData, name: str, source: str) -> tuple[TopicData, dict[str, Any]]:
    """Interpolate ``aux.values[name]`` linearly onto the IMU stamps; IMU rows outside its span are cut.

    Both topics must share the time origin of one clock (same log); the aux ``t`` is shifted by the
    difference of their ``t0_ns``.

    Parameters
    ----------
    imu : TopicData
        The IMU topic.
    aux : TopicData
        The second topic (magnetometer, temperature).
    name : str
        Entry of ``aux.values`` to merge.
    source : str
        The log, for messages.

    Returns
    -------
    imu : TopicData
        The IMU with ``values[name]`` added (rows outside ``aux``'s span removed).
    note : dict
        What was done, for ``meta``.

    Raises
    ------
    FileFormatError
        If ``aux`` has fewer than 2 messages or does not overlap the IMU in time.
    """
    shift = (int(aux.meta["t0_ns"]) - int(imu.meta["t0_ns"])) * 1e-9
    ta = aux.t + shift
    if ta.size < 2:
        raise FileFormatError(f"{source}: topic {aux.topic!r} has {ta.size} message(s); {name} needs at least 2")
    keep = (imu.t >= ta[0]) & (imu.t <= ta[-1])
    if not keep.any():
        raise FileFormatError(
            f"{source}: topic {aux.topic!r} spans [{ta[0]:.6g}, {ta[-1]:.6g}] s and the IMU "
            f"[{imu.t[0]:.6g}, {imu.t[-1]:.6g}] s (same origin): they do not overlap"
        )
    i0, i1 = int(np.argmax(keep)), int(keep.size - np.argmax(keep[::-1]))
    sl = slice(i0, i1)
    t_imu = imu.t[sl]
    v = np.asarray(aux.values[name], dtype=np.float64)
    cols = v.reshape(v.shape[0], -1)
    merged = np.column_stack([np.interp(t_imu, ta, cols[:, j]) for j in range(cols.shape[1])])
    merged = merged.reshape((t_imu.size,) + v.shape[1:])
    vals = {k: a[sl] for k, a in imu.values.items()}
    vals[name] = merged
    dt_aux = aux.meta.get("time", {}).get("dt_median_s")
    note = {"topic": aux.topic, "instance": aux.instance, "interpolation": "linear", "rows_cut_start": i0,
            "rows_cut_end": int(imu.t.size - i1), "rate_hz": 1.0 / dt_aux if dt_aux else None}
    out = TopicData(imu.topic, imu.kind, t_imu, vals, {**imu.units, name: aux.units[name]},
                    None if imu.t_receive is None else imu.t_receive[sl], imu.instance, dict(imu.meta))
    return out, note
