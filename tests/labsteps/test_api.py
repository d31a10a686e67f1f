"""LabContext.step_options: the one check of a lab step's option table (unknown keys, positive numbers)."""

from __future__ import annotations

import pytest

from imunav.errors import ConfigError
from imunav.lab.steps._api import LabContext

_DEFAULTS = {"fs": 100.0, "dwell_s": 30.0, "figures": True}


def _ctx(tmp_path, table):
    return LabContext(out_dir=tmp_path, seed=0, progress=None, config={"noise": table}, step="noise")


def test_given_options_override_the_defaults_and_the_rest_stay(tmp_path):
    opts = _ctx(tmp_path, {"fs": 50}).step_options(_DEFAULTS, positive=("fs", "dwell_s"))
    assert opts == {"fs": 50, "dwell_s": 30.0, "figures": True}
    assert _DEFAULTS["fs"] == 100.0  # the defaults are not changed


def test_unknown_option_is_named_with_the_step_and_the_allowed_ones(tmp_path):
    with pytest.raises(ConfigError, match=r"^\[noise\]: unknown option\(s\) \['colour'\]; allowed: \['dwell_s', 'figures', 'fs'\]$"):
        _ctx(tmp_path, {"colour": 1}).step_options(_DEFAULTS)


@pytest.mark.parametrize("bad", [0, -1.5, "10", None])
def test_positive_options_refuse_zero_negative_and_non_numbers(tmp_path, bad):
    with pytest.raises(ConfigError, match=rf"^\[noise\] dwell_s must be a positive number, got {bad!r}$"):
        _ctx(tmp_path, {"dwell_s": bad}).step_options(_DEFAULTS, positive=("fs", "dwell_s"))
    # an option not listed as positive is not checked
    assert _ctx(tmp_path, {"figures": 0}).step_options(_DEFAULTS, positive=("fs",))["figures"] == 0
