"""HDF5 and MAT v7.3 files without h5py (the ``hdf5`` extra): one line that names the extra; MAT v5 still reads."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from builders import static_imu
from cli_contract import invoke, one_error_line

from imunav.errors import MissingDependencyError
from imunav.io import read_imu, write_imu


def _without_h5py(monkeypatch: pytest.MonkeyPatch) -> None:
    for k in [k for k in sys.modules if k == "h5py" or k.startswith("h5py.")] or ["h5py"]:
        monkeypatch.setitem(sys.modules, k, None)  # `import h5py` raises ImportError


def test_hdf5_and_mat73_name_the_extra_without_h5py(monkeypatch, tmp_path):
    data = static_imu(n=50)
    h5, m73, m5 = tmp_path / "rec.h5", tmp_path / "rec73.mat", tmp_path / "rec5.mat"
    write_imu(data, h5)
    write_imu(data, m73, format="mat73")
    write_imu(data, m5)
    _without_h5py(monkeypatch)
    for path in (h5, m73):
        with pytest.raises(MissingDependencyError, match=r"pip install 'imunav\[hdf5\]'"):
            read_imu(path)
    with pytest.raises(MissingDependencyError, match=r"imunav\[hdf5\]"):
        write_imu(data, tmp_path / "new.h5")
    assert not (tmp_path / "new.h5").exists()
    np.testing.assert_array_equal(read_imu(m5).gyro, data.gyro)  # MAT v5 is scipy's
    line = one_error_line(invoke("info", h5))
    assert "imunav[hdf5]" in line
