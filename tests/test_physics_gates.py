"""Physics and geometry gates (issue 16, item 5): out-of-range inputs are refused, not computed."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.errors import DegenerateGeometryError, InvalidInputError


@pytest.mark.parametrize("lat_deg,h", [(100.0, 0.0), (-90.5, 0.0), (45.0, 1e12), (45.0, -2e4), (45.0, 1.5e5)])
def test_earth_refuses_out_of_range_lat_h(lat_deg, h):
    with pytest.raises(InvalidInputError):
        earth.normal_gravity(np.radians(lat_deg), h)
    with pytest.raises(InvalidInputError):
        earth.gravity_ned(np.radians(lat_deg), h)


def test_earth_rate_refuses_latitude_beyond_pole():
    with pytest.raises(InvalidInputError, match="latitude"):
        earth.earth_rate_ned(np.radians(100.0))


@pytest.mark.parametrize("lat_deg,h", [(90.0, 0.0), (-90.0, 0.0), (0.0, -1e4), (45.0, 1e5)])
def test_earth_accepts_the_range_ends(lat_deg, h):
    assert 9.0 < earth.normal_gravity(np.radians(lat_deg), h) < 10.0


def test_cli_simulate_refuses_bad_latitude_and_height(tmp_path):
    from typer.testing import CliRunner

    from imunav.cli.main import app

    for extra in (["--lat-deg", "100"], ["--lat-deg", "45", "--h-m", "1e12"]):
        r = CliRunner().invoke(app, ["simulate", "static", "--duration", "2", "--out", str(tmp_path / "s.csv"), *extra])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert not (tmp_path / "s.csv").exists()


def _mag_degenerate():
    rng = np.random.default_rng(0)
    point = np.tile([20.0, -5.0, 40.0], (200, 1))
    t = rng.uniform(-1, 1, 200)
    line = np.outer(t, [1.0, 2.0, 0.5]) * 30 + [3, 4, 5]
    ang = rng.uniform(0, 2 * np.pi, 200)
    plane = np.c_[30 * np.cos(ang), 30 * np.sin(ang), np.zeros(200)] + [1, 2, 3]
    return {"point": point, "line": line, "plane": plane}


@pytest.mark.parametrize("kind", ["point", "line", "plane"])
def test_minmax_refuses_degenerate_geometry(kind):
    from imunav.calib.magnetometer import hard_iron_minmax

    with pytest.raises(DegenerateGeometryError):
        hard_iron_minmax(_mag_degenerate()[kind])


def test_minmax_accepts_a_sphere():
    from imunav.calib.magnetometer import hard_iron_minmax

    rng = np.random.default_rng(1)
    u = rng.normal(size=(500, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    assert np.allclose(hard_iron_minmax(30 * u + [5, -3, 2]), [5, -3, 2], atol=1.0)


@pytest.mark.parametrize("kind", ["point", "line", "plane"])
def test_cli_minmax_degenerate_is_an_error_not_nan(tmp_path, kind):
    from typer.testing import CliRunner

    from imunav.cli.main import app

    np.savez(tmp_path / "m.npz", mag=_mag_degenerate()[kind])
    r = CliRunner().invoke(app, ["calibrate", "mag", str(tmp_path / "m.npz"), "--method", "minmax",
                                 "--out", str(tmp_path / "c.json")])
    assert r.exit_code == 2 and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "c.json").exists()
