"""Datasheet specification: loading a spec file and checking results against it."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.errors import ConfigError
from imunav.lab.report import check_spec, load_spec
from imunav.units import from_display


def test_spec_load_and_check(tmp_path):
    p = tmp_path / "spec.toml"
    p.write_text(
        '[spec.gyro_arw]\nmax = 0.3\nunit = "deg/sqrt(h)"\n'
        '[spec.accel_bias]\nmin = -50\nmax = 50\nunit = "ug"\n'
        '[spec.missing]\nmax = 1\n'
    )
    spec = load_spec(p)
    assert spec["gyro_arw"].max_si == pytest.approx(from_display(0.3, "deg/sqrt(h)"))
    arw_ok = from_display(0.25, "deg/sqrt(h)")
    res = {c.name: c for c in check_spec({"gyro_arw": (arw_ok, arw_ok * 0.1), "accel_bias": -from_display(60, "ug")}, spec)}
    assert res["gyro_arw"].passed is True
    assert res["accel_bias"].passed is False
    assert res["missing"].passed is False and np.isnan(res["missing"].value_si)
    # conservative: 0.25 + 1.96*0.05 = 0.348 > 0.3 fails
    cons = check_spec({"gyro_arw": (arw_ok, arw_ok * 0.2)}, {"gyro_arw": spec["gyro_arw"]}, conservative=True)
    assert cons[0].passed is False


def test_spec_errors(tmp_path):
    with pytest.raises(ConfigError, match="specification file not found"):
        load_spec(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[spec.x]\nmax = 1\nunit = 'furlongs'\n")
    with pytest.raises(ConfigError, match="spec.x"):
        load_spec(bad)
    with pytest.raises(ConfigError, match="min and/or max"):
        load_spec({"spec": {"x": {"unit": "ppm"}}})
    with pytest.raises(ConfigError, match="unknown keys"):
        load_spec({"x": {"max": 1, "maxx": 2}})
    with pytest.raises(ConfigError, match="not valid TOML"):
        (tmp_path / "t.toml").write_text("[spec\n")
        load_spec(tmp_path / "t.toml")
