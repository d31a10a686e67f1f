"""One vocabulary: every public configuration class names its fields by the naming table (imunav.vocabulary).

The classes are discovered, not listed: every dataclass named ``*Config`` defined in a public module of the
package (no ``_private`` part in its dotted name).  A class added tomorrow is checked without touching this file.
"""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from dataclasses import dataclass

import pytest

import imunav
from imunav.vocabulary import NAMING_TABLE, RENAMED_FIELDS, check_config_class, check_field_name, renamed_hint


def _public_config_classes() -> list[type]:
    found: dict[str, type] = {}
    for info in pkgutil.walk_packages(imunav.__path__, "imunav."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if (isinstance(obj, type) and name.endswith("Config") and not name.startswith("_")
                    and obj.__module__ == mod.__name__ and dataclasses.is_dataclass(obj)):
                found[f"{obj.__module__}.{name}"] = obj
    return [found[k] for k in sorted(found)]


CONFIGS = _public_config_classes()


def test_discovery_finds_the_configuration_classes():
    names = {c.__name__ for c in CONFIGS}
    # the classes of issue 25's survey: a discovery that lost one of them would check nothing about it
    assert {"GinsConfig", "MekfConfig", "UkfConfig", "GravityKfConfig", "ZuptConfig", "LstmConfig",
            "BodyWindFilterConfig", "LongHorizonConfig", "FlightConfig", "LabConfig", "KfGinsConfig"} <= names


@pytest.mark.parametrize("cls", CONFIGS, ids=lambda c: c.__name__)
def test_configuration_fields_follow_the_naming_table(cls):
    assert check_config_class(cls) == []


@dataclass(frozen=True)
class _OldStyleConfig:
    sigma_gyro: float = 0.005  # a density in one class, a per-sample σ in another: the name issue 25 removed
    arw: float = 1e-3
    p0_att: float = 0.1
    acc_lpf_tau: float = 0.0
    odo_noise: float = 0.05
    gyro_bias_rw: float = 1e-5
    noise: object = None


def test_the_check_fails_on_names_that_break_the_table():
    problems = check_config_class(_OldStyleConfig)
    for field in ("sigma_gyro", "arw", "p0_att", "acc_lpf_tau", "odo_noise", "gyro_bias_rw"):
        assert any(f"'{field}'" in p for p in problems), field
    assert any("'noise'" in p and "Any" not in p for p in problems)
    # the same check passes the renamed fields: it is the names that fail, not any field
    for good in ("gyro_noise_density", "gyro_noise_std", "init_att_std", "accel_lpf_time_constant", "odo_noise_std",
                 "gyro_bias_random_walk", "wind_corr_time", "corr_time", "alpha_noise_std_deg", "rest_gyro_threshold",
                 "init_wind_var", "g"):
        assert check_field_name(good) == [], good


def test_the_check_fails_on_a_field_typed_any():
    from typing import Any

    @dataclass
    class Loose:
        gyro_noise_density: Any = 0.0

    assert check_config_class(Loose) == ["Loose.'gyro_noise_density': typed 'Any'; give it a type without Any"]


def test_each_pattern_of_the_table_passes_its_examples():
    for rule in NAMING_TABLE:
        for example in rule.examples:
            cls_name, field = example.split(".")
            assert check_field_name(field) == [], example
            cls = next(c for c in CONFIGS if c.__name__ == cls_name)
            assert field in {f.name for f in dataclasses.fields(cls)}, example


def test_the_renamed_table_names_fields_that_exist_and_old_names_that_do_not():
    by_name = {c.__name__: {f.name for f in dataclasses.fields(c)} for c in CONFIGS}
    for cls_name, table in RENAMED_FIELDS.items():
        for old, new in table.items():
            assert new in by_name[cls_name], f"{cls_name}.{new}"
            assert old not in by_name[cls_name], f"{cls_name}.{old}"
    assert renamed_hint("GinsConfig", ["arw", "bogus"]) == " (renamed: arw -> gyro_noise_density)"
    assert renamed_hint("GinsConfig", ["bogus"]) == ""
