"""Wind triangle."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.airdata import wind as wd
from imunav.errors import InvalidInputError, ShapeError


def test_wind_triangle():
    # wind from the west at 20 m/s (blowing east), course north, TAS 100
    wn, we = wd.wind_from_speed_direction(20.0, np.deg2rad(270.0))
    assert wn == pytest.approx(0.0, abs=1e-12) and we == pytest.approx(20.0)
    hdg, gs = wd.heading_for_course(100.0, 0.0, wn, we)
    assert np.rad2deg(hdg) == pytest.approx(360 - np.rad2deg(np.arcsin(0.2)))
    assert gs == pytest.approx(np.sqrt(100**2 - 20**2))
    wn2, we2 = wd.wind_from_speeds(100.0, hdg, gs, 0.0)
    assert (wn2, we2) == (pytest.approx(0.0, abs=1e-9), pytest.approx(20.0))
    spd, frm = wd.wind_speed_direction(wn2, we2)
    assert spd == pytest.approx(20.0) and np.rad2deg(frm) == pytest.approx(270.0)
    assert np.rad2deg(wd.drift_angle(hdg, 0.0)) == pytest.approx(np.rad2deg(np.arcsin(0.2)))
    vg = np.array([[100.0, 20.0, 0.0]])
    np.testing.assert_allclose(wd.wind_from_velocities(vg, [[100.0, 0.0, 0.0]]), [[0.0, 20.0, 0.0]])
    with pytest.raises(InvalidInputError, match="crosswind component exceeds"):
        wd.heading_for_course(10.0, 0.0, 0.0, 20.0)
    with pytest.raises(ShapeError, match="same shape"):
        wd.wind_from_velocities(np.zeros(3), np.zeros(2))
