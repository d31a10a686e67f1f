"""What feeds a navigation filter, read from a robot's or a drone's own log.

:func:`read_nav_sources` reads a ROS 1 bag, a ROS 2 bag (sqlite3 or MCAP), a PX4 ULog or a folder of
KF-GINS text files (:func:`read_text_sources`) into one :class:`NavSources`: the IMU (:class:`~imunav.timeseries.ImuData`), GNSS fixes
(:class:`~imunav.io.gnss.GnssData`), wheel odometry (:class:`~imunav.io.aiding.OdometerData`),
magnetometer (:class:`~imunav.io.aiding.MagnetometerData`) and barometer
(:class:`~imunav.io.aiding.BaroData`), every one on the IMU's time origin (``t`` in s since
``NavSources.t0_ns``), in SI units and imunav frames (FRD body, NED world; ROS FLU / ENU converted at
the edge, see :mod:`imunav.io.logs`).

Choosing topics
---------------
:func:`nav_topics` lists the candidates of each role; :func:`choose_nav_topics` takes the one a user
names, else the only candidate.  With none, a role is absent (the IMU is required); with several, an
:class:`~imunav.errors.InvalidInputError` lists them with the option that chooses (``--gnss-topic``
...).  Candidates, by role:

=========  ==========================================  ===================================================
role       ROS message type                            PX4 ULog topic (the first present group)
=========  ==========================================  ===================================================
imu        ``sensor_msgs/Imu``                         ``sensor_combined``; else ``vehicle_imu`` instances
gnss       ``sensor_msgs/NavSatFix``                   ``vehicle_gps_position``; else ``sensor_gps``
odometer   ``nav_msgs/Odometry``; when the bag has     (none)
           none, ``geometry_msgs/TwistStamped``
mag        ``sensor_msgs/MagneticField``               ``vehicle_magnetometer``; else ``sensor_mag``
baro       ``sensor_msgs/FluidPressure``               ``vehicle_air_data``; else ``sensor_baro``
=========  ==========================================  ===================================================

PX4's ``vehicle_*`` topics are the estimator's own selection among the sensor instances, so they are
preferred to the raw ``sensor_*`` ones.

Conversions
-----------
* GNSS (:func:`gnss_fixes`): header stamps; position σ from the NavSatFix covariance (ENU diagonal →
  NED) or PX4's ``eph`` (north and east) and ``epv`` (down), as PX4's EKF2 uses them; PX4's ellipsoidal
  height when filled; PX4's NED velocity with σ ``s_variance_m_s`` when valid for every fix kept.
  Receiver faults are refused and counted in ``GnssData.meta["faults"]`` (and ``meta["removed"]``):
  fixes without a solution (``status.status < 0``, PX4 ``fix_type < 3``), non-finite or (0, 0)
  positions, covariance of unknown type (0) or not positive (unless ``gnss_pos_std`` is given: those
  fixes then take it and are counted as ``sigma_assumed``), duplicated stamps (the first kept) and stamps
  out of order (sorted).  Jumps are left to the filter's gate.
* Odometer: ``nav_msgs/Odometry`` ``twist.twist.linear.x``, the forward speed in the child frame
  (REP-105), σ the square root of ``twist.covariance[0]`` when every message gives one (> 0);
  ``geometry_msgs/TwistStamped``: ``twist.linear.x`` as published, no σ.
* Magnetometer: µT, body FRD.
* Barometer: ISA pressure altitude of the pressure (:func:`imunav.atmosphere.pressure_altitude`; its
  offset from the ellipsoid is a bias for the filter), σ from the pressure variance through
  ``dh/dp = −R T / (g₀ p)`` when every message gives one.
* Every aid is cut to the IMU's span (count in ``meta``); an aid whose stamps never overlap the IMU is
  refused.
* The IMU's mounting: a ROS bag's ``/tf_static`` chain from the base frame (the odometry's child frame,
  else ``base_link``) to the IMU's ``frame_id`` gives ``imu_to_base`` (rotation IMU FRD → base FRD) and
  ``imu_lever_base`` (the IMU's origin in the base frame, FRD, m).

KF-GINS text files
------------------
A folder holding :data:`TEXT_LOG_CONFIG` (``sources.toml``) is a log too: the TOML names the files and the
GPS week of their seconds of week::

    gps_week = 2314        # optional: without it the time is the files' own (not UTC)
    imu = "imu.txt"        # KF-GINS increments: s of week, dtheta x y z rad, dvel x y z m/s (body FRD)
    gnss = "gnss.txt"      # optional: s of week, lat lon deg, h m, sigma N E D m (KF-GINS GNSS text)
    odometer = "odo.txt"   # optional: s of week, forward speed m/s[, its sigma m/s]

The stamps are the seconds of week to the nanosecond (``round(sow · 1e9)``; as UTC with the week and the
leap seconds of the date), the IMU rates each increment over its interval (:func:`text_log_intervals`:
the step from the sample before; the first row's, the median step), the fixes and speeds go through the
same conversions as a bag's ``NavSatFix`` and ``Odometry`` (covariance of type DIAGONAL_KNOWN): the same
drive as a bag and as text gives the same sources.

Time
----
``t0_unix`` is the UTC time of the IMU's first stamp: ROS stamps when they are UTC (after 1980-01-06;
robots whose clock starts at boot are not), PX4 boot time shifted by the GNSS receiver's
``time_utc_usec``.  :meth:`NavSources.gps_time` turns times into GPS week and seconds of week
(:func:`imunav.io.gpstime.utc_to_gps`), or says they are not UTC.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.atmosphere import G0, R_AIR, isa, pressure_altitude
from imunav.errors import ConfigError, FileFormatError, InvalidInputError
from imunav.io import logs
from imunav.io.aiding import BaroData, MagnetometerData, OdometerData
from imunav.io.comma2k19 import is_comma2k19_segment, read_comma2k19
from imunav.io.gnss import GnssData, lat_lon_radians, read_table
from imunav.io.gpstime import GPS_EPOCH_UNIX, leap_seconds
from imunav.io.kfgins import read_kfgins_imu
from imunav.io.navinputs import read_odometer
from imunav.io.navsources import NavSources, SourceInfo
from imunav.io.rosbag import read_static_tf
from imunav.io.topics import TopicData, TopicInfo, log_kind, topic_data
from imunav.rotation import C_FLU_FRD, dcm_from_quat, quat_from_dcm
from imunav.timeseries import ImuData
from imunav.toml import read_toml

__all__ = ["ROLES", "FLAGS", "SourceInfo", "NavSources", "nav_topics", "choose_nav_topics", "read_nav_sources",
           "gnss_fixes", "TEXT_LOG_CONFIG", "is_text_log", "is_nav_log", "read_text_sources", "text_log_intervals"]

Array = NDArray[np.float64]

#: The roles of a navigation log's topics.
ROLES = ("imu", "gnss", "odometer", "mag", "baro")
#: CLI option choosing each role's topic.
FLAGS = {"imu": "--imu-topic", "gnss": "--gnss-topic", "odometer": "--odo-topic", "mag": "--mag-topic",
         "baro": "--baro-topic"}
_KW = {"imu": "imu_topic", "gnss": "gnss_topic", "odometer": "odo_topic", "mag": "mag_topic", "baro": "baro_topic"}
_WHAT = {"imu": "IMU", "gnss": "GNSS", "odometer": "odometry", "mag": "magnetometer", "baro": "barometer"}
#: Candidates by role, in groups: the first group with a topic in the log gives the candidates.
_ROS = {"imu": (("sensor_msgs/msg/Imu",),), "gnss": (("sensor_msgs/msg/NavSatFix",),),
        "odometer": (("nav_msgs/msg/Odometry",), ("geometry_msgs/msg/TwistStamped",)),
        "mag": (("sensor_msgs/msg/MagneticField",),), "baro": (("sensor_msgs/msg/FluidPressure",),)}
_ULOG = {"imu": (("sensor_combined",), ("vehicle_imu",)), "gnss": (("vehicle_gps_position",), ("sensor_gps",)),
         "odometer": (), "mag": (("vehicle_magnetometer",), ("sensor_mag",)),
         "baro": (("vehicle_air_data",), ("sensor_baro",))}


# -- topic choice --------------------------------------------------------------------------------
def _name(info: TopicInfo, multi: bool) -> str:
    return f"{info.topic}:{info.instance}" if multi and info.instance is not None else info.topic


def _candidates(infos: list[TopicInfo], ulog: bool) -> dict[str, list[TopicInfo]]:
    out: dict[str, list[TopicInfo]] = {}
    for role in ROLES:
        out[role] = []
        for group in (_ULOG if ulog else _ROS)[role]:
            found = [i for i in infos if (i.topic if ulog else i.msgtype) in group and i.count > 0]
            if found:
                out[role] = found
                break
    return out


def nav_topics(path: str | os.PathLike[str]) -> dict[str, list[TopicInfo]]:
    """The candidate topics of each role (module docstring), from the log's index.

    Parameters
    ----------
    path : str or os.PathLike
        ROS 1 ``.bag``, ROS 2 folder / ``.db3`` / ``.mcap``, or PX4 ``.ulg``.

    Returns
    -------
    dict of str to list of TopicInfo
        Role -> candidates (empty when none).

    Raises
    ------
    FileFormatError
        If the file is not a bag or a ULog.
    MissingDependencyError
        If ``rosbags`` / ``pyulog`` is not installed.
    """
    return _candidates(logs.list_topics(path), log_kind(path) == "ulog")


def choose_nav_topics(path: str | os.PathLike[str], *, imu_topic: str | None = None, gnss_topic: str | None = None,
                      odo_topic: str | None = None, mag_topic: str | None = None,
                      baro_topic: str | None = None) -> dict[str, TopicInfo | None]:
    """The topic of each role: the one named, else the only candidate, else None (the IMU is required).

    Parameters
    ----------
    path : str or os.PathLike
        The log.
    imu_topic, gnss_topic, odo_topic, mag_topic, baro_topic : str, optional
        The topic of a role (PX4: ``name`` or ``name:instance``); None: chosen automatically.

    Returns
    -------
    dict of str to TopicInfo or None
        Role -> the topic (its ``topic`` is ``name:instance`` for a PX4 topic with several instances).

    Raises
    ------
    FileFormatError
        If the log has no IMU topic.
    InvalidInputError
        If a role has several candidates and none is named (the message lists them and the option), or a
        named topic is not in the log or not of the role's type.
    """
    source = os.fspath(path)
    ulog = log_kind(path) == "ulog"
    infos = logs.list_topics(path)
    cands = _candidates(infos, ulog)
    given = {"imu": imu_topic, "gnss": gnss_topic, "odometer": odo_topic, "mag": mag_topic, "baro": baro_topic}
    out: dict[str, TopicInfo | None] = {}
    for role in ROLES:
        c = cands[role]
        multi = ulog and len({i.topic for i in c}) < len(c)
        names = [_name(i, multi) for i in c]
        want = given[role]
        if want is not None:
            allowed = [i for g in (_ULOG if ulog else _ROS)[role] for i in infos
                       if (i.topic if ulog else i.msgtype) in g]
            base, _, inst = want.rpartition(":") if ulog and ":" in want else (want, "", "")
            hit = [i for i in allowed if i.topic == base and (not inst or str(i.instance) == inst)]
            if len(hit) != 1:
                listed = ", ".join(_name(i, True) for i in allowed) or "none"
                raise InvalidInputError(f"{source}: {FLAGS[role]} {want!r}: not a {_WHAT[role]} topic of the log "
                                        f"({'ambiguous: give name:instance; ' if len(hit) > 1 else ''}"
                                        f"its {_WHAT[role]} topics: {listed})")
            out[role] = TopicInfo(want, hit[0].msgtype, hit[0].count, hit[0].instance, hit[0].duration_s,
                                  hit[0].rate_hz, hit[0].kind)
        elif len(c) == 1:
            out[role] = TopicInfo(names[0], c[0].msgtype, c[0].count, c[0].instance, c[0].duration_s, c[0].rate_hz,
                                  c[0].kind)
        elif not c:
            if role == "imu":
                listed = ", ".join(sorted({f"{i.topic} ({i.msgtype})" if not ulog else i.topic for i in infos}))
                raise FileFormatError(f"{source}: no IMU topic in the log (sensor_msgs/Imu, PX4 sensor_combined or "
                                      f"vehicle_imu); its topics: {listed or 'none'}")
            out[role] = None
        else:
            listed = ", ".join(f"{n} ({i.msgtype}, {i.count} msgs)" for n, i in zip(names, c, strict=True))
            raise InvalidInputError(f"{source}: {len(c)} {_WHAT[role]} topics: {listed}; choose one with "
                                    f"{FLAGS[role]} (or {_KW[role]}=)")
    return out


# -- conversions ---------------------------------------------------------------------------------
def _on_origin(td: TopicData, t0_ns: int) -> Array:
    """The topic's times in s since ``t0_ns`` (same clock)."""
    return (int(td.meta["t0_ns"]) - t0_ns) * 1e-9 + td.t


def gnss_fixes(td: TopicData, t0_ns: int, *, pos_std: ArrayLike | None = None) -> GnssData:
    """GNSS fixes of a ``gnss`` topic with receiver faults refused and counted (module docstring).

    Parameters
    ----------
    td : TopicData
        A ``gnss`` topic (``sensor_msgs/NavSatFix``, PX4 ``vehicle_gps_position`` / ``sensor_gps``).
    t0_ns : int
        Origin of the returned ``t`` on the log's clock, ns (the IMU's first stamp).
    pos_std : array_like, shape (3,) or (), optional
        σ north, east, down (m) for the fixes whose covariance is unknown or not positive; None: refuse them.

    Returns
    -------
    GnssData
        The usable fixes; ``meta["faults"]`` counts every refused or marked fix by reason, ``meta["removed"]``
        lists the removals, ``meta["t0_ns"]`` is ``t0_ns``.

    Raises
    ------
    InvalidInputError
        If no fix is usable (the message says why, and the options), or ``td`` is not a GNSS topic.
    """
    source = str(td.meta.get("source", "log"))
    if td.kind != "gnss":
        raise InvalidInputError(f"{source}: topic {td.topic!r} is {td.kind}, not GNSS fixes")
    v = td.values
    n = td.n
    lat = np.asarray(v["lat_deg"], dtype=np.float64)
    lon = np.asarray(v["lon_deg"], dtype=np.float64)
    alt = np.asarray(v["alt_m"], dtype=np.float64)
    height_ref = "ellipsoid (NavSatFix altitude)"
    if "alt_ellipsoid_m" in v and np.any(np.asarray(v["alt_ellipsoid_m"]) != 0):
        alt, height_ref = np.asarray(v["alt_ellipsoid_m"], dtype=np.float64), "ellipsoid (PX4 alt_ellipsoid)"
    elif "alt_ellipsoid_m" in v:
        height_ref = "mean sea level (PX4 alt; alt_ellipsoid not filled)"
    ros = "fix_status" in v
    if ros:
        no_fix = np.asarray(v["fix_status"]) < 0
        cov = np.asarray(v["pos_cov_enu_diag"], dtype=np.float64)
        with np.errstate(invalid="ignore"):
            std = np.sqrt(cov[:, [1, 0, 2]])  # ENU variances -> NED sigma
        unknown = np.asarray(v["pos_cov_type"]) == 0
    else:
        no_fix = np.asarray(v.get("fix_type", np.full(n, 3))) < 3
        eph = np.asarray(v.get("eph_m", np.full(n, np.nan)), dtype=np.float64)
        epv = np.asarray(v.get("epv_m", np.full(n, np.nan)), dtype=np.float64)
        std = np.column_stack([eph, eph, epv])
        unknown = np.zeros(n, dtype=bool)
    no_solution = ~no_fix & (~(np.isfinite(lat) & np.isfinite(lon) & np.isfinite(alt)) | ((lat == 0) & (lon == 0)))
    ok = ~no_fix & ~no_solution
    bad_sigma = ~unknown & ~np.all(np.isfinite(std) & (std > 0), axis=1)
    unknown, bad_sigma = unknown & ok, bad_sigma & ok
    faults = {"no_fix": int(no_fix.sum()), "no_solution": int(no_solution.sum()),
              "covariance_unknown": int(unknown.sum()), "covariance_not_positive": int(bad_sigma.sum()),
              "duplicate_stamp": int(td.meta.get("time", {}).get("duplicates_dropped", 0)),
              "out_of_order": int(td.meta.get("time", {}).get("out_of_order", 0)), "sigma_assumed": 0}
    removed = []
    if faults["no_fix"]:
        removed.append({"reason": "no fix" + (" (status.status < 0)" if ros else " (fix_type < 3)"),
                        "epochs": faults["no_fix"]})
    if faults["no_solution"]:
        removed.append({"reason": "no solution (non-finite or (0, 0) position)", "epochs": faults["no_solution"]})
    if faults["duplicate_stamp"]:
        removed.append({"reason": "duplicated stamp (the first kept)", "epochs": faults["duplicate_stamp"]})
    keep = ok.copy()
    no_sigma = unknown | bad_sigma
    if pos_std is not None:
        fill = np.broadcast_to(np.asarray(pos_std, dtype=np.float64), (3,))
        if not np.all(np.isfinite(fill) & (fill > 0)):
            raise InvalidInputError(f"gnss pos_std must be > 0 m (north, east, down); got {pos_std!r}")
        std = std.copy()
        std[no_sigma] = fill
        faults["sigma_assumed"] = int(no_sigma.sum())
    elif no_sigma.any():
        keep &= ~no_sigma
        removed.append({"reason": "covariance unknown or not positive", "epochs": int(no_sigma.sum())})
    where = f"{source}: GNSS topic {td.topic!r}"
    if not keep.any():
        why = ", ".join(f"{k.replace('_', ' ')}: {c}" for k, c in faults.items() if c and k != "sigma_assumed")
        hint = (" or give gnss_pos_std (a sigma for fixes without a covariance)" if no_sigma.any() and pos_std is None
                else "")
        raise InvalidInputError(f"{where}: none of its {n} fixes is usable ({why or 'no fix'}); choose another "
                                f"topic with --gnss-topic{hint}")
    vel = vstd = None
    notes = {}
    if "vel_ned" in v:
        vv = np.asarray(v["vel_ned"], dtype=np.float64)[keep]
        sv = np.asarray(v.get("speed_std", np.full(n, np.nan)), dtype=np.float64)[keep]
        valid = np.asarray(v.get("vel_ned_valid", np.ones(n)))[keep].astype(bool) & np.isfinite(sv) & (sv > 0) \
            & np.all(np.isfinite(vv), axis=1)
        if valid.all():
            vel, vstd = vv, np.repeat(sv[:, None], 3, axis=1)
        else:
            notes["velocity"] = (f"not used: {int((~valid).sum())} of the {int(keep.sum())} fixes kept have no valid "
                                 "velocity or speed sigma")
    t = _on_origin(td, t0_ns)[keep]
    meta = {"source": source, "topic": td.topic, "msgtype": td.meta.get("msgtype"), "t0_ns": int(t0_ns),
            "faults": faults, "removed": removed, "height": height_ref, **notes}
    return GnssData(t, np.column_stack([np.radians(lat[keep]), np.radians(lon[keep]), alt[keep]]), std[keep], vel,
                    vstd, meta)


def _span_cut(t: Array, t_end: float, role: str, topic: str, source: str) -> tuple[NDArray[np.bool_], dict[str, Any]]:
    """Samples inside the IMU span [0, t_end]; refuses a topic that never overlaps it."""
    inside = (t >= 0.0) & (t <= t_end)
    if not inside.any():
        raise InvalidInputError(
            f"{source}: {_WHAT[role]} topic {topic!r} spans {t[0]:.6g}..{t[-1]:.6g} s and the IMU 0..{t_end:.6g} s "
            f"(from the IMU's first stamp): they never overlap - choose another topic with {FLAGS[role]}"
        )
    return inside, {"cut_outside_imu_span": int((~inside).sum())}


def _rate(t: Array) -> float | None:
    return (t.size - 1) / float(t[-1] - t[0]) if t.size >= 2 and t[-1] > t[0] else None


def _odometer(td: TopicData, t0_ns: int, t_end: float, source: str) -> tuple[OdometerData, dict[str, Any]]:
    t = _on_origin(td, t0_ns)
    inside, meta = _span_cut(t, t_end, "odometer", td.topic, source)
    if td.kind == "odometry":
        speed = np.asarray(td.values["speed"], dtype=np.float64)
        var = np.asarray(td.values["speed_var"], dtype=np.float64)[inside]
        std = np.sqrt(var) if np.all(np.isfinite(var) & (var > 0)) else None
        meta["speed"] = f"twist.twist.linear.x in the child frame {td.meta.get('child_frame_id')!r} (REP-105)"
        meta["speed_std"] = "sqrt(twist.covariance[0])" if std is not None else \
            f"unknown (twist.covariance[0] <= 0 on {int((var <= 0).sum())} messages): the filter's sigma applies"
    elif td.kind == "gnss_velocity":
        speed = np.asarray(td.values["linear_raw"], dtype=np.float64)[:, 0]
        std = None
        meta["speed"] = f"twist.linear.x as published (frame {td.meta.get('frame_id')!r}); no covariance"
    else:
        raise InvalidInputError(f"{source}: topic {td.topic!r} is {td.kind}; odometry needs nav_msgs/Odometry or "
                                "geometry_msgs/TwistStamped")
    rate = td.values.get("rate_frd")
    yaw_rate = None if rate is None else np.asarray(rate, dtype=np.float64)[inside, 2]
    if yaw_rate is not None and not np.all(np.isfinite(yaw_rate)):
        meta["yaw_rate"] = (f"not used: twist.angular.z is not finite on {int((~np.isfinite(yaw_rate)).sum())} "
                            "messages (rest is then found from the speed alone)")
        yaw_rate = None
    elif yaw_rate is not None:
        meta["yaw_rate"] = "twist.angular.z, FLU -> FRD (sign flipped)"
    meta.update({"source": source, "topic": td.topic, "t0_ns": int(t0_ns)})
    return OdometerData(t[inside], speed[inside], dict(meta), std, yaw_rate), meta


def _baro(td: TopicData, t0_ns: int, t_end: float, source: str) -> tuple[BaroData, dict[str, Any]]:
    t = _on_origin(td, t0_ns)
    inside, meta = _span_cut(t, t_end, "baro", td.topic, source)
    p = np.asarray(td.values["pressure"], dtype=np.float64)[inside]
    h = pressure_altitude(p)
    std = None
    if "variance" in td.values:
        var = np.asarray(td.values["variance"], dtype=np.float64)[inside]
        if np.all(np.isfinite(var) & (var > 0)):
            std = np.sqrt(var) * R_AIR * isa(h).temperature / (G0 * p)  # |dh/dp| sigma_p
    meta.update({"source": source, "topic": td.topic, "t0_ns": int(t0_ns),
                 "height": "ISA pressure altitude (geopotential m) of the static pressure",
                 "height_std": "from the pressure variance" if std is not None else "unknown: the filter's sigma applies"})
    return BaroData(t[inside], h, dict(meta), std), meta


def _mag(td: TopicData, t0_ns: int, t_end: float, source: str) -> tuple[MagnetometerData, dict[str, Any]]:
    t = _on_origin(td, t0_ns)
    inside, meta = _span_cut(t, t_end, "mag", td.topic, source)
    meta.update({"source": source, "topic": td.topic, "t0_ns": int(t0_ns), "unit": "uT, body FRD"})
    return MagnetometerData(t[inside], np.asarray(td.values["mag"], dtype=np.float64)[inside], dict(meta)), meta


def _mounting(path: str | os.PathLike[str], imu_frame: str | None, base: str) -> tuple[Array | None, Array | None, str]:
    """(q IMU FRD -> base FRD, lever in base FRD, note) from the bag's /tf_static chain base -> IMU frame, or the
    identity when the IMU's frame_id is the base frame itself."""
    if imu_frame is None:
        return None, None, "the IMU topic has no frame_id"
    if imu_frame == base:
        return np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), (
            f"the IMU's frame_id is the base frame {base!r}: its values are in the vehicle's axes (REP-105), the "
            "identity; give --imu-rotation if the driver's frame_id is wrong")
    tfs = {tr.child: tr for tr in read_static_tf(path)}
    if not tfs:
        return None, None, "no /tf_static in the bag"
    c = np.eye(3)
    p = np.zeros(3)
    frame, seen = imu_frame, set()
    while frame != base:  # walk up from the IMU frame: x_parent = C x_child + p
        if frame not in tfs or frame in seen:
            return None, None, f"/tf_static has no chain from {base!r} to the IMU frame {imu_frame!r}"
        seen.add(frame)
        tr = tfs[frame]
        ci = dcm_from_quat(tr.q)
        c, p = ci @ c, ci @ p + tr.translation
        frame = tr.parent
    f = C_FLU_FRD  # ROS frames are FLU-like; imunav's FRD is the same flip in both frames
    return quat_from_dcm(f @ c @ f), f @ p, f"/tf_static chain {base} -> {imu_frame}"


# -- the reader ----------------------------------------------------------------------------------
def read_nav_sources(path: str | os.PathLike[str], *, imu_topic: str | None = None, gnss_topic: str | None = None,
                     odo_topic: str | None = None, mag_topic: str | None = None, baro_topic: str | None = None,
                     gnss_pos_std: ArrayLike | None = None, base_frame: str | None = None,
                     gyro: str | None = None) -> NavSources:
    """Read what feeds a navigation filter from a ROS bag, a PX4 ULog, a folder of KF-GINS text files or a
    comma2k19 segment (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        ROS 1 ``.bag``, ROS 2 folder / ``.db3`` / ``.mcap``, PX4 ``.ulg``, or a folder of KF-GINS text files
        (:func:`read_text_sources`), or a comma2k19 segment folder (:func:`imunav.io.comma2k19.read_comma2k19`).
    imu_topic, gnss_topic, odo_topic, mag_topic, baro_topic : str, optional
        The topic of each role; None: the only candidate (:func:`choose_nav_topics`).
    gnss_pos_std : array_like, shape (3,) or (), optional
        σ (m, north, east, down) given to GNSS fixes without a usable covariance; None: they are refused.
    base_frame : str, optional
        The vehicle frame of ``/tf_static`` (default: the odometry's child frame, else ``base_link``).
    gyro : {"calibrated", "raw"}, optional
        A comma2k19 segment's gyro (default calibrated); refused for other logs, whose IMU topic says.

    Returns
    -------
    NavSources
        Every source on the IMU's time origin.

    Raises
    ------
    FileFormatError
        If the log cannot be read or has no IMU topic.
    InvalidInputError
        If a role has several candidates and none is chosen, a named topic is absent, the GNSS topic has no
        usable fix, or an aid's stamps never overlap the IMU's (each a one-line message naming the option).
    MissingDependencyError
        If ``rosbags`` / ``pyulog`` is not installed.
    """
    source = os.fspath(path)
    named = [FLAGS[r] for r, v in (("imu", imu_topic), ("gnss", gnss_topic), ("odometer", odo_topic),
                                   ("mag", mag_topic), ("baro", baro_topic)) if v is not None]
    if is_comma2k19_segment(path):
        if named or base_frame is not None:
            raise InvalidInputError(f"{source}: a comma2k19 segment has one sensor of each kind; leave out "
                                    f"{', '.join(named) or 'base_frame'} (--gyro chooses the calibrated or raw gyro)")
        return read_comma2k19(path, gyro=gyro or "calibrated", gnss_pos_std=gnss_pos_std)
    if gyro is not None:
        raise InvalidInputError(f"{source}: --gyro chooses a comma2k19 segment's gyro; this log's IMU topic is "
                                "chosen with --imu-topic")
    if is_text_log(path):
        if named or base_frame is not None:
            raise InvalidInputError(f"{source}: a folder of KF-GINS text files names its files in {TEXT_LOG_CONFIG}; "
                                    f"leave out {', '.join(named) or 'base_frame'}")
        return read_text_sources(path, gnss_pos_std=gnss_pos_std)
    chosen = choose_nav_topics(path, imu_topic=imu_topic, gnss_topic=gnss_topic, odo_topic=odo_topic,
                               mag_topic=mag_topic, baro_topic=baro_topic)
    imu_info = chosen["imu"]
    assert imu_info is not None
    aid_topics = [info.topic for role, info in chosen.items() if role != "imu" and info is not None]
    if log_kind(path) == "rosbag":  # one pass over the bag for every topic
        tds = logs.read_topics(path, [imu_info.topic, *aid_topics])
        imu = logs.imu_from_topic(tds[imu_info.topic], source)
    else:
        tds = {}
        imu = logs.read_log_imu(path, topic=imu_info.topic)
    t0_ns = int(imu.meta["t0_ns"])
    t_end = float(imu.t[-1])
    topics = {"imu": SourceInfo("imu", imu_info.topic, imu_info.msgtype, imu_info.count, imu.n, _rate(imu.t))}
    meta: dict[str, Any] = {"imu": {"time": imu.meta.get("time"), "frame_id": imu.meta.get("frame_id")}}
    if "logger_dropouts" in imu.meta:
        meta["logger_dropouts"] = imu.meta["logger_dropouts"]
    aids: dict[str, Any] = {"gnss": None, "odometer": None, "mag": None, "baro": None}
    child: str | None = None
    utc_stamps = log_kind(path) == "rosbag" and t0_ns * 1e-9 >= GPS_EPOCH_UNIX
    t0_unix: float | None = t0_ns * 1e-9 if utc_stamps else None
    meta["time"] = ("header stamps in UTC" if utc_stamps else
                    "the log's clock is not UTC (before 1980-01-06: a clock counting from boot)")
    for role in ("gnss", "odometer", "mag", "baro"):
        info = chosen[role]
        if info is None:
            meta[role] = f"no {_WHAT[role]} topic in the log"
            continue
        td = tds[info.topic] if info.topic in tds else logs.read_topic(path, info.topic)
        if role == "odometer":
            child = td.meta.get("child_frame_id")
        aids[role], meta[role] = _aid(role, td, t0_ns, t_end, source, gnss_pos_std)
        if role == "gnss" and log_kind(path) == "ulog" and "time_utc_us" in td.values:
            off = _utc_offset_ns(td)
            t0_unix = None if off is None else (t0_ns + off) * 1e-9
            if off is not None:
                meta["utc_offset_ns"] = off
                meta["time"] = "PX4 boot time shifted to UTC by the receiver's time_utc_usec"
        data_t = aids[role].t
        topics[role] = SourceInfo(role, info.topic, info.msgtype, info.count, int(data_t.size), _rate(data_t))
    q_mount = lever = None
    if log_kind(path) == "rosbag":
        base = base_frame or child or "base_link"
        q_mount, lever, meta["mounting"] = _mounting(path, imu.meta.get("frame_id"), base)
    return NavSources(source, t0_ns, imu, aids["gnss"], aids["odometer"], aids["mag"], aids["baro"], topics,
                      t0_unix, q_mount, lever, meta)


def _aid(role: str, td: TopicData, t0_ns: int, t_end: float, source: str,
         gnss_pos_std: ArrayLike | None) -> tuple[Any, dict[str, Any]]:
    """One aid's data from its topic, on the IMU's origin and cut to its span, and what was refused or cut."""
    if role == "gnss":
        g = gnss_fixes(td, t0_ns, pos_std=gnss_pos_std)
        inside, cut = _span_cut(g.t, t_end, role, td.topic, source)
        g = g.select(inside, "outside the IMU span")
        return g, {"faults": g.meta["faults"], "removed": g.meta.get("removed", []), **cut}
    return {"odometer": _odometer, "mag": _mag, "baro": _baro}[role](td, t0_ns, t_end, source)


def _utc_offset_ns(td: TopicData) -> int | None:
    """UTC − boot time (ns) of a PX4 log, from the receiver's ``time_utc_usec`` (median over the fixes)."""
    utc = np.asarray(td.values["time_utc_us"], dtype=np.int64)
    ok = utc > int(GPS_EPOCH_UNIX * 1_000_000)
    if not ok.any():
        return None
    boot_ns = int(td.meta["t0_ns"]) + np.round(td.t[ok] * 1e9).astype(np.int64)
    return int(np.median(utc[ok] * 1000 - boot_ns))


# -- KF-GINS text files as a log -----------------------------------------------------------------
#: The file that makes a folder of KF-GINS text files a log (module docstring).
TEXT_LOG_CONFIG = "sources.toml"
_TEXT_KEYS = {"gps_week", "imu", "gnss", "odometer"}
_WEEK_NS = 604_800 * 1_000_000_000


def is_text_log(path: str | os.PathLike[str]) -> bool:
    """True for a folder holding :data:`TEXT_LOG_CONFIG` (a drive as KF-GINS text files).

    Parameters
    ----------
    path : str or os.PathLike
        Any path.

    Returns
    -------
    bool
        Whether :func:`read_nav_sources` reads it as KF-GINS text files.
    """
    return os.path.isfile(os.path.join(os.fspath(path), TEXT_LOG_CONFIG))


def is_nav_log(path: str | os.PathLike[str]) -> bool:
    """True for what :func:`read_nav_sources` reads: a bag, a ULog (:func:`imunav.io.topics.log_kind`), a folder
    of KF-GINS text files (:func:`is_text_log`) or a comma2k19 segment
    (:func:`imunav.io.comma2k19.is_comma2k19_segment`).

    Parameters
    ----------
    path : str or os.PathLike
        Any path.

    Returns
    -------
    bool
        Whether the path is a log.
    """
    return log_kind(path) is not None or is_text_log(path) or is_comma2k19_segment(path)


def text_log_intervals(t: ArrayLike) -> Array:
    """The interval of each IMU sample of a text log, s: the step from the sample before; the first row's, the
    median step.  The rates of the increments are ``increment / interval`` (and a writer's increments
    ``rate · interval``, so that the two round-trip).

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing sample times, s (N >= 2).

    Returns
    -------
    numpy.ndarray, shape (N,)
        The intervals, s.
    """
    d = np.diff(np.asarray(t, dtype=np.float64))
    return np.concatenate([[float(np.median(d))], d])


def _text_stamps(sow: Array, week: int | None) -> NDArray[np.int64]:
    """Integer-ns stamps of seconds of week: UTC since 1970 with the week (GPS − leap seconds of the date), else
    the seconds of week themselves."""
    ns = np.round(np.asarray(sow, dtype=np.float64) * 1e9).astype(np.int64)
    if week is None:
        return ns
    gps_ns = GPS_EPOCH_UNIX * 1_000_000_000 + week * _WEEK_NS + ns
    leap = leap_seconds(gps_ns * 1e-9 - leap_seconds(gps_ns * 1e-9))
    return gps_ns - leap * 1_000_000_000


def read_text_sources(folder: str | os.PathLike[str], *, gnss_pos_std: ArrayLike | None = None) -> NavSources:
    """A drive given as KF-GINS text files (module docstring), as the :class:`NavSources` of a log.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder holding :data:`TEXT_LOG_CONFIG` and the files it names (relative to the folder).
    gnss_pos_std : array_like, shape (3,) or (), optional
        As in :func:`read_nav_sources` (the files' σ must be > 0 otherwise).

    Returns
    -------
    NavSources
        Every source on the IMU's time origin; ``topics`` names the files.

    Raises
    ------
    ConfigError
        If ``sources.toml`` is missing, not valid TOML, has an unknown key, no ``imu`` or a week that is not a
        non-negative integer.
    FileFormatError, InvalidInputError
        From the KF-GINS readers (a file that is not KF-GINS text, time not increasing), or an aid that never
        overlaps the IMU.
    """
    d = os.fspath(folder)
    cfg_path = os.path.join(d, TEXT_LOG_CONFIG)
    cfg = read_toml(cfg_path, "KF-GINS sources")
    unknown = sorted(set(cfg) - _TEXT_KEYS)
    if unknown:
        raise ConfigError(f"{cfg_path}: unknown key(s) {unknown}; the keys are {sorted(_TEXT_KEYS)}")
    if not isinstance(cfg.get("imu"), str):
        raise ConfigError(f"{cfg_path}: imu = \"FILE\" (the KF-GINS IMU increments) is required")
    week = cfg.get("gps_week")
    if week is not None and (not isinstance(week, int) or isinstance(week, bool) or week < 0):
        raise ConfigError(f"{cfg_path}: gps_week must be a non-negative integer (the GPS week of the files' seconds "
                          f"of week); got {week!r}")
    for k in ("gnss", "odometer"):
        if k in cfg and not isinstance(cfg[k], str):
            raise ConfigError(f"{cfg_path}: {k} must be a file name; got {cfg[k]!r}")
    files = {k: os.path.join(d, cfg[k]) for k in ("imu", "gnss", "odometer") if k in cfg}
    inc = read_kfgins_imu(files["imu"])
    stamps = _text_stamps(inc.t, week)
    imu_td = topic_data(cfg["imu"], "imu", stamps, {}, {}, d)
    dt = text_log_intervals(imu_td.t)[:, None]
    imu = ImuData.from_arrays(imu_td.t, inc.dtheta / dt, inc.dvel / dt,
                              meta={**imu_td.meta, "format": "kf-gins increments",
                                    "rates": "increment / interval (imunav.io.navlog.text_log_intervals)"})
    t0_ns = int(imu_td.meta["t0_ns"])
    t_end = float(imu.t[-1])
    topics = {"imu": SourceInfo("imu", cfg["imu"], "KF-GINS IMU increments", inc.n, imu.n, _rate(imu.t))}
    meta: dict[str, Any] = {"imu": {"time": imu_td.meta.get("time"), "frame_id": None}}
    utc = week is not None and t0_ns * 1e-9 >= GPS_EPOCH_UNIX
    meta["time"] = (f"GPS week {week} and the files' seconds of week, as UTC" if utc else
                    "the files' seconds of week without a GPS week (gps_week in sources.toml): not UTC")
    aids: dict[str, Any] = {"gnss": None, "odometer": None, "mag": None, "baro": None}
    for role in ("gnss", "odometer"):
        if role not in files:
            meta[role] = f"no {_WHAT[role]} file in {TEXT_LOG_CONFIG}"
            continue
        td, what = _text_topic(role, files[role], cfg[role], week, d)
        aids[role], meta[role] = _aid(role, td, t0_ns, t_end, d, gnss_pos_std)
        if role == "odometer":
            meta[role]["speed"] = "the odometer file's forward speed"
        topics[role] = SourceInfo(role, cfg[role], what, td.n, int(aids[role].t.size), _rate(aids[role].t))
    return NavSources(d, t0_ns, imu, aids["gnss"], aids["odometer"], None, None, topics,
                      t0_ns * 1e-9 if utc else None, None, None, meta)


def _text_topic(role: str, path: str, name: str, week: int | None, folder: str) -> tuple[TopicData, str]:
    """A text file as the topic a bag would hold: GNSS as NavSatFix fields (status FIX, diagonal covariance
    known), the odometer as Odometry fields (speed, its variance or 0: unknown)."""
    if role == "gnss":
        a = read_table(path, (7, 13), "KF-GINS GNSS")
        lat_lon_radians(a[:, 1], a[:, 2], "deg", path)  # the unit check of the KF-GINS reader
        n = a.shape[0]
        std = a[:, 4:7] if a.shape[1] == 7 else a[:, 7:10]
        vals: dict[str, Any] = {"lat_deg": a[:, 1], "lon_deg": a[:, 2], "alt_m": a[:, 3],
                                "fix_status": np.zeros(n, dtype=np.int8),
                                "pos_cov_enu_diag": std[:, [1, 0, 2]] ** 2, "pos_cov_type": np.full(n, 2, np.uint8)}
        if a.shape[1] == 13:
            vals.update(vel_ned=a[:, 4:7], speed_std=np.max(a[:, 10:13], axis=1))
        return topic_data(name, "gnss", _text_stamps(a[:, 0], week), vals, {}, folder, duplicates="drop",
                          meta={"msgtype": "KF-GINS GNSS text"}), "KF-GINS GNSS text"
    o = read_odometer(path)
    var = np.zeros(o.t.size) if o.speed_std is None else o.speed_std**2
    return topic_data(name, "odometry", _text_stamps(o.t, week), {"speed": o.speed, "speed_var": var}, {}, folder,
                      meta={"msgtype": "odometer text"}), "odometer text (time, speed[, sigma])"
