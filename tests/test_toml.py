"""``imunav.toml``: the one TOML writer and reader of the package."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from imunav.errors import ConfigError
from imunav.toml import read_toml, toml_text


def test_round_trip_of_python_and_numpy_values(tmp_path):
    """numpy scalars and arrays (what a result or a configuration holds) are written as the Python values they
    hold: a TOML reader gives back the same numbers, with their types."""
    d = {"n": np.int64(3), "x": np.float64(0.1), "ok": np.bool_(True), "v": np.array([1.5, -2.0, np.inf]),
         "m": np.arange(4).reshape(2, 2), "name": 'a "quoted"\nline', "t": {"k": np.int32(-7), "f": 1e-300}}
    text = toml_text(d)
    back = tomllib.loads(text)
    assert back["n"] == 3 and isinstance(back["n"], int)
    assert back["x"] == 0.1 and isinstance(back["x"], float)
    assert back["ok"] is True
    assert back["v"][:2] == [1.5, -2.0] and math.isinf(back["v"][2])
    assert back["m"] == [[0, 1], [2, 3]]
    assert back["name"] == d["name"]
    assert back["t"] == {"k": -7, "f": 1e-300}
    p = tmp_path / "c.toml"
    p.write_text(text, encoding="utf-8")
    assert read_toml(p)["t"]["k"] == -7


def test_a_value_toml_cannot_hold_is_refused():
    with pytest.raises(TypeError, match="t.x: cannot write NoneType"):
        toml_text({"t": {"x": None}})


def test_reader_messages(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        read_toml(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("x = [1,\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="not valid TOML"):
        read_toml(tmp_path / "bad.toml")
