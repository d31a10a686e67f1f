"""The sources of a navigation filter read from a log, on the IMU's time origin: :class:`NavSources` and the
:class:`SourceInfo` of each role (the readers are :mod:`imunav.io.navlog` and :mod:`imunav.io.comma2k19`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError
from imunav.io.aiding import BaroData, MagnetometerData, OdometerData
from imunav.io.gnss import GnssData
from imunav.io.gpstime import GPS_EPOCH_UNIX, GpsTime, utc_to_gps
from imunav.timeseries import ImuData

__all__ = ["SourceInfo", "NavSources"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SourceInfo:
    """One topic feeding the filter.

    Attributes
    ----------
    role : str
        ``imu``, ``gnss``, ``odometer``, ``mag`` or ``baro``.
    topic : str
        Topic name (PX4: ``name`` or ``name:instance``).
    msgtype : str
        Message type (PX4: the topic name).
    count : int
        Messages in the log.
    used : int
        Samples kept (after the faults refused and the cut to the IMU span).
    rate_hz : float or None
        Mean rate of the messages kept, Hz.
    """

    role: str
    topic: str
    msgtype: str
    count: int
    used: int
    rate_hz: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict.

        Returns
        -------
        dict
            The attributes by name.
        """
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class NavSources:
    """Everything a log holds for a navigation filter, on the IMU's time origin.

    Attributes
    ----------
    source : str
        The log.
    t0_ns : int
        The IMU's first stamp on the log's clock, ns (since 1970 for UTC stamps, since boot otherwise);
        every ``t`` below is in s since it.
    imu : ImuData
        Body FRD, SI.
    gnss, odometer, mag, baro : GnssData, OdometerData, MagnetometerData, BaroData, or None
        The aids, None when the log has no such topic.
    topics : dict of str to SourceInfo
        The topic used for each role present.
    t0_unix : float or None
        UTC of ``t0_ns``, s since 1970 (None when the log's clock is not UTC and no receiver gives UTC).
    imu_to_base : numpy.ndarray, shape (4,), or None
        Rotation from the IMU's FRD frame to the vehicle base's FRD frame, Hamilton scalar-first, from the
        bag's ``/tf_static`` (None without one).
    imu_lever_base : numpy.ndarray, shape (3,), or None
        The IMU's origin in the base frame, FRD, m (with ``imu_to_base``).
    meta : dict
        Per role: faults counted, samples cut, notes (``"gnss": "no GNSS topic in the log"`` ...).
    """

    source: str
    t0_ns: int
    imu: ImuData
    gnss: GnssData | None
    odometer: OdometerData | None
    mag: MagnetometerData | None
    baro: BaroData | None
    topics: dict[str, SourceInfo]
    t0_unix: float | None = None
    imu_to_base: Array | None = None
    imu_lever_base: Array | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def utc_t0_ns(self) -> int:
        """UTC of ``t0_ns`` in integer ns since 1970 (``t0_ns`` itself for UTC stamps; PX4: shifted by the
        receiver's offset, to the ns); raises when the time is not UTC."""
        if self.t0_unix is None:
            raise InvalidInputError(f"{self.source}: the log's time is not UTC")
        return int(self.meta.get("utc_offset_ns", 0)) + self.t0_ns

    @property
    def time_is_utc(self) -> bool:
        """True when the stamps are UTC (``t0_unix`` known and after 1980-01-06)."""
        return self.t0_unix is not None and self.t0_unix >= GPS_EPOCH_UNIX

    def gps_time(self, t: ArrayLike) -> GpsTime:
        """GPS week and seconds of week of times ``t`` (s since ``t0_ns``).

        Parameters
        ----------
        t : array_like, shape (N,)
            Times on the sources' origin, s.

        Returns
        -------
        GpsTime
            With ``is_utc`` False (week 0, ``sow`` the log's own time ``t0_ns·1e-9 + t``) when the stamps
            are not UTC.
        """
        ta = np.atleast_1d(np.asarray(t, dtype=np.float64))
        if not self.time_is_utc:
            return GpsTime(np.zeros(ta.size, dtype=np.int64), self.t0_ns * 1e-9 + ta, 0, False)
        return utc_to_gps(ta, self.utc_t0_ns)

    def to_dict(self) -> dict[str, Any]:
        """What a run's summary reports about its inputs (JSON-ready).

        Returns
        -------
        dict
            ``source``, ``t0_unix``, ``time_is_utc``, ``sources`` (per role: topic, type, count, used,
            rate), ``imu_to_base``, ``imu_lever_base`` and the per-role ``meta``.
        """
        return {"source": self.source, "t0_unix": self.t0_unix, "time_is_utc": self.time_is_utc,
                "sources": {k: v.to_dict() for k, v in self.topics.items()},
                "imu_to_base": None if self.imu_to_base is None else self.imu_to_base.tolist(),
                "imu_lever_base": None if self.imu_lever_base is None else self.imu_lever_base.tolist(),
                "meta": self.meta}
