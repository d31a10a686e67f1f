"""GPS time from a log's UTC stamps: GPS week and seconds of week, with the leap seconds of the date.

GPS time started at 1980-01-06 00:00:00 UTC and has no leap seconds; UTC has had them since, so
``GPS = UTC + n`` with ``n`` the leap seconds inserted between 1980 and the date (IERS Bulletin C; the
table below, the last at 2017-01-01: 16 s from 2012-07-01, 17 s from 2015-07-01, 18 s from 2017-01-01).
Stamps earlier than 1980-01-06 cannot be UTC (a robot whose clock starts at boot, PX4's boot time): they
are flagged, never converted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["GpsTime", "utc_to_gps", "leap_seconds", "GPS_EPOCH_UNIX", "LEAP_SECONDS"]

#: 1980-01-06T00:00:00Z in seconds since 1970 (the GPS epoch).
GPS_EPOCH_UNIX = 315_964_800
_WEEK = 604_800
#: (UTC date from which it holds, as seconds since 1970; GPS − UTC in s), oldest first.
LEAP_SECONDS: tuple[tuple[int, int], ...] = (
    (362_793_600, 1),    # 1981-07-01
    (394_329_600, 2),    # 1982-07-01
    (425_865_600, 3),    # 1983-07-01
    (489_024_000, 4),    # 1985-07-01
    (567_993_600, 5),    # 1988-01-01
    (631_152_000, 6),    # 1990-01-01
    (662_688_000, 7),    # 1991-01-01
    (709_948_800, 8),    # 1992-07-01
    (741_484_800, 9),    # 1993-07-01
    (773_020_800, 10),   # 1994-07-01
    (820_454_400, 11),   # 1996-01-01
    (867_715_200, 12),   # 1997-07-01
    (915_148_800, 13),   # 1999-01-01
    (1_136_073_600, 14),  # 2006-01-01
    (1_230_768_000, 15),  # 2009-01-01
    (1_341_100_800, 16),  # 2012-07-01
    (1_435_708_800, 17),  # 2015-07-01
    (1_483_228_800, 18),  # 2017-01-01
)
_LEAP_T = np.array([t for t, _ in LEAP_SECONDS], dtype=np.float64)
_LEAP_N = np.array([0] + [n for _, n in LEAP_SECONDS], dtype=np.int64)


def leap_seconds(unix_s: ArrayLike) -> NDArray[np.int64]:
    """GPS − UTC (s) at UTC times given in seconds since 1970.

    Parameters
    ----------
    unix_s : array_like
        UTC, s since 1970-01-01 (POSIX time).

    Returns
    -------
    numpy.ndarray of int64
        The leap-second count of each date (0 before 1981-07-01).
    """
    return _LEAP_N[np.searchsorted(_LEAP_T, np.asarray(unix_s, dtype=np.float64), side="right")]


@dataclass(frozen=True)
class GpsTime:
    """Log stamps as GPS time.

    Attributes
    ----------
    week : numpy.ndarray of int64, shape (N,)
        GPS week (0 where ``is_utc`` is False).
    sow : numpy.ndarray, shape (N,)
        Seconds of week, s (the stamps themselves where ``is_utc`` is False).
    leap_s : int
        GPS − UTC at the first stamp, s (0 when the stamps are not UTC).
    is_utc : bool
        False when the stamps lie before 1980-01-06: a clock counting from boot, not UTC.
    """

    week: NDArray[np.int64]
    sow: NDArray[np.float64]
    leap_s: int
    is_utc: bool


def utc_to_gps(t: ArrayLike, t0_ns: int = 0) -> GpsTime:
    """GPS week and seconds of week of UTC stamps ``t0_ns · 1e-9 + t`` (``GPS = UTC + leap seconds``).

    The integer origin keeps the result exact to float64 of ``t``: a UTC time of 1.7e9 s as one float64
    has a resolution of 0.24 µs, seconds of week 1e-10 s.

    Parameters
    ----------
    t : array_like, shape (N,)
        Stamps, s: since ``t0_ns`` (or since 1970-01-01 UTC with the default ``t0_ns = 0``).
    t0_ns : int
        Origin of ``t`` in ns since 1970-01-01 UTC (e.g. ``NavSources.t0_ns``).

    Returns
    -------
    GpsTime
        Week and seconds of week; when the first stamp lies before the GPS epoch the stamps are not UTC:
        ``is_utc`` is False, the week 0 and ``sow`` the stamps ``t0_ns · 1e-9 + t``.

    Examples
    --------
    >>> g = utc_to_gps([1_483_228_800.0])  # 2017-01-01T00:00:00Z
    >>> int(g.week[0]), float(g.sow[0]), g.leap_s
    (1930, 18.0, 18)
    """
    u = np.atleast_1d(np.asarray(t, dtype=np.float64))
    t0 = int(t0_ns)
    if u.size == 0 or t0 * 1e-9 + u[0] < GPS_EPOCH_UNIX:
        return GpsTime(np.zeros(u.size, dtype=np.int64), t0 * 1e-9 + u, 0, False)
    leap = leap_seconds(t0 * 1e-9 + u)
    base = t0 - GPS_EPOCH_UNIX * 1_000_000_000  # ns of the origin after the GPS epoch, UTC scale
    week0 = base // (_WEEK * 1_000_000_000)
    sow = (base - week0 * _WEEK * 1_000_000_000) * 1e-9 + u + leap
    carry = np.floor(sow / _WEEK).astype(np.int64)
    return GpsTime(week0 + carry, sow - carry * _WEEK, int(leap[0]), True)
