"""The air-data flight file: written and read back unchanged, and scored the same either way."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.airdata.flightfile import read_flight_file, simulate_flight_file, wind_errors, write_flight_file
from imunav.airdata.scenario import WindScenario
from imunav.errors import FileFormatError


def test_thesis_file_round_trip_and_wind_errors(tmp_path):
    made = simulate_flight_file(WindScenario(kind="outliers"), seed=3)
    path = write_flight_file(tmp_path / "th.npz", made)
    back = read_flight_file(path)
    assert back.kind == "thesis" and back.meta == made.meta and back.source == str(path)
    assert sorted(back.arrays) == sorted(made.arrays)
    assert all(np.array_equal(back.arrays[k], made.arrays[k]) for k in made.arrays)
    assert back.summary(path) == {"file": str(path), "type": "thesis", "kind": "outliers",
                                  "steps": made.arrays["t"].size, "seed": 3}
    run = wind_errors(back, robust="nis")
    assert run.summary == wind_errors(made, robust="nis").summary
    assert run.summary["robust"] == "nis" and wind_errors(back).summary["robust"] == "none"
    # the χ² gate rejects the injected outliers: the wind stays well below the difference loop's error
    assert max(run.summary["wind_rms_per_axis"]) < 0.5 * min(run.summary["difference_loop_rms_per_axis"])
    assert run.summary["rejected_samples"] > 0


def test_a_file_that_is_not_a_flight_file_is_refused(tmp_path):
    bad = tmp_path / "x.npz"
    np.savez(bad, a=np.zeros(3))
    with pytest.raises(FileFormatError, match="no 'meta' entry"):
        read_flight_file(bad)
    np.savez(bad, meta=np.array('{"type": "boat"}'))
    with pytest.raises(FileFormatError, match="unknown file type 'boat'"):
        read_flight_file(bad)
    with pytest.raises(FileFormatError, match="no such file"):
        read_flight_file(tmp_path / "missing.npz")
    made = simulate_flight_file(WindScenario(), seed=0)
    made.arrays.pop("v_ads")
    with pytest.raises(FileFormatError, match="missing entry 'v_ads'"):
        wind_errors(made)
