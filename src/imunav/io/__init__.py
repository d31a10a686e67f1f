"""Readers, writers and dataset loaders.

:func:`read_imu` / :func:`write_imu` handle CSV (column mapping), Parquet,
HDF5, MAT (v5 and v7.3) and NPZ recordings; every writer is atomic.
:func:`to_dataframe` / :func:`from_dataframe` convert to and from pandas.

``read_imu``, ``write_imu``, ``format_from_suffix``, ``FORMATS`` (:mod:`imunav.io.core`) and ``to_dataframe``,
``from_dataframe`` (:mod:`imunav.io.dataframe`) load their module on first use (PEP 562 ``__getattr__``): importing
one reader (``imunav.io.ulog``, ``imunav.io.rosbag``, ``imunav.io.logs``) runs this ``__init__`` without loading
every format's reader, and with them pandas (the CSV reader's) and scipy.io (the MAT reader's), 0.5-0.9 s of a
first ``imunav attitude run`` on a PX4 log (issue 35).  ``from imunav.io import read_imu`` works as before.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from imunav.io.datasets import shared_data_dir, shared_data_path

if TYPE_CHECKING:  # the lazy names' definitions (tests/test_import_graph.py resolves them here)
    from imunav.io.core import FORMATS, format_from_suffix, read_imu, write_imu
    from imunav.io.dataframe import from_dataframe, to_dataframe

__all__ = ["FORMATS", "format_from_suffix", "read_imu", "write_imu", "from_dataframe", "to_dataframe",
           "shared_data_dir", "shared_data_path"]

#: the names loaded on first access by :func:`__getattr__`, and their module
_LAZY = {"FORMATS": "core", "format_from_suffix": "core", "read_imu": "core", "write_imu": "core",
        "from_dataframe": "dataframe", "to_dataframe": "dataframe"}


def __getattr__(name: str) -> Any:
    """The names of ``_LAZY`` on first access (PEP 562); one of the package's lazy re-exports, allowed by
    ``tests/test_import_graph.py`` (``LAZY_REEXPORTS``) and ``docs/design.md`` (section 1)."""
    where = _LAZY.get(name)
    if where == "core":
        from imunav.io import core as module  # lazy re-export: loads every format's reader
    elif where == "dataframe":
        from imunav.io import dataframe as module  # lazy re-export: loads pandas
    else:
        raise AttributeError(f"module 'imunav.io' has no attribute {name!r}")
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
