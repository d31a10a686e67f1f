"""GPS time from UTC stamps: leap seconds of the date, the not-UTC flag (imunav.io.gpstime)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from imunav.io.gpstime import GPS_EPOCH_UNIX, leap_seconds, utc_to_gps


def _unix(iso: str) -> float:
    return dt.datetime.fromisoformat(iso).replace(tzinfo=dt.timezone.utc).timestamp()


@pytest.mark.parametrize(("iso", "leap"), [
    ("2014-03-01T12:00:00", 16), ("2015-06-30T23:59:59", 16), ("2015-07-01T00:00:00", 17),
    ("2016-12-31T23:59:59", 17), ("2017-01-01T00:00:00", 18), ("2024-05-14T09:30:00", 18),
])
def test_leap_seconds_of_the_date(iso, leap):
    assert int(leap_seconds(_unix(iso))) == leap
    assert utc_to_gps([_unix(iso)]).leap_s == leap


def test_week_and_seconds_of_week():
    # 2017-01-01T00:00:00Z (a Sunday) starts GPS week 1930; GPS is 18 s ahead
    g = utc_to_gps([_unix("2017-01-01T00:00:00"), _unix("2017-01-01T00:00:00") + 0.25])
    assert g.is_utc and g.week.tolist() == [1930, 1930]
    np.testing.assert_allclose(g.sow, [18.0, 18.25], atol=1e-6)
    # the GPS epoch itself is week 0, second 0
    g0 = utc_to_gps([float(GPS_EPOCH_UNIX)])
    assert g0.week[0] == 0 and g0.sow[0] == 0.0 and g0.leap_s == 0
    # a week boundary: 2024-05-11T23:59:42Z UTC is GPS 2024-05-12T00:00:00 = start of week 2314
    g1 = utc_to_gps([_unix("2024-05-11T23:59:42"), _unix("2024-05-11T23:59:41")])
    assert g1.week.tolist() == [2314, 2313]
    assert g1.sow[0] == pytest.approx(0.0, abs=1e-6) and g1.sow[1] == pytest.approx(604799.0, abs=1e-6)


def test_clock_from_boot_is_not_utc():
    g = utc_to_gps([47.58, 48.0])
    assert not g.is_utc and g.week.tolist() == [0, 0] and g.leap_s == 0
    np.testing.assert_array_equal(g.sow, [47.58, 48.0])


def test_integer_origin_keeps_the_nanoseconds():
    # one float64 of 1.7e9 s resolves 0.24 us; the integer origin keeps the seconds of week to float64 of t
    t0_ns = 1_715_679_000 * 1_000_000_000 + 123_456_789
    g = utc_to_gps([0.15, 400.35], t0_ns)
    sow0 = 2 * 86400 + 9.5 * 3600 + 18 + 0.123456789
    np.testing.assert_allclose(g.sow, [sow0 + 0.15, sow0 + 400.35], rtol=0, atol=1e-9)
    assert g.week.tolist() == [2314, 2314]
