"""PX4 ULog files through ``pyulog`` (extra ``imunav[px4]``); see :mod:`imunav.io.logs`.

PX4 is FRD body / NED world with Hamilton scalar-first ``q`` (body → NED), imunav's own conventions,
so vectors and quaternions pass through; only units change (gauss → µT, µs → s, hPa → Pa).  A topic
with several instances (``multi_id``, one per sensor) is chosen with ``instance=`` or ``"name:k"``.

=========================================  =============  =============================================
topic                                      kind           values
=========================================  =============  =============================================
``sensor_combined``                        ``imu``        ``gyro_rad``, ``accelerometer_m_s2`` and, in
                                                          older logs, ``magnetometer_ga`` (→ µT); time
                                                          ``timestamp`` (the gyro sample time)
``vehicle_imu``                            ``imu``        rates from the integrated increments:
                                                          ``gyro = delta_angle / delta_angle_dt`` and
                                                          ``accel = delta_velocity / delta_velocity_dt``
                                                          (the mean over each interval ending at
                                                          ``timestamp_sample``; coning-corrected by PX4)
``sensor_gyro`` / ``sensor_accel``         ``gyro`` /     ``gyro`` / ``accel`` and ``temp``; as an IMU the
                                           ``accel``      accel of the same instance is interpolated
                                                          onto the gyro stamps
``sensor_mag``, ``vehicle_magnetometer``   ``mag``        ``mag`` (gauss → µT)
``vehicle_gps_position``, ``sensor_gps``,  ``gnss``       ``lat_deg``, ``lon_deg``, ``alt_m`` (MSL),
``*global_position*``                                     ``vel_ned``, ``fix_type``, ``eph_m``, ``epv_m``
``sensor_baro``                            ``pressure``   ``pressure`` (Pa; logs before PX4 1.13 store
                                                          hPa, recognised by a median under 2000) and
                                                          ``temp``
``*local_position*``                       ``position``   ``pos_ned``, ``vel_ned``
``vehicle_attitude``,                      ``attitude``   ``q_nb`` (passes through: PX4's ``q`` is
``vehicle_attitude_groundtruth``,                         body → NED, Hamilton, scalar first; checked
``estimator_attitude``                                    against an attitude filter on real flights)
=========================================  =============  =============================================

Time: ``timestamp_sample`` when the topic fills it (the sensor's sample time), else ``timestamp``; the
publication ``timestamp`` is then kept as the receive time.  Every topic shares the log's clock (PX4
boot time).  The logger's dropouts (messages it lost when its buffer overflowed) are reported in
``meta["logger_dropouts"]`` (count, total and longest in ms), not refused.  GNSS topics keep the first of
messages that repeat a stamp (count in ``meta["time"]["duplicates_dropped"]``).  ``vehicle_air_data``
gives ``pressure`` (``baro_pressure_pa``), ``baro_alt_m`` and ``temp``; GNSS topics also give
``alt_ellipsoid_m``, ``speed_std`` (``s_variance_m_s``), ``vel_ned_valid`` and ``time_utc_us``.  ULog has no index: listing the topics
parses the file once (pyulog), keeping only each topic's time stamps.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import atomic_path
from imunav.io.kfgins import NavTrack
from imunav.io.topics import TopicData, TopicInfo, merge_onto, topic_data
from imunav.rotation import quat_interp

__all__ = ["list_topics", "read_topic", "read_imu_topic", "read_px4_groundtruth", "write_ulog", "IMU_TOPICS", "GROUNDTRUTH_TOPICS"]

#: ULog topics that give an IMU (gyro + accel); ``sensor_combined`` is the default.
IMU_TOPICS = ("sensor_combined", "vehicle_imu", "sensor_gyro", "sensor_accel")
_GAUSS_TO_UT = 100.0
#: PX4 parameters kept in ``meta["px4_params"]``: the estimator in use and the magnetic declination it
#: applied (deg), which an attitude filter referenced to magnetic north differs from in yaw.
_PARAMS = ("SYS_MC_EST_GROUP", "EKF2_MAG_DECL", "EKF2_DECL_TYPE", "ATT_MAG_DECL", "ATT_MAG_DECL_A")


def _load(path: str | os.PathLike[str], names: list[str] | None) -> Any:
    # optional: pyulog (imunav[px4]); topics.require has checked it is installed
    from pyulog import ULog

    source = os.fspath(path)
    try:
        return ULog(source, names)
    except (FileNotFoundError, PermissionError, IsADirectoryError):
        raise
    except Exception as e:  # pyulog raises several types for a bad file
        raise FileFormatError(f"{source}: cannot read it as a PX4 ULog ({type(e).__name__}: {e})") from None


def kind_of(name: str, fields: set[str]) -> str | None:
    """What imunav reads from a ULog topic with these fields (None: nothing).

    Parameters
    ----------
    name : str
        Topic name (``sensor_combined``, ``sensor_mag``, ...).
    fields : set of str
        Its field names.

    Returns
    -------
    str or None
        ``imu``, ``mag``, ``gnss``, ``pressure``, ``temperature``, ``attitude`` ..., or None.
    """
    if name in ("sensor_combined", "vehicle_imu"):
        return "imu"
    if name == "sensor_gyro":
        return "gyro"
    if name == "sensor_accel":
        return "accel"
    if name in ("sensor_mag", "vehicle_magnetometer"):
        return "mag"
    if name in ("sensor_baro", "vehicle_air_data"):
        return "pressure"
    if "q[0]" in fields and "attitude" in name and "setpoint" not in name:
        return "attitude"
    if {"lat", "lon"} <= fields or {"latitude_deg", "longitude_deg"} <= fields:
        return "gnss"
    if "local_position" in name and {"x", "y", "z"} <= fields:
        return "position"
    return None


def list_topics(path: str | os.PathLike[str]) -> list[TopicInfo]:
    """Topic instances of a ULog with count, duration and rate (see :func:`imunav.io.logs.list_topics`).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file.

    Returns
    -------
    list of TopicInfo
        Sorted by topic and instance.

    Raises
    ------
    FileFormatError
        If the file cannot be parsed as a ULog.
    """
    ulog = _load(path, None)
    out = []
    for d in ulog.data_list:
        ts = np.asarray(d.data["timestamp"], dtype=np.int64)
        n = int(ts.size)
        dur = float(ts.max() - ts.min()) * 1e-6 if n else None
        rate = (n - 1) / dur if dur and n >= 2 else None
        out.append(TopicInfo(d.name, d.name, n, int(d.multi_id), dur, rate, kind_of(d.name, set(d.data))))
    return sorted(out, key=lambda i: (i.topic, i.instance))


def _split(topic: str, instance: int | None, source: str) -> tuple[str, int | None]:
    name, sep, k = topic.rpartition(":")
    if sep and k.isdigit():
        if instance is not None and int(k) != instance:
            raise InvalidInputError(f"{source}: topic {topic!r} names instance {k} but instance={instance}")
        return name, int(k)
    return topic, instance


def _dataset(path: str | os.PathLike[str], topic: str, instance: int | None, ulog: Any = None) -> tuple[Any, Any]:
    """The parsed log and the dataset of ``topic`` (instance ``instance``); ``ulog``: the log already parsed with
    that topic among its names (not parsed a second time)."""
    source = os.fspath(path)
    name, inst = _split(topic, instance, source)
    if ulog is None:
        ulog = _load(path, [name])
    found = [d for d in ulog.data_list if d.name == name]
    if not found:
        names = sorted({d.name for d in _load(path, None).data_list})
        hint = "; this log has no IMU data (no " + ", ".join(IMU_TOPICS) + ")" if not set(IMU_TOPICS) & set(names) else ""
        raise InvalidInputError(f"{source}: no topic {name!r} in the log{hint}; its topics: {', '.join(names)}")
    ids = sorted(int(d.multi_id) for d in found)
    if inst is None:
        if len(found) > 1:
            raise InvalidInputError(
                f"{source}: topic {name!r} has {len(found)} instances {ids}; choose one with instance=... "
                f"(CLI: --instance), or topic='{name}:{ids[0]}' (CLI: --topic {name}:{ids[0]})"
            )
        return ulog, found[0]
    for d in found:
        if int(d.multi_id) == inst:
            return ulog, d
    raise InvalidInputError(f"{source}: topic {name!r} has no instance {inst}; its instances: {ids}")


def _cols(data: dict[str, np.ndarray], base: str, n: int = 3) -> np.ndarray:
    return np.column_stack([np.asarray(data[f"{base}[{i}]"], dtype=np.float64) for i in range(n)])


def _xyz(data: dict[str, np.ndarray]) -> np.ndarray:
    return np.column_stack([np.asarray(data[a], dtype=np.float64) for a in "xyz"])


def _values(name: str, kind: str, data: dict[str, np.ndarray], source: str) -> tuple[dict, dict, dict]:
    f = data
    meta: dict[str, Any] = {}
    if kind == "imu" and name == "sensor_combined":
        vals = {"gyro": _cols(f, "gyro_rad"), "accel": _cols(f, "accelerometer_m_s2")}
        units = {"gyro": "rad/s", "accel": "m/s^2"}
        if "magnetometer_ga[0]" in f:
            vals["mag"] = _cols(f, "magnetometer_ga") * _GAUSS_TO_UT
            units["mag"] = "uT"
        if "accelerometer_timestamp_relative" in f:
            rel = np.asarray(f["accelerometer_timestamp_relative"], dtype=np.int64)
            meta["accel_time_offset_us"] = {"min": int(rel.min()), "max": int(rel.max())}
    elif kind == "imu":  # vehicle_imu: integrated increments -> mean rates over each interval
        dta = np.asarray(f["delta_angle_dt"], dtype=np.float64) * 1e-6
        dtv = np.asarray(f["delta_velocity_dt"], dtype=np.float64) * 1e-6
        bad = np.flatnonzero((dta <= 0) | (dtv <= 0))
        if bad.size:
            raise FileFormatError(f"{source}: vehicle_imu has a zero integration interval at messages {bad[:5].tolist()}")
        vals = {"gyro": _cols(f, "delta_angle") / dta[:, None], "accel": _cols(f, "delta_velocity") / dtv[:, None]}
        units = {"gyro": "rad/s", "accel": "m/s^2"}
        meta["integration"] = ("rates = delta_angle / delta_angle_dt, accel = delta_velocity / delta_velocity_dt: "
                               "means over the interval ending at timestamp_sample (lag dt/2)")
        meta["integration_dt_median_s"] = float(np.median(dta))
    elif kind in ("gyro", "accel"):
        vals = {kind: _xyz(f)}
        units = {kind: "rad/s" if kind == "gyro" else "m/s^2"}
        if "temperature" in f and np.all(np.isfinite(f["temperature"])):
            vals["temp"], units["temp"] = np.asarray(f["temperature"], dtype=np.float64), "degC"
    elif kind == "mag":
        vals = {"mag": (_cols(f, "magnetometer_ga") if "magnetometer_ga[0]" in f else _xyz(f)) * _GAUSS_TO_UT}
        units = {"mag": "uT"}
    elif kind == "pressure" and name == "vehicle_air_data":
        vals = {"pressure": np.asarray(f["baro_pressure_pa"], dtype=np.float64),
                "baro_alt_m": np.asarray(f["baro_alt_meter"], dtype=np.float64)}
        units = {"pressure": "Pa", "baro_alt_m": "m"}
        if "baro_temp_celcius" in f:
            vals["temp"], units["temp"] = np.asarray(f["baro_temp_celcius"], dtype=np.float64), "degC"
        meta["baro_alt_m"] = "PX4's pressure altitude (its QNH parameter SENS_BARO_QNH)"
    elif kind == "pressure":
        p = np.asarray(f["pressure"], dtype=np.float64)
        hpa = bool(np.median(p) < 2000.0)
        vals, units = {"pressure": p * 100.0 if hpa else p}, {"pressure": "Pa"}
        meta["pressure_unit_in_log"] = "hPa" if hpa else "Pa"
        if "temperature" in f:
            vals["temp"], units["temp"] = np.asarray(f["temperature"], dtype=np.float64), "degC"
    elif kind == "attitude":
        vals, units = {"q_nb": _cols(f, "q", 4)}, {"q_nb": "1"}
    elif kind == "gnss":
        if "latitude_deg" in f:
            lat, lon = (np.asarray(f[k], dtype=np.float64) for k in ("latitude_deg", "longitude_deg"))
            alt = np.asarray(f.get("altitude_msl_m", f.get("alt")), dtype=np.float64)
        else:
            lat, lon = (np.asarray(f[k], dtype=np.float64) * (1e-7 if f[k].dtype.kind == "i" else 1.0)
                        for k in ("lat", "lon"))
            a = f["alt"]
            alt = np.asarray(a, dtype=np.float64) * (1e-3 if a.dtype.kind == "i" else 1.0)  # int mm, float m
        vals = {"lat_deg": lat, "lon_deg": lon, "alt_m": alt}
        units = {"lat_deg": "deg", "lon_deg": "deg", "alt_m": "m"}
        meta["altitude"] = "above mean sea level (PX4 alt)"
        if "alt_ellipsoid" in f:
            a = f["alt_ellipsoid"]
            vals["alt_ellipsoid_m"] = np.asarray(a, dtype=np.float64) * (1e-3 if a.dtype.kind == "i" else 1.0)
            units["alt_ellipsoid_m"] = "m"
        if "vel_n_m_s" in f:
            vals["vel_ned"] = np.column_stack([np.asarray(f[f"vel_{a}_m_s"], dtype=np.float64) for a in "ned"])
            units["vel_ned"] = "m/s"
        for k, key, unit in (("fix_type", "fix_type", "1"), ("eph", "eph_m", "m"), ("epv", "epv_m", "m"),
                             ("satellites_used", "satellites_used", "1"), ("vel_ned_valid", "vel_ned_valid", "1"),
                             ("s_variance_m_s", "speed_std", "m/s"), ("time_utc_usec", "time_utc_us", "us")):
            if k in f:
                vals[key], units[key] = np.asarray(f[k]), unit
        if "s_variance_m_s" in f:
            meta["speed_std"] = "s_variance_m_s: PX4's speed accuracy, a 1-sigma in m/s despite its name"
    elif kind == "position":
        vals = {"pos_ned": _xyz(f)}
        units = {"pos_ned": "m"}
        if {"vx", "vy", "vz"} <= set(f):
            vals["vel_ned"] = np.column_stack([np.asarray(f[k], dtype=np.float64) for k in ("vx", "vy", "vz")])
            units["vel_ned"] = "m/s"
    else:
        raise InvalidInputError(f"{source}: imunav does not read topic {name!r}")
    return vals, units, meta


def _read(ulog: Any, d: Any, source: str) -> TopicData:
    kind = kind_of(d.name, set(d.data))
    if kind is None:
        raise InvalidInputError(
            f"{source}: imunav does not read topic {d.name!r}; it reads IMU ({', '.join(IMU_TOPICS)}), magnetometer, "
            "GNSS, barometer, local-position and attitude topics"
        )
    vals, units, meta = _values(d.name, kind, d.data, source)
    # timestamp_sample when filled (the simulator's ground-truth topics leave it 0)
    has_sample = "timestamp_sample" in d.data and bool(np.all(np.asarray(d.data["timestamp_sample"]) > 0))
    stamps_us = np.asarray(d.data["timestamp_sample" if has_sample else "timestamp"], dtype=np.int64)
    recv = np.asarray(d.data["timestamp"], dtype=np.int64) * 1000 if has_sample else None
    meta.update({"format": "ulog", "msgtype": d.name, "time_field": "timestamp_sample" if has_sample else "timestamp",
                 "clock": "PX4 boot time (t0_ns since boot)"})
    params = {k: ulog.initial_parameters[k] for k in _PARAMS if k in ulog.initial_parameters}
    if params:
        meta["px4_params"] = params
    sys_name = ulog.msg_info_dict.get("sys_name")
    if sys_name is not None:
        meta["system"] = {k: str(ulog.msg_info_dict[k]) for k in ("sys_name", "ver_hw", "ver_sw") if k in ulog.msg_info_dict}
    drops = [float(x.duration) for x in getattr(ulog, "dropouts", [])]
    meta["logger_dropouts"] = {"count": len(drops), "total_ms": float(sum(drops)),
                               "longest_ms": max(drops) if drops else 0.0}
    return topic_data(d.name, kind, stamps_us * 1000, vals, units, source, receive_ns=recv,
                      instance=int(d.multi_id), meta=meta, duplicates="drop" if kind == "gnss" else "raise")


def read_topic(path: str | os.PathLike[str], topic: str, *, instance: int | None = None) -> TopicData:
    """Read one topic instance of a ULog (see the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file.
    topic : str
        Topic name, optionally ``"name:instance"``.
    instance : int, optional
        ``multi_id`` when the topic has several instances.

    Returns
    -------
    TopicData
        The topic in SI units, body FRD / world NED, ``t`` in s since ``meta["t0_ns"]``.
    """
    ulog, d = _dataset(path, topic, instance)
    return _read(ulog, d, os.fspath(path))


def read_imu_topic(path: str | os.PathLike[str], topic: str | None, *, instance: int | None = None) -> TopicData:
    """The IMU of a ULog: ``sensor_combined`` by default, else ``vehicle_imu`` / a gyro + accel instance pair.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file.
    topic : str or None
        IMU topic (``sensor_combined``, ``vehicle_imu``, ``sensor_gyro`` / ``sensor_accel``); None: the default.
    instance : int, optional
        ``multi_id`` of the topic.

    Returns
    -------
    TopicData
        The IMU topic in SI units: gyro (rad/s) and specific force (m/s²) in body FRD, ``t`` in s since
        ``meta["t0_ns"]``.

    Raises
    ------
    InvalidInputError
        If the topic is not an IMU topic, or several candidates exist and none is chosen.
    FileFormatError
        If the log has no IMU topic at all, or a gyro / accel pair cannot be matched in time.
    """
    source = os.fspath(path)
    parsed = None
    if topic is None:
        topic = "sensor_combined"
        parsed = _load(path, list(IMU_TOPICS))
        names = {d.name for d in parsed.data_list}
        if "sensor_combined" not in names:
            if not names:
                raise FileFormatError(f"{source}: this log has no IMU data (none of {', '.join(IMU_TOPICS)})")
            raise InvalidInputError(f"{source}: no sensor_combined; choose an IMU with topic=... among "
                                    f"{', '.join(sorted(names))} (and instance=...)")
    name, inst = _split(topic, instance, source)
    if name not in IMU_TOPICS:
        raise InvalidInputError(f"{source}: topic {name!r} is not an IMU topic; choose one of {', '.join(IMU_TOPICS)}")
    if name in ("sensor_gyro", "sensor_accel"):
        # the topic named first, so that a missing topic or an ambiguous instance is reported as asked for
        other = "sensor_accel" if name == "sensor_gyro" else "sensor_gyro"
        first = read_topic(path, name, instance=inst)
        try:
            second = read_topic(path, other, instance=first.instance)
        except InvalidInputError as e:
            raise InvalidInputError(f"{name} as an IMU needs {other} of the same instance ({first.instance}): {e}") from None
        g, a = (first, second) if name == "sensor_gyro" else (second, first)
        g = TopicData(g.topic, "imu", g.t, {"gyro": g.values["gyro"]}, {"gyro": "rad/s"}, g.t_receive, g.instance,
                      dict(g.meta))
        imu, note = merge_onto(g, a, "accel", source)
        if "temp" in a.values:
            imu, _ = merge_onto(imu, a, "temp", source)
        imu.meta["accel_from"] = note
        return imu
    # the default topic from the log parsed above (parsing it again for the one topic took as long: issue 35)
    ulog, d = _dataset(path, name, inst, parsed)
    return _read(ulog, d, source)


#: Ground-truth topics of PX4's simulator, read by :func:`read_px4_groundtruth`.
GROUNDTRUTH_TOPICS = ("vehicle_global_position_groundtruth", "vehicle_local_position_groundtruth",
                      "vehicle_attitude_groundtruth")


def read_px4_groundtruth(path: str | os.PathLike[str], *, t0_ns: int = 0) -> NavTrack:
    """The simulator's ground truth of a PX4 SITL log, as a reference track.

    Position from ``vehicle_global_position_groundtruth`` (lat / lon in degrees, ``alt_ellipsoid``), on
    its own stamps; NED velocity from ``vehicle_local_position_groundtruth`` (``vx, vy, vz``, linear) and
    attitude from ``vehicle_attitude_groundtruth`` (``q``, slerp) interpolated onto them (zero / identity
    where the log lacks the topic, said in ``meta["missing"]``).  Stamps outside the span of a topic take
    its nearest value.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file of a simulated flight.
    t0_ns : int
        Origin of the returned time on the log's clock, ns since boot (e.g. ``NavSources.t0_ns`` to compare
        with a navigation solution from the same log).

    Returns
    -------
    NavTrack
        ``t`` in s since ``t0_ns``; ``meta`` holds the topics used and ``altitude_filled`` (False when the
        simulator left the altitudes at 0, as PX4 1.13 SITL does: compare horizontally then).

    Raises
    ------
    InvalidInputError
        If the log has no ``vehicle_global_position_groundtruth`` (not a simulated flight).
    MissingDependencyError
        If ``pyulog`` is not installed.
    """
    source = os.fspath(path)
    ulog = _load(path, list(GROUNDTRUTH_TOPICS))
    got = {d.name: d.data for d in ulog.data_list if int(d.multi_id) == 0}
    if GROUNDTRUTH_TOPICS[0] not in got:
        raise InvalidInputError(f"{source}: no {GROUNDTRUTH_TOPICS[0]} topic: the log is not from PX4's simulator "
                                "(SITL), it has no ground truth")
    g = got[GROUNDTRUTH_TOPICS[0]]
    ts = np.asarray(g["timestamp"], dtype=np.int64) * 1000
    t = (ts - int(t0_ns)) * 1e-9
    lat, lon = (np.radians(np.asarray(g[k], dtype=np.float64)) for k in ("lat", "lon"))
    alt = np.asarray(g.get("alt_ellipsoid", g["alt"]), dtype=np.float64)
    missing = []
    vel = np.zeros((t.size, 3))
    loc = got.get(GROUNDTRUTH_TOPICS[1])
    if loc is not None:
        tl = (np.asarray(loc["timestamp"], dtype=np.int64) * 1000 - int(t0_ns)) * 1e-9
        vel = np.column_stack([np.interp(t, tl, np.asarray(loc[k], dtype=np.float64)) for k in ("vx", "vy", "vz")])
    else:
        missing.append(GROUNDTRUTH_TOPICS[1])
    q = np.tile([1.0, 0.0, 0.0, 0.0], (t.size, 1))
    att = got.get(GROUNDTRUTH_TOPICS[2])
    if att is not None:
        ta = (np.asarray(att["timestamp"], dtype=np.int64) * 1000 - int(t0_ns)) * 1e-9
        q = quat_interp(ta, _cols(att, "q", 4), np.clip(t, ta[0], ta[-1]))
    else:
        missing.append(GROUNDTRUTH_TOPICS[2])
    meta = {"source": source, "format": "ulog", "topics": [k for k in GROUNDTRUTH_TOPICS if k in got],
            "missing": missing, "t0_ns": int(t0_ns), "clock": "PX4 boot time",
            "altitude_filled": bool(np.any(alt != 0.0))}
    return NavTrack(t, np.column_stack([lat, lon, alt]), vel, q, 0, meta)


# -- writing ------------------------------------------------------------------------------------
_ULOG_TYPES = {np.dtype(np.uint64): "uint64_t", np.dtype(np.int64): "int64_t", np.dtype(np.uint32): "uint32_t",
               np.dtype(np.int32): "int32_t", np.dtype(np.uint16): "uint16_t", np.dtype(np.int16): "int16_t",
               np.dtype(np.uint8): "uint8_t", np.dtype(np.int8): "int8_t", np.dtype(np.float32): "float",
               np.dtype(np.float64): "double", np.dtype(np.bool_): "bool"}


def _ulog_msg(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path: str | os.PathLike[str], topics: Any, *, info: Any = None, t_start_us: int = 0) -> Path:
    """Write topics as a PX4 ULog file (format version 1) that :func:`read_topic` and ``pyulog`` read, atomically.

    A minimal logger: one format definition and one subscription (``multi_id`` 0) per topic, then every
    data message in time order.  Each topic is a mapping of field name to array, one row per message,
    with ``timestamp`` (µs, integer) first; a 2-D array ``(N, k)`` is a ``type[k] name`` field (read back
    as ``name[0]`` ... ``name[k-1]``).  The array dtype is the field type (``float32`` → ``float``,
    ``float64`` → ``double``, ``int32`` → ``int32_t`` ...): write PX4's own types to test a reader on what
    PX4 logs.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file to write (never an existing one).
    topics : mapping
        Topic name -> mapping of field name -> array; ``timestamp`` is required.
    info : mapping of str to str, optional
        Information messages (``sys_name``, ``ver_sw`` ...), written as ``char[n]`` values.
    t_start_us : int
        The header's start time, µs.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InvalidInputError
        If the file exists, a topic has no ``timestamp``, its fields differ in length, or a dtype has no
        ULog type.
    """
    target = Path(path)
    if target.exists():
        raise InvalidInputError(f"{target} exists; outputs never overwrite - choose another path")
    head = b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", int(t_start_us))
    out = [head, _ulog_msg(b"B", bytes(16) + bytes(24))]
    for k, v in dict(info or {}).items():
        val = str(v).encode()
        key = f"char[{len(val)}] {k}".encode()
        out.append(_ulog_msg(b"I", bytes([len(key)]) + key + val))
    rows: list[tuple[int, int, bytes]] = []  # (timestamp, order, message)
    subs = []
    for msg_id, (name, fields) in enumerate(dict(topics).items()):
        cols = {k: np.asarray(a) for k, a in dict(fields).items()}
        if next(iter(cols), None) != "timestamp":
            raise InvalidInputError(f"write_ulog: topic {name!r} must have 'timestamp' (us) as its first field")
        cols["timestamp"] = cols["timestamp"].astype(np.uint64)
        n = cols["timestamp"].shape[0]
        spec, dt = [], []
        for k, a in cols.items():
            if a.shape[0] != n:
                raise InvalidInputError(f"write_ulog: {name}.{k} has {a.shape[0]} rows, timestamp {n}")
            typ = _ULOG_TYPES.get(a.dtype)
            if typ is None:
                raise InvalidInputError(f"write_ulog: {name}.{k} has dtype {a.dtype}, which ULog has no type for")
            width = a.shape[1] if a.ndim == 2 else 0
            spec.append(f"{typ}[{width}] {k}" if width else f"{typ} {k}")
            dt.append((k, a.dtype.newbyteorder("<"), (width,)) if width else (k, a.dtype.newbyteorder("<")))
        out.append(_ulog_msg(b"F", f"{name}:{';'.join(spec)};".encode()))
        rec = np.empty(n, dtype=np.dtype(dt, align=False))
        for k, a in cols.items():
            rec[k] = a
        subs.append(_ulog_msg(b"A", struct.pack("<BH", 0, msg_id) + name.encode()))
        prefix = struct.pack("<H", msg_id)
        raw = rec.tobytes()
        size = rec.dtype.itemsize
        for i, ts in enumerate(cols["timestamp"].tolist()):
            rows.append((int(ts), msg_id, _ulog_msg(b"D", prefix + raw[i * size:(i + 1) * size])))
    rows.sort(key=lambda r: (r[0], r[1]))
    out += subs
    out += [r[2] for r in rows]
    with atomic_path(target) as tmp:
        Path(tmp).write_bytes(b"".join(out))
    return target
