"""ROS 1 and ROS 2 bags through ``rosbags`` (extra ``imunav[ros]``); see :mod:`imunav.io.logs`.

Accepted: a ROS 1 ``.bag``, a ROS 2 bag folder (``metadata.yaml`` with sqlite3 or MCAP storage), or a
bare ROS 2 ``.db3`` / ``.mcap`` file.  Messages are deserialized by ``rosbags`` (the bag's own type
definitions, else the latest ROS 2 type store); imunav only copies their fields into arrays, in chunks,
so memory grows with the selected topic only.

Message types read (frames: FLU body / ENU world → FRD / NED, see :mod:`imunav.io.logs`):

========================================  =================  =========================================
type                                      kind               values
========================================  =================  =========================================
``sensor_msgs/msg/Imu``                   ``imu``            ``gyro``, ``accel``, and ``q_nb`` when the
                                                             orientation is filled (covariance[0] ≠ -1);
                                                             the three covariances in ``meta``
``sensor_msgs/msg/MagneticField``         ``mag``            ``mag`` (T → µT), covariance in ``meta``
``sensor_msgs/msg/NavSatFix``             ``gnss``           ``lat_deg``, ``lon_deg``, ``alt_m``
                                                             (ellipsoid), ``fix_status``, ``pos_cov``
``geometry_msgs/msg/TwistStamped``        ``gnss_velocity``  ``vel_ned`` (twist.linear taken as ENU,
                                                             as GNSS drivers publish it), ``rate_frd``
                                                             and ``linear_raw`` (twist.linear as published)
``nav_msgs/msg/Odometry``                 ``odometry``       ``speed`` (twist.linear.x in the child frame,
                                                             REP-105: the forward speed), ``vel_body``
                                                             (FRD), ``rate_frd``, ``speed_var``
                                                             (twist covariance[0]); ``child_frame_id`` in
                                                             ``meta``
``sensor_msgs/msg/FluidPressure``         ``pressure``       ``pressure`` (Pa), ``variance``
``sensor_msgs/msg/Temperature``           ``temperature``    ``temp`` (°C), ``variance``
========================================  =================  =========================================

GNSS topics (``gnss``) keep the first of messages that repeat a stamp and count the others in
``meta["time"]["duplicates_dropped"]`` (a receiver driver re-publishing a fix); every other kind refuses
duplicated stamps.  :func:`read_static_tf` reads ``/tf_static``.

A topic whose messages name more than one ``header.frame_id`` is refused: its samples would mix
sensor frames.  ROS 1 ``header.seq`` gaps are counted in ``meta["seq_gaps"]`` (dropped messages).
"""

from __future__ import annotations

import heapq
import os
import shutil
import tempfile
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, ImunavError, InvalidInputError
from imunav.io.aiding import MagnetometerData, OdometerData
from imunav.io.gnss import GnssData
from imunav.io.topics import (
    TopicData,
    TopicInfo,
    enu_to_ned,
    frd_to_ros,
    ned_to_enu,
    require,
    ros_to_frd,
    topic_data,
)
from imunav.rotation import from_convention
from imunav.timeseries import ImuData

__all__ = ["list_topics", "read_topic", "read_topics", "read_imu_topic", "read_static_tf", "StaticTransform", "write_bag", "KINDS",
           "STORAGES"]

#: Message type -> kind read by imunav.
KINDS = {
    "sensor_msgs/msg/Imu": "imu",
    "sensor_msgs/msg/MagneticField": "mag",
    "sensor_msgs/msg/NavSatFix": "gnss",
    "geometry_msgs/msg/TwistStamped": "gnss_velocity",
    "nav_msgs/msg/Odometry": "odometry",
    "sensor_msgs/msg/FluidPressure": "pressure",
    "sensor_msgs/msg/Temperature": "temperature",
}
_CHUNK = 65536
#: Messages of a fixed-layout topic parsed at once (their raw bytes are held meanwhile: about 3 MB for an Imu topic).
_FIXED_CHUNK = 8192


def _open(path: str | os.PathLike[str]) -> Any:
    """An opened-to-be ``AnyReader`` on ``path`` (rosbags errors become FileFormatError)."""
    # optional: rosbags (imunav[ros]); topics.require has checked it is installed
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore  # optional: rosbags

    return AnyReader([Path(path)], default_typestore=get_typestore(Stores.LATEST))


class _Bag:
    """Context manager: an open AnyReader whose errors are reported as FileFormatError naming the bag."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.source = os.fspath(path)
        self.reader: Any = None
        try:
            self.reader = _open(path)
        except (FileNotFoundError, PermissionError):
            raise
        except Exception as e:  # rosbags raises several types for a bad bag
            raise FileFormatError(f"{self.source}: cannot open it as a ROS bag ({type(e).__name__}: {e})") from None

    def __enter__(self) -> Any:
        try:
            self.reader.open()
        except (FileNotFoundError, PermissionError):
            raise
        except Exception as e:  # rosbags raises several types for a bad bag
            raise FileFormatError(
                f"{self.source}: cannot read it as a ROS bag ({type(e).__name__}: {e}); the bag may be truncated "
                "(a ROS 1 bag still being recorded needs `rosbag reindex`) or of another format"
            ) from None
        return self.reader

    def __exit__(self, typ: Any, exc: Any, tb: Any) -> bool:
        self.reader.close()
        if isinstance(exc, Exception) and not isinstance(exc, (ImunavError, FileNotFoundError, PermissionError)):
            frames = []
            while tb is not None:
                frames.append(tb.tb_frame.f_code.co_filename)
                tb = tb.tb_next
            if any(f"{os.sep}rosbags{os.sep}" in f for f in frames):  # rosbags reading a record: a damaged bag
                raise FileFormatError(
                    f"{self.source}: a record of the bag cannot be read ({type(exc).__name__}: {exc}); the bag is "
                    "damaged (a chunk that does not decompress or a message that does not decode): copy or record "
                    "it again") from exc
        return False


def _span_ns(reader: Any, conns: list[Any], count: int) -> tuple[int, int] | None:
    """First and last record time of a topic, from time windows at each end of the bag (the index finds
    the chunks or rows of a window; nothing else is read)."""
    if count == 0:
        return None
    start, end = int(reader.start_time), int(reader.end_time)
    w0 = max(int((end - start) * min(1.0, 20.0 / count)), 1_000_000)  # about 20 messages of the topic

    def edge(from_start: bool) -> int | None:
        w, pos = w0, (start if from_start else end + 1)
        while (pos < end + 1) if from_start else (pos > start):
            lo, hi = (pos, pos + w) if from_start else (max(pos - w, start), pos)
            ts = [t for _, t, _ in reader.messages(connections=conns, start=lo, stop=hi)]
            if ts:
                return ts[0] if from_start else ts[-1]
            pos = hi if from_start else lo
            w *= 8
        return None

    first, last = edge(True), edge(False)
    if first is None or last is None:
        return None
    return first, last


def list_topics(path: str | os.PathLike[str]) -> list[TopicInfo]:
    """Topics of a bag with type, count (from the index), duration and rate (see :func:`imunav.io.logs.list_topics`).

    Parameters
    ----------
    path : str or os.PathLike
        ROS 1 ``.bag``, ROS 2 folder, ``.db3`` or ``.mcap``.

    Returns
    -------
    list of TopicInfo
        Sorted by topic.

    Raises
    ------
    MissingDependencyError
        If ``rosbags`` is not installed (``pip install 'imunav[ros]'``).
    FileFormatError
        If the bag cannot be opened.
    """
    out = []
    with _Bag(path) as reader:
        for name, info in sorted(reader.topics.items()):
            conns = list(info.connections)
            count = int(info.msgcount)
            span = _span_ns(reader, conns, count)
            dur = None if span is None else (span[1] - span[0]) * 1e-9
            rate = (count - 1) / dur if dur and count >= 2 else None
            msgtype = info.msgtype or ", ".join(sorted({c.msgtype for c in conns}))
            out.append(TopicInfo(name, msgtype, count, None, dur, rate, KINDS.get(msgtype)))
    return out


# -- per-type field extraction (one tuple of floats per message) ---------------------------------
def _vec(v: Any) -> tuple[float, float, float]:
    return (v.x, v.y, v.z)


_FIELDS: dict[str, tuple[Callable[[Any], tuple], int, tuple[str, ...]]] = {
    # kind: (extract, number of floats, covariance attribute names compared across messages)
    "imu": (lambda m: (m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z,
                       m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z,
                       m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z), 10,
            ("angular_velocity_covariance", "linear_acceleration_covariance", "orientation_covariance")),
    "mag": (lambda m: _vec(m.magnetic_field), 3, ("magnetic_field_covariance",)),
    "gnss": (lambda m: (m.latitude, m.longitude, m.altitude, m.status.status, m.position_covariance[0],
                        m.position_covariance[4], m.position_covariance[8], m.position_covariance_type), 8, ()),
    "gnss_velocity": (lambda m: (*_vec(m.twist.linear), *_vec(m.twist.angular)), 6, ()),
    "odometry": (lambda m: (*_vec(m.twist.twist.linear), *_vec(m.twist.twist.angular), m.twist.covariance[0]), 7, ()),
    "pressure": (lambda m: (m.fluid_pressure, m.variance), 2, ()),
    "temperature": (lambda m: (m.temperature, m.variance), 2, ()),
}


def _finish(collector: Any) -> tuple[np.ndarray, np.ndarray, dict]:
    """The result of a :func:`_collector` fed every message."""
    try:
        collector.send(None)
    except StopIteration as stop:
        return stop.value  # type: ignore[no-any-return]
    raise RuntimeError("a collector did not finish")  # pragma: no cover - the generator ends on None


def _collector(reader: Any, conns: list[Any], kind: str, source: str, topic: str) -> Any:
    """A started generator that takes the messages ``(conn, ts, raw)`` of one topic by ``send`` and, sent None,
    ends with the result of :func:`_collect` (so that one pass over a bag feeds several topics)."""
    gen = _collecting(reader, conns, kind, source, topic)
    next(gen)
    return gen


def _collecting(reader: Any, conns: list[Any], kind: str, source: str, topic: str) -> Any:
    extract, k, cov_names = _FIELDS[kind]
    ros1 = not reader.is2
    total = sum(int(c.msgcount) for c in conns)
    ints = np.empty((max(total, 1), 4 if ros1 else 3), dtype=np.int64)
    flts = np.empty((max(total, 1), k), dtype=np.float64)
    frames: dict[str, int] = {}
    cov_first: dict[str, np.ndarray] = {}
    cov_varies = False
    cov_bytes: list[bytes] = []
    ci: list[tuple] = []
    cf: list[tuple] = []
    n = 0
    deser = reader.deserialize
    odo = kind == "odometry"
    children: dict[str, int] = {}

    def put(rows_i: Any, rows_f: Any) -> None:
        nonlocal n, ints, flts
        m = len(rows_i)
        if n + m > ints.shape[0]:  # the index under-counted: grow
            ints = np.concatenate([ints, np.empty((n + m, ints.shape[1]), np.int64)])
            flts = np.concatenate([flts, np.empty((n + m, k), np.float64)])
        if m:
            ints[n:n + m] = rows_i
            flts[n:n + m] = rows_f
        n += m

    def flush() -> None:
        put(ci, cf)
        ci.clear()
        cf.clear()

    def one(conn: Any, ts: int, raw: Any) -> None:
        """One message, deserialized by rosbags (every type; the IMU's fallback)."""
        nonlocal cov_first, cov_bytes, cov_varies
        try:
            msg = deser(raw, conn.msgtype)
        except Exception as e:  # rosbags raises several types for a damaged message
            raise FileFormatError(f"{source}: topic {topic!r}: message {n + len(ci)} cannot be decoded ({e})") from None
        h = msg.header
        st = h.stamp
        ci.append((st.sec, st.nanosec, ts, h.seq) if ros1 else (st.sec, st.nanosec, ts))
        cf.append(extract(msg))
        fid = h.frame_id
        frames[fid] = frames.get(fid, 0) + 1
        if odo:
            cid = msg.child_frame_id
            children[cid] = children.get(cid, 0) + 1
        if cov_names:
            if not cov_first:
                cov_first = {c: np.array(getattr(msg, c), dtype=np.float64) for c in cov_names}
                cov_bytes = [cov_first[c].tobytes() for c in cov_names]
            elif not cov_varies:  # bytes, not np.array_equal: a tenth of the time per message
                cov_varies = [getattr(msg, c).tobytes() for c in cov_names] != cov_bytes

    if kind in _LAYOUTS:
        # sensor_msgs/Imu and nav_msgs/Odometry have a fixed layout once their strings' lengths are known: a chunk
        # is parsed with numpy (_fixed_chunk); a chunk it cannot vouch for goes through rosbags message by message
        pending: list[tuple[Any, int, Any]] = []

        def drain() -> None:
            nonlocal cov_first, cov_bytes, cov_varies
            fast = _fixed_chunk(pending, ros1, deser, kind)
            if fast is None:
                for item in pending:
                    one(*item)
            else:
                rows_i, rows_f, fids, kids, covs = fast
                put(rows_i, rows_f)
                for fid, c in fids.items():
                    frames[fid] = frames.get(fid, 0) + c
                for cid, c in kids.items():
                    children[cid] = children.get(cid, 0) + c
                if cov_names and not cov_first:
                    cov_first = {c: covs[c][0].copy() for c in cov_names}
                    cov_bytes = [cov_first[c].tobytes() for c in cov_names]
                if cov_names and not cov_varies:
                    cov_varies = any(np.any(covs[c].view(np.uint64) != cov_first[c].view(np.uint64))
                                     for c in cov_names)
            pending.clear()
            flush()

        while (item := (yield)) is not None:
            pending.append(item)
            if len(pending) >= _FIXED_CHUNK:
                drain()
        drain()
    else:
        while (item := (yield)) is not None:
            one(*item)
            if len(ci) >= _CHUNK:
                flush()
        flush()
    if n == 0:
        raise FileFormatError(f"{source}: topic {topic!r} has no messages")
    if len(frames) > 1:
        raise FileFormatError(
            f"{source}: topic {topic!r} mixes frame_ids {frames} (messages per frame); its samples come from "
            "different sensor frames - record one topic per sensor, or split the topic by frame_id first"
        )
    if len(children) > 1:
        raise FileFormatError(
            f"{source}: topic {topic!r} mixes child_frame_ids {children} (messages per frame); its twists are in "
            "different frames - record one odometry topic per frame"
        )
    info = {"frame_id": next(iter(frames)), "cov": cov_first, "cov_varies": cov_varies,
            "child_frame_id": next(iter(children)) if children else None}
    return ints[:n], flts[:n], info


@dataclass(frozen=True)
class _Layout:
    """A message of fixed layout once its strings' lengths are known: the header (stamp, ``frame_id``), ``strings``
    more strings, then ``doubles`` float64; ``pick`` takes the values of :data:`_FIELDS` from them (one row per
    message), ``covs`` the covariances compared across messages (name -> first index, 9 values)."""

    strings: int
    doubles: int
    pick: Callable[[np.ndarray], np.ndarray]
    covs: dict[str, int]


_LAYOUTS = {
    # orientation x y z w (0-3), its covariance (4-12), angular_velocity (13-15), its covariance (16-24),
    # linear_acceleration (25-27), its covariance (28-36)
    "imu": _Layout(0, 37, lambda d: d[:, [13, 14, 15, 25, 26, 27, 3, 0, 1, 2]],
                   {"angular_velocity_covariance": 16, "linear_acceleration_covariance": 28,
                    "orientation_covariance": 4}),
    # child_frame_id; pose.pose position (0-2), orientation (3-6), pose.covariance (7-42), twist.twist linear
    # (43-45), angular (46-48), twist.covariance (49-84)
    "odometry": _Layout(1, 85, lambda d: d[:, [43, 44, 45, 46, 47, 48, 49]], {}),
}


def _fixed_chunk(items: list[tuple[Any, int, Any]], ros1: bool, deser: Callable[[Any, str], Any],
                 kind: str) -> tuple[np.ndarray, np.ndarray, dict[str, int], dict[str, int], dict[str, np.ndarray]] | None:
    """Messages of a fixed layout (:data:`_LAYOUTS`) parsed with numpy from their raw bytes, or None when the chunk
    is not of that layout (the caller then deserializes each message).

    ROS 2 (CDR, little- or big-endian, 4-byte encapsulation header): ``stamp.sec`` int32, ``stamp.nanosec``
    uint32, each string as a uint32 length (with the NUL) and its bytes, aligned to 4, then the float64 aligned
    to 8 from the start of the data.  ROS 1 (little-endian, no alignment): ``seq``, ``stamp.sec``,
    ``stamp.nsec`` (uint32), each string as a uint32 length and its bytes, the float64.  Messages of one length
    whose strings have the same lengths share every offset: one numpy view each.  Each group is checked against
    rosbags' own deserialization of its first message (stamp, strings and every value read, bit for bit), so that
    a bag whose message definition differs falls back.

    Returns
    -------
    tuple or None
        ``(ints (N, 4 | 3) [sec, nanosec, receive_ns(, seq)], floats (N, k) as _FIELDS extracts them,
        {frame_id: count}, {child_frame_id: count}, {covariance name: (N, 9)})`` in the order of ``items``.
    """
    lay = _LAYOUTS[kind]
    extract, k, _ = _FIELDS[kind]
    n = len(items)
    if n == 0:
        return None
    try:
        raws = [bytes(r) for _, _, r in items]
    except TypeError:
        return None
    lens = np.fromiter((len(r) for r in raws), dtype=np.int64, count=n)
    ints = np.empty((n, 4 if ros1 else 3), dtype=np.int64)
    flts = np.empty((n, k), dtype=np.float64)
    covs = {c: np.empty((n, 9), dtype=np.float64) for c in lay.covs}
    fids: dict[str, int] = {}
    kids: dict[str, int] = {}
    ints[:, 2] = [ts for _, ts, _ in items]
    for length in np.unique(lens).tolist():
        idx = np.flatnonzero(lens == length)
        buf = np.frombuffer(b"".join(raws[i] for i in idx), dtype=np.uint8).reshape(idx.size, length)
        if ros1:
            end, base, pos = "<", 0, 12
        else:
            enc = buf[:, :4]
            if not np.all(enc == enc[0]) or enc[0, 0] != 0 or enc[0, 1] not in (0, 1):
                return None  # mixed or unknown encapsulation (PL_CDR, ...)
            end, base, pos = ("<" if enc[0, 1] == 1 else ">"), 4, 8

        def col(off: int, dtype: str, count: int = 1, buf: np.ndarray = buf, end: str = end) -> np.ndarray:
            """``count`` values of ``dtype`` ("u4", "i4", "f8") from byte ``off`` of every message, native order."""
            w = np.dtype(dtype).itemsize * count
            if off + w > buf.shape[1]:
                raise IndexError(off)
            return np.ascontiguousarray(buf[:, off:off + w]).view(end + dtype).astype(dtype).reshape(-1, count)

        names = []
        try:
            for _ in range(1 + lay.strings):  # frame_id, then the message's own strings
                if not ros1:
                    pos = (pos + 3) // 4 * 4
                size = col(base + pos, "u4")[:, 0]
                if not np.all(size == size[0]) or base + pos + 4 + int(size[0]) > length:
                    return None
                text = buf[:, base + pos + 4:base + pos + 4 + int(size[0])]
                if not np.all(text == text[0]):
                    return None  # strings of one length that differ: the per-message path counts them
                name = bytes(text[0]).decode("utf-8", errors="replace")
                names.append(name if ros1 else name[:-1])  # CDR strings end with a NUL, counted in their length
                pos += 4 + int(size[0])
            o = pos if ros1 else (pos + 7) // 8 * 8
            if base + o + 8 * lay.doubles != length:
                return None
            d = col(base + o, "f8", lay.doubles)
            ints[idx, 0] = col(base + (4 if ros1 else 0), "u4" if ros1 else "i4")[:, 0]
            ints[idx, 1] = col(base + (8 if ros1 else 4), "u4")[:, 0]
            if ros1:
                ints[idx, 3] = col(0, "u4")[:, 0]
        except IndexError:
            return None
        flts[idx] = lay.pick(d)
        for c, j in lay.covs.items():
            covs[c][idx] = d[:, j:j + 9]
        fids[names[0]] = fids.get(names[0], 0) + idx.size
        if lay.strings:
            kids[names[1]] = kids.get(names[1], 0) + idx.size
        # the group's first message as rosbags reads it: any difference and the chunk goes the slow way
        i0 = int(idx[0])
        conn, _, raw = items[i0]
        try:
            m = deser(raw, conn.msgtype)
            ref = np.array(extract(m), dtype=np.float64)
        except Exception:  # rosbags raises several types for a damaged message
            return None
        st, h = m.header.stamp, m.header
        same = (int(ints[i0, 0]) == st.sec and int(ints[i0, 1]) == st.nanosec and h.frame_id == names[0]
                and (not lay.strings or m.child_frame_id == names[1])
                and ref.shape == flts[i0].shape and np.array_equal(ref.view(np.uint64), flts[i0].view(np.uint64))
                and (not ros1 or int(ints[i0, 3]) == h.seq)
                and all(np.array_equal(np.asarray(getattr(m, c), dtype=np.float64).view(np.uint64),
                                       covs[c][i0].view(np.uint64)) for c in covs))
        if not same:
            return None
    return ints, flts, fids, kids, covs


def _rot_cov(c: np.ndarray) -> list[float]:
    """Row-major 3×3 covariance FLU → FRD (C Σ Cᵀ); unknown (-1 first entry, REP-145) is kept as is."""
    s = np.asarray(c, dtype=np.float64).reshape(3, 3)
    if s[0, 0] == -1.0:
        return s.reshape(-1).tolist()
    return ros_to_frd(ros_to_frd(s).T).reshape(-1).tolist()  # C Σ Cᵀ with C symmetric


def _values(kind: str, f: np.ndarray, info: dict) -> tuple[dict[str, np.ndarray], dict[str, str], dict[str, Any]]:
    meta: dict[str, Any] = {"frame_id": info["frame_id"]}
    if kind == "imu":
        vals = {"gyro": ros_to_frd(f[:, 0:3]), "accel": ros_to_frd(f[:, 3:6])}
        units = {"gyro": "rad/s", "accel": "m/s^2"}
        cov = info["cov"]
        meta["covariance"] = {
            "gyro": _rot_cov(cov["angular_velocity_covariance"]),
            "accel": _rot_cov(cov["linear_acceleration_covariance"]),
            "varies": info["cov_varies"],
        }
        if cov["orientation_covariance"][0] != -1.0:
            # orientation: FLU body -> ENU world (REP-103) -> imunav FRD body -> NED
            vals["q_nb"] = from_convention(f[:, 6:10], "enu", body="flu")
            units["q_nb"] = "1"
        meta["frames"] = "FLU -> FRD: (x, -y, -z)"
    elif kind == "mag":
        vals = {"mag": ros_to_frd(f[:, 0:3]) * 1e6}
        units = {"mag": "uT"}
        meta["covariance"] = {"mag_T2": _rot_cov(info["cov"]["magnetic_field_covariance"]), "varies": info["cov_varies"]}
        meta["frames"] = "FLU -> FRD: (x, -y, -z); tesla -> uT"
    elif kind == "gnss":
        vals = {"lat_deg": f[:, 0], "lon_deg": f[:, 1], "alt_m": f[:, 2], "fix_status": f[:, 3].astype(np.int8),
                "pos_cov_enu_diag": f[:, 4:7], "pos_cov_type": f[:, 7].astype(np.uint8)}
        units = {"lat_deg": "deg", "lon_deg": "deg", "alt_m": "m", "fix_status": "1", "pos_cov_enu_diag": "m^2",
                 "pos_cov_type": "1"}
        meta["altitude"] = "above the WGS 84 ellipsoid (sensor_msgs/NavSatFix)"
    elif kind == "gnss_velocity":
        vals = {"vel_ned": enu_to_ned(f[:, 0:3]), "rate_frd": ros_to_frd(f[:, 3:6]), "linear_raw": f[:, 0:3]}
        units = {"vel_ned": "m/s", "rate_frd": "rad/s", "linear_raw": "m/s"}
        meta["frames"] = ("twist.linear taken as ENU -> NED (y, x, -z); twist.angular FLU -> FRD; linear_raw: "
                          "twist.linear as published (a wheel driver's body-frame twist: x is the forward speed)")
    elif kind == "odometry":
        vals = {"speed": f[:, 0], "vel_body": ros_to_frd(f[:, 0:3]), "rate_frd": ros_to_frd(f[:, 3:6]),
                "speed_var": f[:, 6]}
        units = {"speed": "m/s", "vel_body": "m/s", "rate_frd": "rad/s", "speed_var": "m^2/s^2"}
        meta["child_frame_id"] = info["child_frame_id"]
        meta["frames"] = ("twist in the child frame (REP-105), FLU -> FRD (x, -y, -z); speed = twist.linear.x; "
                          "speed_var = twist.covariance[0] (0 or -1: unknown)")
    elif kind == "pressure":
        vals, units = {"pressure": f[:, 0], "variance": f[:, 1]}, {"pressure": "Pa", "variance": "Pa^2"}
    else:
        vals, units = {"temp": f[:, 0], "variance": f[:, 1]}, {"temp": "degC", "variance": "degC^2"}
    return vals, units, meta


def _choose(topics: dict[str, Any], topic: str | None, source: str, want: Iterable[str] | None) -> str:
    if topic is not None:
        if topic not in topics:
            listed = ", ".join(f"{k} ({v.msgtype})" for k, v in sorted(topics.items())) or "none"
            raise InvalidInputError(f"{source}: no topic {topic!r} in the bag; its topics: {listed}")
        return topic
    cands = sorted(k for k, v in topics.items() if KINDS.get(v.msgtype) in (want or ()))
    if len(cands) == 1:
        return cands[0]
    if not cands:
        listed = ", ".join(f"{k} ({v.msgtype})" for k, v in sorted(topics.items())) or "none"
        raise FileFormatError(f"{source}: no sensor_msgs/Imu topic in the bag; its topics: {listed}")
    raise InvalidInputError(f"{source}: {len(cands)} IMU topics: {', '.join(cands)}; choose one with "
                            f"topic=... (CLI: --topic)")


def read_topic(path: str | os.PathLike[str], topic: str, *, instance: int | None = None,
               _want: Iterable[str] | None = None) -> TopicData:
    """Read one topic of a bag (see the module docstring for the types and conversions).

    Parameters
    ----------
    path : str or os.PathLike
        The bag (file or ROS 2 folder).
    topic : str
        Topic name; with ``None`` (internal use) the single topic of a kind in ``_want``.
    instance : int, optional
        Must be None (ROS topics have no instances).

    Returns
    -------
    TopicData
        The topic in SI units, body FRD / world NED, ``t`` in s since ``meta["t0_ns"]``.

    Raises
    ------
    InvalidInputError
        If ``instance`` is given, the topic is absent, or its message type is not one imunav reads.
    FileFormatError
        If the topic is empty, mixes frame ids, or a message cannot be decoded.
    """
    source = os.fspath(path)
    if instance is not None:
        raise InvalidInputError(f"{source}: instance= is for PX4 ULog topics; a ROS bag chooses by topic= only")
    return _read_topics(path, [topic], _want)[0]


def read_topics(path: str | os.PathLike[str], topics: Sequence[str]) -> dict[str, TopicData]:
    """Several topics of a bag in one pass over its messages (what :func:`read_topic` gives for each).

    Parameters
    ----------
    path : str or os.PathLike
        The bag (file or ROS 2 folder).
    topics : sequence of str
        Topic names (each once).

    Returns
    -------
    dict of str to TopicData
        Topic -> its data, as :func:`read_topic` returns it.

    Raises
    ------
    InvalidInputError
        If a topic is absent or its message type is not one imunav reads.
    FileFormatError
        If a topic is empty, mixes frame ids, or a message cannot be decoded.
    """
    names = list(dict.fromkeys(topics))
    return dict(zip(names, _read_topics(path, names, None), strict=True))


def _read_topics(path: str | os.PathLike[str], wanted: Sequence[str | None],
                 want: Iterable[str] | None) -> list[TopicData]:
    source = os.fspath(path)
    with _Bag(path) as reader:
        topics = reader.topics
        chosen = []
        for topic in wanted:
            name = _choose(topics, topic, source, want)
            info = topics[name]
            kind = KINDS.get(info.msgtype or "")
            if kind is None:
                raise InvalidInputError(
                    f"{source}: topic {name!r} is {info.msgtype}; imunav reads {', '.join(sorted(KINDS))}"
                )
            chosen.append((name, info, kind))
        collectors = {name: _collector(reader, list(info.connections), kind, source, name)
                      for name, info, kind in chosen}
        conns = [c for _, info, _ in chosen for c in info.connections]
        for item in reader.messages(connections=conns):
            collectors[item[0].topic].send(item)
        results = {name: _finish(c) for name, c in collectors.items()}
        is2 = reader.is2
    out = []
    for name, info, kind in chosen:
        ints, flts, cinfo = results[name]
        stamps = ints[:, 0] * 1_000_000_000 + ints[:, 1]
        vals, units, meta = _values(kind, flts, cinfo)
        meta.update({"format": "rosbag2" if is2 else "rosbag1", "msgtype": info.msgtype})
        if not is2:
            seq = ints[:, 3]
            ds = np.diff(seq)
            meta["seq_gaps"] = {"gaps": int(np.sum(ds > 1)), "missing": int(np.sum(ds[ds > 1] - 1))}
        out.append(topic_data(name, kind, stamps, vals, units, source, receive_ns=ints[:, 2], meta=meta,
                              duplicates="drop" if kind == "gnss" else "raise"))
    return out


def read_imu_topic(path: str | os.PathLike[str], topic: str | None, *, instance: int | None = None) -> TopicData:
    """The IMU topic ``topic`` (or the only ``sensor_msgs/Imu`` topic); errors list the candidates.

    Parameters
    ----------
    path : str or os.PathLike
        The bag.
    topic : str or None
        The ``sensor_msgs/Imu`` topic; None when the bag has exactly one.
    instance : None
        Must be None (ROS topics have no instances).

    Returns
    -------
    TopicData
        The IMU topic in SI units: gyro (rad/s) and specific force (m/s²) in body FRD, ``t`` in s since
        ``meta["t0_ns"]``.

    Raises
    ------
    InvalidInputError
        If the topic is not an IMU topic, or there are none or several and none is chosen.
    """
    d = read_topic(path, topic, instance=instance, _want=("imu",))
    if d.kind != "imu":
        raise InvalidInputError(f"{os.fspath(path)}: topic {d.topic!r} is {d.meta['msgtype']}, not sensor_msgs/Imu; "
                                "choose an IMU topic")
    return d


# -- static transforms --------------------------------------------------------------------------
#: Topics read by :func:`read_static_tf`.
TF_STATIC_TOPICS = ("/tf_static", "tf_static")


@dataclass(frozen=True)
class StaticTransform:
    """One ``/tf_static`` transform, as published (ROS frames, REP-103).

    Attributes
    ----------
    parent : str
        ``header.frame_id`` (e.g. ``base_link``).
    child : str
        ``child_frame_id`` (e.g. ``imu_link``).
    q : numpy.ndarray, shape (4,)
        Rotation of the child frame in the parent, Hamilton scalar-first ``(w, x, y, z)``: it maps vectors
        resolved in the child frame to the parent frame.
    translation : numpy.ndarray, shape (3,)
        Origin of the child frame in the parent frame, m.
    """

    parent: str
    child: str
    q: np.ndarray
    translation: np.ndarray


def read_static_tf(path: str | os.PathLike[str]) -> list[StaticTransform]:
    """The static transforms of a bag (``/tf_static``, ``tf2_msgs/TFMessage``); empty when it has none.

    A transform published again replaces the earlier one (as tf2 does).

    Parameters
    ----------
    path : str or os.PathLike
        The bag.

    Returns
    -------
    list of StaticTransform
        In the order of their child frames.

    Raises
    ------
    FileFormatError
        If the bag cannot be read or a transform cannot be decoded.
    """
    source = os.fspath(path)
    out: dict[str, StaticTransform] = {}
    with _Bag(path) as reader:
        conns = [c for c in reader.connections if c.topic in TF_STATIC_TOPICS]
        if not conns:  # messages(connections=[]) would read every topic
            return []
        for conn, _, raw in reader.messages(connections=conns):
            try:
                msg = reader.deserialize(raw, conn.msgtype)
            except Exception as e:  # rosbags raises several types for a damaged message
                raise FileFormatError(f"{source}: {conn.topic}: a message cannot be decoded ({e})") from None
            for tr in msg.transforms:
                r, v = tr.transform.rotation, tr.transform.translation
                out[tr.child_frame_id] = StaticTransform(tr.header.frame_id, tr.child_frame_id,
                                                         np.array([r.w, r.x, r.y, r.z]), np.array([v.x, v.y, v.z]))
    return [out[k] for k in sorted(out)]


# -- writing ------------------------------------------------------------------------------------
#: Storage names of :func:`write_bag`.
STORAGES = ("ros1", "sqlite3", "mcap")
_DEFAULT_T0_NS = 1_700_000_000_000_000_000  # 2023-11-14T22:13:20Z, when a recording has no t0_ns
_MSGTYPE = {"imu": "sensor_msgs/msg/Imu", "mag": "sensor_msgs/msg/MagneticField",
            "temperature": "sensor_msgs/msg/Temperature", "gnss": "sensor_msgs/msg/NavSatFix",
            "odometry": "nav_msgs/msg/Odometry", "pressure": "sensor_msgs/msg/FluidPressure",
            "gnss_velocity": "geometry_msgs/msg/TwistStamped"}
_TOPIC_KINDS = ("imu", "mag", "temperature", "gnss", "pressure", "gnss_velocity")


def _stamps(d: Any) -> np.ndarray:
    t0 = int(d.meta.get("t0_ns", _DEFAULT_T0_NS))
    return t0 + np.round(np.asarray(d.t, dtype=np.float64) * 1e9).astype(np.int64)


def _stream(name: str, d: Any, mag_suffix: str) -> list[tuple[str, str, Any]]:
    """(topic, kind, data) of what ``write_bag`` writes for one entry of its mapping."""
    if isinstance(d, ImuData):
        out = [(name, "imu", d)]
        if d.mag is not None:
            out.append((name + mag_suffix, "mag", d))
        if d.temp is not None:
            out.append((name + "/temperature", "temperature", d))
        return out
    if isinstance(d, TopicData) and d.kind in _TOPIC_KINDS:
        return [(name, d.kind, d)]
    if isinstance(d, GnssData):
        return [(name, "gnss", d)]
    if isinstance(d, OdometerData):
        return [(name, "odometry", d)]
    if isinstance(d, MagnetometerData):
        return [(name, "mag", d)]
    raise InvalidInputError(f"write_bag: topic {name!r} must be an ImuData, GnssData, OdometerData, MagnetometerData "
                            f"or a TopicData of kind {', '.join(_TOPIC_KINDS)}; got {type(d).__name__}")


def write_bag(path: str | os.PathLike[str], topics: Any, *, storage: str = "mcap", frame_id: str = "imu",
              mag_suffix: str = "/mag", frame_ids: Any = None,
              static_tf: Sequence[StaticTransform] = ()) -> Path:
    """Write recordings as a ROS bag, atomically: the inverse of the readers.

    =======================================================  ==================================================
    data                                                     written as
    =======================================================  ==================================================
    :class:`~imunav.timeseries.ImuData`                      ``sensor_msgs/Imu`` (+ ``MagneticField`` on
                                                             ``topic + mag_suffix``, ``Temperature``)
    :class:`~imunav.io.gnss.GnssData`                        ``sensor_msgs/NavSatFix``: status FIX, service GPS,
                                                             diagonal ENU covariance (type DIAGONAL_KNOWN)
    :class:`~imunav.io.aiding.OdometerData`                  ``nav_msgs/Odometry`` (frame ``odom``, child
                                                             ``base_link``): twist.linear.x = speed, covariance[0]
                                                             = ``speed_std²`` (0: unknown); the pose is not written
    :class:`~imunav.io.aiding.MagnetometerData`              ``sensor_msgs/MagneticField``
    TopicData of kind imu, mag, temperature, gnss,           the message the reader reads it from (values as the
    pressure, gnss_velocity                                  reader returns them: a ``gnss`` TopicData writes its
                                                             ``fix_status``, covariance and type as given, so that
                                                             receiver faults can be written; a ``gnss_velocity``
                                                             one its ``linear_raw``, else ``vel_ned`` as ENU)
    =======================================================  ==================================================

    Body vectors go FRD → FLU, µT → T, NED → ENU; the stamps are ``meta["t0_ns"] + round(t · 1e9)`` ns (a
    fixed 2023 date when there is no ``t0_ns``); the record time equals the stamp.

    Parameters
    ----------
    path : str or os.PathLike
        ``.bag`` for ``storage="ros1"``; for ROS 2 a folder (``metadata.yaml`` + storage file).
    topics : mapping
        Mapping topic -> data (table above).
    storage : str
        ``"ros1"``, ``"sqlite3"`` or ``"mcap"``.
    frame_id : str
        ``header.frame_id`` of every message whose topic is not in ``frame_ids``.
    mag_suffix : str
        Suffix of the magnetometer topic written beside each ImuData's IMU topic.
    frame_ids : mapping, optional
        Topic -> ``header.frame_id`` (an odometry topic's header frame stays ``odom``).
    static_tf : sequence of StaticTransform
        Transforms written once on ``/tf_static`` at the first stamp (:func:`read_static_tf` reads them).

    Returns
    -------
    pathlib.Path
        The bag written.

    Raises
    ------
    InvalidInputError
        If ``storage`` is unknown, the ROS 2 folder exists, or a topic's data is none of the table's.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from imunav.timeseries import ImuData
    >>> d = ImuData(np.arange(5) / 100, np.zeros((5, 3)), np.tile([0, 0, -9.81], (5, 1)))
    >>> p = write_bag(os.path.join(tempfile.mkdtemp(), "rec"), {"/imu": d})
    >>> from imunav.io import read_imu
    >>> read_imu(p).accel[0, 2]
    np.float64(-9.81)
    """
    require("rosbag", "writing a ROS bag")
    if storage not in STORAGES:
        raise InvalidInputError(f"storage={storage!r}: choose one of {list(STORAGES)}")
    streams: list[tuple[str, str, Any]] = []  # (topic, kind, data)
    for name, d in dict(topics).items():
        streams.extend(_stream(name, d, mag_suffix))
    fids = dict(frame_ids or {})
    frames = {t: fids.get(t, "odom" if k == "odometry" else frame_id) for t, k, _ in streams}
    target = Path(path)
    if storage != "ros1" and target.exists():
        raise InvalidInputError(f"{target} exists; a ROS 2 bag is a new folder - remove it or choose another path")
    # written in a temporary folder beside the target, then renamed onto it (atomic on one file system)
    tmpdir = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent if target.parent.exists() else None))
    try:
        _write(tmpdir / target.name, streams, storage, frames, list(static_tf))
        os.replace(tmpdir / target.name, target)
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
    return target


def _rows(kind: str, d: Any) -> list[tuple]:
    """One tuple of message fields per sample, in ROS frames and units."""
    if isinstance(d, TopicData):
        v = d.values
        if kind == "imu":
            return list(zip(frd_to_ros(v["gyro"]).tolist(), frd_to_ros(v["accel"]).tolist(), strict=True))
        if kind == "mag":
            return [(m,) for m in (frd_to_ros(v["mag"]) * 1e-6).tolist()]
        if kind == "temperature":
            return [(x,) for x in np.asarray(v["temp"], dtype=float).tolist()]
        if kind == "pressure":
            var = v.get("variance", np.zeros(d.n))
            return list(zip(np.asarray(v["pressure"], float).tolist(), np.asarray(var, float).tolist(), strict=True))
        if kind == "gnss_velocity":
            lin = np.asarray(v["linear_raw"], float) if "linear_raw" in v else ned_to_enu(v["vel_ned"])
            ang = frd_to_ros(v["rate_frd"]) if "rate_frd" in v else np.zeros((d.n, 3))
            return list(zip(lin.tolist(), ang.tolist(), strict=True))
        cov = np.asarray(v["pos_cov_enu_diag"], dtype=float)
        return list(zip(np.asarray(v["lat_deg"], float).tolist(), np.asarray(v["lon_deg"], float).tolist(),
                        np.asarray(v["alt_m"], float).tolist(), np.asarray(v["fix_status"]).astype(int).tolist(),
                        cov.tolist(), np.asarray(v["pos_cov_type"]).astype(int).tolist(), strict=True))
    if isinstance(d, GnssData):
        deg = np.degrees(d.lla[:, :2])
        cov = d.pos_std[:, [1, 0, 2]] ** 2  # NED sigma -> ENU variances
        return list(zip(deg[:, 0].tolist(), deg[:, 1].tolist(), d.lla[:, 2].tolist(), [0] * d.n, cov.tolist(),
                        [2] * d.n, strict=True))
    if isinstance(d, OdometerData):
        var = np.zeros(d.t.size) if d.speed_std is None else d.speed_std ** 2
        return list(zip(d.speed.tolist(), var.tolist(), strict=True))
    if isinstance(d, MagnetometerData):
        return [(m,) for m in (frd_to_ros(d.field_b) * 1e-6).tolist()]
    if kind == "imu":  # ImuData
        return list(zip(frd_to_ros(d.gyro).tolist(), frd_to_ros(d.accel).tolist(), strict=True))
    if kind == "mag":
        return [(m,) for m in (frd_to_ros(d.mag) * 1e-6).tolist()]
    return [(x,) for x in np.asarray(d.temp, dtype=float).tolist()]


def _write(path: Path, streams: list[tuple[str, str, Any]], storage: str, frames: dict[str, str],
           static_tf: list[StaticTransform]) -> None:
    # optional: rosbags (imunav[ros]) only to read or write a bag
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if storage == "ros1" else Stores.LATEST)
    if "tf2_msgs/msg/TFMessage" not in ts.types:  # the ROS 1 store lacks it
        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    T = ts.types
    Time, Header, Vec = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"], T["geometry_msgs/msg/Vector3"]
    Quat = T["geometry_msgs/msg/Quaternion"]
    ros1 = storage == "ros1"
    if ros1:
        # optional: rosbags (imunav[ros]) only to read or write a bag
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
        ser = ts.serialize_ros1
    else:
        # optional: rosbags (imunav[ros]) only to read or write a bag
        from rosbags.rosbag2 import StoragePlugin, Writer

        writer = Writer(path, version=9, storage_plugin=StoragePlugin[storage.upper()])
        ser = ts.serialize_cdr
    zero9, zero36 = np.zeros(9), np.zeros(36)
    unknown = np.r_[-1.0, np.zeros(8)]

    def header(i: int, s: int, fid: str) -> Any:
        sec, nsec = divmod(s, 1_000_000_000)
        return Header(seq=i, stamp=Time(sec=sec, nanosec=nsec), frame_id=fid) if ros1 else \
            Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=fid)

    def message(kind: str, hdr: Any, r: tuple) -> Any:
        if kind == "imu":
            return T[_MSGTYPE[kind]](header=hdr, orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0),
                                     orientation_covariance=unknown, angular_velocity=Vec(*r[0]),
                                     angular_velocity_covariance=zero9, linear_acceleration=Vec(*r[1]),
                                     linear_acceleration_covariance=zero9)
        if kind == "mag":
            return T[_MSGTYPE[kind]](header=hdr, magnetic_field=Vec(*r[0]), magnetic_field_covariance=zero9)
        if kind == "temperature":
            return T[_MSGTYPE[kind]](header=hdr, temperature=r[0], variance=0.0)
        if kind == "pressure":
            return T[_MSGTYPE[kind]](header=hdr, fluid_pressure=r[0], variance=r[1])
        if kind == "gnss_velocity":
            return T[_MSGTYPE[kind]](header=hdr, twist=T["geometry_msgs/msg/Twist"](linear=Vec(*r[0]),
                                                                                    angular=Vec(*r[1])))
        if kind == "gnss":
            cov = np.zeros(9)
            cov[[0, 4, 8]] = r[4]
            return T[_MSGTYPE[kind]](header=hdr, status=T["sensor_msgs/msg/NavSatStatus"](status=r[3], service=1),
                                     latitude=r[0], longitude=r[1], altitude=r[2], position_covariance=cov,
                                     position_covariance_type=r[5])
        tw_cov = zero36.copy()
        tw_cov[0] = r[1]
        pose = T["geometry_msgs/msg/PoseWithCovariance"](
            pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
                                             orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0)), covariance=zero36)
        twist = T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](linear=Vec(x=r[0], y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)),
            covariance=tw_cov)
        return T[_MSGTYPE[kind]](header=hdr, child_frame_id="base_link", pose=pose, twist=twist)

    def gen(topic: str, kind: str, d: Any, conn: Any):
        fid = frames[topic]
        for i, (s, r) in enumerate(zip(_stamps(d).tolist(), _rows(kind, d), strict=True)):
            yield s, conn, ser(message(kind, header(i, s, fid), r), _MSGTYPE[kind])

    with writer:
        gens = []
        first = None
        for topic, kind, d in streams:
            conn = writer.add_connection(topic, _MSGTYPE[kind], typestore=ts)
            gens.append(gen(topic, kind, d, conn))
            s0 = int(_stamps(d)[0])
            first = s0 if first is None else min(first, s0)
        if static_tf:
            conn = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
            trs = [T["geometry_msgs/msg/TransformStamped"](
                header=header(0, first or _DEFAULT_T0_NS, tr.parent), child_frame_id=tr.child,
                transform=T["geometry_msgs/msg/Transform"](translation=Vec(*map(float, tr.translation)),
                                                           rotation=Quat(w=float(tr.q[0]), x=float(tr.q[1]),
                                                                         y=float(tr.q[2]), z=float(tr.q[3]))))
                for tr in static_tf]
            raw = ser(T["tf2_msgs/msg/TFMessage"](transforms=trs), "tf2_msgs/msg/TFMessage")
            gens.append(iter([(first or _DEFAULT_T0_NS, conn, raw)]))
        for s, conn, raw in heapq.merge(*gens, key=lambda x: x[0]):
            writer.write(conn, s, raw)
