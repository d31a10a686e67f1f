"""Unit conversions at the edge and IEEE-952 display units."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imunav import units as U
from imunav.errors import InvalidInputError, MissingDependencyError, UnitError


def test_edge_conversions():
    np.testing.assert_allclose(U.to_si([180.0], "deg/s", "gyro"), [math.pi])
    np.testing.assert_allclose(U.to_si(1.0, "g", "accel"), 9.80665)
    np.testing.assert_allclose(U.to_si(60.0, "rpm", "angular_rate"), 2 * math.pi)
    np.testing.assert_allclose(U.to_si(250.0, "ms", "time"), 0.25)
    # raw counts: +-2 g on 16 bits -> 16384 LSB/g
    np.testing.assert_allclose(U.to_si(16384, "counts", "accel", scale=U.G0 / 16384), U.G0)
    np.testing.assert_allclose(U.to_si(110, "counts", "accel", scale=2.0, offset=10), 200.0)
    np.testing.assert_allclose(U.from_si(U.to_si(3.0, "kn", "velocity"), "kn", "velocity"), 3.0)


def test_display_units_worked_values():
    # 1 deg/sqrt(h) = (pi/180)/60 rad/sqrt(s) = 2.9089e-4 rad/sqrt(s)
    assert U.from_display(1.0, "deg/sqrt(h)") == pytest.approx(math.pi / 180 / 60, rel=1e-15)
    # 1 deg/h bias = 4.8481e-6 rad/s
    assert U.from_display(1.0, "°/h") == pytest.approx(4.84813681109536e-06, rel=1e-12)
    # rate random walk 1 deg/h/sqrt(h) = (pi/180)/3600/60 rad/s/sqrt(s)
    assert U.from_display(1.0, "deg/h/sqrt(h)") == pytest.approx(math.pi / 180 / 3600 / 60, rel=1e-15)
    # 1 m/s/sqrt(h) VRW = 1/60 m/s/sqrt(s)
    assert U.from_display(1.0, "m/s/sqrt(h)") == pytest.approx(1 / 60, rel=1e-15)
    assert U.to_display(U.G0 * 1e-6, "µg") == pytest.approx(1.0, rel=1e-15)
    assert U.to_display(1e-6, "ppm") == pytest.approx(1.0)
    assert U.to_display(1e-3, "mrad") == pytest.approx(1.0)
    x = np.array([1e-4, 2e-4])
    np.testing.assert_allclose(U.from_display(U.to_display(x, "deg/h"), "deg/h"), x, rtol=1e-15)


def test_unit_errors_are_clear():
    with pytest.raises(UnitError, match="unknown unit 'furlong/s' for angular_rate; accepted"):
        U.to_si(1.0, "furlong/s", "gyro")
    with pytest.raises(UnitError, match="needs a finite, non-zero scale"):
        U.to_si(1.0, "counts", "accel")
    with pytest.raises(UnitError, match="only used with unit='counts'"):
        U.to_si(1.0, "g", "accel", scale=2.0)
    with pytest.raises(UnitError, match="unknown quantity"):
        U.to_si(1.0, "m", "colour")
    with pytest.raises(UnitError, match="unknown display unit"):
        U.to_display(1.0, "deg/fortnight")
    assert issubclass(UnitError, InvalidInputError) and issubclass(UnitError, ValueError)


def test_missing_dependency_message():
    e = MissingDependencyError("torch", "learn", "Training the LSTM detector")
    assert "pip install 'imunav[learn]'" in str(e) and isinstance(e, ImportError)
