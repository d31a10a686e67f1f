"""Readers, writers and dataset loaders.

:func:`read_imu` / :func:`write_imu` handle CSV (column mapping), Parquet,
HDF5, MAT (v5 and v7.3) and NPZ recordings; every writer is atomic.
:func:`to_dataframe` / :func:`from_dataframe` convert to and from pandas.
"""

from imunav.io.core import FORMATS, format_from_suffix, read_imu, write_imu
from imunav.io.dataframe import from_dataframe, to_dataframe
from imunav.io.datasets import shared_data_dir, shared_data_path

__all__ = ["FORMATS", "format_from_suffix", "read_imu", "write_imu", "from_dataframe", "to_dataframe",
           "shared_data_dir", "shared_data_path"]
