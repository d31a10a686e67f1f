"""The one result base (imunav.results.Result): strict JSON, atomic files, used by every result type."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import json
import pkgutil

import numpy as np
import pytest

import imunav
from imunav.filters import consistency_test
from imunav.results import Result


@dataclasses.dataclass(frozen=True)
class _Fit(Result):
    value: np.ndarray
    scale: float
    name: str


def test_to_dict_is_strict_json_and_to_json_writes_it(tmp_path):
    r = _Fit(np.array([[1.0, np.nan], [np.inf, -2.5]]), float("nan"), "x")
    d = r.to_dict()
    assert d == {"value": [[1.0, None], [None, -2.5]], "scale": None, "name": "x"}
    out = r.to_json(tmp_path / "sub" / "fit.json")
    text = out.read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert json.loads(text) == d
    assert sorted(p.name for p in out.parent.iterdir()) == ["fit.json"]  # no temporary file left behind


def test_a_failed_write_leaves_the_old_file(tmp_path):
    target = tmp_path / "fit.json"
    target.write_text("old")

    @dataclasses.dataclass(frozen=True)
    class Bad(Result):
        def to_dict(self):
            raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        Bad().to_json(target)
    assert target.read_text() == "old"


def test_package_results_serialise_through_the_base(tmp_path):
    # a real result: the consistency result of the filters, NaN-free arrays, tuple and bool fields
    c = consistency_test(np.random.default_rng(0).chisquare(2, (20, 50)), 2)
    back = json.loads(c.to_json(tmp_path / "c.json").read_text())
    assert back["dof"] == 2 and back["n_runs"] == 20 and isinstance(back["passed"], bool)
    np.testing.assert_array_equal(back["mean_per_step"], c.mean_per_step)


def _package_dataclasses():
    """Every dataclass defined in the package (CLI modules aside), by qualified name."""
    found = {}
    for mod in pkgutil.walk_packages(imunav.__path__, "imunav."):
        if ".cli" in mod.name or mod.name.endswith("__main__"):
            continue
        try:
            m = importlib.import_module(mod.name)
        except ImportError:  # optional extras (torch, rosbags, ...) absent
            continue
        for name, obj in inspect.getmembers(m, inspect.isclass):
            if obj.__module__ == m.__name__ and dataclasses.is_dataclass(obj):
                found[f"{m.__name__}.{name}"] = obj
    return found


def _result_classes():
    return {k: c for k, c in _package_dataclasses().items() if k.endswith("Result")}


def test_every_result_dataclass_derives_from_the_base():
    found = _result_classes()
    assert len(found) >= 15  # the walk did find the package's results
    missing = sorted(k for k, c in found.items() if not issubclass(c, Result))
    assert not missing, f"result dataclasses without imunav.results.Result: {missing}"


def test_every_attitude_track_has_the_one_euler_method():
    """Every dataclass holding ``q_nb`` (results, states, trajectories) gets ``euler()`` from EulerMixin."""
    from imunav.results import EulerMixin
    from imunav.rotation import euler_from_quat

    with_q = {k: c for k, c in _package_dataclasses().items() if "q_nb" in {f.name for f in dataclasses.fields(c)}}
    assert {"imunav.attitude.result.AttitudeResult", "imunav.ins.zupt.filter.ZuptResult",
            "imunav.ins.gins.result.GinsResult"} <= set(with_q)
    missing = sorted(k for k, c in with_q.items() if not issubclass(c, EulerMixin))
    assert not missing, f"dataclasses with q_nb but without EulerMixin.euler: {missing}"

    @dataclasses.dataclass(frozen=True)
    class Track(EulerMixin, Result):
        q_nb: np.ndarray

    q = np.random.default_rng(3).normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    np.testing.assert_array_equal(Track(q).euler(), euler_from_quat(q))
